//! pbrt-v3's image-modulated point lights: `goniometric` (lights/goniometric.cpp), whose
//! intensity in each direction is read from an image over (phi, theta), and `projection`
//! (lights/projection.cpp), which casts an image through a perspective frustum. Here are their
//! images, direction-to-image mappings and constructors; [`Light`] holds the enum arms.
//!
//! Both read their image with pbrt-v3's `ReadImage`, which returns PNG values as stored
//! (bytes / 255, no sRGB decoding) and EXR values as linear, and look it up through a
//! `MIPMap<RGBSpectrum>` at its finest level: bilinear interpolation (`MIPMap::triangle` at
//! level 0), with the MIP map's default wrap mode, repeat, on both axes, and the image's first
//! (top) row at t = 0. acr does the same lookup in the full-resolution image, as its other
//! image lookups do; the one difference is that pbrt-v3 first resamples an image whose sides
//! are not powers of two (Lanczos) to the next powers of two, which acr does not.

use crate::geometry::{Spectrum, Vec2, Vec3};
use crate::image_io::RgbImage;
use crate::light::{Light, LightSample};
use crate::mipmap::MipMap;
use crate::texture::{ImageMap, Wrap};
use glam::{DMat4, Mat4};
use std::f32::consts::PI;

/// pbrt-v3's `InvPi`.
const INV_PI: f32 = std::f32::consts::FRAC_1_PI;
/// pbrt-v3's `Inv2Pi` (exactly half of [`INV_PI`] in f32).
const INV_2PI: f32 = 0.5 * std::f32::consts::FRAC_1_PI;
/// The projection's near plane (pbrt-v3's `hither`): directions closer to the light's xy
/// plane, or behind it, get nothing.
const HITHER: f32 = 1e-3;

/// An image a goniometric or projection light scales its intensity by.
#[derive(Clone, Debug)]
pub struct LightImage {
    /// Top row first, as read (pbrt-v3's MIP map keeps the file's order), wrapped around on
    /// both axes (pbrt-v3's `ImageWrap::Repeat`): the image as read.
    map: ImageMap<Spectrum>,
    /// Its MIP map (resampled to powers of two, as pbrt-v3's lights build one), which lookups
    /// read.
    mip: MipMap<Spectrum>,
    /// What pbrt-v3's `Power` looks up, see [`LightImage::average`].
    average: Spectrum,
}

impl LightImage {
    /// From an image as [`crate::image_io::read_image`] returns it; `None` when it has no
    /// pixels.
    pub fn new(img: &RgbImage) -> Option<Self> {
        let (width, height) = (img.width, img.height);
        if width == 0 || height == 0 || img.pixels.len() != width * height {
            return None;
        }
        let map = ImageMap::from_rows(width, height, img.pixels.clone(), Wrap::Repeat);
        let mip = MipMap::new(&map, false, 8.0);
        // pbrt-v3's Power: a trilinear lookup at the centre with width 0.5.
        let average = mip.lookup_width(Vec2::splat(0.5), 0.5);
        Some(Self { map, mip, average })
    }

    /// Width in pixels.
    pub fn width(&self) -> usize {
        self.map.width()
    }

    /// Height in pixels.
    pub fn height(&self) -> usize {
        self.map.height()
    }

    /// The mean pixel, as pbrt-v3's `Power` takes it: its MIP map looked up at (0.5, 0.5) with
    /// width 0.5, which lands on the 2x2 (or 2x1) level at its centre, the mean of the image
    /// (resampled to powers of two).
    pub fn average(&self) -> Spectrum {
        self.average
    }

    /// The mean over the pixels of the largest channel of `intensity` times the pixel (negative
    /// values as 0): the power bound of pbrt-v4's `Bounds` for these lights, per steradian.
    pub fn mean_max(&self, intensity: Spectrum) -> f32 {
        let texels = self.map.texels();
        let sum: f64 = texels
            .iter()
            .map(|p| f64::from((intensity * p.max(Spectrum::ZERO)).max_element()))
            .sum();
        (sum / texels.len() as f64) as f32
    }

