//! Directives from tokens: reads each directive's arguments and parameter list and hands them to
//! the [`Builder`]. Include files are a stack of tokenizers, so nothing here recurses.

use crate::builder::Builder;
use crate::error::{Error, Result};
use crate::lexer::{Token, TokenKind, Tokenizer};
use crate::params::{Param, ParamList, ParamType, TextureRef, Values};
use crate::paths::{io_message, resolve_path};
use crate::scene::SceneDescription;
use crate::source::{Loc, SourceFile};
use crate::suggest::did_you_mean;
use glam::{DMat4, DVec3};
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Deepest `Include` nesting accepted; deeper is almost surely a file including itself.
pub const MAX_INCLUDE_DEPTH: usize = 64;

/// Every directive of the pbrt-v3 subset, for the "did you mean" hint.
pub const DIRECTIVES: &[&str] = &[
    "Identity",
    "Translate",
    "Scale",
    "Rotate",
    "LookAt",
    "CoordinateSystem",
    "CoordSysTransform",
    "Transform",
    "ConcatTransform",
    "TransformTimes",
    "ActiveTransform",
    "ReverseOrientation",
    "Camera",
    "Sampler",
    "Film",
    "PixelFilter",
    "Integrator",
    "Accelerator",
    "WorldBegin",
    "WorldEnd",
    "AttributeBegin",
    "AttributeEnd",
    "TransformBegin",
    "TransformEnd",
    "ObjectBegin",
    "ObjectEnd",
    "ObjectInstance",
    "Shape",
    "Material",
    "MakeNamedMaterial",
    "NamedMaterial",
    "Texture",
    "LightSource",
    "AreaLightSource",
    "Include",
    "MakeNamedMedium",
    "MediumInterface",
];

/// Parses the scene file at `path` and every file it includes.
pub fn parse_file(path: &Path) -> Result<SceneDescription> {
    let text = read_text(path)?;
    parse_source(SourceFile::read_from(path, text))
}

/// Parses scene text as if it were the file at `path` (used for relative names and messages).
pub fn parse_str(text: &str, path: &Path) -> Result<SceneDescription> {
    parse_source(SourceFile::new(path, text))
}

fn parse_source(file: Arc<SourceFile>) -> Result<SceneDescription> {
    let mut parser = Parser {
        base_dir: file.dir().to_path_buf(),
        builder: Builder::new(Arc::clone(&file)),
        stack: vec![Tokenizer::new(file)],
        peeked: None,
    };
    parser.run()?;
    Ok(parser.builder.finish())
}

/// Reads a scene file, mapping I/O and encoding errors to a clear message.
fn read_text(path: &Path) -> Result<String> {
    let bytes = crate::source::read_file(path, crate::source::FileKind::Scene)
        .map_err(|e| Error::file(path, io_message(&e)))?;
    decode_text(path, bytes)
}

/// The text of a scene file's bytes; invalid UTF-8 is an error at its line and column.
fn decode_text(path: &Path, bytes: Vec<u8>) -> Result<String> {
    String::from_utf8(bytes).map_err(|e| {
        let at = e.utf8_error().valid_up_to();
        let bytes = e.into_bytes();
        let byte = bytes.get(at).copied().unwrap_or(0);
        let message = format!("not a text file: byte 0x{byte:02x} at offset {at} is not UTF-8");
        let file = SourceFile::new(path, String::from_utf8_lossy(&bytes).into_owned());
        Error::at(&Loc::new(&file, at), message)
    })
}

fn describe(kind: &TokenKind) -> String {
    match kind {
        TokenKind::Word(w) => format!("'{w}'"),
        TokenKind::Str(s) => format!("string \"{s}\""),
        TokenKind::Number(n) => format!("number {n}"),
        TokenKind::Open => "'['".to_owned(),
        TokenKind::Close => "']'".to_owned(),
    }
}

struct Parser {
    base_dir: PathBuf,
    builder: Builder,
    /// The include stack: the file being read is the last.
    stack: Vec<Tokenizer>,
    /// A token read ahead from the file on top of the stack.
    peeked: Option<Token>,
}

impl Parser {
    fn file(&self) -> &Arc<SourceFile> {
        // The stack is never empty while directives are being read.
        self.stack
            .last()
            .map(Tokenizer::file)
            .unwrap_or_else(|| self.builder.main_file())
    }

    fn loc(&self, offset: usize) -> Loc {
        Loc::new(self.file(), offset)
    }

