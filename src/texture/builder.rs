//! Building textures from a scene description, on demand, each once (`TextureBuilder`).

use crate::geometry::Spectrum;
use crate::mipmap::MipMap;
use crate::procedural::NoisePattern;
use acr_parser::{
    Error, Loc, ParamList, Result, SceneDescription, TextureDesc, TextureRef, TextureValue, Values,
    Warning,
};
use glam::{DMat4, Mat4};
use std::collections::{HashMap, HashSet};
use std::fmt::Debug;

use std::path::{Path, PathBuf};
use std::sync::Arc;

use super::source::{read_source, ByteImage, Source};
use super::texels::Quantiser;
use super::*;

/// The texture classes pbrt-v3 has that acr does not implement (pbrt-v3 builds `ptex` only
/// with the Ptex library).
const UNSUPPORTED_CLASSES: [&str; 1] = ["ptex"];
/// The texture classes acr implements.
const CLASSES: [&str; 12] = [
    "constant",
    "scale",
    "mix",
    "checkerboard",
    "imagemap",
    "bilerp",
    "uv",
    "fbm",
    "wrinkled",
    "windy",
    "marble",
    "dots",
];

/// The pattern of a 3D noise texture class from its parameters, with pbrt-v3's defaults.
fn noise_pattern(kind: &str, p: &ParamList) -> Result<NoisePattern> {
    let octaves = || -> Result<u32> {
        let v = p.int_or("octaves", 8)?;
        if !(0..=64).contains(&v) {
            let loc = &p.get("octaves").expect("given").loc;
            return Err(Error::at(
                loc,
                format!("octaves {v} is out of range (0 to 64)"),
            ));
        }
        Ok(v as u32)
    };
    let float = |name: &str, default: f64| -> Result<f32> {
        let v = p.float_or(name, default)?;
        if !v.is_finite() {
            let loc = &p.get(name).expect("given").loc;
            return Err(Error::at(loc, format!("{name} must be finite")));
        }
        Ok(v as f32)
    };
    Ok(match kind {
        "fbm" => NoisePattern::Fbm {
            omega: float("roughness", 0.5)?,
            octaves: octaves()?,
        },
        "wrinkled" => NoisePattern::Wrinkled {
            omega: float("roughness", 0.5)?,
            octaves: octaves()?,
        },
        "windy" => NoisePattern::Windy,
        _ => NoisePattern::Marble {
            omega: float("roughness", 0.5)?,
            octaves: octaves()?,
            scale: float("scale", 1.0)?,
            variation: float("variation", 0.2)?,
        },
    })
}

/// What identifies a converted image map and its MIP map (pbrt-v3's `TexInfo`).
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
struct ImageKey {
    path: PathBuf,
    gamma: bool,
    scale: u32,
    invert: bool,
    wrap: Wrap,
    trilinear: bool,
    max_anisotropy: u32,
}

/// Builds textures on demand from a scene description's texture definitions, each at most once,
/// building each image map's MIP map once; collects warnings (each kind once). A decoded image
/// file is kept only until the next file is read: the MIP maps are what stays.
pub struct TextureBuilder<'a> {
    desc: &'a SceneDescription,
    main_dir: PathBuf,
    pub(super) floats: Vec<Option<Arc<FloatTexture>>>,
    spectra: Vec<Option<Arc<SpectrumTexture>>>,
    /// The image files read so far.
    files: HashSet<PathBuf>,
    /// The last file decoded, for the next map of the same file.
    last_file: Option<(PathBuf, Arc<Source>)>,
    /// Quantisers by their table's bits (most textures share the sRGB one).
    quantisers: HashMap<[u32; 256], Arc<Quantiser>>,
    float_maps: HashMap<ImageKey, Arc<MipMap<f32>>>,
    spectrum_maps: HashMap<ImageKey, Arc<MipMap<Spectrum>>>,
    warned: HashSet<String>,
    warnings: Vec<Warning>,
    /// Render space from world space (see [`crate::scene::Scene::render_from_world`]).
    render_from_world: DMat4,
}

