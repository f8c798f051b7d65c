//! Parameter lists: `"type name" value(s)` pairs, typed, located, and remembering lookups.

use crate::error::{Error, Result};
use crate::source::Loc;
use std::fmt;
use std::sync::atomic::{AtomicBool, Ordering};

/// A parameter's declared type. pbrt-v3's synonyms map to one variant each.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ParamType {
    /// `integer`
    Integer,
    /// `float`
    Float,
    /// `point2`
    Point2,
    /// `vector2`
    Vector2,
    /// `point3` or `point`
    Point3,
    /// `vector3` or `vector`
    Vector3,
    /// `normal3` or `normal`
    Normal,
    /// `rgb` or `color`
    Rgb,
    /// `spectrum`: wavelength/value pairs or a file name
    Spectrum,
    /// `blackbody`: temperature (and, in pbrt-v3, a scale)
    Blackbody,
    /// `bool`
    Bool,
    /// `string`
    String,
    /// `texture`: the name of a texture
    Texture,
}

impl ParamType {
    /// The type named in a declaration, or `None` if unknown.
    pub fn from_name(name: &str) -> Option<Self> {
        Some(match name {
            "integer" => Self::Integer,
            "float" => Self::Float,
            "point2" => Self::Point2,
            "vector2" => Self::Vector2,
            "point3" | "point" => Self::Point3,
            "vector3" | "vector" => Self::Vector3,
            "normal3" | "normal" => Self::Normal,
            "rgb" | "color" => Self::Rgb,
            "spectrum" => Self::Spectrum,
            "blackbody" => Self::Blackbody,
            "bool" => Self::Bool,
            "string" => Self::String,
            "texture" => Self::Texture,
            _ => return None,
        })
    }

    /// The canonical name (pbrt-v4's spelling).
    pub fn name(self) -> &'static str {
        match self {
            Self::Integer => "integer",
            Self::Float => "float",
            Self::Point2 => "point2",
            Self::Vector2 => "vector2",
            Self::Point3 => "point3",
            Self::Vector3 => "vector3",
            Self::Normal => "normal",
            Self::Rgb => "rgb",
            Self::Spectrum => "spectrum",
            Self::Blackbody => "blackbody",
            Self::Bool => "bool",
            Self::String => "string",
            Self::Texture => "texture",
        }
    }

    /// How many numbers make one value of this type (1 for non-numeric types).
    pub fn arity(self) -> usize {
        match self {
            Self::Point2 | Self::Vector2 => 2,
            Self::Point3 | Self::Vector3 | Self::Normal | Self::Rgb => 3,
            _ => 1,
        }
    }
}

/// A texture reference, resolved against the textures in scope where it was used.
#[derive(Debug, Clone, PartialEq)]
pub struct TextureRef {
    /// The name as written.
    pub name: String,
    /// Index into `SceneDescription::textures` of the float texture of that name, if any.
    pub float: Option<usize>,
    /// Index of the spectrum (colour) texture of that name, if any.
    pub spectrum: Option<usize>,
}

/// A parameter's values.
#[derive(Debug, Clone, PartialEq)]
pub enum Values {
    /// Integers.
    Ints(Vec<i32>),
    /// Numbers of any float-valued type (float, point, rgb, blackbody, spectrum pairs...).
    Floats(Vec<f64>),
    /// Strings (string, or a spectrum's file name).
    Strings(Vec<String>),
    /// Booleans.
    Bools(Vec<bool>),
    /// A texture reference.
    Texture(TextureRef),
}

impl Values {
    /// Number of scalar values.
    pub fn len(&self) -> usize {
        match self {
            Values::Ints(v) => v.len(),
            Values::Floats(v) => v.len(),
            Values::Strings(v) => v.len(),
            Values::Bools(v) => v.len(),
            Values::Texture(_) => 1,
        }
    }

    /// True when there are no values.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// One parameter of a directive.
#[derive(Debug)]
pub struct Param {
    /// Declared type.
    pub ty: ParamType,
    /// Name, e.g. `fov`.
    pub name: String,
    /// Values.
    pub values: Values,
    /// Where its declaration starts.
    pub loc: Loc,
    used: AtomicBool,
    /// How many values it had before [`Param::keep_head`] dropped all but the first.
    full_len: Option<usize>,
}

/// How many values the scene dump shows of a long parameter.
const SHOWN: usize = 12;

impl Clone for Param {
    fn clone(&self) -> Self {
        Self {
            ty: self.ty,
            name: self.name.clone(),
            values: self.values.clone(),
            loc: self.loc.clone(),
            used: AtomicBool::new(self.was_used()),
            full_len: self.full_len,
        }
    }
}

impl Param {
    /// A parameter, not yet looked up.
    pub fn new(ty: ParamType, name: impl Into<String>, values: Values, loc: Loc) -> Self {
        Self {
            ty,
            name: name.into(),
            values,
            loc,
            used: AtomicBool::new(false),
            full_len: None,
        }
    }

