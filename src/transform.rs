//! Transforms that move during the shutter, interpolated as pbrt-v3's AnimatedTransform does:
//! each end is decomposed into translation, rotation (a quaternion, by polar decomposition) and
//! scale; translation and scale are interpolated linearly and rotation by slerp.

use glam::{DMat3, DMat4, DQuat, Mat4, Quat, Vec3};
use std::cell::RefCell;
use std::sync::atomic::{AtomicU64, Ordering};

/// One end of a motion, decomposed.
#[derive(Clone, Copy, Debug)]
struct Decomposed {
    translation: Vec3,
    rotation: Quat,
    scale: Mat4,
}

/// Decomposes `m` into translation, rotation and scale (pbrt-v3 AnimatedTransform::Decompose):
/// the rotation is the polar factor of the upper 3x3, found by iterating M <- (M + M^-T) / 2.
fn decompose(m: &DMat4) -> Decomposed {
    let translation = m.w_axis.truncate();
    let mut r = DMat3::from_mat4(*m);
    for _ in 0..100 {
        let inv_t = r.inverse().transpose();
        let next = (r + inv_t) * 0.5;
        let diff = (next - r)
            .to_cols_array()
            .iter()
            .fold(0.0f64, |a, x| a.max(x.abs()));
        r = next;
        if diff < 1e-12 || !diff.is_finite() {
            break;
        }
    }
    // A reflection (negative determinant) stays in the scale part: take the rotation's polar
    // factor of -r so that the quaternion is a proper rotation.
    let rot = if r.determinant() < 0.0 { -r } else { r };
    let q = DQuat::from_mat3(&rot).normalize();
    let rot4 = DMat4::from_quat(q);
    let mut linear = *m;
    linear.w_axis = glam::DVec4::W;
    let scale = rot4.inverse() * linear;
    Decomposed {
        translation: translation.as_vec3(),
        rotation: q.as_quat(),
        scale: scale.as_mat4(),
    }
}

/// pbrt-v3's slerp from one rotation to another (normalised lerp when they are nearly
/// parallel), with the angle and the perpendicular quaternion computed once: they do not
/// depend on the time, and a moving instance interpolates once per ray.
#[derive(Clone, Copy, Debug)]
struct Slerp {
    a: Quat,
    b: Quat,
    cos_theta: f32,
    theta: f32,
    perp: Quat,
}

impl Slerp {
    /// The path from `a` to `b`.
    fn new(a: Quat, b: Quat) -> Self {
        let cos_theta = a.dot(b);
        let (theta, perp) = if cos_theta > 0.9995 {
            (0.0, Quat::IDENTITY)
        } else {
            (
                cos_theta.clamp(-1.0, 1.0).acos(),
                (b - a * cos_theta).normalize(),
            )
        };
        Self {
            a,
            b,
            cos_theta,
            theta,
            perp,
        }
    }

    /// The rotation at `t` in [0, 1].
    fn at(&self, t: f32) -> Quat {
        if self.cos_theta > 0.9995 {
            (self.a * (1.0 - t) + self.b * t).normalize()
        } else {
            let thetap = self.theta * t;
            self.a * thetap.cos() + self.perp * thetap.sin()
        }
    }
}

/// A transform that may move between `start_time` and `end_time`.
#[derive(Clone, Debug)]
pub struct MotionTransform {
    start: Mat4,
    end: Mat4,
    start_time: f32,
    end_time: f32,
    /// When it moves: its two ends decomposed, and the rotation's path between them.
    parts: Option<([Decomposed; 2], Slerp)>,
    /// A number no other transform built in this process has: the key of its matrices in
    /// [`MotionTransform::at_with_inverse`]'s per-thread cache.
    id: u64,
}

/// The next [`MotionTransform::id`].
static NEXT_ID: AtomicU64 = AtomicU64::new(1);

/// One cached evaluation: a transform's id, the time's bits, the matrix and its inverse.
#[derive(Clone, Copy)]
struct CachedAt {
    id: u64,
    time: u32,
    at: Mat4,
    inverse: Mat4,
}

/// Slots of the per-thread cache (direct-mapped by id: the moving instances of a scene have
/// consecutive ids, so up to this many never evict one another).
const CACHE_SLOTS: usize = 16;

thread_local! {
    /// The last evaluations on this thread. Every ray of a path carries the camera sample's
    /// time, so a path's rays, its shadow rays and its hits' interactions all ask for the same
    /// instance at the same time: one interpolation and one inverse serve them all.
    static CACHE: RefCell<[CachedAt; CACHE_SLOTS]> = const {
        RefCell::new(
            [CachedAt {
                id: 0,
                time: 0,
                at: Mat4::IDENTITY,
                inverse: Mat4::IDENTITY,
            }; CACHE_SLOTS],
        )
    };
}