    fn peek(&mut self) -> Result<Option<&Token>> {
        if self.peeked.is_none() {
            self.peeked = self.read()?;
        }
        Ok(self.peeked.as_ref())
    }

    /// The next token; `None` at the end of the main file.
    fn next(&mut self) -> Result<Option<Token>> {
        match self.peeked.take() {
            Some(t) => Ok(Some(t)),
            None => self.read(),
        }
    }

    /// The next token of the file on top of the stack; at the end of an included file, the
    /// next of the file that included it, even inside a directive: pbrt-v3's tokenizer stack
    /// (its parser.cpp), where the tokens after an `Include` continue the parameter list of
    /// the included file's last directive. The main file stays on the stack, so every token's
    /// offset is in [`Parser::file`] when it is read.
    fn read(&mut self) -> Result<Option<Token>> {
        while let Some(t) = self.stack.last_mut() {
            if let Some(tok) = t.next_token()? {
                return Ok(Some(tok));
            }
            if self.stack.len() == 1 {
                break;
            }
            self.stack.pop();
        }
        Ok(None)
    }

    fn run(&mut self) -> Result<()> {
        while let Some(tok) = self.next()? {
            let loc = self.loc(tok.offset);
            match tok.kind {
                TokenKind::Word(w) => self.directive(&w, loc)?,
                other => {
                    return Err(Error::at(
                        &loc,
                        format!("expected a directive, found {}", describe(&other)),
                    ))
                }
            }
        }
        self.builder.end_of_input(&self.end_loc_of_main());
        Ok(())
    }

    fn end_loc_of_main(&self) -> Loc {
        let file = self.builder.main_file();
        Loc::new(file, file.len())
    }

    fn directive(&mut self, name: &str, loc: Loc) -> Result<()> {
        self.builder.check_after_world_end(name, &loc)?;
        let b = &mut self.builder;
        match name {
            "Identity" => {
                b.set_transform(DMat4::IDENTITY);
                Ok(())
            }
            "Translate" => {
                let v = self.numbers::<3>(name, &loc)?;
                self.builder
                    .concat(crate::transform::translate(DVec3::from(v)));
                Ok(())
            }
            "Scale" => {
                let v = self.numbers::<3>(name, &loc)?;
                self.builder.concat(crate::transform::scale(DVec3::from(v)));
                Ok(())
            }
            "Rotate" => {
                let [angle, x, y, z] = self.numbers::<4>(name, &loc)?;
                let m = crate::transform::rotate(angle, DVec3::new(x, y, z))
                    .ok_or_else(|| Error::at(&loc, "Rotate about a zero-length axis"))?;
                self.builder.concat(m);
                Ok(())
            }
            "LookAt" => {
                let v = self.numbers::<9>(name, &loc)?;
                let m = crate::transform::look_at(
                    DVec3::new(v[0], v[1], v[2]),
                    DVec3::new(v[3], v[4], v[5]),
                    DVec3::new(v[6], v[7], v[8]),
                )
                .ok_or_else(|| {
                    Error::at(
                        &loc,
                        "LookAt: the eye and the target coincide, or the up vector is parallel \
                         to the viewing direction",
                    )
                })?;
                self.builder.concat(m);
                Ok(())
            }
            "Transform" => {
                let v = self.numbers::<16>(name, &loc)?;
                self.builder.set_transform(DMat4::from_cols_array(&v));
                Ok(())
            }
            "ConcatTransform" => {
                let v = self.numbers::<16>(name, &loc)?;
                self.builder.concat(DMat4::from_cols_array(&v));
                Ok(())
            }
            "CoordinateSystem" => {
                let s = self.string_arg(name, &loc)?;
                self.builder.coordinate_system(s);
                Ok(())
            }
            "CoordSysTransform" => {
                let s = self.string_arg(name, &loc)?;
                self.builder.coord_sys_transform(&s, &loc)
            }
            "TransformTimes" => {
                let [a, b] = self.numbers::<2>(name, &loc)?;
                self.builder.transform_times(a, b, &loc)
            }
            "ActiveTransform" => {
                let which = match self.next()? {
                    Some(Token {
                        kind: TokenKind::Word(w),
                        ..
                    }) => w,
                    _ => {
                        return Err(Error::at(
                            &loc,
                            "ActiveTransform needs StartTime, EndTime or All",
                        ))
                    }
                };
                self.builder.active_transform(&which, &loc)
            }
            "ReverseOrientation" => b.reverse_orientation(&loc),
            "WorldBegin" => b.world_begin(&loc),
            "WorldEnd" => b.world_end(&loc),
            "AttributeBegin" => b.attribute_begin(&loc),
            "AttributeEnd" => b.attribute_end(&loc),
            "TransformBegin" => b.transform_begin(&loc),
            "TransformEnd" => b.transform_end(&loc),
            "ObjectEnd" => b.object_end(&loc),
            "ObjectBegin" => {
                let s = self.string_arg(name, &loc)?;
                self.builder.object_begin(s, &loc)
            }
            "ObjectInstance" => {
                let s = self.string_arg(name, &loc)?;
                self.builder.object_instance(&s, &loc)
            }
            "NamedMaterial" => {
                let s = self.string_arg(name, &loc)?;
                self.builder.named_material(&s, &loc)
            }
            "Camera" | "Sampler" | "Film" | "PixelFilter" | "Integrator" | "Accelerator"
            | "Shape" | "Material" | "LightSource" | "AreaLightSource" | "MakeNamedMaterial"
            | "MakeNamedMedium" => {
                let arg = self.string_arg(name, &loc)?;
                let params = self.params()?;
                self.builder.plugin_directive(name, arg, params, loc)
            }
            "Texture" => {
                let tex_name = self.string_arg(name, &loc)?;
                let value = self.string_arg(name, &loc)?;
                let class = self.string_arg(name, &loc)?;
                let params = self.params()?;
                self.builder.texture(tex_name, &value, class, params, loc)
            }
            "MediumInterface" => {
                // One name stands for both sides, as in pbrt-v3's parser.
                let inside = self.string_arg(name, &loc)?;
                let outside = if matches!(
                    self.peek()?,
                    Some(Token {
                        kind: TokenKind::Str(_),
                        ..
                    })
                ) {
                    self.string_arg(name, &loc)?
                } else {
                    inside.clone()
                };
                self.builder.medium_interface(&inside, &outside, &loc)
            }
            "Include" => {
                let s = self.string_arg(name, &loc)?;
                self.include(&s, &loc)
            }
            _ => Err(Error::at(
                &loc,
                format!(
                    "unknown directive '{name}'{}",
                    did_you_mean(name, DIRECTIVES.iter().copied())
                ),
            )),
        }
    }

