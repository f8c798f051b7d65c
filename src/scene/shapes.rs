//! Building a scene's shapes: each pbrt-v3 shape description becomes primitives of the
//! geometry it belongs to (the world's or an object instance's), with its surface and, for
//! shapes that can emit, its area light.

use super::{Builder, Surface};
use crate::accel::{Geometry, Prim, PrimKind};
use crate::geometry::Vec3;
use crate::shapes::{Cylinder, Disk, Sphere, Transform, TriangleMesh};
use acr_parser::{PluginDesc, Result, ShapeDesc, Warning};
use glam::DMat4;
use std::sync::Arc;
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
    /// never be hit, and as emitters their area would divide by zero).
    fn add_triangles(
        &mut self,
        geom: &mut Geometry,
        tm: TriangleMesh,
        prims: &mut Vec<PrimKind>,
        loc: &acr_parser::Loc,
        kind: &str,
    ) {
        let mesh_index = geom.meshes.len() as u32;
        let n = tm.triangle_count();
        let before = prims.len();
        prims.extend(
            (0..n)
                .filter(|&tri| {
                    // The intersection test's own zero-area test, and finite vertices.
                    let [a, b, c] = tm.vertices(tri);
                    let n = (a - c).cross(b - c);
                    n != Vec3::ZERO && n.is_finite()
                })
                .map(|tri| PrimKind::Triangle {
                    mesh: mesh_index,
                    tri: tri as u32,
                }),
        );
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
        let material = shape.material.map(|m| m as u32);
        let to_world = transform_of(m);
        let params = &p.params;
        let mut prims: Vec<PrimKind> = Vec::new();
        match kind {
            "trianglemesh" | "plymesh" => {
                let Some(mesh) = &shape.mesh else {
                    return Ok(());
                };
                let tm = TriangleMesh::from_mesh(mesh, &to_world, shape.reverse_orientation);
                self.add_triangles(geom, tm, &mut prims, &p.loc, kind);
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
            "loopsubdiv" => {
                let mesh =
                    crate::shapes::loopsubdiv::mesh_from_params(params, &p.loc, self.warnings)?;
                let tm = TriangleMesh::from_mesh(&mesh, &to_world, shape.reverse_orientation);
                self.add_triangles(geom, tm, &mut prims, &p.loc, kind);
            }
            "heightfield" => {
                let mesh = crate::shapes::heightfield::mesh_from_params(params, &p.loc)?;
                let tm = TriangleMesh::from_mesh(&mesh, &to_world, shape.reverse_orientation);
                self.add_triangles(geom, tm, &mut prims, &p.loc, kind);
            }
            "nurbs" => {
                let mesh = crate::shapes::nurbs::mesh_from_params(params, &p.loc)?;
                let tm = TriangleMesh::from_mesh(&mesh, &to_world, shape.reverse_orientation);
                self.add_triangles(geom, tm, &mut prims, &p.loc, kind);
            }
            "sphere" => {
                let r = params.float_or("radius", 1.0)? as f32;
                if !self.positive_size(p, "radius", r) {
                    return Ok(());
                }
                let s = Sphere::new(
                    r,
                    params.float_or("zmin", -r as f64)? as f32,
                    params.float_or("zmax", r as f64)? as f32,
                    params.float_or("phimax", 360.0)? as f32,
                    to_world,
                    shape.reverse_orientation,
                );
                prims.push(PrimKind::Sphere(geom.spheres.len() as u32));
                geom.spheres.push(s);
            }
            "disk" => {
                let (r, ri) = (
                    params.float_or("radius", 1.0)? as f32,
                    params.float_or("innerradius", 0.0)? as f32,
                );
                if !self.positive_size(p, "radius", r)
                    || !self.positive_size(p, "radius - innerradius", r - ri.max(0.0))
                {
                    return Ok(());
                }
                let d = Disk::new(
                    params.float_or("height", 0.0)? as f32,
                    r,
                    ri.max(0.0),
                    params.float_or("phimax", 360.0)? as f32,
                    to_world,
                    shape.reverse_orientation,
                );
                prims.push(PrimKind::Disk(geom.disks.len() as u32));
                geom.disks.push(d);
            }
            "cylinder" => {
                let r = params.float_or("radius", 1.0)? as f32;
                let (z0, z1) = (
                    params.float_or("zmin", -1.0)? as f32,
                    params.float_or("zmax", 1.0)? as f32,
                );
                if !self.positive_size(p, "radius", r)
                    || !self.positive_size(p, "|zmax - zmin|", (z1 - z0).abs())
                {
                    return Ok(());
                }
                let c = Cylinder::new(
                    r,
                    z0,
                    z1,
                    params.float_or("phimax", 360.0)? as f32,
                    to_world,
                    shape.reverse_orientation,
                );
                prims.push(PrimKind::Cylinder(geom.cylinders.len() as u32));
                geom.cylinders.push(c);
            }
            "cone" | "paraboloid" | "hyperboloid" => {
                let built = crate::shapes::revolved::from_params(
                    kind,
                    params,
                    to_world,
                    shape.reverse_orientation,
                )?;
                let shape = match built {
                    Ok(s) => s,
                    Err(why) => {
                        self.warnings.push(Warning::at(&p.loc, why));
                        return Ok(());
                    }
                };
                area_light = self.no_emission(area_light, p);
                prims.push(PrimKind::Revolved(geom.revolved.len() as u32));
                geom.revolved.push(shape);
            }
            "curve" => {
                let curves = crate::shapes::curve::from_params(
                    params,
                    &p.loc,
                    to_world,
                    shape.reverse_orientation,
                    self.warnings,
                )?;
                area_light = self.no_emission(area_light, p);
                for (common, pieces) in curves {
                    let index = geom.curve_commons.len() as u32;
                    geom.curve_commons.push(common);
                    for mut piece in pieces {
                        piece.common = index;
                        prims.push(PrimKind::Curve(geom.curves.len() as u32));
                        geom.curves.push(piece);
                    }
                }
            }
            other => {
                self.warn_once(
                    format!("shape {other}"),
                    &p.loc,
                    format!("unknown shape \"{other}\"; shapes of this type are skipped"),
                );
                return Ok(());
            }
        }
        // Coordinates beyond f32's range (or NaN) relative to the camera: no box holds them.
        let before = prims.len();
        prims.retain(|&k| {
            let (lo, hi) = geom.kind_bounds(k);
            crate::accel::finite_box(lo, hi)
        });
        if prims.len() < before {
            self.warnings.push(Warning::at(
                &p.loc,
                format!(
                    "{kind}: {} of {before} primitives lie beyond the range of 32-bit floats \
                     seen from the camera, or have NaN coordinates, and are skipped",
                    before - prims.len()
                ),
            ));
        }
        if area_light.is_none() {
            let surface = self.surface(Surface {
                material,
                area_light: None,
            });
            for kind in prims {
                geom.push(Prim { kind, surface });
            }
            return Ok(());
        }
        let light = area_light.cloned();
        for kind in prims {
            // One light per primitive, as pbrt-v3 makes one DiffuseAreaLight per shape.
            let surface = self.surface(Surface {
                material,
                area_light: None,
            });
            if let Some(l) = &light {
                self.area_lights.push((Arc::clone(l), kind, surface));
            }
            geom.push(Prim { kind, surface });
        }
        Ok(())
    }
}
