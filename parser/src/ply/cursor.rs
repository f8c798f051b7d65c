//! Bounds-checked reads of a PLY body's values, ascii or binary.

use super::types::{Format, Kind, Scalar};

/// Why a read failed; turned into a message by [`Fail::context`].
pub(super) enum Fail {
    Eof,
    Negative(f64),
    Msg(String),
}

impl Fail {
    pub(super) fn context(self, what: &str, i: usize) -> String {
        match self {
            Fail::Eof => format!("file ends inside {what} {i}"),
            Fail::Negative(n) => format!("{what} {i} has a list of negative length {n}"),
            Fail::Msg(m) => m,
        }
    }
}

/// Reads body values one at a time, in any of the three encodings.
pub(super) struct Cursor<'a> {
    pub(super) bytes: &'a [u8],
    pub(super) pos: usize,
    /// Ascii: the line of the current position, for messages.
    pub(super) line: usize,
    pub(super) format: Format,
}

impl<'a> Cursor<'a> {
    pub(super) fn remaining(&self) -> usize {
        self.bytes.len().saturating_sub(self.pos)
    }

    /// Binary: whether big-endian; ascii: `None`.
    pub(super) fn big_endian(&self) -> Option<bool> {
        match self.format {
            Format::Ascii => None,
            Format::BinaryLe => Some(false),
            Format::BinaryBe => Some(true),
        }
    }

    pub(super) fn take(&mut self, n: usize) -> Option<&'a [u8]> {
        let end = self.pos.checked_add(n)?;
        let s = self.bytes.get(self.pos..end)?;
        self.pos = end;
        Some(s)
    }

    /// The next whitespace-separated ascii word.
    pub(super) fn token(&mut self) -> Option<&'a [u8]> {
        let b = self.bytes;
        let mut p = self.pos;
        while let Some(&c) = b.get(p) {
            if c == b'\n' {
                self.line += 1;
            } else if !c.is_ascii_whitespace() {
                break;
            }
            p += 1;
        }
        let start = p;
        while let Some(&c) = b.get(p) {
            if c.is_ascii_whitespace() {
                break;
            }
            p += 1;
        }
        self.pos = p;
        b.get(start..p).filter(|t| !t.is_empty())
    }

    /// One value of type `ty`, as f64.
    pub(super) fn scalar(&mut self, ty: Scalar) -> Result<f64, Fail> {
        let Some(be) = self.big_endian() else {
            return self.ascii(ty);
        };
        let s = self.take(ty.size()).ok_or(Fail::Eof)?;
        Ok(decode(s, 0, ty, be))
    }

    pub(super) fn ascii(&mut self, ty: Scalar) -> Result<f64, Fail> {
        let tok = self.token().ok_or(Fail::Eof)?;
        let s = std::str::from_utf8(tok).ok();
        let v = if ty.is_int() {
            s.and_then(|s| s.parse::<i64>().ok()).map(|v| v as f64)
        } else {
            s.and_then(|s| s.parse::<f64>().ok())
        };
        v.ok_or_else(|| {
            let shown: String = String::from_utf8_lossy(tok).chars().take(40).collect();
            let what = if ty.is_int() {
                "an integer"
            } else {
                "a number"
            };
            Fail::Msg(format!(
                "ascii line {}: expected {what}, found '{shown}'",
                self.line
            ))
        })
    }

    /// A list's length.
    pub(super) fn list_len(&mut self, ty: Scalar) -> Result<usize, Fail> {
        let n = self.scalar(ty)?;
        if n < 0.0 {
            return Err(Fail::Negative(n));
        }
        // Counts are integers (checked in the header); the cast saturates.
        Ok(n as usize)
    }

    /// Reads past one property value.
    pub(super) fn skip(&mut self, kind: Kind) -> Result<(), Fail> {
        match kind {
            Kind::Scalar(ty) => self.skip_items(1, ty),
            Kind::List { count, item } => {
                let n = self.list_len(count)?;
                self.skip_items(n, item)
            }
        }
    }

    pub(super) fn skip_items(&mut self, n: usize, ty: Scalar) -> Result<(), Fail> {
        if self.format == Format::Ascii {
            // Each value is a word of at least one byte, so this ends at the end of the file.
            for _ in 0..n {
                self.ascii(ty)?;
            }
            return Ok(());
        }
        let len = n.checked_mul(ty.size()).ok_or(Fail::Eof)?;
        self.take(len).map(|_| ()).ok_or(Fail::Eof)
    }
}

/// The `N` bytes at `off` in `s`, or zeros where `s` is too short (never, for callers here).
#[inline(always)]
pub(super) fn arr<const N: usize>(s: &[u8], off: usize) -> [u8; N] {
    s.get(off..off.saturating_add(N))
        .and_then(|x| <[u8; N]>::try_from(x).ok())
        .unwrap_or([0; N])
}

/// The binary value of type `ty` at `off` in `s`.
#[inline]
pub(super) fn decode(s: &[u8], off: usize, ty: Scalar, be: bool) -> f64 {
    macro_rules! num {
        ($t:ty) => {{
            let a = arr(s, off);
            f64::from(if be {
                <$t>::from_be_bytes(a)
            } else {
                <$t>::from_le_bytes(a)
            })
        }};
    }
    match ty {
        Scalar::I8 => num!(i8),
        Scalar::U8 => num!(u8),
        Scalar::I16 => num!(i16),
        Scalar::U16 => num!(u16),
        Scalar::I32 => num!(i32),
        Scalar::U32 => num!(u32),
        Scalar::F32 => num!(f32),
        Scalar::F64 => num!(f64),
    }
}