    fn include(&mut self, name: &str, loc: &Loc) -> Result<()> {
        if self.stack.len() > MAX_INCLUDE_DEPTH {
            return Err(Error::at(
                loc,
                format!(
                    "Include nested more than {MAX_INCLUDE_DEPTH} deep (does a file include itself?)"
                ),
            ));
        }
        let path = resolve_path(name, self.file(), &self.base_dir);
        let bytes =
            crate::source::read_file(&path, crate::source::FileKind::Scene).map_err(|e| {
                Error::at(
                    loc,
                    format!("cannot read included file \"{name}\": {}", io_message(&e)),
                )
            })?;
        let text = decode_text(&path, bytes)?;
        let file = SourceFile::read_from(path, text);
        self.builder.add_file(Arc::clone(&file));
        self.stack.push(Tokenizer::new(file));
        Ok(())
    }

    /// A directive's string argument.
    fn string_arg(&mut self, directive: &str, loc: &Loc) -> Result<String> {
        match self.next()? {
            Some(Token {
                kind: TokenKind::Str(s),
                ..
            }) => Ok(s),
            Some(t) => Err(Error::at(
                &self.loc(t.offset),
                format!(
                    "{directive} expects a quoted string here, found {}",
                    describe(&t.kind)
                ),
            )),
            None => Err(Error::at(
                loc,
                format!("{directive} expects a quoted string, but the file ends"),
            )),
        }
    }

    /// Exactly `N` numbers, with or without brackets around them.
    fn numbers<const N: usize>(&mut self, directive: &str, loc: &Loc) -> Result<[f64; N]> {
        let bracketed = matches!(
            self.peek()?,
            Some(Token {
                kind: TokenKind::Open,
                ..
            })
        );
        if bracketed {
            self.next()?;
        }
        let mut out = [0.0; N];
        for (i, slot) in out.iter_mut().enumerate() {
            match self.next()? {
                Some(Token {
                    kind: TokenKind::Number(v),
                    ..
                }) => *slot = v,
                other => {
                    let at = other
                        .as_ref()
                        .map_or_else(|| loc.clone(), |t| self.loc(t.offset));
                    let found =
                        other.map_or("the end of the file".to_owned(), |t| describe(&t.kind));
                    return Err(Error::at(
                        &at,
                        format!("{directive} expects {N} numbers, found {found} after {i}"),
                    ));
                }
            }
        }
        if bracketed {
            match self.next()? {
                Some(Token {
                    kind: TokenKind::Close,
                    ..
                }) => {}
                other => {
                    let at = other
                        .as_ref()
                        .map_or_else(|| loc.clone(), |t| self.loc(t.offset));
                    return Err(Error::at(
                        &at,
                        format!("{directive} expects exactly {N} numbers followed by ']'"),
                    ));
                }
            }
        }
        Ok(out)
    }

