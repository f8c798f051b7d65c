//! Media from their `MakeNamedMedium` descriptions, checked as docs/media.md says: pbrt-v3's
//! parameters and defaults (`MakeMedium` in src/core/api.cpp), with located errors where
//! pbrt-v3 would render nonsense or a different image silently.

use super::{Grid, HenyeyGreenstein, Homogeneous, Medium, MediumKind};
use crate::geometry::Spectrum;
use acr_parser::{Error, Loc, MediumDesc, ParamList, ParamType, Result, Warning};
use glam::{DMat4, DVec3};

/// The medium types pbrt-v3 knows.
const KINDS: [&str; 2] = ["homogeneous", "heterogeneous"];

/// Where parameter `name` was written, or the directive.
fn loc_of<'a>(params: &'a ParamList, name: &str, directive: &'a Loc) -> &'a Loc {
    params.get(name).map_or(directive, |p| &p.loc)
}

/// Every medium of the scene, in render space (`render_from_world`), in definition order.
pub fn build_media(
    media: &[MediumDesc],
    render_from_world: DMat4,
    warnings: &mut Vec<Warning>,
) -> Result<Vec<Medium>> {
    media
        .iter()
        .map(|m| build_medium(m, render_from_world, warnings))
        .collect()
}

/// sigma_a and sigma_s: the preset's (or pbrt-v3's defaults, whole milk's), overridden by the
/// parameters, times `scale`; every value finite and not negative.
fn coefficients(m: &MediumDesc, warnings: &mut Vec<Warning>) -> Result<(Spectrum, Spectrum)> {
    let (params, loc) = (&m.plugin.params, &m.plugin.loc);
    let mut sigma_a = Spectrum::new(0.0011, 0.0024, 0.014);
    let mut sigma_s = Spectrum::new(2.55, 3.21, 3.77);
    if let Some(preset) = params.string("preset")?.filter(|p| !p.is_empty()) {
        match super::presets::lookup(preset) {
            Some((a, s)) => (sigma_a, sigma_s) = (a, s),
            None => {
                let hint = acr_parser::closest(preset, super::presets::names())
                    .map_or(String::new(), |k| format!(" (did you mean \"{k}\"?)"));
                warnings.push(Warning::at(
                    loc_of(params, "preset", loc),
                    format!(
                        "medium preset \"{preset}\" is not in pbrt-v3's table{hint}; its default \
                         coefficients are used, as pbrt-v3 does"
                    ),
                ));
            }
        }
    }
    let scale = params.float_or("scale", 1.0)? as f32;
    let g_ok = |v: Spectrum| v.is_finite() && v.min_element() >= 0.0;
    let mut out = [Spectrum::ZERO; 2];
    for (i, (name, default)) in [("sigma_a", sigma_a), ("sigma_s", sigma_s)]
        .into_iter()
        .enumerate()
    {
        let v = crate::texture::spectrum_value(params, name)?.unwrap_or(default) * scale;
        if !g_ok(v) {
            let at = if params.get(name).is_some() {
                loc_of(params, name, loc)
            } else {
                loc_of(params, "scale", loc)
            };
            return Err(Error::at(
                at,
                format!(
                    "medium \"{}\": {name} ({}, {}, {}) after scale {scale} must be finite and \
                     not negative",
                    m.name, v.x, v.y, v.z
                ),
            ));
        }
        out[i] = v;
    }
    Ok((out[0], out[1]))
}

