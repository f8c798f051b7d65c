//! Ray-scene intersection on obvhs's compressed wide BVH (CWBVH, built with PLOC).
//!
//! Two levels: every static shape outside an object definition goes, in world space, into one
//! BVH; object definitions and moving shapes get a BVH each in their own space, placed in the
//! world by instances, which a top-level BVH (TLAS) holds. An instance's transform may move: the
//! ray is taken into the instance's space at the ray's time. A static scene with no instances
//! builds no TLAS and no motion structures. Shadow rays stop at the first hit.

use crate::geometry::{Ray, SurfaceInteraction, Vec3};
use crate::shapes::triangle::{
    intersect_triangle_verts, triangle_bounds, triangle_interaction, TriangleRay, TriangleVerts,
};
use crate::shapes::{Cylinder, Disk, Sphere, TriangleMesh};
use crate::transform::MotionTransform;
use glam::{Mat4, Vec3A};
use obvhs::aabb::Aabb;
use obvhs::cwbvh::CwBvh;
use obvhs::BvhBuildParams;
use std::time::Duration;

/// What a BVH leaf primitive is, and the surface (material, area light) it carries.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Prim {
    /// The kind of primitive and its index in its geometry's lists.
    pub kind: PrimKind,
    /// Index into the scene's surfaces.
    pub surface: u32,
}

/// The kinds of primitive.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PrimKind {
    /// Triangle `tri` of mesh `mesh`.
    Triangle {
        /// Mesh index.
        mesh: u32,
        /// Triangle index within the mesh.
        tri: u32,
    },
    /// A sphere.
    Sphere(u32),
    /// A disk.
    Disk(u32),
    /// A cylinder.
    Cylinder(u32),
}

/// Shapes in one space (the world, or an instance's), with a BVH over them.
#[derive(Default)]
pub struct Geometry {
    /// Triangle meshes.
    pub meshes: Vec<TriangleMesh>,
    /// Spheres.
    pub spheres: Vec<Sphere>,
    /// Disks.
    pub disks: Vec<Disk>,
    /// Cylinders.
    pub cylinders: Vec<Cylinder>,
    /// Primitives in BVH leaf order.
    prims: Vec<Prim>,
    /// The vertices of each triangle primitive, in leaf order beside `prims` (zeros for other
    /// kinds): the traversal reads one contiguous record instead of three indirections.
    tri_verts: Vec<TriangleVerts>,
    bvh: Option<CwBvh>,
}

/// Where along a ray a primitive was hit, with what is needed to finish the interaction.
#[derive(Clone, Copy, Debug)]
enum LocalHit {
    Triangle(crate::shapes::triangle::TriangleHit),
    Sphere(crate::shapes::sphere::SphereHit),
    Disk(crate::shapes::disk::DiskHit),
    Cylinder(crate::shapes::cylinder::CylinderHit),
}

/// The closest hit of a ray.
#[derive(Clone, Copy, Debug)]
pub struct Hit {
    /// Ray parameter of the hit.
    pub t: f32,
    /// The primitive hit.
    pub prim: Prim,
    /// The instance it belongs to, if any.
    instance: Option<u32>,
    local: LocalHit,
}

fn to_obvhs(ray: &Ray, t_max: f32) -> obvhs::ray::Ray {
    // `+ 0.0` turns -0.0 components into +0.0: obvhs's traversal misses some axis-aligned
    // rays whose direction has a negative zero (measured: direction -Z missed a triangle
    // straight ahead that +0.0 components hit).
    let d = ray.d + Vec3::ZERO;
    obvhs::ray::Ray::new(Vec3A::from(ray.o), Vec3A::from(d), 0.0, t_max)
}

impl Geometry {
    /// Adds a primitive (call [`Geometry::build`] after the last).
    pub fn push(&mut self, prim: Prim) {
        self.prims.push(prim);
    }

    /// Number of primitives.
    pub fn len(&self) -> usize {
        self.prims.len()
    }

    /// True when there are no primitives.
    pub fn is_empty(&self) -> bool {
        self.prims.is_empty()
    }

    /// Bounds of one primitive.
    fn prim_bounds(&self, p: &Prim) -> (Vec3, Vec3) {
        self.kind_bounds(p.kind)
    }