/// Per-value-type access to the builder's caches and parameter lookups.
trait Build: TexValue {
    fn cache<'b>(b: &'b mut TextureBuilder<'_>) -> &'b mut Vec<Option<Arc<Texture<Self>>>>;
    fn maps<'b>(b: &'b mut TextureBuilder<'_>) -> &'b mut HashMap<ImageKey, Arc<MipMap<Self>>>;
    /// The texture of this value type that a `"texture"` parameter names, if there is one.
    fn index(t: &TextureRef) -> Option<usize>;
    /// The parameter as a constant of this value type, if written as one.
    fn value(params: &ParamList, name: &str) -> Result<Option<Self>>;
    /// The value type's name in messages.
    const NAME: &'static str;
    fn kind() -> TextureValue;
}

impl Build for f32 {
    fn cache<'b>(b: &'b mut TextureBuilder<'_>) -> &'b mut Vec<Option<Arc<Texture<Self>>>> {
        &mut b.floats
    }
    fn maps<'b>(b: &'b mut TextureBuilder<'_>) -> &'b mut HashMap<ImageKey, Arc<MipMap<Self>>> {
        &mut b.float_maps
    }
    fn index(t: &TextureRef) -> Option<usize> {
        t.float
    }
    fn value(params: &ParamList, name: &str) -> Result<Option<Self>> {
        float_value(params, name)
    }
    const NAME: &'static str = "float";
    fn kind() -> TextureValue {
        TextureValue::Float
    }
}

impl Build for Spectrum {
    fn cache<'b>(b: &'b mut TextureBuilder<'_>) -> &'b mut Vec<Option<Arc<Texture<Self>>>> {
        &mut b.spectra
    }
    fn maps<'b>(b: &'b mut TextureBuilder<'_>) -> &'b mut HashMap<ImageKey, Arc<MipMap<Self>>> {
        &mut b.spectrum_maps
    }
    fn index(t: &TextureRef) -> Option<usize> {
        t.spectrum
    }
    fn value(params: &ParamList, name: &str) -> Result<Option<Self>> {
        spectrum_value(params, name)
    }
    const NAME: &'static str = "spectrum";
    fn kind() -> TextureValue {
        TextureValue::Spectrum
    }
}

impl<'a> TextureBuilder<'a> {
    /// A file named in the scene at `loc`, found as [`resolve_file`] finds it.
    pub fn resolve_file(&self, name: &str, loc: &Loc) -> PathBuf {
        resolve_file(name, loc, &self.main_dir)
    }

    /// A builder for `desc`'s textures; `main_dir` is the main scene file's directory.
    pub fn new(desc: &'a SceneDescription, main_dir: &Path) -> Self {
        let n = desc.textures.len();
        Self {
            desc,
            main_dir: main_dir.to_path_buf(),
            floats: vec![None; n],
            spectra: vec![None; n],
            files: HashSet::new(),
            last_file: None,
            quantisers: HashMap::new(),
            float_maps: HashMap::new(),
            spectrum_maps: HashMap::new(),
            warned: HashSet::new(),
            warnings: Vec::new(),
            render_from_world: DMat4::IDENTITY,
        }
    }

    /// Places textures in render space (a 3D texture or a planar mapping keeps its world
    /// position on the surface).
    pub fn with_render_from_world(mut self, m: DMat4) -> Self {
        self.render_from_world = m;
        self
    }

    /// The main scene file's directory.
    pub fn main_dir(&self) -> &Path {
        &self.main_dir
    }

    /// Records a warning at `loc` unless one with the same `key` was already given.
    pub fn warn_once(&mut self, key: impl Into<String>, loc: &Loc, message: impl Into<String>) {
        if self.warned.insert(key.into()) {
            self.warnings.push(Warning::at(loc, message));
        }
    }

    /// Number of distinct image files read so far.
    pub fn files_read(&self) -> usize {
        self.files.len()
    }

