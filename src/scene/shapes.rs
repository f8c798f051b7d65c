//! Building a scene's shapes: each pbrt-v3 shape description becomes primitives of the
//! geometry it belongs to (the world's or an object instance's), with its surface and, for
//! shapes that can emit, its area light.

use super::{Builder, Surface};
use crate::accel::{Geometry, Prim, PrimKind};
use crate::geometry::Vec3;
use crate::shapes::triangle::triangle_bounds;
use crate::shapes::{Cylinder, Disk, Sphere, Transform, TriangleMesh};
use acr_parser::{PluginDesc, Result, ShapeDesc, Warning};
use glam::DMat4;
use rayon::prelude::*;
use std::sync::Arc;

/// Shapes of at least this many primitives are checked on every thread (a parallel call costs
/// microseconds, and a scene may have thousands of small shapes).
const PARALLEL_MIN: usize = 1 << 14;

/// Shape types pbrt-v3 has and acr does not: warned about once and skipped.
const UNSUPPORTED_SHAPES: &[&str] = &[];
/// A transform and its inverse from a double-precision matrix.
fn transform_of(m: &DMat4) -> Transform {
    let m32 = m.as_mat4();
    Transform {
        m: m32,
        inv: m.inverse().as_mat4(),
    }
}

impl Builder<'_> {
    /// Drops the area light of a shape pbrt-v3 cannot sample (its `Sample` aborts), with a
    /// warning: the shape renders, unlit by itself.
    fn no_emission<'l, L>(&mut self, area_light: Option<&'l L>, p: &PluginDesc) -> Option<&'l L> {
        if area_light.is_some() {
            self.warnings.push(Warning::at(
                &p.loc,
                format!(
                    "AreaLightSource on a {0}: pbrt-v3 cannot sample a {0} (its Sample aborts); \
                     the shape is rendered without emission",
                    p.kind
                ),
            ));
        }
        None
    }

    /// Whether a shape's size is positive and finite; if not, warns that the shape is skipped
    /// (a zero or negative radius makes a shape with no area, which no ray can hit and no
    /// light can sample without dividing by zero).
    fn positive_size(&mut self, p: &PluginDesc, what: &str, v: f32) -> bool {
        if v > 0.0 && v.is_finite() {
            return true;
        }
        let loc = p.params.get(what).map_or(&p.loc, |x| &x.loc);
        self.warnings.push(Warning::at(
            loc,
            format!(
                "{}: {what} is {v}; the shape has no area and is skipped",
                p.kind
            ),
        ));
        false
    }

    /// Adds a triangle mesh and a primitive for each of its triangles with a positive, finite
    /// world-space area; warns once per shape about the others, which are skipped (they could
    /// never be hit, and as emitters their area would divide by zero). True when every triangle
    /// was also found within the BVH's range (`within_range` has nothing to do).
    fn add_triangles(
        &mut self,
        geom: &mut Geometry,
        tm: TriangleMesh,
        prims: &mut Vec<PrimKind>,
        loc: &acr_parser::Loc,
        kind: &str,
    ) -> bool {
        let mesh_index = geom.meshes.len() as u32;
        let n = tm.triangle_count();
        let before = prims.len();
        // The intersection test's own zero-area test, and finite vertices.
        let fine = |tri: usize| {
            let [a, b, c] = tm.vertices(tri);
            let n = (a - c).cross(b - c);
            n != Vec3::ZERO && n.is_finite()
        };
        let prim = |tri: usize| PrimKind::Triangle {
            mesh: mesh_index,
            tri: tri as u32,
        };
        // A large mesh's triangles on every thread (a million took 15 ms on one), with the
        // range check of `within_range` in the same pass; rayon's collect keeps their order.
        let in_range = |tri: usize| {
            let (lo, hi) = triangle_bounds(&tm, tri);
            crate::accel::box_in_range(lo, hi)
        };
        let checked =
            n >= PARALLEL_MIN && (0..n).into_par_iter().all(|tri| fine(tri) && in_range(tri));
        if checked {
            prims.par_extend((0..n).into_par_iter().map(prim));
        } else {
            prims.extend((0..n).filter(|&tri| fine(tri)).map(prim));
        }
        let skipped = n - (prims.len() - before);
        if skipped > 0 {
            self.warnings.push(Warning::at(
                loc,
                format!(
                    "{kind}: {skipped} of {n} triangles are degenerate (zero area or \
                     non-finite vertices) and are skipped"
                ),
            ));
        }
        geom.meshes.push(tm);
        checked
    }

    /// Adds one shape's primitives to `geom`, placed by `m` (world- or instance-from-object).
    /// Area lights are only allowed for static world shapes (`emit`).
    pub(super) fn add_shape(
        &mut self,
        geom: &mut Geometry,
        shape: &ShapeDesc,
        m: &DMat4,
        emit: bool,
    ) -> Result<()> {
        let p = &shape.plugin;
        let kind = p.kind.as_str();
        if UNSUPPORTED_SHAPES.contains(&kind) {
            self.warn_once(
                format!("shape {kind}"),
                &p.loc,
                format!("shape \"{kind}\" is not supported; shapes of this type are skipped"),
            );
            return Ok(());
        }
        let mut area_light = shape.area_light.as_ref().filter(|_| emit);
        let Some(made) = self.primitives(geom, shape, transform_of(m))? else {
            return Ok(());
        };
        if !made.can_emit {
            area_light = self.no_emission(area_light, p);
        }
        let prims = if made.in_range {
            made.prims
        } else {
            self.within_range(geom, made.prims, p)
        };
        let material = shape.material.map(|m| m as u32);
        let (inside, outside) = (shape.media.inside, shape.media.outside);
        // Only a surface between two different media changes a ray's medium (pbrt-v3's
        // IsMediumTransition); any other keeps the medium the ray arrived in.
        let media = (inside != outside).then_some(crate::medium::MediumInterface {
            inside: inside.map(|m| m as u32),
            outside: outside.map(|m| m as u32),
        });
        let surface = Surface {
            material,
            area_light: None,
            media,
        };
        // An area light's own media, as declared (what its light subpaths start in).
        let declared = crate::medium::MediumInterface {
            inside: inside.map(|m| m as u32),
            outside: outside.map(|m| m as u32),
        };
        self.add_surfaces(geom, prims, surface, area_light.map(|l| (l, declared)));
        Ok(())
    }

    /// The primitives of one shape, added to `geom`'s shapes of its kind but not yet to its
    /// primitives; `None` when the shape is skipped (with a warning where it says why).
    fn primitives(
        &mut self,
        geom: &mut Geometry,
        shape: &ShapeDesc,
        to_world: Transform,
    ) -> Result<Option<Made>> {
        let p = &shape.plugin;
        let kind = p.kind.as_str();
        let flip = shape.reverse_orientation;
        let mut in_range = false;
        let prims = match kind {
            "trianglemesh" | "plymesh" | "loopsubdiv" | "heightfield" | "nurbs" => {
                self.mesh(geom, shape, &to_world)?.map(|(prims, checked)| {
                    in_range = checked;
                    prims
                })
            }
            "sphere" => self.sphere(geom, p, to_world, flip)?,
            "disk" => self.disk(geom, p, to_world, flip)?,
            "cylinder" => self.cylinder(geom, p, to_world, flip)?,
            "cone" | "paraboloid" | "hyperboloid" => {
                return self.revolved(geom, p, to_world, flip);
            }
            "curve" => return self.curves(geom, p, to_world, flip).map(Some),
            other => {
                self.warn_once(
                    format!("shape {other}"),
                    &p.loc,
                    format!("unknown shape \"{other}\"; shapes of this type are skipped"),
                );
                None
            }
        };
        Ok(prims.map(|prims| Made {
            prims,
            can_emit: true,
            in_range,
        }))
    }

    /// A triangle mesh (`trianglemesh`, `plymesh`) or a shape acr turns into one
    /// (`loopsubdiv`, `heightfield`, `nurbs`); `None` for a mesh shape without its mesh.
    fn mesh(
        &mut self,
        geom: &mut Geometry,
        shape: &ShapeDesc,
        to_world: &Transform,
    ) -> Result<Option<(Vec<PrimKind>, bool)>> {
        let p = &shape.plugin;
        let params = &p.params;
        let kind = p.kind.as_str();
        let built;
        let mesh = match kind {
            "loopsubdiv" => {
                built = crate::shapes::loopsubdiv::mesh_from_params(params, &p.loc, self.warnings)?;
                &built
            }
            "heightfield" => {
                built = crate::shapes::heightfield::mesh_from_params(params, &p.loc)?;
                &built
            }
            "nurbs" => {
                built = crate::shapes::nurbs::mesh_from_params(params, &p.loc)?;
                &built
            }
            _ => match &shape.mesh {
                Some(mesh) => mesh,
                None => return Ok(None),
            },
        };
        let tm = TriangleMesh::from_mesh(mesh, to_world, shape.reverse_orientation);
        let mut prims = Vec::new();
        let in_range = self.add_triangles(geom, tm, &mut prims, &p.loc, kind);
        if matches!(kind, "trianglemesh" | "plymesh") {
            // Parameters pbrt-v3 reads for meshes that acr has no use for.
            for unused in ["alpha", "shadowalpha", "S", "faceIndices"] {
                if let Some(x) = params.get(unused) {
                    self.warn_once(
                        format!("mesh param {unused}"),
                        &x.loc,
                        format!("mesh parameter \"{unused}\" is not supported; ignored"),
                    );
                }
            }
        }
        Ok(Some((prims, in_range)))
    }

    /// A sphere; `None` when its radius is not positive.
    fn sphere(
        &mut self,
        geom: &mut Geometry,
        p: &PluginDesc,
        to_world: Transform,
        flip: bool,
    ) -> Result<Option<Vec<PrimKind>>> {
        let params = &p.params;
        let r = params.float_or("radius", 1.0)? as f32;
        if !self.positive_size(p, "radius", r) {
            return Ok(None);
        }
        let s = Sphere::new(
            r,
            params.float_or("zmin", -r as f64)? as f32,
            params.float_or("zmax", r as f64)? as f32,
            params.float_or("phimax", 360.0)? as f32,
            to_world,
            flip,
        );
        geom.spheres.push(s);
        Ok(Some(vec![PrimKind::Sphere(geom.spheres.len() as u32 - 1)]))
    }

    /// A disk or annulus; `None` when its radius or width is not positive.
    fn disk(
        &mut self,
        geom: &mut Geometry,
        p: &PluginDesc,
        to_world: Transform,
        flip: bool,
    ) -> Result<Option<Vec<PrimKind>>> {
        let params = &p.params;
        let (r, ri) = (
            params.float_or("radius", 1.0)? as f32,
            params.float_or("innerradius", 0.0)? as f32,
        );
        if !self.positive_size(p, "radius", r)
            || !self.positive_size(p, "radius - innerradius", r - ri.max(0.0))
        {
            return Ok(None);
        }
        let d = Disk::new(
            params.float_or("height", 0.0)? as f32,
            r,
            ri.max(0.0),
            params.float_or("phimax", 360.0)? as f32,
            to_world,
            flip,
        );
        geom.disks.push(d);
        Ok(Some(vec![PrimKind::Disk(geom.disks.len() as u32 - 1)]))
    }

    /// A cylinder; `None` when its radius or height is not positive.
    fn cylinder(
        &mut self,
        geom: &mut Geometry,
        p: &PluginDesc,
        to_world: Transform,
        flip: bool,
    ) -> Result<Option<Vec<PrimKind>>> {
        let params = &p.params;
        let r = params.float_or("radius", 1.0)? as f32;
        let (z0, z1) = (
            params.float_or("zmin", -1.0)? as f32,
            params.float_or("zmax", 1.0)? as f32,
        );
        if !self.positive_size(p, "radius", r)
            || !self.positive_size(p, "|zmax - zmin|", (z1 - z0).abs())
        {
            return Ok(None);
        }
        let c = Cylinder::new(
            r,
            z0,
            z1,
            params.float_or("phimax", 360.0)? as f32,
            to_world,
            flip,
        );
        geom.cylinders.push(c);
        Ok(Some(vec![PrimKind::Cylinder(
            geom.cylinders.len() as u32 - 1,
        )]))
    }

    /// A cone, paraboloid or hyperboloid, which cannot emit; `None`, with a warning saying
    /// why, when its parameters make no surface.
    fn revolved(
        &mut self,
        geom: &mut Geometry,
        p: &PluginDesc,
        to_world: Transform,
        flip: bool,
    ) -> Result<Option<Made>> {
        let built = crate::shapes::revolved::from_params(&p.kind, &p.params, to_world, flip)?;
        let shape = match built {
            Ok(s) => s,
            Err(why) => {
                self.warnings.push(Warning::at(&p.loc, why));
                return Ok(None);
            }
        };
        geom.revolved.push(shape);
        Ok(Some(Made {
            prims: vec![PrimKind::Revolved(geom.revolved.len() as u32 - 1)],
            can_emit: false,
            in_range: false,
        }))
    }

    /// A curve's segments, each split into its pieces, which cannot emit.
    fn curves(
        &mut self,
        geom: &mut Geometry,
        p: &PluginDesc,
        to_world: Transform,
        flip: bool,
    ) -> Result<Made> {
        let curves =
            crate::shapes::curve::from_params(&p.params, &p.loc, to_world, flip, self.warnings)?;
        let mut prims = Vec::new();
        for (common, pieces) in curves {
            let index = geom.curve_commons.len() as u32;
            geom.curve_commons.push(common);
            for mut piece in pieces {
                piece.common = index;
                prims.push(PrimKind::Curve(geom.curves.len() as u32));
                geom.curves.push(piece);
            }
        }
        Ok(Made {
            prims,
            can_emit: false,
            in_range: false,
        })
    }

    /// `prims` without those whose coordinates lie beyond the BVH's range
    /// ([`crate::accel::MAX_COORDINATE`] from the camera) or are NaN. Warns of those dropped.
    fn within_range(
        &mut self,
        geom: &Geometry,
        mut prims: Vec<PrimKind>,
        p: &PluginDesc,
    ) -> Vec<PrimKind> {
        let before = prims.len();
        let within = |&k: &PrimKind| {
            let (lo, hi) = geom.kind_bounds(k);
            crate::accel::box_in_range(lo, hi)
        };
        // Mostly every primitive is in range: checked on every thread, kept as it is.
        if prims.len() >= PARALLEL_MIN && prims.par_iter().all(within) {
            return prims;
        }
        prims.retain(within);
        if prims.len() < before {
            self.warnings.push(Warning::at(
                &p.loc,
                format!(
                    "{}: {} of {before} primitives lie farther than {:e} from the camera \
                     (the BVH's range), or have NaN coordinates, and are skipped",
                    p.kind,
                    before - prims.len(),
                    crate::accel::MAX_COORDINATE
                ),
            ));
        }
        prims
    }

    /// Adds `prims` to `geom` with their `surface`: one surface for them all, or
    /// with an area light one each, its light waiting for the world's final layout.
    fn add_surfaces(
        &mut self,
        geom: &mut Geometry,
        prims: Vec<PrimKind>,
        surface: Surface,
        area_light: Option<(&Arc<PluginDesc>, crate::medium::MediumInterface)>,
    ) {
        let Some((light, media)) = area_light else {
            let surface = self.surface(surface);
            let prim = |&kind: &PrimKind| Prim { kind, surface };
            if prims.len() >= PARALLEL_MIN {
                geom.extend(prims.par_iter().map(prim));
            } else {
                prims.iter().for_each(|k| geom.push(prim(k)));
            }
            return;
        };
        for kind in prims {
            // One light per primitive, as pbrt-v3 makes one DiffuseAreaLight per shape.
            let surface = self.surface(surface);
            self.area_lights
                .push((Arc::clone(light), kind, surface, media));
            geom.push(Prim { kind, surface });
        }
    }
}

/// The primitives a shape made, and whether they may carry its area light.
struct Made {
    /// The primitives.
    prims: Vec<PrimKind>,
    /// False for shapes pbrt-v3 cannot sample: their area light is dropped.
    can_emit: bool,
    /// True when every primitive is known to lie within the BVH's range.
    in_range: bool,
}