/// One medium.
fn build_medium(
    m: &MediumDesc,
    render_from_world: DMat4,
    warnings: &mut Vec<Warning>,
) -> Result<Medium> {
    let (params, loc) = (&m.plugin.params, &m.plugin.loc);
    let kind = m.plugin.kind.as_str();
    if !KINDS.contains(&kind) {
        let hint = acr_parser::closest(kind, KINDS)
            .map_or(String::new(), |k| format!(" (did you mean \"{k}\"?)"));
        return Err(Error::at(
            loc_of(params, "type", loc),
            format!(
                "MakeNamedMedium \"{}\": unknown medium type \"{kind}\"{hint}",
                m.name
            ),
        ));
    }
    let (sigma_a, sigma_s) = coefficients(m, warnings)?;
    let g = params.float_or("g", 0.0)? as f32;
    if g.is_nan() || g.abs() >= 1.0 {
        return Err(Error::at(
            loc_of(params, "g", loc),
            format!(
                "medium \"{}\": g {g} must lie strictly between -1 and 1",
                m.name
            ),
        ));
    }
    let phase = HenyeyGreenstein { g };
    if kind == "homogeneous" {
        return Ok(Medium {
            kind: MediumKind::Homogeneous(Homogeneous::new(sigma_a, sigma_s)),
            phase,
        });
    }
    let grid = grid(m, sigma_a, sigma_s, render_from_world, warnings)?;
    Ok(Medium {
        kind: MediumKind::Grid(Box::new(grid)),
        phase,
    })
}

/// `heterogeneous`: the density grid, its count checked against nx * ny * nz, placed in the
/// box p0..p1 of the medium's space.
fn grid(
    m: &MediumDesc,
    sigma_a: Spectrum,
    sigma_s: Spectrum,
    render_from_world: DMat4,
    warnings: &mut Vec<Warning>,
) -> Result<Grid> {
    let (params, loc) = (&m.plugin.params, &m.plugin.loc);
    let name = &m.name;
    let mut n = [0usize; 3];
    for (i, axis) in ["nx", "ny", "nz"].into_iter().enumerate() {
        let v = params.int_or(axis, 1)?;
        n[i] = usize::try_from(v).ok().filter(|&v| v > 0).ok_or_else(|| {
            Error::at(
                loc_of(params, axis, loc),
                format!("medium \"{name}\": {axis} {v} must be at least 1"),
            )
        })?;
    }
    let Some(values) = params.floats("density")? else {
        return Err(Error::at(
            loc,
            format!("heterogeneous medium \"{name}\" needs a \"float density\" parameter"),
        ));
    };
    let dloc = loc_of(params, "density", loc);
    let expected = n[0].checked_mul(n[1]).and_then(|v| v.checked_mul(n[2]));
    if expected != Some(values.len()) {
        return Err(Error::at(
            dloc,
            format!(
                "medium \"{name}\": {} density values, but nx * ny * nz = {} * {} * {} = {}",
                values.len(),
                n[0],
                n[1],
                n[2],
                expected.map_or("more than can be held".to_owned(), |e| e.to_string())
            ),
        ));
    }
    let mut density = Vec::with_capacity(values.len());
    for (i, &v) in values.iter().enumerate() {
        let f = v as f32;
        if !f.is_finite() || f < 0.0 {
            return Err(Error::at(
                dloc,
                format!("medium \"{name}\": density value {i} is {v}; densities must be finite and not negative"),
            ));
        }
        density.push(f);
    }
    let p0 = params.vec3("p0", ParamType::Point3)?.unwrap_or([0.0; 3]);
    let p1 = params.vec3("p1", ParamType::Point3)?.unwrap_or([1.0; 3]);
    let (p0, p1) = (DVec3::from_array(p0), DVec3::from_array(p1));
    if !(p0.is_finite() && p1.is_finite() && p1.cmpgt(p0).all()) {
        return Err(Error::at(
            loc_of(params, "p1", loc),
            format!("medium \"{name}\": the box p0 {p0} .. p1 {p1} must be finite and p1 > p0 on every axis"),
        ));
    }
    let sigma_t = sigma_a + sigma_s;
    if sigma_t.x != sigma_t.y || sigma_t.x != sigma_t.z {
        warnings.push(Warning::at(
            loc,
            format!(
                "heterogeneous medium \"{name}\": sigma_a + sigma_s ({}, {}, {}) is not the same \
                 in every channel; its first is used, as pbrt-v3 does",
                sigma_t.x, sigma_t.y, sigma_t.z
            ),
        ));
    }
    let data_from_unit = DMat4::from_translation(p0) * DMat4::from_scale(p1 - p0);
    let render_from_grid = render_from_world * m.world_from_medium * data_from_unit;
    Ok(Grid::new(
        sigma_s,
        sigma_t.x,
        n,
        density,
        render_from_grid.as_mat4(),
    ))
}
