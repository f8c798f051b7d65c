//! `whitted`: pbrt-v3's WhittedIntegrator. Emission at the hit, one light sample from every
//! light (no MIS: a light is only found by sampling it), and specular reflection and
//! transmission followed recursively to `maxdepth`, the camera ray's differentials carried
//! through them (docs/light-transport.md).

use super::direct::{first_surface, follow_specular_lobes, Tally};
use crate::bsdf::Bsdf;
use crate::geometry::{Ray, RayDifferentials, Spectrum};
use crate::scene::Scene;
use crate::stream::SampleStream;

/// The radiance along `ray` by Whitted's recursion; `depth` counts specular bounces.
pub fn whitted_li(
    scene: &Scene,
    ray: Ray,
    diff: Option<&RayDifferentials>,
    stream: &mut SampleStream,
    max_depth: u32,
    depth: u32,
    tally: &mut Tally,
) -> Spectrum {
    // A surface without material passes the ray on at the same depth, without emission, as
    // pbrt-v3's recursion does.
    let (hit, pass_through) = match first_surface(scene, ray, tally) {
        Ok(h) => h,
        Err(sky) => return sky,
    };
    let mut si = hit.si;
    // The differentials hold for the ray as it left the camera or a specular bounce.
    let camera_diff = diff.filter(|_| pass_through == 0);
    if let Some(d) = camera_diff {
        si.compute_differentials(d);
    }
    // pbrt-v3 takes the cosine against the shading normal before bump mapping changes it.
    let n = si.shading_n;
    let mut l = Spectrum::ZERO;
    if let Some(li) = hit.surface.area_light {
        l += scene.lights[li as usize].l(&si, si.wo);
    }
    let Some(material) = hit.surface.material else {
        return l;
    };
    let material = &scene.materials[material as usize];
    material.shade(&mut si);
    // Separate lobes (a glass's reflection and transmission apart), as pbrt-v3's Whitted.
    let mut bsdf = Bsdf::empty();
    material.bsdf_into_with(&si, false, &mut bsdf);
    tally.probe.surface(&si, &bsdf);
    // A purely specular BSDF is black to every light sample: pbrt-v3 draws them for nothing.
    if bsdf.has_non_specular() {
        for light in &scene.lights {
            let u = stream.next_2d();
            let Some(ls) = light.sample_li(&scene.accel.world, si.p, u) else {
                continue;
            };
            if ls.pdf == 0.0 || ls.li == Spectrum::ZERO {
                continue;
            }
            let f = bsdf.f(si.wo, ls.wi);
            if f == Spectrum::ZERO {
                continue;
            }
            tally.rays += 1;
            if !scene.occluded(&si, ls.p) {
                l += f * ls.li * ls.wi.dot(n).abs() / ls.pdf;
            }
        }
    }
    if depth + 1 < max_depth {
        l += follow_specular_lobes(&si, &bsdf, camera_diff, stream, |next, d, stream| {
            whitted_li(scene, next, d, stream, max_depth, depth + 1, tally)
        });
    }
    l
}