    /// The warnings collected. Parameters of textures that were never built (no rendering
    /// material uses them) are marked used, so that the unused-parameter report does not list
    /// them.
    pub fn finish(self) -> Vec<Warning> {
        for (i, t) in self.desc.textures.iter().enumerate() {
            if self.floats[i].is_none() && self.spectra[i].is_none() {
                for p in t.plugin.params.iter() {
                    p.mark_used();
                }
            }
        }
        self.warnings
    }

    /// The float texture defined at `desc.textures[index]`.
    pub fn float_texture(&mut self, index: usize) -> Result<Arc<FloatTexture>> {
        self.texture::<f32>(index)
    }

    /// The spectrum texture defined at `desc.textures[index]`.
    pub fn spectrum_texture(&mut self, index: usize) -> Result<Arc<SpectrumTexture>> {
        self.texture::<Spectrum>(index)
    }

    /// A float material parameter as a texture: a `"texture"` reference to a float texture, or
    /// a `float` value; `None` when absent (or of another type, which is left unused).
    pub fn float_param_opt(
        &mut self,
        params: &ParamList,
        name: &str,
    ) -> Result<Option<FloatTexture>> {
        self.param_opt(params, name)
    }

    /// [`TextureBuilder::float_param_opt`] with a default.
    pub fn float_param(
        &mut self,
        params: &ParamList,
        name: &str,
        default: f32,
    ) -> Result<FloatTexture> {
        Ok(self
            .float_param_opt(params, name)?
            .unwrap_or(Texture::Constant(default)))
    }

    /// A colour material parameter as a texture: a `"texture"` reference to a spectrum texture,
    /// or an `rgb`, `spectrum` or `blackbody` value; `None` when absent (or of another type,
    /// which is left unused).
    pub fn spectrum_param_opt(
        &mut self,
        params: &ParamList,
        name: &str,
    ) -> Result<Option<SpectrumTexture>> {
        self.param_opt(params, name)
    }

    /// A material parameter as a texture of value type `T`: a `"texture"` reference to such a
    /// texture, or a constant of that type; `None` when absent (or of another type, which is
    /// left unused).
    fn param_opt<T: Build>(
        &mut self,
        params: &ParamList,
        name: &str,
    ) -> Result<Option<Texture<T>>> {
        let Some(p) = find(params, name) else {
            return Ok(None);
        };
        if let Values::Texture(t) = &p.values {
            p.mark_used();
            return match T::index(t) {
                Some(i) => Ok(Some((*self.texture::<T>(i)?).clone())),
                None => {
                    self.warn_once(
                        format!("texture kind {}", t.name),
                        &p.loc,
                        format!(
                            "\"{}\" is not a {} texture, as parameter \"{name}\" needs; \
                             its default is used",
                            t.name,
                            T::NAME
                        ),
                    );
                    Ok(None)
                }
            };
        }
        Ok(T::value(params, name)?.map(Texture::Constant))
    }

    /// [`TextureBuilder::spectrum_param_opt`] with a default.
    pub fn spectrum_param(
        &mut self,
        params: &ParamList,
        name: &str,
        default: Spectrum,
    ) -> Result<SpectrumTexture> {
        Ok(self
            .spectrum_param_opt(params, name)?
            .unwrap_or(Texture::Constant(default)))
    }

    fn param_or<T: Build>(
        &mut self,
        params: &ParamList,
        name: &str,
        default: T,
    ) -> Result<Arc<Texture<T>>> {
        Ok(Arc::new(
            self.param_opt::<T>(params, name)?
                .unwrap_or(Texture::Constant(default)),
        ))
    }

    /// The 3D textures' mapping from render space, as pbrt-v3 builds it: its
    /// `IdentityMapping3D(tex2world)` takes the texture's transform as the world-to-texture
    /// one, so the texture's CTM is applied to the world point, not its inverse (`Scale 0.5`
    /// before a `Texture` makes a 3D pattern twice as coarse, where a 2D mapping's would be
    /// twice as fine). Kept, so that images match.
    fn texture_from_render_3d(&self, world_from_texture: DMat4) -> Mat4 {
        let m = world_from_texture * self.render_from_world.inverse();
        if m.is_finite() {
            m.as_mat4()
        } else {
            Mat4::IDENTITY
        }
    }

