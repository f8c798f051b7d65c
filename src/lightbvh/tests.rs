//! Tests of the light BVH: probabilities, importance against pbrt-v4's formula, bounds.

use super::bounds::{angle_between, safe_acos, DirectionCone};
use super::*;
use crate::accel::Geometry;
use crate::accel::PrimKind;
use crate::geometry::Spectrum;
use crate::light::AreaShape;
use crate::shapes::{Transform, TriangleMesh};

/// A small deterministic generator for test inputs.
struct Lcg(u64);
impl Lcg {
    fn next(&mut self) -> f32 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((self.0 >> 40) as f32) / (1u64 << 24) as f32
    }
    fn vec(&mut self, scale: f32) -> Vec3 {
        Vec3::new(self.next(), self.next(), self.next()) * 2.0 * scale - Vec3::splat(scale)
    }
}

/// `n` one-sided triangles scattered and turned every way, a point light, a spot light and
/// a distant light; the world holding the triangles.
fn scene(n: usize, seed: u64) -> (Vec<Light>, Geometry) {
    let mut rng = Lcg(seed);
    let mut positions = Vec::new();
    for _ in 0..n {
        let c = rng.vec(5.0);
        for _ in 0..3 {
            positions.push(c + rng.vec(0.3));
        }
    }
    let mesh = acr_parser::Mesh {
        positions: positions.iter().map(|p| p.to_array()).collect(),
        normals: None,
        uvs: None,
        indices: (0..3 * n as u32).collect(),
    };
    let mut world = Geometry::default();
    world
        .meshes
        .push(TriangleMesh::from_mesh(&mesh, &Transform::IDENTITY, false));
    let mut lights: Vec<Light> = (0..n)
        .map(|tri| {
            let kind = PrimKind::Triangle {
                mesh: 0,
                tri: tri as u32,
            };
            Light::Area {
                shape: AreaShape { kind },
                l_emit: Spectrum::new(1.0 + rng.next(), 1.0, 0.5),
                two_sided: tri % 5 == 0,
                area: crate::light::prim_area(&world, kind),
            }
        })
        .collect();
    lights.push(Light::Point {
        pos: Vec3::new(0.0, 6.0, 0.0),
        intensity: Spectrum::splat(20.0),
    });
    lights.push(Light::Spot {
        pos: Vec3::new(2.0, 6.0, 0.0),
        light_from_world: crate::light::spot_frame(Vec3::NEG_Y),
        intensity: Spectrum::splat(30.0),
        cos_total: 30f32.to_radians().cos(),
        cos_falloff_start: 25f32.to_radians().cos(),
    });
    lights.push(Light::Distant {
        w: Vec3::Y,
        radiance: Spectrum::ONE,
        world_radius: 10.0,
    });
    (lights, world)
}

fn contexts(count: usize, seed: u64) -> Vec<LightContext> {
    let mut rng = Lcg(seed);
    (0..count)
        .map(|i| LightContext {
            p: rng.vec(8.0),
            n: if i % 7 == 0 {
                Vec3::ZERO
            } else {
                rng.vec(1.0).normalize_or(Vec3::Z)
            },
        })
        .collect()
}

#[test]
fn probabilities_sum_to_one_and_sampling_reports_them() {
    for n in [1, 2, 3, 5, 64, 1000] {
        let (lights, world) = scene(n, n as u64);
        let bvh = LightBvh::new(&lights, &world);
        for ctx in contexts(40, 7 + n as u64) {
            let pmfs: Vec<f32> = (0..lights.len()).map(|i| bvh.pmf(ctx, i)).collect();
            let total: f64 = pmfs.iter().map(|&p| p as f64).sum();
            // At most 1: as in pbrt-v4, the walk stops (no light) at a node whose bounds
            // prove that none of its lights reaches the point, and that mass is lost.
            assert!(total <= 1.0 + 1e-4, "n {n}: total {total}");
            // The distant light alone is chosen with 1/2, whatever the tree does.
            assert!(total >= 0.5 - 1e-6, "n {n}: total {total}");
            // Stratified u: the share of walks that choose nothing is the lost mass, and
            // every choice reports the probability pmf() gives it.
            let count = 4000;
            let mut none = 0;
            for j in 0..count {
                match bvh.sample(ctx, (j as f32 + 0.5) / count as f32) {
                    Some((i, p)) => {
                        assert!(p > 0.0, "n {n}: chosen with probability 0");
                        let q = pmfs[i];
                        assert!((p - q).abs() <= 1e-5 * q, "n {n}: sample {p} != pmf {q}");
                    }
                    None => none += 1,
                }
            }
            let lost = none as f64 / count as f64;
            assert!(
                (lost - (1.0 - total)).abs() < 2e-3,
                "n {n}: {lost} of the walks chose nothing, lost mass {}",
                1.0 - total
            );
        }
    }
}