    /// A parameter list: `"type name" value` or `"type name" [ values ]`, repeated.
    fn params(&mut self) -> Result<ParamList> {
        let mut list = ParamList::new();
        while let Some(Token {
            kind: TokenKind::Str(_),
            ..
        }) = self.peek()?
        {
            let Some(Token {
                kind: TokenKind::Str(decl),
                offset,
            }) = self.next()?
            else {
                break;
            };
            let loc = self.loc(offset);
            let param = self.param(&decl, loc)?;
            if let Some(old) = list.push(param) {
                self.builder.warn(
                    &old.loc,
                    format!(
                        "parameter \"{}\" is given again later; the later one is used",
                        old.name
                    ),
                );
            }
        }
        Ok(list)
    }

    fn param(&mut self, decl: &str, loc: Loc) -> Result<Param> {
        let mut words = decl.split_whitespace();
        let (Some(ty_name), Some(name), None) = (words.next(), words.next(), words.next()) else {
            return Err(Error::at(
                &loc,
                format!("expected a parameter declaration \"type name\", found \"{decl}\""),
            ));
        };
        let ty = ParamType::from_name(ty_name).ok_or_else(|| {
            const TYPES: &[&str] = &[
                "integer",
                "float",
                "point2",
                "vector2",
                "point3",
                "vector3",
                "normal3",
                "point",
                "vector",
                "normal",
                "rgb",
                "color",
                "spectrum",
                "blackbody",
                "bool",
                "string",
                "texture",
            ];
            Error::at(
                &loc,
                format!(
                    "unknown parameter type '{ty_name}'{}",
                    did_you_mean(ty_name, TYPES.iter().copied())
                ),
            )
        })?;
        let raw = self.raw_values(name, &loc)?;
        let values = convert(ty, name, raw, &loc)?;
        Ok(Param::new(ty, name, values, loc))
    }

    /// The value or bracketed values of a parameter, as written.
    fn raw_values(&mut self, name: &str, loc: &Loc) -> Result<Raw> {
        let mut raw = Raw::default();
        match self.next()? {
            Some(Token {
                kind: TokenKind::Open,
                ..
            }) => loop {
                match self.next()? {
                    Some(Token {
                        kind: TokenKind::Close,
                        ..
                    }) => break,
                    Some(t) => raw.push(t, self.file(), name)?,
                    None => {
                        return Err(Error::at(
                            loc,
                            format!("parameter \"{name}\": '[' is never closed"),
                        ))
                    }
                }
            },
            Some(
                t @ Token {
                    kind: TokenKind::Number(_) | TokenKind::Str(_) | TokenKind::Word(_),
                    ..
                },
            ) => {
                if matches!(&t.kind, TokenKind::Word(w) if w != "true" && w != "false") {
                    return Err(Error::at(
                        &self.loc(t.offset),
                        format!("parameter \"{name}\" has no value"),
                    ));
                }
                raw.push(t, self.file(), name)?;
            }
            Some(t) => {
                return Err(Error::at(
                    &self.loc(t.offset),
                    format!(
                        "expected a value for parameter \"{name}\", found {}",
                        describe(&t.kind)
                    ),
                ))
            }
            None => {
                return Err(Error::at(
                    loc,
                    format!("parameter \"{name}\" has no value: the file ends"),
                ))
            }
        }
        Ok(raw)
    }
}

/// Values as written, before the declared type is applied.
#[derive(Default)]
struct Raw {
    numbers: Vec<f64>,
    strings: Vec<String>,
    /// Bare `true`/`false` (pbrt-v4 style).
    bools: Vec<bool>,
}

