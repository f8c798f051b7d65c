//! Camera and light subpaths (pbrt-v3's `GenerateCameraSubpath`, `GenerateLightSubpath` and
//! `RandomWalk`), generic over where their random decisions come from, so that mlt drives
//! them from its primary sample space.

use super::path_slots::Subpath;
use super::vertex::{adjoint_f, correct_shading_normal, Mode, SurfacePoint, Vertex, VertexKind};
use super::{LightChoice, MAX_PASS_THROUGH};
use crate::accel::Hit;
use crate::camera::CameraSample;
use crate::geometry::{
    offset_ray_origin, Ray, RayDifferentials, Spectrum, SurfaceInteraction, Vec2, Vec3,
};
use crate::light::WorldSphere;
use crate::scene::Scene;
use crate::stream::SampleSource;

/// pbrt-v3's `GenerateCameraSubpath` for a film position drawn from `sampler`: the film
/// point (uniform over the full film), then time and lens, then the walk. Returns the
/// vertices made and the raster position.
pub fn generate_camera_subpath<S: SampleSource + ?Sized>(
    scene: &Scene,
    sampler: &mut S,
    max_depth: usize,
    path: &mut Subpath,
) -> (usize, Vec2) {
    let (w, h) = scene.film.resolution;
    let u = sampler.next_2d();
    let film = Vec2::new(u.x * w as f32, u.y * h as f32);
    let time = sampler.next_1d();
    let lens = sampler.next_2d();
    let ray = scene
        .camera
        .generate_ray(&CameraSample { film, lens, time });
    let n = generate_camera_subpath_from(scene, ray, None, sampler, max_depth, path);
    (n, film)
}

/// The camera subpath that starts with the camera ray `ray` (and its differentials, which
/// the first hit takes): the vertices made, at most `max_depth`.
pub fn generate_camera_subpath_from<S: SampleSource + ?Sized>(
    scene: &Scene,
    ray: Ray,
    diff: Option<&RayDifferentials>,
    sampler: &mut S,
    max_depth: usize,
    path: &mut Subpath,
) -> usize {
    let pdf_dir = |ray: &Ray| scene.camera.pdf_we(ray.o, ray.d, ray.time).1;
    camera_subpath(
        scene,
        (ray, diff),
        sampler,
        (max_depth, true),
        path,
        pdf_dir,
    )
}

/// [`generate_camera_subpath_from`] for a ray the camera generated through a point of its
/// film (mlt's): the ray's density from its cosine alone, without mapping it back onto the
/// film (`Camera::pdf_we_dir_on_film`). Without `last_scatters` a surface vertex at the
/// walk's last bounce gets no BSDF (mlt's s = 0 strategy reads only its emission).
pub fn generate_camera_subpath_on_film<S: SampleSource + ?Sized>(
    scene: &Scene,
    (ray, diff): (Ray, Option<&RayDifferentials>),
    sampler: &mut S,
    (max_depth, last_scatters): (usize, bool),
    path: &mut Subpath,
) -> usize {
    let pdf_dir = |ray: &Ray| scene.camera.pdf_we_dir_on_film(ray.o, ray.d, ray.time);
    camera_subpath(
        scene,
        (ray, diff),
        sampler,
        (max_depth, last_scatters),
        path,
        pdf_dir,
    )
}

/// The camera subpath from `ray`, the density of its direction from `pdf_dir`.
#[inline(always)]
fn camera_subpath<S: SampleSource + ?Sized>(
    scene: &Scene,
    (ray, diff): (Ray, Option<&RayDifferentials>),
    sampler: &mut S,
    (max_depth, last_scatters): (usize, bool),
    path: &mut Subpath,
    pdf_dir: impl Fn(&Ray) -> f32,
) -> usize {
    path.clear();
    if max_depth == 0 {
        return 0;
    }
    let at = (ray.o, Vec3::ZERO, ray.time);
    path.push_endpoint(VertexKind::Camera, at, Spectrum::ONE, None);
    if max_depth == 1 {
        // The camera alone (mlt's t = 1): the ray's density would go unused.
        return 1;
    }
    let walk = Walk {
        beta: Spectrum::ONE,
        pdf: pdf_dir(&ray),
        max_depth: max_depth - 1,
        mode: Mode::Radiance,
        medium: scene.camera_medium,
        last_scatters,
    };
    random_walk(scene, ray, diff, sampler, walk, path) + 1
}