    /// Bilinear interpolation at `st` in [0, 1]², t = 0 at the top row: pbrt-v3's
    /// `MIPMap::Lookup(st)` with no filter width, its bilinear `triangle` at level 0 (of the
    /// image resampled to powers of two).
    #[inline]
    pub fn lookup(&self, st: Vec2) -> Spectrum {
        self.mip.lookup(st, Vec2::ZERO, Vec2::ZERO)
    }
}

/// Where a goniometric light's image is read for the light-space direction `wl` (not
/// necessarily unit): pbrt-v3's `GonioPhotometricLight::Scale`, which swaps y and z, so that
/// the image's rows run from the light's +y (theta = 0, top row) to its -y, and its columns
/// around the y axis from +x (phi = 0) towards +z: (u, v) = (phi / 2pi, theta / pi).
#[inline]
pub fn goniometric_st(wl: Vec3) -> Vec2 {
    let w = wl.normalize();
    let wp = Vec3::new(w.x, w.z, w.y);
    let theta = wp.z.clamp(-1.0, 1.0).acos();
    let p = wp.y.atan2(wp.x);
    let phi = if p < 0.0 { p + 2.0 * PI } else { p };
    Vec2::new(phi * INV_2PI, theta * INV_PI)
}

/// A goniometric light's scale for the light-space direction `wl`: its image there, or 1 with
/// no image (pbrt-v3's `RGBSpectrum(1.f)` when the map could not be read).
#[inline]
pub fn goniometric_scale(map: Option<&LightImage>, wl: Vec3) -> Spectrum {
    map.map_or(Spectrum::ONE, |m| m.lookup(goniometric_st(wl)))
}

/// A projection light's frustum and image: pbrt-v3's `ProjectionLight` without its transform.
#[derive(Clone, Debug)]
pub struct ImageProjection {
    /// The image, if any (without one, 1 inside the frustum).
    map: Option<LightImage>,
    /// The screen window's least corner.
    screen_lo: Vec2,
    /// The screen window's greatest corner.
    screen_hi: Vec2,
    /// 1 / tan(fov / 2), the perspective's scale.
    inv_tan: f32,
    /// Cosine of the angle between the light's +z and the screen window's corner: the
    /// frustum's widest direction (pbrt-v3's `cosTotalWidth`).
    pub cos_total_width: f32,
}

impl ImageProjection {
    /// pbrt-v3's `ProjectionLight` constructor: the screen window spans [-1, 1] on the image's
    /// shorter side and keeps its aspect ratio on the longer (a square without an image), and
    /// the perspective has field of view `fov_degrees` across the shorter side.
    pub fn new(map: Option<LightImage>, fov_degrees: f32) -> Self {
        let aspect = map
            .as_ref()
            .map_or(1.0, |m| m.width() as f32 / m.height() as f32);
        let (screen_lo, screen_hi) = if aspect > 1.0 {
            (Vec2::new(-aspect, -1.0), Vec2::new(aspect, 1.0))
        } else {
            (Vec2::new(-1.0, -1.0 / aspect), Vec2::new(1.0, 1.0 / aspect))
        };
        // pbrt-v3's Perspective(fov, 1e-3, 1e30): Radians is (Pi / 180) * deg.
        let inv_tan = 1.0 / ((PI / 180.0) * fov_degrees / 2.0).tan();
        // pbrt-v3 un-projects the window's corner (screen z = 0 is the near plane) and takes the
        // cosine of its direction; in closed form, the corner's direction is (x, y, tan)-like.
        let corner = Vec3::new(screen_hi.x / inv_tan, screen_hi.y / inv_tan, 1.0).normalize();
        Self {
            map,
            screen_lo,
            screen_hi,
            inv_tan,
            cos_total_width: corner.z,
        }
    }

    /// The image, if any.
    pub fn map(&self) -> Option<&LightImage> {
        self.map.as_ref()
    }