impl MotionTransform {
    /// From the parser's start and end matrices and times.
    pub fn new(desc: &acr_parser::AnimatedTransform) -> Self {
        let moving = desc.is_animated() && desc.end_time > desc.start_time;
        let parts = moving.then(|| {
            let a = decompose(&desc.start);
            let mut b = decompose(&desc.end);
            // Take the shorter way round.
            if a.rotation.dot(b.rotation) < 0.0 {
                b.rotation = -b.rotation;
            }
            ([a, b], Slerp::new(a.rotation, b.rotation))
        });
        Self {
            start: desc.start.as_mat4(),
            end: desc.end.as_mat4(),
            start_time: desc.start_time as f32,
            end_time: desc.end_time as f32,
            parts,
            id: NEXT_ID.fetch_add(1, Ordering::Relaxed),
        }
    }

    /// True when the transform changes during the shutter.
    pub fn is_moving(&self) -> bool {
        self.parts.is_some()
    }

    /// The transform at `time` (clamped to the start and end).
    pub fn at(&self, time: f32) -> Mat4 {
        let Some(([a, b], rotation)) = &self.parts else {
            return self.start;
        };
        if time <= self.start_time {
            return self.start;
        }
        if time >= self.end_time {
            return self.end;
        }
        let dt = (time - self.start_time) / (self.end_time - self.start_time);
        let trans = a.translation.lerp(b.translation, dt);
        let rot = rotation.at(dt);
        let scale = Mat4::from_cols(
            a.scale.x_axis.lerp(b.scale.x_axis, dt),
            a.scale.y_axis.lerp(b.scale.y_axis, dt),
            a.scale.z_axis.lerp(b.scale.z_axis, dt),
            a.scale.w_axis.lerp(b.scale.w_axis, dt),
        );
        Mat4::from_translation(trans) * Mat4::from_quat(rot) * scale
    }

    /// The transform at `time` and its inverse, as `at(time)` and `at(time).inverse()` give
    /// them (bit for bit: the same computation, remembered per thread for the last time asked).
    pub fn at_with_inverse(&self, time: f32) -> (Mat4, Mat4) {
        self.with_at(time, |at, inverse| (*at, *inverse))
    }

    /// `f` applied to the transform at `time` and its inverse (those of
    /// [`MotionTransform::at_with_inverse`]) where the per-thread cache holds them: a caller
    /// that needs a few products of them does not copy 128 bytes out first.
    #[inline]
    pub fn with_at<R>(&self, time: f32, f: impl FnOnce(&Mat4, &Mat4) -> R) -> R {
        let slot = (self.id % CACHE_SLOTS as u64) as usize;
        let bits = time.to_bits();
        CACHE.with(|cache| {
            let mut cache = cache.borrow_mut();
            let c = &mut cache[slot];
            if c.id != self.id || c.time != bits {
                // Field by field, into the slot: a whole `CachedAt` built aside and copied
                // in was stored in pieces and reloaded at once, which stalls.
                c.id = self.id;
                c.time = bits;
                c.at = self.at(time);
                c.inverse = c.at.inverse();
            }
            f(&c.at, &c.inverse)
        })
    }

    /// A box containing `bounds` (min, max) transformed at every time of the shutter.
    ///
    /// pbrt-v3 solves for the extrema of each corner's path; here the path is sampled finely and
    /// the box padded by the largest chord-to-arc gap a rotation step can leave.
    pub fn motion_bounds(&self, bounds: (Vec3, Vec3)) -> (Vec3, Vec3) {
        let corners = corners(bounds);
        let Some(([a, b], _)) = &self.parts else {
            return transform_box(&self.start, &corners);
        };
        const STEPS: usize = 128;
        let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
        for i in 0..=STEPS {
            let t = self.start_time + (self.end_time - self.start_time) * i as f32 / STEPS as f32;
            let (l, h) = transform_box(&self.at(t), &corners);
            lo = lo.min(l);
            hi = hi.max(h);
        }
        // Sagitta of one step's rotation arc for the farthest corner from the rotation centre.
        let angle = 2.0 * a.rotation.dot(b.rotation).clamp(-1.0, 1.0).acos();
        let step = angle / STEPS as f32;
        let radius = (hi - lo).length();
        let pad = radius * (1.0 - (step * 0.5).cos()) + 1e-6 * radius;
        (lo - Vec3::splat(pad), hi + Vec3::splat(pad))
    }
}

