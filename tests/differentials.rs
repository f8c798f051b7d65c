//! Ray differentials against pbrt-v3 (`tests/data/pbrt-v3/diffcheck.cpp`): the camera ray's
//! differentials (pinhole and thin lens), the hit's screen-space derivatives, and what uses
//! them: the noise octaves (FBm, Turbulence) and the closed-form box-filtered checkerboard.

use acr::bsdf::Bxdf;
use acr::camera::CameraSample;
use acr::geometry::{Vec2, Vec3};
use acr::scene::Scene;
use std::path::Path;

fn scene(lens: f32) -> Scene {
    let text = format!(
        r#"LookAt 0 0.5 -4  0 0 0  0 1 0
Camera "perspective" "float fov" 50 "float lensradius" {lens} "float focaldistance" 4
Film "image" "integer xresolution" 64 "integer yresolution" 48
WorldBegin
Texture "check" "spectrum" "checkerboard" "float uscale" 64 "float vscale" 64
    "rgb tex1" [1 1 1] "rgb tex2" [0 0 0]
Material "matte" "texture Kd" "check"
Shape "sphere" "float radius" 1
WorldEnd
"#
    );
    let desc = acr_parser::parse_str(&text, Path::new("/tmp/differentials.pbrt")).unwrap();
    Scene::build(&desc, &mut Vec::new()).unwrap()
}

fn close(got: f32, want: f32, rel: f32, abs: f32) -> bool {
    (got - want).abs() <= rel * want.abs() + abs
}

#[test]
fn camera_ray_differentials_match_pbrt_v3() {
    let data = include_str!("data/pbrt-v3/differentials.txt");
    let scenes = [scene(0.0), scene(0.2)];
    let mut checked = 0;
    for line in data.lines() {
        let v: Vec<f32> = line
            .split_whitespace()
            .map(|x| x.parse().unwrap())
            .collect();
        let s = &scenes[usize::from(v[0] > 0.0)];
        let (ray, diff) = s.camera.generate_ray_differential(&CameraSample {
            film: Vec2::new(v[1], v[2]),
            lens: Vec2::new(0.3, 0.7),
            time: 0.0,
        });
        let diff = diff.scaled(&ray, 1.0 / 4.0);
        let hit = s.intersect(&ray).expect("the ray hits the sphere");
        let mut si = hit.si;
        si.compute_differentials(&diff);
        let world = s.render_from_world.inverse().as_mat4();
        let p = world.transform_point3(si.p);
        let want_p = Vec3::new(v[3], v[4], v[5]);
        assert!((p - want_p).length() < 1e-4, "{line}: p {p}");
        let d = si.diff;
        let got = [
            d.dpdx.x, d.dpdx.y, d.dpdx.z, d.dpdy.x, d.dpdy.y, d.dpdy.z, d.dudx, d.dvdx, d.dudy,
            d.dvdy,
        ];
        for (k, (&g, &w)) in got.iter().zip(&v[6..16]).enumerate() {
            assert!(close(g, w, 2e-3, 2e-6), "{line}: value {k} {g} against {w}");
        }
        // The noise octaves stop at the footprint as pbrt-v3's do.
        let fbm = acr::noise::fbm(p, d.dpdx, d.dpdy, 0.5, 8);
        let turbulence = acr::noise::turbulence(p, d.dpdx, d.dpdy, 0.5, 8);
        assert!(close(fbm, v[16], 1e-3, 1e-4), "{line}: fbm {fbm}");
        assert!(
            close(turbulence, v[17], 1e-3, 1e-4),
            "{line}: turbulence {turbulence}"
        );
        // The checkerboard box-filtered over the footprint: the matte's Kd.
        let material = &s.materials[hit.surface.material.unwrap() as usize];
        let bsdf = material.bsdf(&material.shading(&si));
        let Bxdf::Lambertian { r } = bsdf.lobes()[0].bxdf else {
            panic!("a Lambertian lobe");
        };
        assert!(
            close(r.x, v[18], 2e-3, 2e-3),
            "{line}: checkerboard {} at uv {} with {d:?}",
            r.x,
            si.uv
        );
        checked += 1;
    }
    assert_eq!(checked, 16);
}