    /// Bounds of the primitive `kind` (its shape must be in this geometry).
    pub fn kind_bounds(&self, kind: PrimKind) -> (Vec3, Vec3) {
        match kind {
            PrimKind::Triangle { mesh, tri } => {
                triangle_bounds(&self.meshes[mesh as usize], tri as usize)
            }
            PrimKind::Sphere(i) => self.spheres[i as usize].world_bound(),
            PrimKind::Disk(i) => self.disks[i as usize].world_bound(),
            PrimKind::Cylinder(i) => self.cylinders[i as usize].world_bound(),
        }
    }

    /// Bounds of everything.
    pub fn bounds(&self) -> (Vec3, Vec3) {
        self.prims.iter().fold(
            (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
            |(lo, hi), p| {
                let (a, b) = self.prim_bounds(p);
                (lo.min(a), hi.max(b))
            },
        )
    }

    /// Builds the BVH and reorders primitives into leaf order.
    pub fn build(&mut self) {
        if self.prims.is_empty() {
            self.bvh = None;
            return;
        }
        let aabbs: Vec<Aabb> = self
            .prims
            .iter()
            .map(|p| {
                let (lo, hi) = self.prim_bounds(p);
                Aabb::new(Vec3A::from(lo), Vec3A::from(hi))
            })
            .collect();
        let params = if aabbs.len() > 100_000 {
            BvhBuildParams::fast_build()
        } else {
            BvhBuildParams::medium_build()
        };
        let bvh = obvhs::cwbvh::builder::build_cwbvh(&aabbs, params, &mut Duration::default());
        self.prims = bvh
            .primitive_indices
            .iter()
            .map(|&i| self.prims[i as usize])
            .collect();
        self.tri_verts = self
            .prims
            .iter()
            .map(|p| match p.kind {
                PrimKind::Triangle { mesh, tri } => {
                    TriangleVerts::new(&self.meshes[mesh as usize].vertices(tri as usize))
                }
                _ => TriangleVerts::default(),
            })
            .collect();
        self.bvh = Some(bvh);
    }

    /// Intersects primitive `id` (a leaf-order index).
    #[inline]
    fn intersect_prim(
        &self,
        id: usize,
        ray: &Ray,
        tri_ray: &TriangleRay,
        t_max: f32,
    ) -> Option<(f32, LocalHit)> {
        match self.prims[id].kind {
            PrimKind::Triangle { .. } => {
                intersect_triangle_verts(&self.tri_verts[id], tri_ray, t_max)
                    .map(|h| (h.t, LocalHit::Triangle(h)))
            }
            PrimKind::Sphere(i) => self.spheres[i as usize]
                .intersect(ray, t_max)
                .map(|(t, h)| (t, LocalHit::Sphere(h))),
            PrimKind::Disk(i) => self.disks[i as usize]
                .intersect(ray, t_max)
                .map(|(t, h)| (t, LocalHit::Disk(h))),
            PrimKind::Cylinder(i) => self.cylinders[i as usize]
                .intersect(ray, t_max)
                .map(|(t, h)| (t, LocalHit::Cylinder(h))),
        }
    }

    /// The closest hit closer than `t_max`.
    pub fn intersect(&self, ray: &Ray, t_max: f32, instance: Option<u32>) -> Option<Hit> {
        let bvh = self.bvh.as_ref()?;
        let mut best: Option<Hit> = None;
        let mut hit = obvhs::ray::RayHit::none();
        let tri_ray = TriangleRay::new(ray);
        bvh.ray_traverse(to_obvhs(ray, t_max), &mut hit, |r, id| {
            let prim = &self.prims[id];
            match self.intersect_prim(id, ray, &tri_ray, r.tmax) {
                Some((t, local)) => {
                    best = Some(Hit {
                        t,
                        prim: *prim,
                        instance,
                        local,
                    });
                    t
                }
                None => f32::INFINITY,
            }
        });
        best
    }

    /// Whether anything lies on the ray closer than `t_max` (stops at the first hit).
    pub fn occluded(&self, ray: &Ray, t_max: f32) -> bool {
        let Some(bvh) = &self.bvh else {
            return false;
        };
        let tri_ray = TriangleRay::new(ray);
        !bvh.ray_traverse_miss(to_obvhs(ray, t_max), |r, id| {
            self.intersect_prim(id, ray, &tri_ray, r.tmax)
                .map_or(f32::INFINITY, |(t, _)| t)
        })
    }

    /// The full interaction of a hit, in this geometry's space.
    fn interaction(&self, ray: &Ray, hit: &Hit) -> SurfaceInteraction {
        match (hit.prim.kind, &hit.local) {
            (PrimKind::Triangle { mesh, tri }, LocalHit::Triangle(h)) => {
                triangle_interaction(&self.meshes[mesh as usize], tri as usize, ray, h)
            }
            (PrimKind::Sphere(i), LocalHit::Sphere(h)) => {
                self.spheres[i as usize].interaction(ray, hit.t, h)
            }
            (PrimKind::Disk(i), LocalHit::Disk(h)) => {
                self.disks[i as usize].interaction(ray, hit.t, h)
            }
            (PrimKind::Cylinder(i), LocalHit::Cylinder(h)) => {
                self.cylinders[i as usize].interaction(ray, hit.t, h)
            }
            // A hit always records the local data of its own primitive kind.
            _ => unreachable_interaction(ray, hit.t),
        }
    }
}

/// Never reached: `Hit::local` is built together with `Hit::prim`. Returns a harmless point
/// rather than panicking.
#[cold]
fn unreachable_interaction(ray: &Ray, t: f32) -> SurfaceInteraction {
    let n = -ray.d.normalize_or_zero();
    SurfaceInteraction {
        p: ray.at(t),
        n,
        uv: glam::Vec2::ZERO,
        dpdu: Vec3::X,
        dpdv: Vec3::Y,
        shading_n: n,
        shading_dpdu: Vec3::X,
        wo: n,
        time: ray.time,
    }
}

/// How an instance sits in the world.
pub enum Placement {
    /// A fixed world-from-instance matrix and its inverse.
    Fixed {
        /// World from instance.
        to_world: Mat4,
        /// Instance from world.
        to_local: Mat4,
    },
    /// A moving transform, evaluated at each ray's time.
    Moving(Box<MotionTransform>),
}

impl Placement {
    fn at(&self, time: f32) -> (Mat4, Mat4) {
        match self {
            Placement::Fixed { to_world, to_local } => (*to_world, *to_local),
            Placement::Moving(m) => {
                let w = m.at(time);
                (w, w.inverse())
            }
        }
    }

