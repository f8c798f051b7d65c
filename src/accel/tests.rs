//! Tests of the acceleration structure: hits, instances, motion, large geometries.

use super::*;
use crate::scene::Scene;
use std::path::Path;

fn build(text: &str) -> Scene {
    let desc =
        acr_parser::parse_str(text, Path::new("accel-test.pbrt")).unwrap_or_else(|e| panic!("{e}"));
    let mut warnings = Vec::new();
    let scene = Scene::build(&desc, &mut warnings).unwrap_or_else(|e| panic!("{e}"));
    assert!(warnings.is_empty(), "{warnings:?}");
    scene
}

/// A ray along +z from (x, y, -5) at `time`.
fn ray_z(x: f32, y: f32, time: f32) -> Ray {
    Ray::new(Vec3::new(x, y, -5.0), Vec3::Z, time)
}

fn close(a: Vec3, b: Vec3) -> bool {
    (a - b).abs().max_element() < 1e-4
}

/// The camera sits at the world origin, so that render space (camera-centred, see
/// `Scene::render_from_world`) is world space and rays and points below are world's.
const CAMERA: &str = "LookAt 0 0 0  0 0 1  0 1 0\n\
                      Camera \"perspective\" \"float shutteropen\" 0 \"float shutterclose\" 1\n";

#[test]
fn a_static_scene_has_no_motion_and_no_instances() {
    let scene = build(&format!(
        "TransformTimes 0 1\n{CAMERA}WorldBegin\n\
         Translate 0 0 1\nShape \"sphere\" \"float radius\" 0.5\n\
         Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3]\n\
         \"point3 P\" [-2 -2 1  2 -2 1  2 2 1  -2 2 1]\nWorldEnd"
    ));
    let accel = &scene.accel;
    assert!(!accel.has_motion());
    // The shutter is open, but nothing moves: no time dimension.
    assert!(!scene.dims.time);
    assert_eq!(scene.dims.names(), ["x", "y"]);
    assert!(accel.instances.is_empty() && accel.objects.is_empty());
    assert!(accel.tlas.is_none());
    assert_eq!(accel.world.len(), 3);
    // The sphere (centre z = 1) is in front of the quad (z = 2).
    let hit = accel
        .intersect(&ray_z(0.0, 0.0, 0.0), f32::INFINITY)
        .unwrap();
    assert!((hit.t - 5.5).abs() < 1e-4, "{}", hit.t);
    assert!(matches!(hit.prim.kind, PrimKind::Sphere(0)));
    let hit = accel
        .intersect(&ray_z(1.0, 1.0, 0.0), f32::INFINITY)
        .unwrap();
    assert!((hit.t - 7.0).abs() < 1e-4, "{}", hit.t);
    assert!(matches!(hit.prim.kind, PrimKind::Triangle { .. }));
    assert!(accel
        .intersect(&ray_z(3.0, 0.0, 0.0), f32::INFINITY)
        .is_none());
}

/// A sphere of radius 0.5 moving from x = -1 (time 0) to x = 1 (time 1).
const MOVING: &str = "TransformTimes 0 1\nWorldBegin\nAttributeBegin\nTranslate -1 0 0\n\
                      ActiveTransform EndTime\nTranslate 2 0 0\nActiveTransform All\n\
                      Shape \"sphere\" \"float radius\" 0.5\nAttributeEnd\nWorldEnd";