/// pbrt-v3's `GenerateLightSubpath`: a light chosen by `choice`, a ray leaving it, then the
/// walk; the vertices made, at most `max_depth`.
pub fn generate_light_subpath<S: SampleSource + ?Sized>(
    scene: &Scene,
    sampler: &mut S,
    max_depth: usize,
    time: f32,
    choice: &LightChoice,
    path: &mut Subpath,
) -> usize {
    path.clear();
    if max_depth == 0 {
        return 0;
    }
    let picked = choice.sample_origin(scene, sampler.next_1d());
    let (u1, u2) = (sampler.next_2d(), sampler.next_2d());
    let Some((index, light_pdf)) = picked else {
        return 0;
    };
    let light = &scene.lights[index];
    let sphere = WorldSphere {
        center: scene.world_center,
        radius: scene.world_radius,
    };
    let Some(e) = light.sample_le(&scene.accel.world, sphere, u1, u2) else {
        return 0;
    };
    // pbrt-v3 gives lights not on a surface the ray's direction as their normal.
    let on_area = e.n != Vec3::ZERO;
    let n = if on_area { e.n } else { e.d };
    let start = path.push_endpoint(VertexKind::Light, (e.o, n, time), e.le, Some(index as u32));
    start.pdf_fwd = e.pdf_pos * light_pdf;
    let beta = e.le * n.dot(e.d).abs() / (light_pdf * e.pdf_pos * e.pdf_dir);
    let o = if on_area {
        offset_ray_origin(e.o, if n.dot(e.d) < 0.0 { -n } else { n })
    } else {
        e.o
    };
    let walk = Walk {
        beta,
        pdf: e.pdf_dir,
        max_depth: max_depth - 1,
        mode: Mode::Importance,
        medium: path[0].medium_toward(scene, e.d),
        last_scatters: true,
    };
    let n_walk = random_walk(scene, Ray::new(o, e.d, time), None, sampler, walk, path);
    // Infinite lights: the first surface's density is the disk's, and the light's that of
    // the direction (pbrt-v3's correction).
    if path[0].is_infinite_light(scene) {
        if n_walk > 0 {
            let v = &mut path[1];
            v.pdf_fwd = e.pdf_pos;
            if v.on_surface() {
                v.pdf_fwd *= e.d.dot(v.ng).abs();
            }
        }
        path[0].pdf_fwd =
            super::vertex::infinite_light_density(scene, e.d, |i| choice.origin_pdf(scene, i));
    }
    n_walk + 1
}

/// Writes `ray`'s interaction at `hit` into `si`. A function of its own so that `si` is an
/// argument, which the compiler knows nothing else reads: it then builds the interaction
/// there instead of on the stack and copying it in.
#[inline(never)]
fn write_interaction(scene: &Scene, ray: &Ray, hit: &Hit, si: &mut SurfaceInteraction) {
    *si = scene.accel.interaction(ray, hit);
}

/// How a random walk starts.
struct Walk {
    /// The throughput so far.
    beta: Spectrum,
    /// The solid-angle density of the first ray's direction.
    pdf: f32,
    /// Most vertices to add.
    max_depth: usize,
    /// Radiance (camera) or importance (light).
    mode: Mode,
    /// The medium the first ray travels in.
    medium: Option<u32>,
    /// Whether a surface vertex at the last bounce gets its BSDF (else nothing reads it).
    last_scatters: bool,
}