    /// Texture `index` of the scene, of value type `T`: built on first use, then shared.
    fn texture<T: Build>(&mut self, index: usize) -> Result<Arc<Texture<T>>> {
        if let Some(t) = T::cache(self).get(index).cloned().flatten() {
            return Ok(t);
        }
        let desc: &'a SceneDescription = self.desc;
        let Some(td) = desc.textures.get(index) else {
            return Err(Error::file(
                self.main_dir.clone(),
                format!("internal: no texture #{index}"),
            ));
        };
        if td.value != T::kind() {
            return Err(Error::at(
                &td.plugin.loc,
                format!("internal: texture \"{}\" has the wrong value type", td.name),
            ));
        }
        let tex = Arc::new(self.new_texture::<T>(td)?);
        if let Some(slot) = T::cache(self).get_mut(index) {
            *slot = Some(Arc::clone(&tex));
        }
        Ok(tex)
    }

    /// A texture of `td`'s class and parameters.
    fn new_texture<T: Build>(&mut self, td: &TextureDesc) -> Result<Texture<T>> {
        let p = &td.plugin.params;
        let loc = &td.plugin.loc;
        Ok(match td.plugin.kind.as_str() {
            "constant" => Texture::Constant(
                self.param_opt::<T>(p, "value")?
                    .and_then(|t| t.as_constant())
                    .unwrap_or(T::ONE),
            ),
            "scale" => Texture::Scale {
                tex1: self.param_or(p, "tex1", T::ONE)?,
                tex2: self.param_or(p, "tex2", T::ONE)?,
            },
            "mix" => Texture::Mix {
                amount: Arc::new(self.float_param(p, "amount", 0.5)?),
                tex1: self.param_or(p, "tex1", T::ZERO)?,
                tex2: self.param_or(p, "tex2", T::ONE)?,
            },
            "checkerboard" => self.checkerboard(td)?,
            "imagemap" => Texture::Image {
                mapping: self.mapping_2d(td)?,
                image: self.image_map::<T>(p, loc)?,
            },
            "bilerp" => self.bilerp(td)?,
            "uv" if T::kind() == TextureValue::Spectrum => Texture::Uv {
                mapping: self.mapping_2d(td)?,
            },
            "uv" => {
                return Err(Error::at(
                    loc,
                    "the \"uv\" texture is a spectrum texture; pbrt-v3 has no float one",
                ))
            }
            "fbm" | "wrinkled" | "windy" | "marble" => self.noise(td)?,
            // pbrt-v3 hands its "inside" parameter to the texture's outside and "outside" to
            // its dots (`CreateDotsFloatTexture` against the constructor's order): the images
            // people have show it so, and so does acr.
            "dots" => Texture::Dots {
                mapping: self.mapping_2d(td)?,
                inside: self.param_or(p, "outside", T::ZERO)?,
                outside: self.param_or(p, "inside", T::ONE)?,
            },
            other if UNSUPPORTED_CLASSES.contains(&other) => {
                self.warn_once(
                    format!("texture class {other}"),
                    loc,
                    format!(
                        "texture class \"{other}\" is not supported (acr, like a pbrt-v3 built \
                         without the Ptex library, has no Ptex reader); a constant 0.5 is used"
                    ),
                );
                Texture::Constant(T::ONE * 0.5)
            }
            other => {
                let hint = acr_parser::closest(other, CLASSES.iter().copied())
                    .map_or(String::new(), |k| format!(" (did you mean \"{k}\"?)"));
                return Err(Error::at(
                    loc,
                    format!("unknown texture class \"{other}\"{hint}"),
                ));
            }
        })
    }