#[test]
fn a_moving_sphere_is_hit_where_it_is_at_the_ray_time() {
    let scene = build(&format!("{CAMERA}{MOVING}"));
    let accel = &scene.accel;
    assert!(accel.has_motion());
    assert!(scene.dims.time);
    assert_eq!(scene.dims.names(), ["x", "y", "t"]);
    assert!(accel.world.is_empty());
    assert_eq!(accel.instances.len(), 1);
    // Bounds cover the whole sweep.
    let (lo, hi) = accel.bounds();
    assert!(lo.x <= -1.5 && hi.x >= 1.5, "{lo} {hi}");
    for (time, centre) in [(0.0, -1.0), (0.5, 0.0), (1.0, 1.0)] {
        let ray = ray_z(centre, 0.0, time);
        let hit = accel
            .intersect(&ray, f32::INFINITY)
            .unwrap_or_else(|| panic!("no hit at x = {centre}, time {time}"));
        assert!((hit.t - 4.5).abs() < 1e-4, "time {time}: t {}", hit.t);
        let si = accel.interaction(&ray, &hit);
        assert!(close(si.p, Vec3::new(centre, 0.0, -0.5)), "{}", si.p);
        assert!(close(si.n, -Vec3::Z), "{}", si.n);
        assert!(accel.occluded(&ray, 10.0));
        assert!(!accel.occluded(&ray, 4.0), "the hit is at 4.5");
        // Where the sphere is not at this time (it is 1 or more away, radius 0.5).
        for x in [centre - 1.0, centre + 1.0, centre + 2.0, centre - 2.0] {
            let away = ray_z(x, 0.0, time);
            assert!(
                accel.intersect(&away, f32::INFINITY).is_none(),
                "hit at x = {x}, time {time}: the sphere is at {centre}"
            );
            assert!(!accel.occluded(&away, f32::INFINITY));
        }
    }
}

#[test]
fn a_motion_with_a_closed_shutter_has_no_time_dimension() {
    let scene = build(&format!(
        "LookAt 0 0 0  0 0 1  0 1 0\n\
         Camera \"perspective\" \"float shutteropen\" 0.5 \"float shutterclose\" 0.5\n\
         {MOVING}"
    ));
    assert!(scene.accel.has_motion());
    assert!(!scene.dims.time);
    // Every ray then has the one time: the sphere is where it is at 0.5.
    assert!(scene
        .accel
        .intersect(&ray_z(0.0, 0.0, 0.5), f32::INFINITY)
        .is_some());
}

#[test]
fn an_object_placed_twice_is_stored_once_and_hit_at_both_places() {
    let scene = build(&format!(
        "{CAMERA}WorldBegin\nObjectBegin \"ball\"\nShape \"sphere\" \"float radius\" 0.5\n\
         ObjectEnd\nAttributeBegin\nTranslate -2 0 0\nObjectInstance \"ball\"\nAttributeEnd\n\
         AttributeBegin\nTranslate 2 0 0\nScale 2 2 2\nObjectInstance \"ball\"\n\
         AttributeEnd\nWorldEnd"
    ));
    let accel = &scene.accel;
    assert!(!accel.has_motion());
    assert!(!scene.dims.time);
    assert!(accel.world.is_empty());
    assert_eq!(accel.objects.len(), 1);
    assert_eq!(accel.objects[0].len(), 1);
    assert_eq!(accel.objects[0].spheres.len(), 1);
    assert_eq!(accel.instances.len(), 2);
    assert!(accel.instances.iter().all(|i| i.object == 0));
    // Left copy: radius 0.5 at x = -2; right copy: radius 1 at x = 2.
    let left = accel
        .intersect(&ray_z(-2.0, 0.0, 0.0), f32::INFINITY)
        .unwrap();
    let right = accel
        .intersect(&ray_z(2.0, 0.0, 0.0), f32::INFINITY)
        .unwrap();
    assert!((left.t - 4.5).abs() < 1e-4, "{}", left.t);
    assert!((right.t - 4.0).abs() < 1e-4, "{}", right.t);
    assert_eq!(left.prim, right.prim);
    assert!(left.instance.is_some() && right.instance.is_some());
    assert_ne!(left.instance, right.instance);
    let si = accel.interaction(&ray_z(2.0, 0.0, 0.0), &right);
    assert!(close(si.p, Vec3::new(2.0, 0.0, -1.0)), "{}", si.p);
    assert!(close(si.n, -Vec3::Z), "{}", si.n);
    // 0.8 off the axis: inside the big copy, outside the small one.
    assert!(accel
        .intersect(&ray_z(2.0, 0.8, 0.0), f32::INFINITY)
        .is_some());
    assert!(accel
        .intersect(&ray_z(-2.0, 0.8, 0.0), f32::INFINITY)
        .is_none());
    // Between them, and where the object is defined (the origin) but not placed.
    for x in [0.0, 3.5, -3.0] {
        assert!(accel
            .intersect(&ray_z(x, 0.0, 0.0), f32::INFINITY)
            .is_none());
        assert!(!accel.occluded(&ray_z(x, 0.0, 0.0), f32::INFINITY));
    }
}