    /// The screen point of the light-space direction `wl`: pbrt-v3's `lightProjection` applied
    /// to the point `wl` (x and y scaled by 1 / tan(fov / 2), then times 1 / z, in that order).
    #[inline]
    pub fn screen_point(&self, wl: Vec3) -> Vec2 {
        let inv_z = 1.0 / wl.z;
        Vec2::new(inv_z * (self.inv_tan * wl.x), inv_z * (self.inv_tan * wl.y))
    }

    /// The screen window: least and greatest corners.
    pub fn screen_window(&self) -> (Vec2, Vec2) {
        (self.screen_lo, self.screen_hi)
    }

    /// pbrt-v3's `ProjectionLight::Projection` for the light-space direction `wl` (as the light
    /// transform gives it, not normalised): nothing behind the near plane or outside the screen
    /// window (edges included), else the image at the screen point mapped to [0, 1]² (1 without
    /// an image).
    #[inline]
    pub fn eval(&self, wl: Vec3) -> Spectrum {
        if wl.z < HITHER {
            return Spectrum::ZERO;
        }
        let p = self.screen_point(wl);
        let (lo, hi) = (self.screen_lo, self.screen_hi);
        // Written so that NaN is outside.
        let inside = p.x >= lo.x && p.x <= hi.x && p.y >= lo.y && p.y <= hi.y;
        if !inside {
            return Spectrum::ZERO;
        }
        match &self.map {
            None => Spectrum::ONE,
            Some(m) => m.lookup(Vec2::new(
                (p.x - lo.x) / (hi.x - lo.x),
                (p.y - lo.y) / (hi.y - lo.y),
            )),
        }
    }

    /// A cone around which every direction the light sends goes, in world space, for the light
    /// BVH: axis, and the cosine of its half-angle. The frustum is the convex cone spanned by
    /// its four corner directions and a linear map keeps it one, so the corners' largest angle
    /// from the mapped +z bounds it whatever the transform's scale or shear (with a small
    /// margin for rounding). Every direction when that angle reaches 90 degrees.
    pub fn world_cone(&self, world_from_light: &Mat4) -> (Vec3, f32) {
        let axis = world_from_light
            .transform_vector3(Vec3::Z)
            .normalize_or_zero();
        let mut cos = 1.0f32;
        for (x, y) in [
            (self.screen_lo.x, self.screen_lo.y),
            (self.screen_lo.x, self.screen_hi.y),
            (self.screen_hi.x, self.screen_lo.y),
            (self.screen_hi.x, self.screen_hi.y),
        ] {
            let corner = Vec3::new(x / self.inv_tan, y / self.inv_tan, 1.0);
            let c = world_from_light
                .transform_vector3(corner)
                .normalize_or_zero();
            cos = cos.min(axis.dot(c));
        }
        let angle = cos.clamp(-1.0, 1.0).acos() + 1e-3;
        if axis == Vec3::ZERO || !cos.is_finite() || angle >= 0.5 * PI {
            return (Vec3::Z, -1.0);
        }
        (axis, angle.cos())
    }
}

/// A delta light's sample at `p` from `pos` along unit `wi` with intensity `intensity`
/// (already scaled for the direction): intensity / distance², pdf 1; `None` when it sends
/// nothing that way.
#[inline]
pub(crate) fn delta_sample(
    pos: Vec3,
    p: Vec3,
    wi: Vec3,
    intensity: Spectrum,
) -> Option<LightSample> {
    if intensity == Spectrum::ZERO {
        return None;
    }
    Some(LightSample {
        wi,
        li: intensity / pos.distance_squared(p),
        pdf: 1.0,
        p: pos,
    })
}

/// The world-to-light transform of a light placed by `world_from_light`, if it has one.
fn light_from(world_from_light: &DMat4) -> Result<Mat4, String> {
    let m = world_from_light.inverse().as_mat4();
    if m.is_finite() && world_from_light.determinant() != 0.0 {
        Ok(m)
    } else {
        Err("the light's transform cannot be inverted".into())
    }
}

