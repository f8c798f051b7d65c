//! pbrt-v3's `MISWeight`: the power heuristic over every strategy that could have made the
//! path, from the ratios of the densities with which each direction of travel makes its
//! vertices ("remapped": a zero density, a specular bounce, counts as 1).
//!
//! Where pbrt-v3 changes the connection vertices' densities in place for the computation
//! (`ScopedAssignment`), this reads them through overrides. One addition: the s = 1 strategy
//! chooses its light at the vertex it connects, as `path` does (the light BVH by default),
//! where a light subpath's origin is chosen once per sample; the ratio of the two choices'
//! densities scales the s = 1 strategy's density (docs/light-transport.md).

use super::vertex::Vertex;
use super::LightChoice;
use crate::scene::Scene;

/// A vertex's densities and delta flag as the strategy sees them.
#[derive(Clone, Copy)]
struct Seen {
    rev: f32,
    fwd: f32,
    delta: bool,
}

impl Seen {
    fn of(v: &Vertex) -> Self {
        Self {
            rev: v.pdf_rev,
            fwd: v.pdf_fwd,
            delta: v.delta,
        }
    }
}

/// 0 counts as 1 (a delta density or one not known).
fn remap0(f: f32) -> f32 {
    if f != 0.0 {
        f
    } else {
        1.0
    }
}

/// The MIS weight of strategy (s, t) for the path `light[..s]` + `camera[..t]`, `sampled` the
/// vertex the strategy sampled itself (the light's for s = 1, the camera's for t = 1).
pub fn mis_weight(
    scene: &Scene,
    light: &[Vertex],
    camera: &[Vertex],
    sampled: Option<&Vertex>,
    s: usize,
    t: usize,
    choice: &LightChoice,
) -> f32 {
    if s + t == 2 {
        return 1.0;
    }
    let qs = match s {
        0 => None,
        1 => sampled,
        _ => light.get(s - 1),
    };
    let pt = match t {
        0 => None,
        1 => sampled,
        _ => camera.get(t - 1),
    };
    let qs_minus = if s > 1 { light.get(s - 2) } else { None };
    let pt_minus = if t > 1 { camera.get(t - 2) } else { None };
    let (Some(pt), true) = (pt, qs.is_some() || pt_minus.is_some()) else {
        return 0.0;
    };
    // The reverse densities of the connection vertices and their predecessors.
    let pt_rev = match (qs, pt_minus) {
        (Some(qs), _) => qs.pdf(scene, qs_minus, pt),
        (None, Some(pm)) => pt.pdf_light_origin(scene, pm, choice),
        _ => 0.0,
    };
    let pt_minus_rev = pt_minus.map(|pm| match qs {
        Some(qs) => pt.pdf(scene, Some(qs), pm),
        None => pt.pdf_light(scene, pm),
    });
    let qs_rev = qs.map(|q| pt.pdf(scene, pt_minus, q));
    let qs_minus_rev = qs_minus.map(|qm| qs.map_or(0.0, |q| q.pdf(scene, Some(pt), qm)));

    let cam = |i: usize| -> Seen {
        let mut v = Seen::of(if i == t - 1 { pt } else { &camera[i] });
        if i == t - 1 {
            v.rev = pt_rev;
            v.delta = false;
        } else if i + 2 == t {
            v.rev = pt_minus_rev.unwrap_or(0.0);
        }
        v
    };
    let lit = |i: usize| -> Seen {
        let q = if i + 1 == s { qs } else { light.get(i) };
        let mut v = q.map_or(
            Seen {
                rev: 0.0,
                fwd: 0.0,
                delta: false,
            },
            Seen::of,
        );
        if i + 1 == s {
            v.rev = qs_rev.unwrap_or(0.0);
            v.delta = false;
        } else if i + 2 == s {
            v.rev = qs_minus_rev.unwrap_or(0.0);
        }
        v
    };
    // The s = 1 strategy's light choice against the origin's: scales its density.
    let c = choice.s1_ratio(scene, light, camera, sampled, s, t);
    let scale = |other: usize| -> f32 {
        let f = |k: usize| if k == 1 { c } else { 1.0 };
        f(other) / f(s)
    };

    let mut sum = 0.0f32;
    let mut ri = 1.0f32;
    for i in (1..t).rev() {
        let v = cam(i);
        ri *= remap0(v.rev) / remap0(v.fwd);
        if !v.delta && !cam(i - 1).delta {
            sum += ri * scale(s + t - i);
        }
    }
    let mut ri = 1.0f32;
    for i in (0..s).rev() {
        let v = lit(i);
        ri *= remap0(v.rev) / remap0(v.fwd);
        let delta_light = if i > 0 {
            lit(i - 1).delta
        } else {
            let v0 = if s == 1 { qs } else { light.first() };
            v0.is_some_and(|v| v.is_delta_light(scene))
        };
        if !v.delta && !delta_light {
            sum += ri * scale(i);
        }
    }
    let w = 1.0 / (1.0 + sum);
    if w.is_finite() {
        w
    } else {
        0.0
    }
}