fn corners((lo, hi): (Vec3, Vec3)) -> [Vec3; 8] {
    std::array::from_fn(|i| {
        Vec3::new(
            if i & 1 == 0 { lo.x } else { hi.x },
            if i & 2 == 0 { lo.y } else { hi.y },
            if i & 4 == 0 { lo.z } else { hi.z },
        )
    })
}

/// The bounding box of `corners` transformed by `m`.
pub fn transform_box(m: &Mat4, corners: &[Vec3; 8]) -> (Vec3, Vec3) {
    corners.iter().fold(
        (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
        |(lo, hi), &c| {
            let p = m.transform_point3(c);
            (lo.min(p), hi.max(p))
        },
    )
}

/// Whether a transform mirrors space (negative determinant of its linear part).
pub fn swaps_handedness(m: &DMat4) -> bool {
    DMat3::from_mat4(*m).determinant() < 0.0
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

    fn motion(start: DMat4, end: DMat4) -> MotionTransform {
        MotionTransform::new(&acr_parser::AnimatedTransform {
            start,
            end,
            start_time: 0.0,
            end_time: 1.0,
        })
    }

    #[test]
    fn ends_are_exact_and_static_does_not_move() {
        let a = DMat4::from_translation(DVec3::new(1.0, 2.0, 3.0));
        let b = DMat4::from_scale_rotation_translation(
            DVec3::new(2.0, 1.0, 0.5),
            DQuat::from_rotation_z(1.0),
            DVec3::new(-1.0, 0.0, 4.0),
        );
        let m = motion(a, b);
        assert!(m.is_moving());
        assert!(m.at(0.0).abs_diff_eq(a.as_mat4(), 1e-6));
        assert!(m.at(1.0).abs_diff_eq(b.as_mat4(), 1e-5));
        assert!(!motion(a, a).is_moving());
    }

    #[test]
    fn cached_evaluation_is_the_computed_one() {
        // Seventeen transforms: the first and the last share a cache slot.
        let ms: Vec<MotionTransform> = (0..17)
            .map(|i| {
                motion(
                    DMat4::from_translation(DVec3::new(i as f64, 0.0, 1.0)),
                    DMat4::from_rotation_y(0.1 * i as f64 + 0.3),
                )
            })
            .collect();
        for t in [0.25f32, 0.5, 0.25, 1.5, 0.5] {
            for m in ms.iter().chain(ms.iter().rev()) {
                let (at, inverse) = m.at_with_inverse(t);
                assert_eq!(at.to_cols_array(), m.at(t).to_cols_array());
                assert_eq!(inverse.to_cols_array(), m.at(t).inverse().to_cols_array());
            }
        }
    }

    #[test]
    fn rotation_is_interpolated_by_angle() {
        let m = motion(
            DMat4::IDENTITY,
            DMat4::from_rotation_z(std::f64::consts::FRAC_PI_2),
        );
        let p = m.at(0.5).transform_point3(Vec3::X);
        let h = std::f32::consts::FRAC_1_SQRT_2;
        assert!((p - Vec3::new(h, h, 0.0)).length() < 1e-5, "{p}");
    }

    #[test]
    fn decomposition_recomposes_with_shear_and_mirror() {
        let m = DMat4::from_cols_array(&[
            2.0, 0.3, 0.0, 0.0, 0.1, -1.5, 0.2, 0.0, 0.0, 0.4, 0.7, 0.0, 5.0, -2.0, 1.0, 1.0,
        ]);
        let d = decompose(&m);
        let r = Mat4::from_translation(d.translation) * Mat4::from_quat(d.rotation) * d.scale;
        assert!(r.abs_diff_eq(m.as_mat4(), 1e-5), "{r} vs {m}");
    }

    #[test]
    fn motion_bounds_contain_the_path() {
        let m = motion(
            DMat4::IDENTITY,
            DMat4::from_rotation_z(3.0) * DMat4::from_translation(DVec3::new(3.0, 0.0, 0.0)),
        );
        let b = (Vec3::splat(-0.5), Vec3::splat(0.5));
        let (lo, hi) = m.motion_bounds(b);
        for i in 0..=1000 {
            let t = i as f32 / 1000.0;
            for c in corners(b) {
                let p = m.at(t).transform_point3(c);
                assert!(
                    p.cmpge(lo).all() && p.cmple(hi).all(),
                    "{t}: {p} outside {lo} {hi}"
                );
            }
        }
    }
}
