//! The cheap counterpart of [`Accel::interaction`]: only the point, the geometric normal and
//! the error bound of a hit, which is all a ray continuing through an interface surface
//! (`Material ""`) or a probe ray passing other surfaces needs (docs/media.md). Spheres and
//! triangles skip their (u, v), tangents, normal derivatives and shading frame; the other
//! shapes, rare as interfaces, take the full interaction's values. The point is the full
//! interaction's bit for bit, the normal too except on spheres (p / r there, equal to a few
//! ulps: images move by float rounding only, docs/media.md).

use super::{local_ray, world_normal, world_p_error, Accel, Geometry, Hit, LocalHit, PrimKind};
use crate::geometry::{Crossing, Ray};
use crate::shapes::triangle::triangle_crossing;

impl Geometry {
    /// The point and normal of a hit, in this geometry's space.
    fn crossing(&self, ray: &Ray, hit: &Hit) -> Crossing {
        match (hit.prim.kind, &hit.local) {
            (PrimKind::Triangle { mesh, tri }, LocalHit::Triangle(h)) => {
                triangle_crossing(&self.meshes[mesh as usize], tri as usize, ray, h)
            }
            (PrimKind::Sphere(i), LocalHit::Sphere(h)) => self.spheres[i as usize].crossing(ray, h),
            _ => self.interaction(ray, hit).crossing(),
        }
    }
}

impl Accel {
    /// The world-space point and normal of a hit, as [`Accel::interaction`] gives them.
    pub fn crossing(&self, ray: &Ray, hit: &Hit) -> Crossing {
        let Some(index) = hit.instance else {
            return self.world.crossing(ray, hit);
        };
        let inst = &self.instances[index as usize];
        let object = &self.objects[inst.object as usize];
        inst.placement.with_at(ray.time, |to_world, to_local| {
            let c = object.crossing(&local_ray(ray, to_local), hit);
            Crossing {
                p: to_world.transform_point3(c.p),
                n: world_normal(to_local, c.n),
                p_error: world_p_error(to_world, c.p_error),
                time: c.time,
            }
        })
    }
}
