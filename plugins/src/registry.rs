//! Plugins by name (after Mitsuba 3's registry): each plugin declares its name, a one-line doc
//! and its parameters (name, type, default, doc), and is created from a parameter list. The
//! scene's `Sampler`, `PixelFilter` and `Integrator` directives and the command line's
//! `--sampler`, `--filter`, `--integrator` and `--set kind.param=value` all go through here.

use acr_parser::{closest, Error, Loc, Param, ParamList, ParamType, Result, SourceFile, Values};
use acr_parser::{PluginDesc, Warning};
use std::fmt;

/// The kinds of plugin.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// Sample points over the rendering space (`Sampler`).
    Sampler,
    /// Reconstruction of the image from the film (`PixelFilter`).
    Filter,
    /// Radiance along a camera ray (`Integrator`).
    Integrator,
}

impl Kind {
    /// The name used on the command line and in `--set KIND.param=value`.
    pub fn name(self) -> &'static str {
        match self {
            Kind::Sampler => "sampler",
            Kind::Filter => "filter",
            Kind::Integrator => "integrator",
        }
    }

    /// The kind a `--set` prefix names.
    pub fn from_name(name: &str) -> Option<Self> {
        Some(match name {
            "sampler" => Kind::Sampler,
            "filter" | "pixelfilter" => Kind::Filter,
            "integrator" => Kind::Integrator,
            _ => return None,
        })
    }
}

impl fmt::Display for Kind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// One declared parameter of a plugin.
#[derive(Clone, Copy, Debug)]
pub struct ParamSpec {
    /// Its name, as written in the scene (`pixelsamples`).
    pub name: &'static str,
    /// Its type (`integer`, `float`, `bool` or `string`).
    pub ty: ParamType,
    /// Its default, as text (`16`, `0.5`, `true`, `all`).
    pub default: &'static str,
    /// What it does, in one line.
    pub doc: &'static str,
}

impl ParamSpec {
    /// A parameter declaration.
    pub const fn new(
        name: &'static str,
        ty: ParamType,
        default: &'static str,
        doc: &'static str,
    ) -> Self {
        Self {
            name,
            ty,
            default,
            doc,
        }
    }
}

/// What a plugin says of itself.
#[derive(Clone, Copy, Debug)]
pub struct PluginInfo {
    /// Its kind.
    pub kind: Kind,
    /// Its name (`sobol`, `gaussian`, `path`).
    pub name: &'static str,
    /// What it is, in one line.
    pub doc: &'static str,
    /// Its parameters.
    pub params: &'static [ParamSpec],
}

/// A registered plugin: its description and the function that builds it.
#[derive(Clone, Copy, Debug)]
pub struct Entry<B> {
    /// Name, doc and parameters.
    pub info: PluginInfo,
    /// Creates the plugin from its checked parameters.
    pub build: B,
}

/// pbrt-v3 names acr maps to the nearest plugin it has, with a warning.
const ALIASES: &[(Kind, &str, &str)] = &[
    (Kind::Sampler, "02sequence", "sobol"),
    (Kind::Sampler, "lowdiscrepancy", "sobol"),
    (Kind::Sampler, "maxmindist", "sobol"),
];

/// Finds the plugin called `name` among `entries` (of kind `kind`). A pbrt-v3 name acr lacks
/// maps to the nearest plugin with a warning; an unknown name is an error at `loc` listing the
/// known names and the closest one.
pub fn lookup<'a, B>(
    entries: &'a [Entry<B>],
    kind: Kind,
    name: &str,
    loc: Option<&Loc>,
    warnings: &mut Vec<Warning>,
) -> Result<&'a Entry<B>> {
    if let Some(e) = entries.iter().find(|e| e.info.name == name) {
        return Ok(e);
    }
    if let Some(&(_, _, to)) = ALIASES.iter().find(|a| a.0 == kind && a.1 == name) {
        if let Some(e) = entries.iter().find(|e| e.info.name == to) {
            let message =
                format!("{kind} \"{name}\" is not implemented; using \"{to}\", the nearest");
            warnings.push(match loc {
                Some(l) => Warning::at(l, message),
                None => Warning { loc: None, message },
            });
            return Ok(e);
        }
    }
    let names: Vec<&str> = entries.iter().map(|e| e.info.name).collect();
    let hint = closest(name, names.iter().copied())
        .map_or(String::new(), |k| format!(" (did you mean \"{k}\"?)"));
    let message = format!(
        "unknown {kind} \"{name}\"{hint}; known: {}",
        names.join(", ")
    );
    Err(match loc {
        Some(l) => Error::at(l, message),
        None => Error::file(format!("--{kind}"), message),
    })
}

