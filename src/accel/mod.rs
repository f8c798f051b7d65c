//! Ray-scene intersection on obvhs's compressed wide BVH (CWBVH; built by obvhs's PLOC, or
//! for large geometries by our own wide builder, `wide.rs`).
//!
//! Two levels: every static shape outside an object definition goes, in world space, into one
//! BVH; object definitions and moving shapes get a BVH each in their own space, placed in the
//! world by instances, which a top-level BVH (TLAS) holds. An instance's transform may move: the
//! ray is taken into the instance's space at the ray's time. A static scene with no instances
//! builds no TLAS and no motion structures. Shadow rays stop at the first hit.

use crate::geometry::{Ray, SurfaceInteraction, Vec3};
use crate::shapes::triangle::{
    intersect_triangle_verts, triangle_bounds, triangle_interaction_at, Corners, TriangleRay,
    TriangleVerts,
};
use crate::shapes::{Curve, CurveCommon, Cylinder, Disk, Revolved, Sphere, TriangleMesh};
use crate::transform::MotionTransform;
use glam::{Mat4, Vec3A};
use obvhs::aabb::Aabb;
use obvhs::cwbvh::CwBvh;
use obvhs::BvhBuildParams;
use rayon::prelude::*;
use std::time::Duration;

mod crossing;
mod traverse;
mod wide;

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
    /// A cone, paraboloid or hyperboloid.
    Revolved(u32),
    /// A piece of a curve.
    Curve(u32),
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
    /// Cones, paraboloids and hyperboloids.
    pub revolved: Vec<Revolved>,
    /// What the pieces of each curve segment share.
    pub curve_commons: Vec<CurveCommon>,
    /// Curve pieces.
    pub curves: Vec<Curve>,
    /// Primitives in BVH leaf order.
    prims: Vec<Prim>,
    /// The vertices of each triangle primitive, in leaf order beside `prims` (NaN for other
    /// kinds, `TriangleVerts::NONE`): the traversal reads one contiguous record instead of
    /// three indirections.
    tri_verts: Vec<TriangleVerts>,
    bvh: Option<CwBvh>,
}

/// Above this many primitives a geometry's BVH is built by [`wide::build_wide_in`] when one mesh
/// holds at least half of them, otherwise by obvhs's PLOC builder. On a million triangles of one
/// mesh the wide builder is 3.7x faster (0.3 s against 1.1 s), needs 190 MiB less and traces as
/// fast; on geometry of very mixed sizes (the interiors' 106,000 to 125,000 primitives, San
/// Miguel's 726,000 in 800 meshes) PLOC's trees with its optimal wide collapse are walked
/// through 20% fewer nodes (docs/BENCHMARKS.md).
const WIDE_BUILD_MIN: usize = 300_000;

/// The BVH builders.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum BvhBuilder {
    /// obvhs: PLOC, reinsertion, then the optimal binary-to-wide collapse.
    Ploc,
    /// Top-down binned SAH straight into wide nodes ([`wide::build_wide_in`]).
    Wide,
}

/// Where along a ray a primitive was hit, with what is needed to finish the interaction.
#[derive(Clone, Copy, Debug)]
enum LocalHit {
    Triangle(crate::shapes::triangle::TriangleHit),
    Sphere(crate::shapes::sphere::SphereHit),
    Disk(crate::shapes::disk::DiskHit),
    Cylinder(crate::shapes::cylinder::CylinderHit),
    Revolved(crate::shapes::RevolvedHit),
    Curve(crate::shapes::CurveHit),
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
    /// The primitive's leaf-order index in its geometry.
    leaf: u32,
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

