//! The triangle's tests.

use super::super::test_util::*;
use super::*;
use crate::geometry::Mat4;

fn mesh_of(positions: &[[f32; 3]], indices: &[u32]) -> acr_parser::Mesh {
    acr_parser::Mesh {
        positions: positions.to_vec(),
        normals: None,
        uvs: None,
        indices: indices.to_vec(),
    }
}

fn single() -> acr_parser::Mesh {
    mesh_of(
        &[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
        &[0, 1, 2],
    )
}

/// The closest hit over all triangles.
fn closest(mesh: &TriangleMesh, ray: &Ray, t_max: f32) -> Option<(usize, TriangleHit)> {
    let mut best: Option<(usize, TriangleHit)> = None;
    let mut t_max = t_max;
    for tri in 0..mesh.triangle_count() {
        if let Some(h) = intersect_triangle(mesh, tri, ray, t_max) {
            t_max = h.t;
            best = Some((tri, h));
        }
    }
    best
}

#[test]
fn hit_gives_t_p_n_uv() {
    let m = TriangleMesh::from_mesh(&single(), &Transform::IDENTITY, false);
    let ray = Ray::new(Vec3::new(0.25, 0.5, 2.0), Vec3::new(0.0, 0.0, -2.0), 0.5);
    let h = intersect_triangle(&m, 0, &ray, f32::INFINITY).unwrap();
    close(h.t, 1.0, 1e-6);
    close(h.b0 + h.b1 + h.b2, 1.0, 1e-6);
    let si = triangle_interaction(&m, 0, &ray, &h);
    close3(si.p, Vec3::new(0.25, 0.5, 0.0), 1e-6);
    // (p0 - p2) x (p1 - p2) for a counter-clockwise triangle seen from +z points to +z.
    close3(si.n, Vec3::Z, 1e-6);
    close3(si.shading_n, si.n, 0.0);
    // Default uvs (0,0), (1,0), (1,1): p = (u - v) x + v y... here b1 = 0.25, b2 = 0.5.
    close(si.uv.x, h.b1 + h.b2, 1e-6);
    close(si.uv.y, h.b2, 1e-6);
    // dp/du and dp/dv reproduce the uv mapping: p0 + u dpdu + v dpdv.
    close3(si.dpdu * si.uv.x + si.dpdv * si.uv.y, si.p, 1e-6);
    close3(si.wo, Vec3::Z, 1e-6);
    assert_eq!(si.time, 0.5);
    // Behind the origin, beyond t_max, parallel: no hit.
    let away = Ray::new(ray.o, -ray.d, 0.0);
    assert!(intersect_triangle(&m, 0, &away, f32::INFINITY).is_none());
    assert!(intersect_triangle(&m, 0, &ray, 0.999).is_none());
    assert!(intersect_triangle(&m, 0, &ray, 1.0).is_some());
    let parallel = Ray::new(Vec3::new(-1.0, 0.2, 0.0), Vec3::X, 0.0);
    assert!(intersect_triangle(&m, 0, &parallel, f32::INFINITY).is_none());
    let outside = Ray::new(Vec3::new(0.8, 0.8, 1.0), -Vec3::Z, 0.0);
    assert!(intersect_triangle(&m, 0, &outside, f32::INFINITY).is_none());
    // From below: same normal (it is not flipped towards the ray).
    let below = Ray::new(Vec3::new(0.2, 0.2, -1.0), Vec3::Z, 0.0);
    let h = intersect_triangle(&m, 0, &below, f32::INFINITY).unwrap();
    close3(triangle_interaction(&m, 0, &below, &h).n, Vec3::Z, 1e-6);
    let (lo, hi) = triangle_bounds(&m, 0);
    assert_eq!((lo, hi), (Vec3::ZERO, Vec3::new(1.0, 1.0, 0.0)));
    close(triangle_area(&m, 0), 0.5, 1e-7);
}

#[test]
fn uvs_give_pbrt_derivatives() {
    let mut mesh = single();
    mesh.uvs = Some(vec![[0.0, 0.0], [2.0, 0.0], [0.0, 4.0]]);
    let m = TriangleMesh::from_mesh(&mesh, &Transform::IDENTITY, false);
    let ray = Ray::new(Vec3::new(0.25, 0.5, 1.0), -Vec3::Z, 0.0);
    let h = intersect_triangle(&m, 0, &ray, f32::INFINITY).unwrap();
    let si = triangle_interaction(&m, 0, &ray, &h);
    close3(si.dpdu, Vec3::new(0.5, 0.0, 0.0), 1e-6);
    close3(si.dpdv, Vec3::new(0.0, 0.25, 0.0), 1e-6);
    close(si.uv.x, 0.5, 1e-6);
    close(si.uv.y, 2.0, 1e-6);
    // Degenerate uvs: pbrt's coordinate system around -n (from (p2 - p0) x (p1 - p0)).
    mesh.uvs = Some(vec![[0.5, 0.5]; 3]);
    let m = TriangleMesh::from_mesh(&mesh, &Transform::IDENTITY, false);
    let si = triangle_interaction(&m, 0, &ray, &h);
    let (a, b) = coordinate_system(-Vec3::Z);
    close3(si.dpdu, a, 1e-6);
    close3(si.dpdv, b, 1e-6);
    close(si.uv.x, 0.5, 1e-6);
    close(si.uv.y, 0.5, 1e-6);
}

#[test]
fn orientation_follows_reverse_orientation_and_handedness() {
    let ray = Ray::new(Vec3::new(0.2, 0.2, 1.0), -Vec3::Z, 0.0);
    let n_of = |m: &TriangleMesh, ray: &Ray| {
        let h = intersect_triangle(m, 0, ray, f32::INFINITY).unwrap();
        let si = triangle_interaction(m, 0, ray, &h);
        let (_, ns) = sample_triangle(m, 0, Vec2::new(0.3, 0.6));
        close3(ns, si.n, 1e-6);
        si.n
    };
    let m = TriangleMesh::from_mesh(&single(), &Transform::IDENTITY, true);
    close3(n_of(&m, &ray), -Vec3::Z, 1e-6);
    // A mirror in x reverses the winding; the handedness flip restores the object-space
    // orientation (+z), and ReverseOrientation then flips it again.
    let mirror = Transform::new(Mat4::from_scale(Vec3::new(-1.0, 1.0, 1.0)));
    let mray = Ray::new(Vec3::new(-0.2, 0.2, 1.0), -Vec3::Z, 0.0);
    let m = TriangleMesh::from_mesh(&single(), &mirror, false);
    assert!(m.transform_swaps_handedness);
    close3(n_of(&m, &mray), Vec3::Z, 1e-6);
    let m = TriangleMesh::from_mesh(&single(), &mirror, true);
    close3(n_of(&m, &mray), -Vec3::Z, 1e-6);
}

#[test]
fn shading_normals_set_the_frame_and_flip_the_geometric_normal() {
    let mut mesh = single();
    // Normals pointing down (-z): the geometric normal is flipped to their hemisphere,
    // whatever ReverseOrientation says (as pbrt-v3).
    let tilt = Vec3::new(0.3, 0.0, -1.0).normalize().to_array();
    mesh.normals = Some(vec![tilt, [0.0, 0.0, -1.0], [0.0, 0.0, -2.0]]);
    for rev in [false, true] {
        let m = TriangleMesh::from_mesh(&mesh, &Transform::IDENTITY, rev);
        let ray = Ray::new(Vec3::new(0.25, 0.25, 1.0), -Vec3::Z, 0.0);
        let h = intersect_triangle(&m, 0, &ray, f32::INFINITY).unwrap();
        let si = triangle_interaction(&m, 0, &ray, &h);
        close3(si.n, -Vec3::Z, 1e-6);
        let expect =
            (h.b0 * Vec3::from_array(tilt) - h.b1 * Vec3::Z - 2.0 * h.b2 * Vec3::Z).normalize();
        close3(si.shading_n, expect, 1e-5);
        close(si.shading_dpdu.length(), 1.0, 1e-5);
        close(si.shading_dpdu.dot(si.shading_n), 0.0, 1e-5);
        // pbrt-v3 computes ts = ss x ns, ss = ts x ns: the shading tangent is dp/du (+x)
        // made orthogonal to ns, and negated.
        assert!(si.shading_dpdu.x < -0.9);
        close3(
            si.shading_dpdu.cross(si.shading_n.cross(si.shading_dpdu)),
            si.shading_n,
            1e-5,
        );
        let (_, n) = sample_triangle(&m, 0, Vec2::new(0.0, 0.0));
        assert!(n.dot(si.n) > 0.0);
        close(n.length(), 1.0, 1e-5);
    }
    // Normals are transformed by the inverse transpose.
    mesh.normals = Some(vec![[1.0, 1.0, 1.0]; 3]);
    let t = Transform::new(Mat4::from_scale(Vec3::new(2.0, 1.0, 1.0)));
    let m = TriangleMesh::from_mesh(&mesh, &t, false);
    close3(
        m.normals.as_ref().unwrap()[0],
        Vec3::new(0.5, 1.0, 1.0),
        1e-6,
    );
    close3(m.positions[1], Vec3::new(2.0, 0.0, 0.0), 0.0);
}

#[test]
fn zero_area_triangles_are_never_hit() {
    let m = TriangleMesh::from_mesh(
        &mesh_of(
            &[[0.0, 0.0, 0.0], [1.0, 1.0, 1.0], [2.0, 2.0, 2.0], [0.0; 3]],
            &[0, 1, 2, 0, 3, 1],
        ),
        &Transform::IDENTITY,
        false,
    );
    let mut rng = Rng::new(7);
    for _ in 0..1000 {
        let o = rng.v3() * 4.0;
        let target = Vec3::splat(rng.f() * 2.0);
        let ray = Ray::new(o, target - o, 0.0);
        assert!(closest(&m, &ray, f32::INFINITY).is_none());
    }
    assert_eq!(triangle_area(&m, 0), 0.0);
}

/// An octahedron |x| + |y| + |z| = 1, scaled by `s` and centred at `c`, outward-wound.
fn octahedron(s: f32, c: Vec3) -> TriangleMesh {
    let mut pos = Vec::new();
    for v in [Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z] {
        pos.push((c + v * s).to_array());
    }
    let mut idx = Vec::new();
    for (x, sx) in [(0u32, 1.0f32), (1, -1.0)] {
        for (y, sy) in [(2u32, 1.0f32), (3, -1.0)] {
            for (z, sz) in [(4u32, 1.0f32), (5, -1.0)] {
                // Outward: (x, y, z) is counter-clockwise seen from outside when the octant's
                // sign product is positive.
                if sx * sy * sz > 0.0 {
                    idx.extend([x, y, z]);
                } else {
                    idx.extend([x, z, y]);
                }
            }
        }
    }
    TriangleMesh::from_mesh(&mesh_of(&pos, &idx), &Transform::IDENTITY, false)
}

/// A cube [-1, 1]^3 scaled by `s` and centred at `c`, each face an n x n grid of quads split
/// along alternating diagonals, outward-wound.
fn subdivided_cube(n: usize, s: f32, c: Vec3) -> TriangleMesh {
    let mut pos: Vec<[f32; 3]> = Vec::new();
    let mut idx: Vec<u32> = Vec::new();
    let mut index_of = std::collections::HashMap::new();
    let mut vertex = |p: Vec3, pos: &mut Vec<[f32; 3]>| -> u32 {
        let key = (p * 1024.0).round().as_ivec3().to_array();
        *index_of.entry(key).or_insert_with(|| {
            pos.push((c + p * s).to_array());
            (pos.len() - 1) as u32
        })
    };
    for axis in 0..3 {
        for sign in [-1.0f32, 1.0] {
            let mut normal = Vec3::ZERO;
            normal[axis] = sign;
            let mut a = Vec3::ZERO;
            a[(axis + 1) % 3] = 1.0;
            let b = normal.cross(a);
            for j in 0..n {
                for i in 0..n {
                    let f = |i: usize, j: usize| {
                        normal
                            + a * (2.0 * i as f32 / n as f32 - 1.0)
                            + b * (2.0 * j as f32 / n as f32 - 1.0)
                    };
                    let v00 = vertex(f(i, j), &mut pos);
                    let v10 = vertex(f(i + 1, j), &mut pos);
                    let v11 = vertex(f(i + 1, j + 1), &mut pos);
                    let v01 = vertex(f(i, j + 1), &mut pos);
                    // (a, b, normal) is right-handed, so v00 v10 v11 is counter-clockwise
                    // seen from outside.
                    if (i + j) % 2 == 0 {
                        idx.extend([v00, v10, v11, v00, v11, v01]);
                    } else {
                        idx.extend([v00, v10, v01, v10, v11, v01]);
                    }
                }
            }
        }
    }
    TriangleMesh::from_mesh(&mesh_of(&pos, &idx), &Transform::IDENTITY, false)
}

/// Every vertex and a set of exact points on every edge of `mesh`.
fn vertices_and_edge_points(mesh: &TriangleMesh) -> Vec<Vec3> {
    let mut pts = mesh.positions.clone();
    for tri in 0..mesh.triangle_count() {
        let v = mesh.vertices(tri);
        for e in 0..3 {
            let (a, b) = (v[e], v[(e + 1) % 3]);
            for k in 1..4 {
                // Exact when the coordinates are on a fine enough binary grid.
                pts.push(a + (b - a) * (k as f32 * 0.25));
            }
        }
    }
    pts
}

/// Asserts that rays through the given surface points and an interior point hit the mesh,
/// from outside (far away) and from the inside, and that the outward normal orientation
/// is consistent.
fn assert_watertight(mesh: &TriangleMesh, center: Vec3, size: f32, far: f32) {
    let mut rng = Rng::new(11);
    let mut count = 0;
    for q in vertices_and_edge_points(mesh) {
        for _ in 0..6 {
            // An interior point (well inside) on the line, and an origin on the far side.
            let inner = center + rng.v3() * (0.3 * size);
            let dir = (q - inner).normalize();
            for (k, o) in [q + dir * far, center, inner].into_iter().enumerate() {
                let ray = Ray::new(o, q - o, 0.0);
                let hit = closest(mesh, &ray, f32::INFINITY);
                let Some((tri, h)) = hit else {
                    panic!("crack: ray from {o} towards {q} (through {inner}) missed");
                };
                let si = triangle_interaction(mesh, tri, &ray, &h);
                // Entering from outside hits a front face, leaving from inside a back face.
                if k == 0 {
                    assert!(si.n.dot(ray.d) < 0.0, "back face hit from outside at {q}");
                    // The origin and direction are rounded: the ray passes q within a few
                    // ulps of the origin's magnitude.
                    let tol = 1e-6 * (far + q.abs().max_element()) + 1e-5 * size;
                    assert!((si.p - q).length() < tol, "entry {} far from {q}", si.p);
                } else {
                    assert!(si.n.dot(ray.d) > 0.0);
                }
                count += 1;
            }
        }
    }
    assert!(count > 100);
}

#[test]
fn octahedron_is_watertight_at_vertices_and_edges() {
    assert_watertight(&octahedron(1.0, Vec3::ZERO), Vec3::ZERO, 1.0, 10.0);
    assert_watertight(&octahedron(1.0, Vec3::ZERO), Vec3::ZERO, 1.0, 1e5);
    let c = Vec3::new(1e6, -1e6, 1e6);
    assert_watertight(&octahedron(1024.0, c), c, 1024.0, 1e5);
}

#[test]
fn subdivided_cube_is_watertight_at_vertices_and_edges() {
    assert_watertight(&subdivided_cube(3, 1.0, Vec3::ZERO), Vec3::ZERO, 1.0, 1e5);
    let c = Vec3::new(-1e6, 1e6, 2e6);
    assert_watertight(&subdivided_cube(4, 4096.0, c), c, 4096.0, 1e5);
}

proptest::proptest! {
    #![proptest_config(proptest::prelude::ProptestConfig {
    cases: 2048,
    // Fixed: CI runs the same cases every time (a failure reproduces); change the seed
    // to explore further.
    rng_seed: proptest::test_runner::RngSeed::Fixed(0xacc0_5eed),
    ..proptest::prelude::ProptestConfig::default()
})]

    /// Property: a closed mesh placed anywhere (rotated, scaled from 1e-3 to 1e4, up to
    /// 1e6 from the origin, at least 1e-4 of its distance across) has no cracks: a ray from outside, aimed through a vertex or a
    /// point of a shared edge at a point inside, hits a front face, and the ray from the
    /// inside point back out through it hits a back face.
    #[test]
    fn closed_meshes_anywhere_have_no_cracks_at_shared_edges_and_vertices(
        cube in proptest::prelude::any::<bool>(),
        n in 1usize..4,
        axis in proptest::array::uniform3(-1.0f32..1.0),
        angle in 0.0f32..360.0,
        log_scale in -3.0f32..4.0,
        centre in proptest::array::uniform3(-1e6f32..1e6),
        tri_pick in 0usize..10_000,
        edge in 0usize..3,
        k in 0u32..4,
        inner_offset in proptest::array::uniform3(-1.0f32..1.0),
        log_far in 0.0f32..5.0,
    ) {
        let centre = Vec3::from_array(centre);
        // At least ~1600 ulps of the centre's coordinates across: smaller meshes collapse
        // in f32 (the ulp at 1e6 is 0.0625) and are no longer the same solid.
        let scale = 10f32.powf(log_scale).max(1e-4 * centre.abs().max_element());
        let axis = Vec3::from_array(axis).try_normalize().unwrap_or(Vec3::Z);
        let m = Mat4::from_translation(centre)
            * Mat4::from_axis_angle(axis, angle.to_radians())
            * Mat4::from_scale(Vec3::splat(scale));
        let mut mesh = if cube {
            subdivided_cube(n, 1.0, Vec3::ZERO)
        } else {
            octahedron(1.0, Vec3::ZERO)
        };
        for p in &mut mesh.positions {
            *p = m.transform_point3(*p);
        }
        let v = mesh.vertices(tri_pick % mesh.triangle_count());
        let (a, b) = (v[edge], v[(edge + 1) % 3]);
        let q = a + (b - a) * (k as f32 * 0.25);
        // Well inside both solids (the octahedron's inscribed sphere has radius 0.577).
        let inner = centre + Vec3::from_array(inner_offset) * (0.3 * scale);
        let dir = (q - inner).normalize();
        let far = scale * 10f32.powf(log_far);
        let from_outside = Ray::new(q + dir * far, -dir, 0.0);
        let hit = closest(&mesh, &from_outside, f32::INFINITY);
        proptest::prop_assert!(hit.is_some(), "crack: ray from outside through {} missed", q);
        let (tri, h) = hit.unwrap();
        let si = triangle_interaction(&mesh, tri, &from_outside, &h);
        proptest::prop_assert!(si.n.dot(from_outside.d) < 0.0, "back face from outside");
        let from_inside = Ray::new(inner, q - inner, 0.0);
        let hit = closest(&mesh, &from_inside, f32::INFINITY);
        proptest::prop_assert!(hit.is_some(), "crack: ray from inside through {} missed", q);
        let (tri, h) = hit.unwrap();
        let si = triangle_interaction(&mesh, tri, &from_inside, &h);
        proptest::prop_assert!(si.n.dot(from_inside.d) > 0.0, "front face from inside");
    }
}

