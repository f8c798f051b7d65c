//! The PLY header: format, elements and their properties, read and checked.

use super::cursor::Cursor;
use super::types::{Format, Kind, Scalar};

#[derive(Clone, Debug)]
pub(super) struct Property {
    pub(super) name: String,
    pub(super) kind: Kind,
}

#[derive(Clone, Debug)]
pub(super) struct Element {
    pub(super) name: String,
    pub(super) count: usize,
    pub(super) props: Vec<Property>,
}

impl Element {
    /// Whether every record has the same binary size (no lists).
    pub(super) fn all_scalar(&self) -> bool {
        self.props.iter().all(|p| matches!(p.kind, Kind::Scalar(_)))
    }
}

pub(super) struct Header {
    pub(super) format: Format,
    pub(super) elements: Vec<Element>,
    /// Offset of the first byte after the end_header line.
    pub(super) body: usize,
    /// Line number of the first body line (for ascii messages).
    pub(super) body_line: usize,
}

pub(super) fn parse_header(bytes: &[u8]) -> Result<Header, String> {
    let mut pos = 0;
    let mut line_no = 0;
    let mut format = None;
    let mut elements: Vec<Element> = Vec::new();
    loop {
        let rest = bytes.get(pos..).unwrap_or_default();
        if rest.is_empty() {
            return Err(if line_no == 0 {
                "header: the file is empty".into()
            } else {
                "header: no end_header line".into()
            });
        }
        let (raw, next) = match rest.iter().position(|&b| b == b'\n') {
            Some(i) => (rest.get(..i).unwrap_or_default(), pos + i + 1),
            None => (rest, bytes.len()),
        };
        pos = next;
        line_no += 1;
        let line = std::str::from_utf8(raw)
            .ok()
            .filter(|l| l.is_ascii())
            .ok_or_else(|| {
                if line_no == 1 {
                    "header: the file does not start with \"ply\"".to_owned()
                } else {
                    format!("header line {line_no} is not text (no end_header line?)")
                }
            })?;
        if line_no == 1 {
            if line.trim() != "ply" {
                return Err("header: the file does not start with \"ply\"".into());
            }
            continue;
        }
        let words: Vec<&str> = line.split_ascii_whitespace().collect();
        let at = |m: String| format!("header line {line_no}: {m}");
        match words.as_slice() {
            [] | ["comment", ..] | ["obj_info", ..] => {}
            ["end_header", ..] => break,
            ["format", f, version] => {
                if format.is_some() {
                    return Err(at("a second format line".into()));
                }
                format = Some(match *f {
                    "ascii" => Format::Ascii,
                    "binary_little_endian" => Format::BinaryLe,
                    "binary_big_endian" => Format::BinaryBe,
                    other => return Err(at(format!("unknown format '{other}'"))),
                });
                if !matches!(*version, "1.0" | "1") {
                    return Err(at(format!("unsupported PLY version '{version}'")));
                }
            }
            ["format", ..] => return Err(at("expected 'format <type> 1.0'".into())),
            ["element", name, count] => {
                let Ok(count) = count.parse::<usize>() else {
                    return Err(at(format!("bad element count '{count}'")));
                };
                elements.push(Element {
                    name: (*name).to_owned(),
                    count,
                    props: Vec::new(),
                });
            }
            ["element", ..] => return Err(at("expected 'element <name> <count>'".into())),
            ["property", rest @ ..] => {
                let (kind, name) = match rest {
                    ["list", count, item, name] => {
                        let count_ty = parse_type(count).map_err(at)?;
                        let item = parse_type(item).map_err(at)?;
                        if !count_ty.is_int() {
                            return Err(at(format!(
                                "a list count type must be an integer type, not '{count}'"
                            )));
                        }
                        (
                            Kind::List {
                                count: count_ty,
                                item,
                            },
                            name,
                        )
                    }
                    ["list", ..] => {
                        return Err(at(
                            "expected 'property list <count type> <item type> <name>'".into(),
                        ))
                    }
                    [ty, name] => (Kind::Scalar(parse_type(ty).map_err(at)?), name),
                    _ => return Err(at("expected 'property <type> <name>'".into())),
                };
                let Some(el) = elements.last_mut() else {
                    return Err(at("property before any element".into()));
                };
                el.props.push(Property {
                    name: (*name).to_owned(),
                    kind,
                });
            }
            [other, ..] => return Err(at(format!("unknown keyword '{other}'"))),
        }
    }
    let format = format.ok_or("header: no format line")?;
    Ok(Header {
        format,
        elements,
        body: pos,
        body_line: line_no + 1,
    })
}

pub(super) fn parse_type(name: &str) -> Result<Scalar, String> {
    Scalar::from_name(name).ok_or_else(|| format!("unknown property type '{name}'"))
}

/// Fails unless `count` records of `el`, each at its smallest, fit in the rest of the file.
pub(super) fn check_fits(el: &Element, cur: &Cursor) -> Result<(), String> {
    let remaining = cur.remaining();
    let (min, slack) = match cur.format {
        // A value is at least one character and a separator; the file's last needs no separator.
        Format::Ascii => (el.props.len().saturating_mul(2), 1),
        _ => (el.props.iter().map(|p| p.kind.min_size()).sum(), 0),
    };
    let need = el.count.checked_mul(min);
    if need.is_some_and(|n| n <= remaining.saturating_add(slack)) {
        return Ok(());
    }
    if cur.format != Format::Ascii && el.all_scalar() && min > 0 {
        // Fixed-size records: say exactly where the data stops.
        let more = (el.count as u128 * min as u128).saturating_sub(remaining as u128);
        return Err(format!(
            "file ends inside {} {} (expected {more} more bytes)",
            el.name,
            remaining / min
        ));
    }
    Err(format!(
        "the header declares {} '{}' records, more than the remaining {remaining} bytes can hold",
        el.count, el.name
    ))
}