    /// The 2D mapping of `td`'s parameters, from render space.
    fn mapping_2d(&self, td: &TextureDesc) -> Result<Mapping2D> {
        Mapping2D::from_params(
            &td.plugin.params,
            &(self.render_from_world * td.world_from_texture),
            &td.plugin.loc,
        )
    }

    /// A `checkerboard`: 2D (its antialiasing mode read) or 3D.
    fn checkerboard<T: Build>(&mut self, td: &TextureDesc) -> Result<Texture<T>> {
        let p = &td.plugin.params;
        let loc = &td.plugin.loc;
        let tex1 = self.param_or(p, "tex1", T::ONE)?;
        let tex2 = self.param_or(p, "tex2", T::ZERO)?;
        match p.int_or("dimension", 2)? {
            2 => Ok(Texture::Checkerboard2D {
                mapping: self.mapping_2d(td)?,
                tex1,
                tex2,
                closed_form: self.closed_form(p, loc)?,
            }),
            3 => Ok(Texture::Checkerboard3D {
                texture_from_world: self.texture_from_render_3d(td.world_from_texture),
                tex1,
                tex2,
            }),
            d => {
                let at = p.get("dimension").map_or(loc, |x| &x.loc);
                Err(Error::at(
                    at,
                    format!("{d}-dimensional checkerboard texture is not supported (2 or 3)"),
                ))
            }
        }
    }

    /// Whether a 2D checkerboard is antialiased in closed form (`aamode`): an unknown mode
    /// warns and is closed form, as in pbrt-v3.
    fn closed_form(&mut self, p: &ParamList, loc: &Loc) -> Result<bool> {
        Ok(match p.string("aamode")? {
            Some("none") => false,
            None | Some("closedform") => true,
            Some(other) => {
                let at = p.get("aamode").map_or(loc, |x| &x.loc);
                self.warn_once(
                    format!("aamode {other}"),
                    at,
                    format!(
                        "checkerboard antialiasing mode \"{other}\" is unknown (none or \
                         closedform); closedform is used, as pbrt-v3 does"
                    ),
                );
                true
            }
        })
    }

    /// A `bilerp` between the constants at its four corners.
    fn bilerp<T: Build>(&mut self, td: &TextureDesc) -> Result<Texture<T>> {
        let p = &td.plugin.params;
        let mapping = self.mapping_2d(td)?;
        let mut v = [T::ZERO, T::ONE, T::ZERO, T::ONE];
        for (slot, name) in v.iter_mut().zip(["v00", "v01", "v10", "v11"]) {
            if let Some(c) = self.param_opt::<T>(p, name)?.and_then(|t| t.as_constant()) {
                *slot = c;
            }
        }
        Ok(Texture::Bilerp { mapping, v })
    }

    /// A 3D noise texture (`fbm`, `wrinkled`, `windy`, `marble`; `marble` is a spectrum
    /// texture only).
    fn noise<T: Build>(&mut self, td: &TextureDesc) -> Result<Texture<T>> {
        let kind = td.plugin.kind.as_str();
        if kind == "marble" && T::kind() != TextureValue::Spectrum {
            return Err(Error::at(
                &td.plugin.loc,
                "the \"marble\" texture is a spectrum texture; pbrt-v3 has no float one",
            ));
        }
        Ok(Texture::Noise {
            texture_from_render: self.texture_from_render_3d(td.world_from_texture),
            pattern: noise_pattern(kind, &td.plugin.params)?,
        })
    }