impl Light {
    /// pbrt-v3's `GonioPhotometricLight` at the origin of `world_from_light`, with intensity
    /// `intensity` (I times scale) and its image, if any.
    pub fn goniometric(
        world_from_light: &DMat4,
        intensity: Spectrum,
        map: Option<LightImage>,
    ) -> Result<Light, String> {
        Ok(Light::Goniometric {
            pos: world_from_light.as_mat4().transform_point3(Vec3::ZERO),
            light_from_world: light_from(world_from_light)?,
            intensity,
            map,
        })
    }

    /// pbrt-v3's `ProjectionLight` at the origin of `world_from_light`, looking along its +z,
    /// with intensity `intensity` (I times scale), its image, if any, and field of view
    /// `fov_degrees`.
    pub fn projection(
        world_from_light: &DMat4,
        intensity: Spectrum,
        map: Option<LightImage>,
        fov_degrees: f32,
    ) -> Result<Light, String> {
        if !(fov_degrees > 0.0 && fov_degrees < 180.0) {
            return Err(format!(
                "fov {fov_degrees} is not between 0 and 180 degrees"
            ));
        }
        Ok(Light::Projection {
            pos: world_from_light.as_mat4().transform_point3(Vec3::ZERO),
            light_from_world: light_from(world_from_light)?,
            intensity,
            projection: ImageProjection::new(map, fov_degrees),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::Geometry;
    use std::path::Path;

    /// The light-to-world transforms of `tests/data/pbrt-v3/lightimagecheck.cpp`.
    fn transforms() -> [DMat4; 2] {
        let rot = |deg: f64, axis: [f64; 3]| {
            DMat4::from_axis_angle(glam::DVec3::from(axis).normalize(), deg.to_radians())
        };
        let t = |x: f64, y: f64, z: f64| DMat4::from_translation(glam::DVec3::new(x, y, z));
        [
            t(0.3, -0.2, 0.5) * rot(35.0, [1.0, 2.0, 0.5]),
            t(-0.4, 0.6, 0.1)
                * rot(-70.0, [0.3, -1.0, 0.8])
                * DMat4::from_scale(glam::DVec3::new(1.5, 0.8, 1.2)),
        ]
    }

    fn image(name: &str) -> LightImage {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/pbrt-v3");
        let img = crate::image_io::read_image(&dir.join(name), false).unwrap();
        LightImage::new(&img).unwrap()
    }

    /// The lights of `lightimagecheck.cpp`, in its order.
    fn lights() -> Vec<Light> {
        let [a, b] = transforms();
        let i = Spectrum::new(1.5, 0.75, 2.0);
        let (wide, tall) = (image("lightimage-8x4.exr"), image("lightimage-4x8.exr"));
        vec![
            Light::goniometric(&a, i, Some(wide.clone())).unwrap(),
            Light::goniometric(&b, i, None).unwrap(),
            Light::projection(&a, i, Some(wide), 60.0).unwrap(),
            Light::projection(&b, i, Some(tall), 30.0).unwrap(),
            Light::projection(&a, i, None, 45.0).unwrap(),
        ]
    }

    /// How far the screen point of the direction from `light` to `p` lies from the screen
    /// window's edges (infinite for other lights): where pbrt-v3's and acr's transforms, a few
    /// ulps apart, may put it on either side.
    fn edge_distance(light: &Light, p: Vec3) -> f32 {
        let Light::Projection {
            pos,
            light_from_world,
            projection,
            ..
        } = light
        else {
            return f32::INFINITY;
        };
        let wl = light_from_world.transform_vector3(-(*pos - p).normalize());
        let s = projection.screen_point(wl);
        let (lo, hi) = projection.screen_window();
        let d = (s.x - lo.x)
            .abs()
            .min((s.x - hi.x).abs())
            .min((s.y - lo.y).abs())
            .min((s.y - hi.y).abs());
        d.min((wl.z - HITHER).abs())
    }

    /// `Sample_Li` and `Power` of pbrt-v3's goniometric and projection lights, printed by
    /// `tests/data/pbrt-v3/lightimagecheck.cpp` (linked with pbrt-v3's libpbrt.a; it says
    /// how) at 300 points around each light (the projections' half
    /// behind or outside their frustum): acr's agree to 1e-5 (relative), power to 1e-4.
    #[test]
    fn samples_match_pbrt_v3() {
        let lights = lights();
        let world = Geometry::default();
        let data = include_str!("../tests/data/pbrt-v3/lightimage.txt");
        let (mut lit, mut dark, mut edge, mut worst) = ([0; 5], [0; 5], 0, 0f32);
        for line in data.lines() {
            let w: Vec<&str> = line.split_whitespace().collect();
            let f = |i: usize| -> f32 { w[i].parse().unwrap() };
            let v3 = |i: usize| Vec3::new(f(i), f(i + 1), f(i + 2));
            let l: usize = w[1].parse().unwrap();
            if w[0] == "power" {
                let got = lights[l].power();
                assert!(
                    (got - v3(2)).abs().max_element() <= 1e-4 * v3(2).max_element(),
                    "{got}\n{line}"
                );
                continue;
            }
            let (p, wi, li, pdf) = (v3(2), v3(5), v3(8), f(11));
            let got = lights[l].sample_li(&world, p, Vec2::new(0.5, 0.5));
            if li == Spectrum::ZERO {
                if let Some(s) = got {
                    assert!(
                        edge_distance(&lights[l], p) < 1e-5,
                        "acr lights where pbrt-v3 does not: {s:?}\n{line}"
                    );
                    edge += 1;
                } else {
                    dark[l] += 1;
                }
                continue;
            }
            let Some(s) = got else {
                assert!(
                    edge_distance(&lights[l], p) < 1e-5,
                    "acr is dark where pbrt-v3 lights:\n{line}"
                );
                edge += 1;
                continue;
            };
            lit[l] += 1;
            assert_eq!(pdf, 1.0);
            assert_eq!(s.pdf, 1.0);
            assert!(
                (s.wi - wi).abs().max_element() < 1e-5,
                "wi {}\n{line}",
                s.wi
            );
            let err = (s.li - li).abs().max_element() / li.max_element();
            assert!(err <= 1e-5, "li {}\n{line}", s.li);
            worst = worst.max(err);
        }
        // Every light was lit from some points, and the projections dark from others.
        assert!(lit.iter().all(|&n| n > 50), "{lit:?}");
        assert!(dark[2..].iter().all(|&n| n > 20), "{dark:?}");
        assert!(edge <= 2, "{edge} points on an edge");
        eprintln!(
            "lit {lit:?}, dark {dark:?}, on an edge {edge}, largest relative error {worst:.2e}"
        );
    }

    /// Every light choice handles the image lights: finite, positive power; bounds whose cone
    /// holds every direction a projection light sends (under a scale and a rotation); each
    /// strategy can choose each light where it shines, with a finite probability.
    #[test]
    fn light_choice_handles_image_lights() {
        use crate::lightbvh::{LightBounds, LightContext};
        use crate::lightdistrib::LightStrategy;
        let text = "Camera \"perspective\"\nWorldBegin\n\
            AttributeBegin\nTranslate 0 3 0\nRotate 90 1 0 0\nScale 1 2 0.5\n\
            LightSource \"projection\" \"string mapname\" \"lightimage-8x4.exr\" \"float fov\" 50\n\
            AttributeEnd\n\
            AttributeBegin\nTranslate 2 1 0\nRotate 30 0 0 1\n\
            LightSource \"goniometric\" \"string mapname\" \"lightimage-4x8.exr\" \"rgb I\" [2 1 1]\n\
            AttributeEnd\n\
            AttributeBegin\nTranslate -2 2 0\nRotate 120 1 0 0\n\
            LightSource \"projection\" \"rgb I\" [1 2 3] \"float fov\" 20\n\
            AttributeEnd\n\
            AttributeBegin\nTranslate 0 1 -4\n\
            LightSource \"goniometric\" \"point3 from\" [0 0 0]\nAttributeEnd\n\
            Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] \"point3 P\" \
            [-5 0 -5 5 0 -5 5 0 5 -5 0 5]\nWorldEnd\n";
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/pbrt-v3");
        let desc = acr_parser::parse_str(text, &dir.join("image-lights.pbrt")).unwrap();
        let mut warnings = Vec::new();
        let scene = crate::scene::Scene::build(&desc, &mut warnings).unwrap();
        assert_eq!(scene.lights.len(), 4);
        // pbrt-v3's lights take no "from": reported unused, as pbrt-v3 does.
        assert_eq!(desc.unused_parameter_warnings().len(), 1);
        for light in &scene.lights {
            let power = light.power();
            assert!(power.is_finite() && power.min_element() > 0.0, "{power}");
            let b = LightBounds::of(light, &scene.accel.world).unwrap();
            assert!(format!("{b:?}").find("NaN").is_none(), "{b:?}");
            let Light::Projection {
                pos,
                light_from_world,
                projection,
                ..
            } = light
            else {
                continue;
            };
            let (axis, cos) = projection.world_cone(&light_from_world.inverse());
            assert!(cos > 0.0 && cos < 1.0, "{cos}");
            // Directions it lights lie in the cone; the cone is not much wider than they are.
            let mut widest = 1.0f32;
            for i in 0..20000 {
                let u = Vec2::new((i as f32 + 0.5) / 20000.0, (i as f32 * 0.618_034).fract());
                let w = crate::sampling::uniform_sample_sphere(u);
                if projection.eval(light_from_world.transform_vector3(w)) != Spectrum::ZERO {
                    assert!(w.dot(axis) >= cos, "{w} outside the cone of {pos}");
                    widest = widest.min(w.dot(axis));
                }
            }
            assert!(widest - cos < 0.05, "{widest} {cos}");
        }
        // From under each light, every strategy can pick it.
        let points = [Vec3::new(0.0, 0.0, 0.0), Vec3::new(2.0, 0.0, 0.3)];
        for strategy in [
            LightStrategy::Uniform,
            LightStrategy::Power,
            LightStrategy::Spatial,
            LightStrategy::Bvh,
        ] {
            for p in points {
                let ctx = LightContext { p, n: Vec3::Y };
                let mut seen = [false; 4];
                for i in 0..64 {
                    let (l, pdf) = scene
                        .choose_light(strategy, ctx, (i as f32 + 0.5) / 64.0)
                        .unwrap();
                    assert!(pdf > 0.0 && pdf.is_finite(), "{strategy:?} {l} {pdf}");
                    assert_eq!(pdf, scene.light_choice_pdf(strategy, ctx, l));
                    seen[l] = true;
                }
                // The first projection light shines on the origin, the first goniometric
                // light everywhere.
                assert!(seen[1], "{strategy:?} at {p}: {seen:?}");
                if p == Vec3::ZERO {
                    assert!(seen[0], "{strategy:?} at {p}: {seen:?}");
                }
            }
        }
    }

    /// An image that cannot be read and a field of view outside (0, 180) are errors at their
    /// place in the file (pbrt-v3 goes on without the image, or with a degenerate frustum).
    #[test]
    fn bad_maps_and_fov_are_located_errors() {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/pbrt-v3");
        for (light, want) in [
            (
                "\"goniometric\"\n  \"string mapname\" \"missing.exr\"",
                "lights.pbrt:4:3: cannot read \"missing.exr\"",
            ),
            (
                "\"projection\"\n  \"string mapname\" \"lightimagecheck.cpp\"",
                "lights.pbrt:4:3: cannot read \"lightimagecheck.cpp\": unsupported image format",
            ),
            (
                "\"projection\" \"float fov\" 180",
                "lights.pbrt:3:1: projection light: fov 180 is not between 0 and 180",
            ),
        ] {
            let text =
                format!("Camera \"perspective\"\nWorldBegin\nLightSource {light}\nWorldEnd\n");
            let desc = acr_parser::parse_str(&text, &dir.join("lights.pbrt")).unwrap();
            let err = crate::scene::Scene::build(&desc, &mut Vec::new())
                .err()
                .unwrap();
            let msg = err.to_string();
            assert!(msg.contains(want), "{msg}");
        }
    }
}