/// splitmix64: a small deterministic generator for the random rays.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1).
    fn f(&mut self) -> f32 {
        (self.next() >> 40) as f32 / (1u64 << 24) as f32
    }

    /// Uniform in [lo, hi).
    fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.f()
    }
}

#[test]
fn shadow_queries_agree_with_closest_hits_on_random_rays() {
    // Every primitive kind, static in the world, in an object placed twice, and moving.
    let scene = build(&format!(
        "{CAMERA}TransformTimes 0 1\nWorldBegin\n\
         Shape \"sphere\" \"float radius\" 0.6\n\
         Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3]\n\
         \"point3 P\" [-3 -1 -3  -3 -1 3  3 -1 3  3 -1 -3]\n\
         AttributeBegin\nTranslate 1.5 0 0\nRotate 90 1 0 0\n\
         Shape \"disk\" \"float radius\" 0.7 \"float innerradius\" 0.2\nAttributeEnd\n\
         AttributeBegin\nTranslate -1.5 0 0\n\
         Shape \"cylinder\" \"float radius\" 0.4 \"float zmin\" -0.5 \"float zmax\" 0.5\n\
         AttributeEnd\n\
         ObjectBegin \"pair\"\nShape \"sphere\" \"float radius\" 0.3\nTranslate 0.5 0 0\n\
         Shape \"trianglemesh\" \"integer indices\" [0 1 2]\n\
         \"point3 P\" [0 0 0  0.6 0 0  0 0.6 0.3]\nObjectEnd\n\
         AttributeBegin\nTranslate 0 1.5 0\nObjectInstance \"pair\"\nAttributeEnd\n\
         AttributeBegin\nTranslate 0 -0.5 1.5\nRotate 40 0 1 0\nObjectInstance \"pair\"\n\
         AttributeEnd\n\
         AttributeBegin\nTranslate 0 0 -1.5\nActiveTransform EndTime\nTranslate 1 1 0\n\
         Rotate 90 0 0 1\nActiveTransform All\n\
         Shape \"sphere\" \"float radius\" 0.35 \"float zmax\" 0.2\nAttributeEnd\nWorldEnd"
    ));
    let accel = &scene.accel;
    assert!(accel.has_motion());
    assert_eq!(accel.objects.len(), 2, "the moving sphere and the object");
    assert_eq!(accel.instances.len(), 3);
    let mut rng = Rng(7);
    let (mut hits, mut misses, mut instanced) = (0, 0, 0);
    for i in 0..60_000 {
        let o = Vec3::new(
            rng.range(-3.0, 3.0),
            rng.range(-2.0, 3.0),
            rng.range(-3.0, 3.0),
        );
        let mut d = Vec3::new(
            rng.range(-1.0, 1.0),
            rng.range(-1.0, 1.0),
            rng.range(-1.0, 1.0),
        );
        if i % 8 == 0 {
            // Axis-aligned, negative zeros included.
            let axis = (rng.next() % 3) as usize;
            let sign = if rng.f() < 0.5 { -1.0 } else { 1.0 };
            d = Vec3::splat(if rng.f() < 0.5 { -0.0 } else { 0.0 });
            d[axis] = sign;
        } else if i % 2 == 0 {
            d = d.normalize_or(Vec3::X);
        }
        let ray = Ray::new(o, d, rng.f());
        let t_max = if i % 3 == 0 {
            f32::INFINITY
        } else {
            rng.range(0.01, 6.0)
        };
        let hit = accel.intersect(&ray, t_max);
        assert_eq!(
            accel.occluded(&ray, t_max),
            hit.is_some(),
            "ray {i}: {ray:?}, t_max {t_max}, hit {hit:?}"
        );
        if let Some(h) = hit {
            hits += 1;
            instanced += usize::from(h.instance.is_some());
            assert!(h.t > 0.0 && h.t <= t_max, "ray {i}: t {} of {t_max}", h.t);
            // Nothing closer: asking again up to the hit finds nothing nearer.
            if let Some(nearer) = accel.intersect(&ray, h.t) {
                assert!(nearer.t >= h.t, "ray {i}: {} before {}", nearer.t, h.t);
            }
        } else {
            misses += 1;
        }
    }
    // Both answers are common, so the agreement means something.
    eprintln!("{hits} hits ({instanced} on instances), {misses} misses");
    assert!(
        hits > 6000 && misses > 6000 && instanced > 500,
        "{hits} hits ({instanced} on instances), {misses} misses"
    );
}