/// A plugin choice: its name and parameters, from a scene directive and the command line.
#[derive(Clone, Debug)]
pub struct Choice {
    /// The plugin's name.
    pub name: String,
    /// Its parameters.
    pub params: ParamList,
    /// The directive that chose it, if a scene did and the command line kept its name.
    pub loc: Option<Loc>,
    /// The parameters came from a directive for another plugin, which the command line
    /// replaced: those the chosen plugin does not declare are dropped without a warning.
    pub replaced: bool,
}

impl Choice {
    /// The scene's directive (or `default` without one), overridden by the command line's
    /// name. A different plugin keeps the scene's parameters it declares too (`pixelsamples`
    /// of a `halton` directive still counts with `--sampler sobol`).
    pub fn new(desc: Option<&PluginDesc>, default: &str, cli: Option<&str>) -> Self {
        let mut c = match desc {
            Some(d) => Self {
                name: d.kind.clone(),
                params: d.params.clone(),
                loc: Some(d.loc.clone()),
                replaced: false,
            },
            None => Self {
                name: default.to_owned(),
                params: ParamList::new(),
                loc: None,
                replaced: false,
            },
        };
        if let Some(name) = cli {
            if name != c.name {
                c.name = name.to_owned();
                c.loc = None;
                c.replaced = true;
            }
        }
        c
    }
}

/// Whether a value declared `given` may stand where `wanted` is declared.
fn type_fits(wanted: ParamType, given: ParamType) -> bool {
    wanted == given
}

/// Checks `params` against the plugin's declarations: a declared parameter of another type is
/// an error at its location; an undeclared one gets a warning naming the closest declared name
/// (or is dropped quietly when the parameters belonged to a replaced plugin).
pub fn check_params(info: &PluginInfo, choice: &Choice, warnings: &mut Vec<Warning>) -> Result<()> {
    for p in choice.params.iter() {
        match info.params.iter().find(|s| s.name == p.name) {
            Some(spec) if !type_fits(spec.ty, p.ty) => {
                return Err(Error::at(
                    &p.loc,
                    format!(
                        "parameter \"{}\" of {} \"{}\" is {}, not {}",
                        p.name,
                        info.kind,
                        info.name,
                        spec.ty.name(),
                        p.ty.name()
                    ),
                ));
            }
            Some(_) => {}
            None => {
                p.mark_used();
                if !choice.replaced {
                    warnings.push(Warning::at(&p.loc, unknown_param_message(info, &p.name)));
                }
            }
        }
    }
    Ok(())
}

fn unknown_param_message(info: &PluginInfo, name: &str) -> String {
    let names = info.params.iter().map(|s| s.name);
    let hint =
        closest(name, names.clone()).map_or(String::new(), |k| format!(" (did you mean \"{k}\"?)"));
    let known: Vec<&str> = names.collect();
    format!(
        "{} \"{}\" has no parameter \"{name}\"{hint}; it has: {}",
        info.kind,
        info.name,
        if known.is_empty() {
            "none".to_owned()
        } else {
            known.join(", ")
        }
    )
}

/// One `--set KIND.PARAM=VALUE` from the command line, split but not yet typed.
#[derive(Clone, Debug)]
pub struct Setting {
    /// The plugin kind it addresses.
    pub kind: Kind,
    /// The parameter's name.
    pub param: String,
    /// The value as written.
    pub value: String,
    /// The whole argument, as a one-line source so that errors can point into it.
    source: std::sync::Arc<SourceFile>,
}

impl Setting {
    /// Parses `KIND.PARAM=VALUE` (`sampler.omega=0.5`).
    pub fn parse(arg: &str) -> Result<Self> {
        let source = SourceFile::new("--set", arg);
        let at = |offset: usize, message: String| Error::at(&Loc::new(&source, offset), message);
        let (lhs, value) = arg.split_once('=').ok_or_else(|| {
            at(
                0,
                format!("\"{arg}\" is not KIND.PARAM=VALUE (e.g. sampler.pixelsamples=16)"),
            )
        })?;
        let (kind, param) = lhs.split_once('.').ok_or_else(|| {
            at(
                0,
                format!("\"{lhs}\" is not KIND.PARAM (KIND is sampler, filter or integrator)"),
            )
        })?;
        let kind = Kind::from_name(kind).ok_or_else(|| {
            at(
                0,
                format!("unknown plugin kind \"{kind}\"; known: sampler, filter, integrator"),
            )
        })?;
        if param.is_empty() {
            return Err(at(lhs.len(), "the parameter name is empty".to_owned()));
        }
        Ok(Self {
            kind,
            param: param.to_owned(),
            value: value.to_owned(),
            source,
        })
    }

