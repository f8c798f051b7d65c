//! Placing a scene's geometry: the world's shapes (fixed ones in render space, moving ones as
//! instances of their own), the object definitions, and their instances, into one
//! acceleration structure.

use super::Builder;
use crate::accel::{Accel, Geometry, Instance, Placement};
use crate::transform::MotionTransform;
use acr_parser::{AnimatedTransform, Result, Warning};
use glam::DMat4;

impl Builder<'_> {
    /// The acceleration structure of every shape, object definition and instance, built.
    pub(super) fn accel(&mut self) -> Result<Accel> {
        let mut accel = Accel::default();
        let world = self.world_shapes(&mut accel)?;
        let first_object = accel.objects.len() as u32;
        self.object_definitions(&mut accel)?;
        self.object_instances(&mut accel, first_object);
        accel.world = world;
        let dropped = accel.build();
        if dropped > 0 {
            self.warnings.push(Warning {
                loc: None,
                message: format!(
                    "{dropped} object instances are placed farther than {:e} from the camera \
                     (the BVH's range) and are skipped",
                    crate::accel::MAX_COORDINATE
                ),
            });
        }
        Ok(accel)
    }

    /// `t` with render space in place of world space.
    fn in_render(&self, t: &AnimatedTransform) -> AnimatedTransform {
        AnimatedTransform {
            start: self.render_from_world * t.start,
            end: self.render_from_world * t.end,
            ..*t
        }
    }

    /// The world's fixed shapes, in render space; each moving shape becomes an object of
    /// `accel` with an instance that moves it (its area light, as in pbrt-v3, dropped).
    fn world_shapes(&mut self, accel: &mut Accel) -> Result<Geometry> {
        let mut world = Geometry::default();
        let desc = self.desc;
        for shape in &desc.shapes {
            let moving = shape.world_from_object.is_animated()
                && shape.world_from_object.end_time > shape.world_from_object.start_time;
            if !moving {
                let m = self.render_from_world * shape.world_from_object.start;
                self.add_shape(&mut world, shape, &m, true)?;
                continue;
            }
            if let Some(al) = &shape.area_light {
                self.warn_once(
                    "moving area light".into(),
                    &al.loc,
                    "area lights on moving shapes are not supported (as in pbrt-v3); the shape \
                     does not emit"
                        .into(),
                );
            }
            let mut g = Geometry::default();
            self.add_shape(&mut g, shape, &DMat4::IDENTITY, false)?;
            accel.objects.push(g);
            accel.instances.push(Instance {
                object: (accel.objects.len() - 1) as u32,
                placement: Placement::Moving(Box::new(MotionTransform::new(
                    &self.in_render(&shape.world_from_object),
                ))),
            });
        }
        Ok(world)
    }

    /// Each object definition's shapes as an object of `accel`, in its own space.
    fn object_definitions(&mut self, accel: &mut Accel) -> Result<()> {
        let desc = self.desc;
        for object in desc.objects.values() {
            let mut g = Geometry::default();
            for shape in &object.shapes {
                if shape.world_from_object.is_animated() {
                    self.warn_once(
                        "animated in object".into(),
                        &shape.plugin.loc,
                        "motion inside an object definition is not supported; the shape is \
                         placed at its start transform (move the instance instead)"
                            .into(),
                    );
                }
                self.add_shape(&mut g, shape, &shape.world_from_object.start, false)?;
            }
            accel.objects.push(g);
        }
        Ok(())
    }

    /// The object instances, fixed or moving; object definitions start at `first_object`
    /// among `accel`'s objects.
    fn object_instances(&self, accel: &mut Accel, first_object: u32) {
        for inst in &self.desc.instances {
            let t = &self.in_render(&inst.world_from_instance);
            let placement = if t.is_animated() && t.end_time > t.start_time {
                Placement::Moving(Box::new(MotionTransform::new(t)))
            } else {
                Placement::Fixed {
                    to_world: t.start.as_mat4(),
                    to_local: t.start.inverse().as_mat4(),
                }
            };
            accel.instances.push(Instance {
                object: first_object + inst.object as u32,
                placement,
            });
        }
    }
}