    /// Drops all values but the first few that the scene dump shows, keeping their count, once
    /// the values live elsewhere (a `trianglemesh`'s arrays, in its [`crate::Mesh`]): a long
    /// mesh's numbers were held twice, as f64 here and as f32 there. Lookups then see the
    /// first values alone.
    pub fn keep_head(&mut self) {
        let len = self.values.len();
        if len <= SHOWN {
            return;
        }
        fn head<T>(v: &mut Vec<T>) {
            v.truncate(SHOWN);
            v.shrink_to_fit();
        }
        match &mut self.values {
            Values::Ints(v) => head(v),
            Values::Floats(v) => head(v),
            Values::Strings(v) => head(v),
            Values::Bools(v) => head(v),
            Values::Texture(_) => return,
        }
        self.full_len = Some(len);
    }

    /// Whether anything has looked this parameter up.
    pub fn was_used(&self) -> bool {
        self.used.load(Ordering::Relaxed)
    }

    /// Marks the parameter as looked up.
    pub fn mark_used(&self) {
        self.used.store(true, Ordering::Relaxed);
    }

    fn wrong_type(&self, wanted: &str) -> Error {
        Error::at(
            &self.loc,
            format!(
                "parameter \"{}\" is declared {}, but {wanted} is expected here",
                self.name,
                self.ty.name()
            ),
        )
    }

    fn one<T: Copy>(&self, values: &[T]) -> Result<T> {
        match values {
            [v] => Ok(*v),
            _ => Err(Error::at(
                &self.loc,
                format!(
                    "parameter \"{}\" needs one value, found {}",
                    self.name,
                    values.len()
                ),
            )),
        }
    }
}

/// A directive's parameters, in the order written.
#[derive(Debug, Clone, Default)]
pub struct ParamList {
    params: Vec<Param>,
}

impl ParamList {
    /// An empty list.
    pub fn new() -> Self {
        Self::default()
    }

    /// Adds a parameter; one of the same name already there is replaced (the later wins, as in
    /// pbrt-v3), and the replaced one is returned so the caller can warn.
    pub fn push(&mut self, param: Param) -> Option<Param> {
        if let Some(i) = self.params.iter().position(|p| p.name == param.name) {
            Some(std::mem::replace(&mut self.params[i], param))
        } else {
            self.params.push(param);
            None
        }
    }

    /// All parameters, mutable (to resolve texture references).
    pub(crate) fn iter_mut(&mut self) -> impl Iterator<Item = &mut Param> {
        self.params.iter_mut()
    }

    /// All parameters, in order.
    pub fn iter(&self) -> impl Iterator<Item = &Param> {
        self.params.iter()
    }

    /// Number of parameters.
    pub fn len(&self) -> usize {
        self.params.len()
    }

    /// True when there are none.
    pub fn is_empty(&self) -> bool {
        self.params.is_empty()
    }

    /// The parameter of that name, marked as used.
    pub fn get(&self, name: &str) -> Option<&Param> {
        let p = self.params.iter().find(|p| p.name == name)?;
        p.mark_used();
        Some(p)
    }

    /// Parameters nobody looked up: misspelled or unsupported, worth a warning.
    pub fn unused(&self) -> impl Iterator<Item = &Param> {
        self.params.iter().filter(|p| !p.was_used())
    }

    /// A single float (an integer value is not accepted: pbrt declares types explicitly).
    pub fn float(&self, name: &str) -> Result<Option<f64>> {
        self.get(name)
            .map(|p| p.one(self.float_values(p)?))
            .transpose()
    }

    /// A float with a default.
    pub fn float_or(&self, name: &str, default: f64) -> Result<f64> {
        Ok(self.float(name)?.unwrap_or(default))
    }