#[test]
fn choices_follow_the_probabilities() {
    // 30 lights, one point; the frequencies of 200,000 stratified choices against pmf.
    let (lights, world) = scene(30, 3);
    let bvh = LightBvh::new(&lights, &world);
    let ctx = LightContext {
        p: Vec3::new(0.5, -1.0, 0.2),
        n: Vec3::Y,
    };
    let draws = 200_000;
    let mut counts = vec![0u32; lights.len()];
    for j in 0..draws {
        let u = (j as f32 + 0.5) / draws as f32;
        if let Some((i, _)) = bvh.sample(ctx, u) {
            counts[i] += 1;
        }
    }
    for (i, &c) in counts.iter().enumerate() {
        let expected = bvh.pmf(ctx, i) as f64 * draws as f64;
        assert!(
            (c as f64 - expected).abs() <= 4.0 + 1e-3 * expected,
            "light {i}: {c} choices, expected {expected}"
        );
    }
}

#[test]
fn a_one_sided_emitter_is_never_chosen_from_behind() {
    // A triangle facing +z (counter-clockwise seen from +z) and a point light.
    let mesh = acr_parser::Mesh {
        positions: vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
        normals: None,
        uvs: None,
        indices: vec![0, 1, 2],
    };
    let mut world = Geometry::default();
    world
        .meshes
        .push(TriangleMesh::from_mesh(&mesh, &Transform::IDENTITY, false));
    let kind = PrimKind::Triangle { mesh: 0, tri: 0 };
    let lights = vec![
        Light::Area {
            shape: AreaShape { kind },
            l_emit: Spectrum::ONE,
            two_sided: false,
            area: 0.5,
        },
        Light::Point {
            pos: Vec3::new(0.0, 0.0, -5.0),
            intensity: Spectrum::ONE,
        },
    ];
    let bvh = LightBvh::new(&lights, &world);
    let behind = LightContext {
        p: Vec3::new(0.2, 0.2, -1.0),
        n: Vec3::Z,
    };
    assert_eq!(bvh.pmf(behind, 0), 0.0);
    assert_eq!(bvh.pmf(behind, 1), 1.0);
    let front = LightContext {
        p: Vec3::new(0.2, 0.2, 1.0),
        n: Vec3::Z,
    };
    assert!(bvh.pmf(front, 0) > 0.5, "{}", bvh.pmf(front, 0));
    // Alone, from behind, nothing can be chosen.
    let alone = LightBvh::new(&lights[..1], &world);
    assert_eq!(alone.sample(behind, 0.3), None);
    assert_eq!(alone.sample(front, 0.3).map(|(i, _)| i), Some(0));
}

/// pbrt-v4's `LightBounds::Importance`, transcribed on its own (scalar, with divisions),
/// to check the tree's four-lane version against.
fn pbrt_importance(b: &LightBounds, ctx: LightContext) -> f32 {
    let cos_sub = |sa: f32, ca: f32, sb: f32, cb: f32| {
        if ca > cb {
            1.0
        } else {
            ca * cb + sa * sb
        }
    };
    let sin_sub = |sa: f32, ca: f32, sb: f32, cb: f32| {
        if ca > cb {
            0.0
        } else {
            sa * cb - ca * sb
        }
    };
    let pc = (b.lo + b.hi) / 2.0;
    let d2 = ctx.p.distance_squared(pc).max((b.hi - b.lo).length() / 2.0);
    let wi = (ctx.p - pc).normalize();
    let mut cos_w = b.w.dot(wi);
    if b.two_sided {
        cos_w = cos_w.abs();
    }
    let sin_w = (1.0 - cos_w * cos_w).max(0.0).sqrt();
    let r2 = b.lo.distance_squared(pc);
    let cos_b = if ctx.p.distance_squared(pc) < r2 {
        -1.0
    } else {
        (1.0 - r2 / ctx.p.distance_squared(pc)).max(0.0).sqrt()
    };
    let sin_b = (1.0 - cos_b * cos_b).max(0.0).sqrt();
    let sin_o = (1.0 - b.cos_theta_o * b.cos_theta_o).max(0.0).sqrt();
    let cos_x = cos_sub(sin_w, cos_w, sin_o, b.cos_theta_o);
    let sin_x = sin_sub(sin_w, cos_w, sin_o, b.cos_theta_o);
    let cos_p = cos_sub(sin_x, cos_x, sin_b, cos_b);
    if cos_p <= b.cos_theta_e {
        return 0.0;
    }
    let mut importance = b.phi * cos_p / d2;
    if ctx.n != Vec3::ZERO {
        let cos_i = wi.dot(ctx.n).abs();
        let sin_i = (1.0 - cos_i * cos_i).max(0.0).sqrt();
        importance *= cos_sub(sin_i, cos_i, sin_b, cos_b);
    }
    importance.max(0.0)
}