#[test]
fn axis_aligned_rays_at_shared_edges_hit() {
    // Rays exactly along the axes at the cube's grid lines (edge functions exactly 0).
    let m = subdivided_cube(4, 1.0, Vec3::ZERO);
    for i in 0..=8 {
        for j in 0..=8 {
            let x = -1.0 + i as f32 * 0.25;
            let y = -1.0 + j as f32 * 0.25;
            if x.abs() == 1.0 || y.abs() == 1.0 {
                continue;
            }
            for (o, d) in [
                (Vec3::new(x, y, 1e5), -Vec3::Z),
                (Vec3::new(x, 1e5, y), -Vec3::Y),
                (Vec3::new(-1e5, x, y), Vec3::X),
                (Vec3::new(x, y, 0.0), Vec3::Z),
            ] {
                let ray = Ray::new(o, d, 0.0);
                let (_, h) = closest(&m, &ray, f32::INFINITY)
                    .unwrap_or_else(|| panic!("crack at {o} along {d}"));
                let p = ray.at(h.t);
                close(p.abs().max_element(), 1.0, 1e-6);
            }
        }
    }
}

#[test]
fn sampled_points_lie_on_the_triangle_with_uniform_density() {
    let t = Transform::new(
        Mat4::from_translation(Vec3::new(3.0, -2.0, 1.0)) * Mat4::from_rotation_y(0.4),
    );
    let m = TriangleMesh::from_mesh(
        &mesh_of(
            &[[0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [0.5, 3.0, 0.0]],
            &[0, 1, 2],
        ),
        &t,
        false,
    );
    let area = triangle_area(&m, 0);
    close(area, 3.0, 1e-5);
    let (lo, hi) = triangle_bounds(&m, 0);
    let [p0, p1, p2] = m.vertices(0);
    let ng = (p1 - p0).cross(p2 - p0).normalize();
    let mut rng = Rng::new(5);
    let n = 20000;
    let mut centroid = Vec3::ZERO;
    for _ in 0..n {
        let (p, nn) = sample_triangle(&m, 0, rng.v2());
        close3(nn, ng, 1e-5);
        close((p - p0).dot(ng), 0.0, 1e-5);
        assert!(p.cmpge(lo - 1e-5).all() && p.cmple(hi + 1e-5).all());
        centroid += p / n as f32;
    }
    // Uniform by area: the mean is the centroid.
    close3(centroid, (p0 + p1 + p2) / 3.0, 0.02);
}