    /// Adds many primitives at once, in order (call [`Geometry::build`] after the last).
    pub fn extend(&mut self, prims: impl IndexedParallelIterator<Item = Prim>) {
        self.prims.par_extend(prims);
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
            PrimKind::Revolved(i) => self.revolved[i as usize].world_bound(),
            PrimKind::Curve(i) => {
                let c = &self.curves[i as usize];
                c.world_bound(&self.curve_commons[c.common as usize])
            }
        }
    }

    /// Bounds of everything (the BVH's box once built).
    pub fn bounds(&self) -> (Vec3, Vec3) {
        if let Some(bvh) = &self.bvh {
            return (bvh.total_aabb.min.into(), bvh.total_aabb.max.into());
        }
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
        let largest_mesh = self.meshes.iter().map(TriangleMesh::triangle_count).max();
        let builder = if self.prims.len() > WIDE_BUILD_MIN
            && largest_mesh.unwrap_or(0) * 2 >= self.prims.len()
        {
            BvhBuilder::Wide
        } else {
            BvhBuilder::Ploc
        };
        self.build_with(builder);
    }

    /// [`Geometry::build`] with the given builder.
    fn build_with(&mut self, builder: BvhBuilder) {
        self.bvh = None;
        if self.prims.is_empty() {
            return;
        }
        // The walk names a leaf's primitives in 29 bits (a 25 GB geometry of triangles).
        assert!(
            self.prims.len() < traverse::MAX_PRIMITIVES,
            "a geometry of {} primitives: at most {} are supported",
            self.prims.len(),
            traverse::MAX_PRIMITIVES - 1
        );
        let bounds = |i: usize| {
            let (lo, hi) = self.prim_bounds(&self.prims[i]);
            Aabb::new(Vec3A::from(lo), Vec3A::from(hi))
        };
        // The triangle records' buffer, allocated first: the wide builder keeps its own records
        // in it while it builds.
        let n = self.prims.len();
        let mut tri_verts: Vec<TriangleVerts> = Vec::with_capacity(n);
        let mut bvh = match builder {
            BvhBuilder::Wide => wide::build_wide_in(n, bounds, tri_verts.spare_capacity_mut()),
            BvhBuilder::Ploc => {
                let aabbs: Vec<Aabb> = (0..self.prims.len()).map(bounds).collect();
                let params = BvhBuildParams::medium_build();
                obvhs::cwbvh::builder::build_cwbvh(&aabbs, params, &mut Duration::default())
            }
        };
        self.prims = bvh
            .primitive_indices
            .par_iter()
            .map(|&i| self.prims[i as usize])
            .collect();
        // The primitives are now in leaf order: the traversal's leaf index is the primitive.
        // (In place: its pages are already there.)
        for (k, i) in bvh.primitive_indices.iter_mut().enumerate() {
            *i = k as u32;
        }
        self.bvh = Some(bvh);
        // Written once per primitive (tens of MB on a large mesh): in parallel.
        let record = |p: &Prim| match p.kind {
            PrimKind::Triangle { mesh, tri } => {
                let m = &self.meshes[mesh as usize];
                let indices = m.vertex_indices(tri as usize).map(|i| i as u32);
                TriangleVerts::with_indices(&m.vertices(tri as usize), Some(indices))
            }
            _ => TriangleVerts::NONE,
        };
        tri_verts.spare_capacity_mut()[..n]
            .par_iter_mut()
            .zip(self.prims.par_iter())
            .for_each(|(slot, p)| {
                slot.write(record(p));
            });
        // SAFETY: the first `n` slots were written just above.
        unsafe { tri_verts.set_len(n) };
        self.tri_verts = tri_verts;
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
        // Triangles are known by their vertex record, which their test reads anyway: the
        // primitive's own record is read for the other kinds only.
        let verts = &self.tri_verts[id];
        if verts.is_triangle() {
            return intersect_triangle_verts(verts, tri_ray, t_max)
                .map(|h| (h.t, LocalHit::Triangle(h)));
        }
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
            PrimKind::Revolved(i) => self.revolved[i as usize]
                .intersect(ray, t_max)
                .map(|(t, h)| (t, LocalHit::Revolved(h))),
            PrimKind::Curve(i) => {
                let c = &self.curves[i as usize];
                c.intersect(&self.curve_commons[c.common as usize], ray, t_max)
                    .map(|(t, h)| (t, LocalHit::Curve(h)))
            }
        }
    }

    /// The closest hit closer than `t_max`.
    pub fn intersect(&self, ray: &Ray, t_max: f32, instance: Option<u32>) -> Option<Hit> {
        let bvh = self.bvh.as_ref()?;
        let mut best: Option<(f32, usize, LocalHit)> = None;
        let tri_ray = TriangleRay::new(ray);
        traverse::closest(bvh, to_obvhs(ray, t_max), |r, id| {
            match self.intersect_prim(id, ray, &tri_ray, r.tmax) {
                Some((t, local)) => {
                    best = Some((t, id, local));
                    t
                }
                None => f32::INFINITY,
            }
        });
        best.map(|(t, id, local)| Hit {
            t,
            prim: self.prims[id],
            instance,
            leaf: id as u32,
            local,
        })
    }

    /// [`Geometry::intersect`] for an instance's geometry, whose box the top-level BVH has
    /// already tested in the world: one primitive (a moving shape) is tested straight away,
    /// without its own BVH's setup and box.
    fn intersect_instanced(&self, ray: &Ray, t_max: f32, instance: u32) -> Option<Hit> {
        if self.prims.len() != 1 {
            return self.intersect(ray, t_max, Some(instance));
        }
        let (t, local) = self.intersect_prim(0, ray, &TriangleRay::new(ray), t_max)?;
        Some(Hit {
            t,
            prim: self.prims[0],
            instance: Some(instance),
            leaf: 0,
            local,
        })
    }

    /// [`Geometry::occluded`] for an instance's geometry, as [`Geometry::intersect_instanced`].
    fn occluded_instanced(&self, ray: &Ray, t_max: f32) -> bool {
        if self.prims.len() != 1 {
            return self.occluded(ray, t_max);
        }
        self.intersect_prim(0, ray, &TriangleRay::new(ray), t_max)
            .is_some()
    }

    /// Whether anything lies on the ray closer than `t_max` (stops at the first hit).
    pub fn occluded(&self, ray: &Ray, t_max: f32) -> bool {
        let Some(bvh) = &self.bvh else {
            return false;
        };
        let tri_ray = TriangleRay::new(ray);
        !traverse::misses(bvh, to_obvhs(ray, t_max), |r, id| {
            self.intersect_prim(id, ray, &tri_ray, r.tmax)
                .map_or(f32::INFINITY, |(t, _)| t)
        })
    }

    /// The full interaction of a hit, in this geometry's space.
    fn interaction(&self, ray: &Ray, hit: &Hit) -> SurfaceInteraction {
        match (hit.prim.kind, &hit.local) {
            // The positions and vertex indices from the traversal's record, which the hit has
            // just read.
            (PrimKind::Triangle { mesh, tri }, LocalHit::Triangle(h)) => {
                let verts = &self.tri_verts[hit.leaf as usize];
                let at = Corners {
                    tri: tri as usize,
                    known: verts.indices(),
                };
                triangle_interaction_at(&self.meshes[mesh as usize], &at, verts.vertices(), ray, h)
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
            (PrimKind::Revolved(i), LocalHit::Revolved(h)) => {
                self.revolved[i as usize].interaction(ray, h)
            }
            (PrimKind::Curve(i), LocalHit::Curve(h)) => {
                let c = &self.curves[i as usize];
                c.interaction(&self.curve_commons[c.common as usize], ray, hit.t, h)
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
        shading_dpdv: Vec3::Y,
        dndu: Vec3::ZERO,
        dndv: Vec3::ZERO,
        wo: n,
        time: ray.time,
        p_error: 0.0,
        diff: Default::default(),
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
    /// `f` applied to the world-from-instance matrix at `time` and its inverse, without
    /// copying a moving transform's out of its cache (`f` must not evaluate moving
    /// transforms itself: the cache is borrowed while it runs).
    #[inline]
    fn with_at<R>(&self, time: f32, f: impl FnOnce(&Mat4, &Mat4) -> R) -> R {
        match self {
            Placement::Fixed { to_world, to_local } => f(to_world, to_local),
            Placement::Moving(m) => m.with_at(time, f),
        }
    }

    /// `ray` in the instance's space (at the ray's time for a moving one), computed where
    /// the moving transform's cache holds the inverse rather than from a copy of it.
    #[inline]
    fn local_ray(&self, ray: &Ray) -> Ray {
        match self {
            Placement::Fixed { to_local, .. } => local_ray(ray, to_local),
            Placement::Moving(m) => m.with_at(ray.time, |_, to_local| local_ray(ray, to_local)),
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
/// The largest coordinate, in render space (camera at the origin), a box the BVH builder
/// takes may have. Its build costs are surface areas times primitive counts, in f32: beyond
/// this a scene's box's area times 2^32 primitives would overflow to infinity, and obvhs's
/// build then picks no split (a panic, or a tree that loses primitives). Far beyond any real
/// scene, which the camera-relative render space keeps near the origin.
pub const MAX_COORDINATE: f32 = 1e12;

/// Whether `[lo, hi]` is a box the BVH builder can take: finite corners within
/// [`MAX_COORDINATE`] of the origin, `lo <= hi`.
pub fn box_in_range(lo: Vec3, hi: Vec3) -> bool {
    let within = |v: Vec3| v.is_finite() && v.abs().max_element() <= MAX_COORDINATE;
    within(lo) && within(hi) && lo.cmple(hi).all()
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
    /// dropped because their placement takes them beyond the BVH's range
    /// ([`MAX_COORDINATE`]).
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
            box_in_range(lo, hi)
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
        // Our walk, as the geometries': obvhs's orders a node's children by the ray's octant
        // and visits every child it pushed (docs/BENCHMARKS.md, "The small rows again: the
        // serial take and the instances' walk").
        traverse::closest(tlas, to_obvhs(ray, t_limit), |r, id| {
            let index = self.tlas_order[id];
            let inst = &self.instances[index as usize];
            let local = inst.placement.local_ray(ray);
            match self.objects[inst.object as usize].intersect_instanced(&local, r.tmax, index) {
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
        !traverse::misses(tlas, to_obvhs(ray, t_max), |_, id| {
            let inst = &self.instances[self.tlas_order[id] as usize];
            let local = inst.placement.local_ray(ray);
            if self.objects[inst.object as usize].occluded_instanced(&local, t_max) {
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
        let object = &self.objects[inst.object as usize];
        inst.placement.with_at(ray.time, |to_world, to_local| {
            let si = object.interaction(&local_ray(ray, to_local), hit);
            transform_interaction(&si, to_world, to_local, ray)
        })
    }
}

/// `ray` in an instance's space.
#[inline]
fn local_ray(ray: &Ray, to_local: &Mat4) -> Ray {
    Ray::new(
        to_local.transform_point3(ray.o),
        to_local.transform_vector3(ray.d),
        ray.time,
    )
}

/// Takes an interaction from instance space to the world.
fn transform_interaction(
    si: &SurfaceInteraction,
    to_world: &Mat4,
    to_local: &Mat4,
    world_ray: &Ray,
) -> SurfaceInteraction {
    let normal = |n: Vec3| world_normal(to_local, n);
    SurfaceInteraction {
        p: to_world.transform_point3(si.p),
        n: normal(si.n),
        uv: si.uv,
        dpdu: to_world.transform_vector3(si.dpdu),
        dpdv: to_world.transform_vector3(si.dpdv),
        shading_n: normal(si.shading_n),
        shading_dpdu: to_world.transform_vector3(si.shading_dpdu),
        shading_dpdv: to_world.transform_vector3(si.shading_dpdv),
        // Derivatives of the normal: transformed as normals, not normalised.
        dndu: to_local.transpose().transform_vector3(si.dndu),
        dndv: to_local.transpose().transform_vector3(si.dndv),
        wo: -world_ray.d.normalize(),
        time: si.time,
        p_error: world_p_error(to_world, si.p_error),
        diff: si.diff,
    }
}

/// An instance-space normal in the world (by the inverse transpose), normalised.
#[inline]
fn world_normal(to_local: &Mat4, n: Vec3) -> Vec3 {
    to_local
        .transpose()
        .transform_vector3(n)
        .normalize_or_zero()
}

/// An instance-space error bound in the world: scaled by the transform's longest axis.
#[inline]
fn world_p_error(to_world: &Mat4, p_error: f32) -> f32 {
    p_error
        * to_world
            .x_axis
            .truncate()
            .length()
            .max(to_world.y_axis.truncate().length())
            .max(to_world.z_axis.truncate().length())
}

#[cfg(test)]
mod tests;