    /// Adds the setting to `choice`'s parameters (replacing one of the same name), typed as
    /// the plugin declares it: an unknown name or a value of the wrong type is an error.
    pub fn apply(&self, info: &PluginInfo, choice: &mut Choice) -> Result<()> {
        let name_loc = Loc::new(&self.source, self.kind.name().len() + 1);
        let value_loc = Loc::new(&self.source, self.source.len() - self.value.len());
        let spec = info
            .params
            .iter()
            .find(|s| s.name == self.param)
            .ok_or_else(|| Error::at(&name_loc, unknown_param_message(info, &self.param)))?;
        let v = self.value.trim();
        let bad = |what: &str| {
            Error::at(
                &value_loc,
                format!(
                    "\"{v}\" is not {what}, as {} \"{}\" parameter \"{}\" needs",
                    info.kind, info.name, spec.name
                ),
            )
        };
        let values = match spec.ty {
            ParamType::Integer => Values::Ints(vec![v.parse().map_err(|_| bad("an integer"))?]),
            ParamType::Float => {
                let x: f64 = v.parse().map_err(|_| bad("a number"))?;
                if !x.is_finite() {
                    return Err(bad("a finite number"));
                }
                Values::Floats(vec![x])
            }
            ParamType::Bool => Values::Bools(vec![match v {
                "true" => true,
                "false" => false,
                _ => return Err(bad("true or false")),
            }]),
            ParamType::String => Values::Strings(vec![v.to_owned()]),
            other => {
                return Err(bad(&format!(
                    "settable from the command line ({})",
                    other.name()
                )))
            }
        };
        choice
            .params
            .push(Param::new(spec.ty, spec.name, values, name_loc));
        Ok(())
    }
}

/// An error with `message` at the first of the parameters `names` that is given, or, when none
/// is, in `context` (what chose the values: `--spp`, the plugin).
pub(crate) fn error_at_param(
    params: &ParamList,
    names: &[&str],
    context: &str,
    message: impl Into<String>,
) -> Error {
    match names.iter().find_map(|n| params.get(n)) {
        Some(p) => Error::at(&p.loc, message),
        None => Error::file(context, message),
    }
}

/// A float parameter that must lie in `range`, or an error at its location.
pub(crate) fn float_in(
    params: &ParamList,
    name: &str,
    default: f64,
    range: std::ops::RangeInclusive<f64>,
) -> Result<f64> {
    let v = params.float_or(name, default)?;
    in_range(params, name, v, range)
}

/// A string parameter that must be one of `options` (the first when absent): its index, or an
/// error at its location naming the options.
pub(crate) fn one_of(params: &ParamList, name: &str, options: &[&str]) -> Result<usize> {
    let Some(v) = params.string(name)? else {
        return Ok(0);
    };
    options.iter().position(|o| *o == v).ok_or_else(|| {
        let loc = &params.get(name).expect("given").loc;
        Error::at(
            loc,
            format!("{name} \"{v}\" is not known ({})", options.join(" or ")),
        )
    })
}

/// An integer parameter that must lie in `range`, or an error at its location.
pub(crate) fn int_in(
    params: &ParamList,
    name: &str,
    default: i32,
    range: std::ops::RangeInclusive<i64>,
) -> Result<u32> {
    let v = i64::from(params.int_or(name, default)?);
    in_range(params, name, v, range).map(|v| v as u32)
}