    /// World bounds of instance-space `bounds` over the shutter.
    fn world_bounds(&self, bounds: (Vec3, Vec3)) -> (Vec3, Vec3) {
        match self {
            Placement::Fixed { to_world, .. } => {
                let c = std::array::from_fn(|i| {
                    Vec3::new(
                        if i & 1 == 0 { bounds.0.x } else { bounds.1.x },
                        if i & 2 == 0 { bounds.0.y } else { bounds.1.y },
                        if i & 4 == 0 { bounds.0.z } else { bounds.1.z },
                    )
                });
                crate::transform::transform_box(to_world, &c)
            }
            Placement::Moving(m) => m.motion_bounds(bounds),
        }
    }
}

/// One placement of a geometry in the world.
pub struct Instance {
    /// Index into [`Accel::objects`].
    pub object: u32,
    /// Where it is.
    pub placement: Placement,
}

/// The scene's acceleration structure.
/// Whether `[lo, hi]` is a box the BVH builder can take: finite corners, `lo <= hi`.
pub fn finite_box(lo: Vec3, hi: Vec3) -> bool {
    lo.is_finite() && hi.is_finite() && lo.cmple(hi).all()
}

#[derive(Default)]
pub struct Accel {
    /// Static shapes in world space.
    pub world: Geometry,
    /// Geometries placed by instances (object definitions, moving shapes).
    pub objects: Vec<Geometry>,
    /// Instances.
    pub instances: Vec<Instance>,
    tlas: Option<CwBvh>,
    tlas_order: Vec<u32>,
}

impl Accel {
    /// Builds every BVH. Call once after adding everything. Gives the number of instances
    /// dropped because their placement takes them beyond f32's range (the BVH builder needs
    /// finite boxes).
    pub fn build(&mut self) -> usize {
        self.world.build();
        for g in &mut self.objects {
            g.build();
        }
        self.instances
            .retain(|i| !self.objects[i.object as usize].is_empty());
        let before = self.instances.len();
        let objects = &self.objects;
        self.instances.retain(|i| {
            let (lo, hi) = i
                .placement
                .world_bounds(objects[i.object as usize].bounds());
            finite_box(lo, hi)
        });
        let dropped = before - self.instances.len();
        if self.instances.is_empty() {
            self.tlas = None;
            return dropped;
        }
        let aabbs: Vec<Aabb> = self
            .instances
            .iter()
            .map(|inst| {
                let b = self.objects[inst.object as usize].bounds();
                let (lo, hi) = inst.placement.world_bounds(b);
                Aabb::new(Vec3A::from(lo), Vec3A::from(hi))
            })
            .collect();
        let bvh = obvhs::cwbvh::builder::build_cwbvh(
            &aabbs,
            BvhBuildParams::medium_build(),
            &mut Duration::default(),
        );
        self.tlas_order = bvh.primitive_indices.clone();
        self.tlas = Some(bvh);
        dropped
    }