impl Raw {
    fn push(&mut self, t: Token, file: &Arc<SourceFile>, name: &str) -> Result<()> {
        let kind_name = match t.kind {
            TokenKind::Number(v) => {
                self.numbers.push(v);
                "number"
            }
            TokenKind::Str(s) => {
                self.strings.push(s);
                "string"
            }
            TokenKind::Word(w) if w == "true" || w == "false" => {
                self.bools.push(w == "true");
                "bool"
            }
            TokenKind::Word(w) => {
                return Err(Error::at(
                    &Loc::new(file, t.offset),
                    format!(
                        "parameter \"{name}\": unexpected '{w}' among its values (missing ']'?)"
                    ),
                ))
            }
            TokenKind::Open | TokenKind::Close => {
                return Err(Error::at(
                    &Loc::new(file, t.offset),
                    format!("parameter \"{name}\": unexpected bracket among its values"),
                ))
            }
        };
        let kinds = [
            !self.numbers.is_empty(),
            !self.strings.is_empty(),
            !self.bools.is_empty(),
        ];
        if kinds.iter().filter(|&&k| k).count() > 1 {
            return Err(Error::at(
                &Loc::new(file, t.offset),
                format!("parameter \"{name}\" mixes {kind_name}s with values of another kind"),
            ));
        }
        Ok(())
    }
}

/// Applies the declared type to the values as written.
fn convert(ty: ParamType, name: &str, raw: Raw, loc: &Loc) -> Result<Values> {
    let wrong = |found: &str| {
        Error::at(
            loc,
            format!(
                "parameter \"{name}\" is declared {} but has {found} values",
                ty.name()
            ),
        )
    };
    let found = if !raw.strings.is_empty() {
        "string"
    } else if !raw.bools.is_empty() {
        "bool"
    } else {
        "numeric"
    };
    match ty {
        ParamType::Integer => {
            if found != "numeric" {
                return Err(wrong(found));
            }
            let ints = raw
                .numbers
                .iter()
                .map(|&v| {
                    if v.fract() == 0.0 && v >= i32::MIN as f64 && v <= i32::MAX as f64 {
                        Ok(v as i32)
                    } else {
                        Err(Error::at(
                            loc,
                            format!("parameter \"{name}\": {v} is not a 32-bit integer"),
                        ))
                    }
                })
                .collect::<Result<Vec<i32>>>()?;
            Ok(Values::Ints(ints))
        }
        ParamType::Float
        | ParamType::Point2
        | ParamType::Vector2
        | ParamType::Point3
        | ParamType::Vector3
        | ParamType::Normal
        | ParamType::Rgb
        | ParamType::Blackbody => {
            if found != "numeric" {
                return Err(wrong(found));
            }
            let arity = ty.arity();
            if raw.numbers.len() % arity != 0 {
                return Err(Error::at(
                    loc,
                    format!(
                        "parameter \"{name}\" has {} numbers, not a multiple of {arity} as a {} needs",
                        raw.numbers.len(),
                        ty.name()
                    ),
                ));
            }
            Ok(Values::Floats(raw.numbers))
        }
        ParamType::Spectrum => match found {
            "string" if raw.strings.len() == 1 => Ok(Values::Strings(raw.strings)),
            "numeric" if raw.numbers.len() % 2 == 0 => Ok(Values::Floats(raw.numbers)),
            "numeric" => Err(Error::at(
                loc,
                format!("parameter \"{name}\": a spectrum needs wavelength-value pairs"),
            )),
            _ => Err(wrong(found)),
        },
        ParamType::Bool => {
            if found == "numeric" && !raw.numbers.is_empty() {
                return Err(wrong(found));
            }
            let mut bools = raw.bools;
            for s in raw.strings {
                match s.as_str() {
                    "true" => bools.push(true),
                    "false" => bools.push(false),
                    _ => {
                        return Err(Error::at(
                            loc,
                            format!("parameter \"{name}\": \"{s}\" is not \"true\" or \"false\""),
                        ))
                    }
                }
            }
            Ok(Values::Bools(bools))
        }
        ParamType::String => {
            if found != "string" && !(raw.numbers.is_empty() && raw.bools.is_empty()) {
                return Err(wrong(found));
            }
            Ok(Values::Strings(raw.strings))
        }
        ParamType::Texture => {
            if found != "string" || raw.strings.len() != 1 {
                return Err(Error::at(
                    loc,
                    format!("parameter \"{name}\" needs one texture name"),
                ));
            }
            let name = raw.strings.into_iter().next().unwrap_or_default();
            Ok(Values::Texture(TextureRef {
                name,
                float: None,
                spectrum: None,
            }))
        }
    }
}