    /// The MIP map an `imagemap` texture's parameters describe, read, converted and built
    /// once.
    fn image_map<T: Build>(&mut self, p: &ParamList, loc: &Loc) -> Result<Arc<MipMap<T>>> {
        let Some(name) = p.string("filename")? else {
            return Err(Error::at(loc, "imagemap texture needs \"string filename\""));
        };
        let at = p.get("filename").map_or(loc, |x| &x.loc).clone();
        let path = resolve_file(name, &at, &self.main_dir);
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .unwrap_or("")
            .to_ascii_lowercase();
        let gamma = p.bool("gamma")?.unwrap_or(ext == "png" || ext == "tga");
        let scale = p.float_or("scale", 1.0)? as f32;
        let invert = p.bool_or("invert", false)?;
        let wrap = match p.string("wrap")?.unwrap_or("repeat") {
            "repeat" => Wrap::Repeat,
            "black" => Wrap::Black,
            "clamp" => Wrap::Clamp,
            other => {
                let wloc = p.get("wrap").map_or(loc, |x| &x.loc).clone();
                self.warn_once(
                    format!("wrap {other}"),
                    &wloc,
                    format!(
                        "unknown wrap mode \"{other}\" (repeat, black or clamp); repeat is used"
                    ),
                );
                Wrap::Repeat
            }
        };
        let trilinear = p.bool_or("trilinear", false)?;
        let max_anisotropy = p.float_or("maxanisotropy", 8.0)? as f32;

        let key_path = std::fs::canonicalize(&path).unwrap_or_else(|_| path.clone());
        let key = ImageKey {
            path: key_path.clone(),
            gamma,
            scale: scale.to_bits(),
            invert,
            wrap,
            trilinear,
            max_anisotropy: max_anisotropy.to_bits(),
        };
        if let Some(m) = T::maps(self).get(&key) {
            return Ok(Arc::clone(m));
        }
        let src = match &self.last_file {
            Some((p, src)) if *p == key_path => Arc::clone(src),
            _ => {
                // The previous file goes first, so that two decoded files never coexist.
                self.last_file = None;
                let src = read_source(&path).map_err(|e| {
                    Error::at(
                        &at,
                        format!("cannot read image \"{}\": {e}", path.display()),
                    )
                })?;
                let src = Arc::new(src);
                self.files.insert(key_path.clone());
                self.last_file = Some((key_path, Arc::clone(&src)));
                src
            }
        };
        let convert = |c| T::from_texel(c, scale, gamma, invert);
        let map = Arc::new(match &*src {
            Source::Values(img) => {
                MipMap::from_image(ImageMap::new(img, wrap, convert), trilinear, max_anisotropy)
            }
            Source::Bytes(img) => byte_mipmap::<T>(
                img,
                convert,
                &mut self.quantisers,
                wrap,
                (trilinear, max_anisotropy),
            ),
        });
        T::maps(self).insert(key, Arc::clone(&map));
        Ok(map)
    }
}

/// The MIP map of an 8-bit image whose pixels `convert` turns into texels: kept in bytes
/// ([`MipMap::from_bytes`]) where a byte's texel value is one table entry (a colour texture, or
/// a grey image; the conversion's table monotone), else in values.
fn byte_mipmap<T: Build>(
    img: &ByteImage,
    convert: impl Fn(Spectrum) -> T,
    quantisers: &mut HashMap<[u32; 256], Arc<Quantiser>>,
    wrap: Wrap,
    (trilinear, max_anisotropy): (bool, f32),
) -> MipMap<T> {
    let unit = img.unit;
    let lut: [f32; 256] = std::array::from_fn(|b| convert(Spectrum::splat(unit[b])).channel(0));
    let per_channel = img.channels == 1 || T::kind() == TextureValue::Spectrum;
    let quantiser = match quantisers.entry(lut.map(f32::to_bits)) {
        std::collections::hash_map::Entry::Occupied(e) => Some(Arc::clone(e.get())),
        std::collections::hash_map::Entry::Vacant(e) => {
            Quantiser::new(&lut).map(|q| Arc::clone(e.insert(Arc::new(q))))
        }
    };
    match quantiser.filter(|_| per_channel) {
        Some(q) => MipMap::from_bytes(img, &lut, &q, wrap, trilinear, max_anisotropy),
        None => MipMap::from_image(
            img.to_map(wrap, |b| convert(img.rgb(b))),
            trilinear,
            max_anisotropy,
        ),
    }
}