/// pbrt-v3's `RandomWalk` (without Russian roulette, as pbrt-v3's bdpt): adds up to
/// `walk.max_depth` vertices to `path` (which holds the start) and returns how many. A ray in
/// a medium may scatter before the surface it would hit: a medium vertex, its phase function
/// sampled for the next direction (docs/media.md).
fn random_walk<S: SampleSource + ?Sized>(
    scene: &Scene,
    mut ray: Ray,
    mut diff: Option<&RayDifferentials>,
    sampler: &mut S,
    walk: Walk,
    path: &mut Subpath,
) -> usize {
    if walk.max_depth == 0 {
        return 0;
    }
    let Walk {
        mut beta,
        pdf,
        max_depth,
        mode,
        mut medium,
        last_scatters,
    } = walk;
    let mut pdf_fwd = pdf;
    let mut bounces = 0;
    let mut pass_through = 0;
    loop {
        let raw = scene.accel.intersect(&ray, f32::INFINITY);
        if let Some(m) = medium {
            let t_hit = raw.map_or(f32::INFINITY, |h| h.t);
            let ms = scene.media[m as usize].sample(&ray, t_hit, &mut || sampler.next_1d());
            beta *= ms.weight;
            if beta == Spectrum::ZERO || !crate::geometry::is_valid_radiance(beta) {
                break;
            }
            if let Some(t) = ms.t {
                let wo = -ray.d.normalize();
                let phase = scene.media[m as usize].phase;
                let at = (ray.at(t), wo, ray.time);
                let prev = path.len() - 1;
                let v = Vertex::medium(at, phase, medium, beta, pdf_fwd, &path[prev], scene);
                path.push(v);
                bounces += 1;
                if bounces >= max_depth {
                    break;
                }
                let (wi, p) = phase.sample_p(wo, sampler.next_2d());
                pdf_fwd = p;
                let n = path.len();
                let rev = path[n - 1].convert_density(p, &path[n - 2], scene);
                path[n - 2].pdf_rev = rev;
                ray = Ray::new(ray.at(t), wi, ray.time);
                continue;
            }
        }
        let Some(h) = raw else {
            // Camera rays that escape end on the infinite lights.
            if mode == Mode::Radiance {
                let d = ray.d.normalize();
                let at = (ray.o + d, -d, ray.time);
                path.push_endpoint(VertexKind::Light, at, beta, None)
                    .pdf_fwd = pdf_fwd;
                bounces += 1;
            }
            break;
        };
        let surface = &scene.surfaces[h.prim.surface as usize];
        // The hit is written where its vertex will be and shaded there: a copy of its 0.2 kB
        // cost more than the work on it (the reads after a bulk copy stall).
        let si = path.next_interaction();
        write_interaction(scene, &ray, &h, si);
        if let Some(d) = diff.take() {
            si.compute_differentials(d);
        }
        let Some(material) = surface.material else {
            pass_through += 1;
            if pass_through > MAX_PASS_THROUGH {
                break;
            }
            let media = super::super::volpath::media_at(surface, medium);
            medium = media.toward(si.n, ray.d);
            ray = si.spawn_ray(ray.d);
            continue;
        };
        let media = super::super::volpath::media_at(surface, medium);
        let material = &scene.materials[material as usize];
        material.shade(si);
        let at = (surface.area_light, media);
        let scatters = last_scatters || bounces + 1 < max_depth;
        path.push_surface(scatters.then_some(material), at, beta, pdf_fwd);
        bounces += 1;
        if bounces >= max_depth {
            break;
        }
        let u_lobe = sampler.next_1d();
        let u = sampler.next_2d();
        let here = path.last().and_then(|v| v.surface.as_ref());
        let Some(SurfacePoint { si, bsdf }) = here else {
            break;
        };
        let wo = si.wo;
        let Some(s) = bsdf.sample_f(wo, u, u_lobe) else {
            break;
        };
        if s.f == Spectrum::ZERO || s.pdf <= 0.0 {
            break;
        }
        pdf_fwd = s.pdf;
        let f = adjoint_f(bsdf, si, (wo, s.wi), s.f, s.specular, mode);
        beta *= f * s.wi.dot(si.shading_n).abs() / s.pdf;
        let mut pdf_rev = bsdf.pdf(s.wi, wo);
        beta *= correct_shading_normal(si, wo, s.wi, mode);
        let next_ray = si.spawn_ray(s.wi);
        medium = media.toward(si.n, s.wi);
        if s.specular {
            pdf_rev = 0.0;
            pdf_fwd = 0.0;
        }
        if !crate::geometry::is_valid_radiance(beta) {
            break;
        }
        let n = path.len();
        path[n - 1].delta = s.specular;
        let rev = path[n - 1].convert_density(pdf_rev, &path[n - 2], scene);
        path[n - 2].pdf_rev = rev;
        ray = next_ray;
    }
    bounces
}