#[test]
fn importance_is_pbrt_v4_s() {
    let (lights, world) = scene(12, 5);
    let bounds: Vec<LightBounds> = lights
        .iter()
        .filter_map(|l| LightBounds::of(l, &world))
        .collect();
    // Single lights and unions of several, four to a node.
    let mut groups: Vec<LightBounds> = bounds.clone();
    for w in bounds.windows(3) {
        groups.push(LightBounds::union(&LightBounds::union(&w[0], &w[1]), &w[2]));
    }
    for chunk in groups.chunks(4) {
        let mut node = Node::empty();
        for (k, b) in chunk.iter().enumerate() {
            node.set(k, b, 0, (0, 1));
        }
        for ctx in contexts(200, 11) {
            let (lanes, _) = node.importance(ctx);
            for (k, b) in chunk.iter().enumerate() {
                let want = pbrt_importance(b, ctx);
                let got = lanes[k];
                assert!(
                    (got - want).abs() <= 1e-3 * want.abs() + 1e-6,
                    "{got} != {want} at {ctx:?} for {b:?}"
                );
            }
            for k in chunk.len()..4 {
                assert_eq!(lanes[k], 0.0, "an empty slot has no importance");
            }
        }
    }
}

#[test]
fn cone_union_holds_both_cones() {
    let mut rng = Lcg(9);
    for _ in 0..500 {
        let a = DirectionCone {
            w: rng.vec(1.0).normalize_or(Vec3::Z),
            cos_theta: rng.next() * 2.0 - 1.0,
        };
        let b = DirectionCone {
            w: rng.vec(1.0).normalize_or(Vec3::X),
            cos_theta: rng.next() * 2.0 - 1.0,
        };
        let u = DirectionCone::union(a, b);
        // Each cone's axis and its rim towards the other's axis lie within the union.
        for c in [a, b] {
            let slack = 1e-4;
            assert!(u.w.dot(c.w) >= u.cos_theta - slack);
            let angle = angle_between(u.w, c.w) + safe_acos(c.cos_theta);
            assert!(angle <= safe_acos(u.cos_theta) + 1e-3 || u.cos_theta <= -1.0);
        }
    }
}

#[test]
fn degenerate_lights_stay_out_of_the_tree() {
    let lights = vec![
        Light::Point {
            pos: Vec3::ZERO,
            intensity: Spectrum::ZERO,
        },
        Light::Point {
            pos: Vec3::splat(f32::NAN),
            intensity: Spectrum::ONE,
        },
        Light::Point {
            pos: Vec3::ONE,
            intensity: Spectrum::ONE,
        },
    ];
    let bvh = LightBvh::new(&lights, &Geometry::default());
    let ctx = LightContext {
        p: Vec3::ZERO,
        n: Vec3::ZERO,
    };
    assert_eq!(bvh.pmf(ctx, 0), 0.0);
    assert_eq!(bvh.pmf(ctx, 1), 0.0);
    assert_eq!(bvh.pmf(ctx, 2), 1.0);
    assert_eq!(bvh.sample(ctx, 0.99).map(|(i, _)| i), Some(2));
    let none = LightBvh::new(&[], &Geometry::default());
    assert_eq!(none.sample(ctx, 0.5), None);
    assert_eq!(none.node_count(), 0);
}