    /// True when anything in the scene moves (there is a moving instance).
    pub fn has_motion(&self) -> bool {
        self.instances
            .iter()
            .any(|i| matches!(i.placement, Placement::Moving(_)))
    }

    /// World bounds of all geometry over the shutter.
    pub fn bounds(&self) -> (Vec3, Vec3) {
        let mut b = self.world.bounds();
        for inst in &self.instances {
            let (lo, hi) = inst
                .placement
                .world_bounds(self.objects[inst.object as usize].bounds());
            b = (b.0.min(lo), b.1.max(hi));
        }
        b
    }

    /// The closest hit closer than `t_max`.
    pub fn intersect(&self, ray: &Ray, t_max: f32) -> Option<Hit> {
        let mut best = self.world.intersect(ray, t_max, None);
        let Some(tlas) = &self.tlas else {
            return best;
        };
        let t_limit = best.map_or(t_max, |h| h.t);
        let mut hit = obvhs::ray::RayHit::none();
        tlas.ray_traverse(to_obvhs(ray, t_limit), &mut hit, |r, id| {
            let index = self.tlas_order[id];
            let inst = &self.instances[index as usize];
            let (_, to_local) = inst.placement.at(ray.time);
            let local = Ray::new(
                to_local.transform_point3(ray.o),
                to_local.transform_vector3(ray.d),
                ray.time,
            );
            match self.objects[inst.object as usize].intersect(&local, r.tmax, Some(index)) {
                Some(h) => {
                    best = Some(h);
                    h.t
                }
                None => f32::INFINITY,
            }
        });
        best
    }

    /// Whether anything lies on the ray closer than `t_max`.
    pub fn occluded(&self, ray: &Ray, t_max: f32) -> bool {
        if self.world.occluded(ray, t_max) {
            return true;
        }
        let Some(tlas) = &self.tlas else {
            return false;
        };
        !tlas.ray_traverse_miss(to_obvhs(ray, t_max), |_, id| {
            let inst = &self.instances[self.tlas_order[id] as usize];
            let (_, to_local) = inst.placement.at(ray.time);
            let local = Ray::new(
                to_local.transform_point3(ray.o),
                to_local.transform_vector3(ray.d),
                ray.time,
            );
            if self.objects[inst.object as usize].occluded(&local, t_max) {
                0.0
            } else {
                f32::INFINITY
            }
        })
    }

    /// The world-space interaction of a hit.
    pub fn interaction(&self, ray: &Ray, hit: &Hit) -> SurfaceInteraction {
        let Some(index) = hit.instance else {
            return self.world.interaction(ray, hit);
        };
        let inst = &self.instances[index as usize];
        let (to_world, to_local) = inst.placement.at(ray.time);
        let local_ray = Ray::new(
            to_local.transform_point3(ray.o),
            to_local.transform_vector3(ray.d),
            ray.time,
        );
        let si = self.objects[inst.object as usize].interaction(&local_ray, hit);
        transform_interaction(&si, &to_world, &to_local, ray)
    }
}

/// Takes an interaction from instance space to the world.
fn transform_interaction(
    si: &SurfaceInteraction,
    to_world: &Mat4,
    to_local: &Mat4,
    world_ray: &Ray,
) -> SurfaceInteraction {
    let normal = |n: Vec3| {
        to_local
            .transpose()
            .transform_vector3(n)
            .normalize_or_zero()
    };
    SurfaceInteraction {
        p: to_world.transform_point3(si.p),
        n: normal(si.n),
        uv: si.uv,
        dpdu: to_world.transform_vector3(si.dpdu),
        dpdv: to_world.transform_vector3(si.dpdv),
        shading_n: normal(si.shading_n),
        shading_dpdu: to_world.transform_vector3(si.shading_dpdu),
        wo: -world_ray.d.normalize(),
        time: si.time,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::Scene;
    use std::path::Path;

    fn build(text: &str) -> Scene {
        let desc = acr_parser::parse_str(text, Path::new("accel-test.pbrt"))
            .unwrap_or_else(|e| panic!("{e}"));
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
}