    fn float_values<'a>(&self, p: &'a Param) -> Result<&'a [f64]> {
        match (&p.values, p.ty) {
            (Values::Floats(v), ParamType::Float) => Ok(v),
            _ => Err(p.wrong_type("float")),
        }
    }

    /// All values of a float array.
    pub fn floats(&self, name: &str) -> Result<Option<&[f64]>> {
        self.get(name).map(|p| self.float_values(p)).transpose()
    }

    /// A single integer.
    pub fn int(&self, name: &str) -> Result<Option<i32>> {
        self.get(name)
            .map(|p| p.one(Self::int_values(p)?))
            .transpose()
    }

    /// An integer with a default.
    pub fn int_or(&self, name: &str, default: i32) -> Result<i32> {
        Ok(self.int(name)?.unwrap_or(default))
    }

    fn int_values(p: &Param) -> Result<&[i32]> {
        match &p.values {
            Values::Ints(v) => Ok(v),
            _ => Err(p.wrong_type("integer")),
        }
    }

    /// All values of an integer array.
    pub fn ints(&self, name: &str) -> Result<Option<&[i32]>> {
        self.get(name).map(Self::int_values).transpose()
    }

    /// A single boolean.
    pub fn bool(&self, name: &str) -> Result<Option<bool>> {
        self.get(name)
            .map(|p| match &p.values {
                Values::Bools(v) => p.one(v),
                _ => Err(p.wrong_type("bool")),
            })
            .transpose()
    }

    /// A boolean with a default.
    pub fn bool_or(&self, name: &str, default: bool) -> Result<bool> {
        Ok(self.bool(name)?.unwrap_or(default))
    }

    /// A single string.
    pub fn string(&self, name: &str) -> Result<Option<&str>> {
        self.get(name)
            .map(|p| match (&p.values, p.ty) {
                (Values::Strings(v), ParamType::String) => match v.as_slice() {
                    [s] => Ok(s.as_str()),
                    _ => Err(Error::at(
                        &p.loc,
                        format!(
                            "parameter \"{}\" needs one string, found {}",
                            p.name,
                            v.len()
                        ),
                    )),
                },
                _ => Err(p.wrong_type("string")),
            })
            .transpose()
    }

    /// The numbers of a parameter of the given numeric type (point3, normal, rgb...), flat.
    pub fn numbers(&self, name: &str, ty: ParamType) -> Result<Option<&[f64]>> {
        self.get(name)
            .map(|p| match &p.values {
                Values::Floats(v) if p.ty == ty => Ok(v.as_slice()),
                _ => Err(p.wrong_type(ty.name())),
            })
            .transpose()
    }

    /// A single 3-vector of the given type (point3, vector3, normal, rgb).
    pub fn vec3(&self, name: &str, ty: ParamType) -> Result<Option<[f64; 3]>> {
        let Some(v) = self.numbers(name, ty)? else {
            return Ok(None);
        };
        match v {
            [a, b, c] => Ok(Some([*a, *b, *c])),
            _ => {
                let p = self.get(name).map(|p| p.loc.clone());
                Err(match p {
                    Some(loc) => Error::at(
                        &loc,
                        format!(
                            "parameter \"{name}\" needs one {}, found {}",
                            ty.name(),
                            v.len() / 3
                        ),
                    ),
                    None => Error::file("", "internal: parameter vanished"),
                })
            }
        }
    }

    /// A texture reference.
    pub fn texture(&self, name: &str) -> Option<&TextureRef> {
        match &self.get(name)?.values {
            Values::Texture(t) => Some(t),
            _ => None,
        }
    }
}

impl fmt::Display for Param {
    /// `type name = values`, long arrays shortened, for the scene-graph dump.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{} {} = ", self.ty.name(), self.name)?;
        fn list<T>(
            f: &mut fmt::Formatter<'_>,
            v: &[T],
            len: usize,
            show: impl Fn(&T) -> String,
        ) -> fmt::Result {
            if len == 1 {
                return write!(f, "{}", show(&v[0]));
            }
            let items: Vec<String> = v.iter().take(SHOWN).map(show).collect();
            write!(f, "[{}", items.join(" "))?;
            if len > SHOWN {
                write!(f, " ... ({len} values)")?;
            }
            write!(f, "]")
        }
        let len = self.full_len.unwrap_or(self.values.len());
        match &self.values {
            Values::Ints(v) => list(f, v, len, |x| x.to_string()),
            Values::Floats(v) => list(f, v, len, |x| crate::fmt_num(*x)),
            Values::Strings(v) => list(f, v, len, |s| format!("{s:?}")),
            Values::Bools(v) => list(f, v, len, |b| b.to_string()),
            Values::Texture(t) => {
                write!(f, "{:?}", t.name)?;
                if let Some(i) = t.float {
                    write!(f, " (float texture #{i})")?;
                }
                if let Some(i) = t.spectrum {
                    write!(f, " (spectrum texture #{i})")?;
                }
                Ok(())
            }
        }
    }
}