/// `v`, the value of parameter `name`, if within `range`; else an error at its location.
fn in_range<T: PartialOrd + fmt::Display>(
    params: &ParamList,
    name: &str,
    v: T,
    range: std::ops::RangeInclusive<T>,
) -> Result<T> {
    if range.contains(&v) {
        return Ok(v);
    }
    let p = params.get(name).expect("a default lies in range");
    Err(Error::at(
        &p.loc,
        format!(
            "{name} {v} is out of range ({} to {})",
            range.start(),
            range.end()
        ),
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    const SPECS: &[ParamSpec] = &[
        ParamSpec::new(
            "pixelsamples",
            ParamType::Integer,
            "16",
            "samples per pixel",
        ),
        ParamSpec::new("omega", ParamType::Float, "0.7", "strictness"),
        ParamSpec::new("jitter", ParamType::Bool, "true", "jitter"),
    ];
    const INFO: PluginInfo = PluginInfo {
        kind: Kind::Sampler,
        name: "test",
        doc: "a test plugin",
        params: SPECS,
    };
    const ENTRIES: &[Entry<()>] = &[
        Entry {
            info: INFO,
            build: (),
        },
        Entry {
            info: PluginInfo {
                name: "sobol",
                ..INFO
            },
            build: (),
        },
    ];

    #[test]
    fn lookup_finds_maps_and_suggests() {
        let mut w = Vec::new();
        assert_eq!(
            lookup(ENTRIES, Kind::Sampler, "sobol", None, &mut w)
                .unwrap()
                .info
                .name,
            "sobol"
        );
        assert!(w.is_empty());
        let e = lookup(ENTRIES, Kind::Sampler, "02sequence", None, &mut w).unwrap();
        assert_eq!(e.info.name, "sobol");
        assert_eq!(w.len(), 1);
        assert!(w[0].message.contains("02sequence"), "{}", w[0].message);
        let err = lookup(ENTRIES, Kind::Sampler, "sobl", None, &mut w)
            .unwrap_err()
            .to_string();
        assert!(err.contains("unknown sampler \"sobl\""), "{err}");
        assert!(err.contains("did you mean \"sobol\""), "{err}");
        assert!(err.contains("known: test, sobol"), "{err}");
    }

    #[test]
    fn settings_are_typed_and_checked() {
        let mut c = Choice::new(None, "test", None);
        Setting::parse("sampler.omega=0.25")
            .unwrap()
            .apply(&INFO, &mut c)
            .unwrap();
        assert_eq!(c.params.float_or("omega", 0.7).unwrap(), 0.25);
        Setting::parse("sampler.pixelsamples=8")
            .unwrap()
            .apply(&INFO, &mut c)
            .unwrap();
        assert_eq!(c.params.int_or("pixelsamples", 16).unwrap(), 8);
        let bad = Setting::parse("sampler.pixelsamples=eight")
            .unwrap()
            .apply(&INFO, &mut c)
            .unwrap_err()
            .to_string();
        assert!(bad.starts_with("--set:1:22:"), "{bad}");
        assert!(bad.contains("not an integer"), "{bad}");
        let unknown = Setting::parse("sampler.omegaa=1")
            .unwrap()
            .apply(&INFO, &mut c)
            .unwrap_err()
            .to_string();
        assert!(unknown.starts_with("--set:1:9:"), "{unknown}");
        assert!(unknown.contains("did you mean \"omega\""), "{unknown}");
        for arg in ["sampler", "sampler=1", "camera.fov=3", "sampler.=1"] {
            assert!(Setting::parse(arg).is_err(), "{arg}");
        }
    }

    #[test]
    fn check_params_rejects_wrong_types_and_warns_on_unknown() {
        let text = "Sampler \"test\" \"float pixelsamples\" 4 \"integer pixelsampels\" 4";
        let desc = acr_parser::parse_str(text, std::path::Path::new("t.pbrt")).unwrap();
        let d = desc.sampler.as_ref().unwrap();
        let err = check_params(&INFO, &Choice::new(Some(d), "x", None), &mut Vec::new())
            .unwrap_err()
            .to_string();
        assert!(err.starts_with("t.pbrt:1:16:"), "{err}");
        assert!(err.contains("is integer, not float"), "{err}");

        let text = "Sampler \"test\" \"integer pixelsampels\" 4";
        let desc = acr_parser::parse_str(text, std::path::Path::new("t.pbrt")).unwrap();
        let d = desc.sampler.as_ref().unwrap();
        let mut w = Vec::new();
        check_params(&INFO, &Choice::new(Some(d), "x", None), &mut w).unwrap();
        assert_eq!(w.len(), 1);
        assert!(w[0].message.contains("did you mean \"pixelsamples\""));
        // Replaced by the command line: the old plugin's parameters go quietly.
        let mut w = Vec::new();
        let c = Choice::new(Some(d), "x", Some("sobol"));
        assert!(c.replaced);
        check_params(&INFO, &c, &mut w).unwrap();
        assert!(w.is_empty());
    }
}