#[test]
fn the_wide_builder_hits_what_ploc_hits() {
    // A 40x40 grid of small triangles at random heights, spheres among them: built by obvhs's
    // PLOC and by the wide builder, the closest hits and shadow answers agree.
    let mut rng = Rng(3);
    let mut points = String::new();
    let mut indices = String::new();
    for k in 0..1600 {
        let (x, z) = ((k % 40) as f32 * 0.15 - 3.0, (k / 40) as f32 * 0.15 - 3.0);
        let y = rng.range(-1.0, 1.0);
        points += &format!(
            "{x} {y} {z}  {} {y} {z}  {x} {} {}  ",
            x + 0.2,
            y + 0.1,
            z + 0.2
        );
        indices += &format!("{} {} {} ", 3 * k, 3 * k + 1, 3 * k + 2);
    }
    let mut text = format!(
        "{CAMERA}WorldBegin\nShape \"trianglemesh\" \"integer indices\" [{indices}] \
         \"point3 P\" [{points}]\n"
    );
    for k in 0..20 {
        text += &format!(
            "AttributeBegin\nTranslate {} {} {}\nShape \"sphere\" \"float radius\" 0.2\n\
             AttributeEnd\n",
            rng.range(-3.0, 3.0),
            rng.range(-1.0, 1.0),
            k as f32 * 0.3 - 3.0
        );
    }
    text += "WorldEnd";
    let whole = build(&text);
    let mut parts = build(&text);
    parts.accel.world.build_with(BvhBuilder::Wide);
    // obvhs's own check of the wide builder's tree: every node reached once, every primitive
    // inside its leaf's box and every box inside its parent's.
    let world = &parts.accel.world;
    let bvh = world.bvh.as_ref().unwrap();
    let boxes: Vec<Aabb> = world
        .prims
        .iter()
        .map(|p| {
            let (lo, hi) = world.prim_bounds(p);
            Aabb::new(Vec3A::from(lo), Vec3A::from(hi))
        })
        .collect();
    let check = bvh.validate(&boxes, true);
    assert_eq!(check.node_count, bvh.nodes.len());
    assert_eq!(check.discovered_primitives.len(), boxes.len());
    let (mut hits, mut misses) = (0, 0);
    for i in 0..20_000 {
        let o = Vec3::new(
            rng.range(-4.0, 4.0),
            rng.range(-2.0, 2.0),
            rng.range(-4.0, 4.0),
        );
        let d = Vec3::new(
            rng.range(-1.0, 1.0),
            rng.range(-1.0, 1.0),
            rng.range(-1.0, 1.0),
        );
        let ray = Ray::new(o, d.normalize_or(Vec3::Y), 0.0);
        let t_max = if i % 2 == 0 {
            f32::INFINITY
        } else {
            rng.range(0.1, 4.0)
        };
        let a = whole.accel.intersect(&ray, t_max);
        let b = parts.accel.intersect(&ray, t_max);
        assert_eq!(
            a.map(|h| (h.t, h.prim)),
            b.map(|h| (h.t, h.prim)),
            "ray {i}"
        );
        assert_eq!(parts.accel.occluded(&ray, t_max), a.is_some(), "ray {i}");
        if a.is_some() {
            hits += 1;
        } else {
            misses += 1;
        }
    }
    assert!(hits > 2000 && misses > 2000, "{hits} hits, {misses} misses");
}
