//! The tokenizer: pbrt-v3 scene text to tokens, each with its byte offset.

use crate::error::{Error, Result};
use crate::source::{Loc, SourceFile};
use nom::branch::alt;
use nom::bytes::complete::take_till;
use nom::character::complete::{char, multispace1, not_line_ending};
use nom::combinator::value;
use nom::multi::many0_count;
use nom::sequence::preceded;
use nom::{IResult, Parser};
use std::sync::Arc;

/// What a token is.
#[derive(Debug, Clone, PartialEq)]
pub enum TokenKind {
    /// A bare word: a directive name, or `true`/`false`, `EndTime`...
    Word(String),
    /// A quoted string, escapes resolved.
    Str(String),
    /// A number (always finite).
    Number(f64),
    /// `[`
    Open,
    /// `]`
    Close,
}

/// A token and the byte offset where it starts.
#[derive(Debug, Clone, PartialEq)]
pub struct Token {
    /// What the token is.
    pub kind: TokenKind,
    /// Byte offset of its first character in the file.
    pub offset: usize,
}

/// Splits one file's text into tokens, lazily.
pub struct Tokenizer {
    file: Arc<SourceFile>,
    /// The file's text, held while it is read.
    text: Arc<String>,
    pos: usize,
}

/// Skips whitespace and `#` comments.
fn skip_blank(input: &str) -> IResult<&str, ()> {
    value(
        (),
        many0_count(alt((multispace1, preceded(char('#'), not_line_ending)))),
    )
    .parse(input)
}

/// The value of a short run of decimal digits with an optional minus sign, exactly.
#[inline]
fn small_integer(word: &str) -> Option<f64> {
    let (neg, digits) = match word.as_bytes() {
        [b'-', rest @ ..] => (true, rest),
        rest => (false, rest),
    };
    if digits.is_empty() || digits.len() > 15 || !digits.iter().all(u8::is_ascii_digit) {
        return None;
    }
    let v = digits
        .iter()
        .fold(0u64, |acc, d| acc * 10 + u64::from(d - b'0')) as f64;
    Some(if neg { -v } else { v })
}

/// Bytes that end a bare token: ASCII whitespace, quotes, brackets and comments.
const fn delimiters() -> [bool; 256] {
    let mut t = [false; 256];
    let ends = b" \t\n\r\x0b\x0c\"[]#";
    let mut i = 0;
    while i < ends.len() {
        t[ends[i] as usize] = true;
        i += 1;
    }
    t
}

static DELIMITER: [bool; 256] = delimiters();

/// A bare token runs until whitespace, a quote, a bracket or a comment. A byte table rather
/// than a per-char predicate: this is the tokenizer's hottest loop. Delimiters are ASCII, so
/// the split always falls on a character boundary.
fn bare(input: &str) -> IResult<&str, &str> {
    let len = input
        .bytes()
        .position(|b| DELIMITER[b as usize])
        .unwrap_or(input.len());
    if len == 0 {
        return Err(nom::Err::Error(nom::error::Error::new(
            input,
            nom::error::ErrorKind::TakeWhile1,
        )));
    }
    Ok((&input[len..], &input[..len]))
}

/// The plain run of a string's characters up to a quote, a backslash or a line break.
fn plain_run(input: &str) -> IResult<&str, &str> {
    take_till(|c: char| matches!(c, '"' | '\\' | '\n')).parse(input)
}

impl Tokenizer {
    /// A tokenizer at the start of `file`.
    pub fn new(file: Arc<SourceFile>) -> Self {
        // A UTF-8 byte order mark is not part of the scene.
        let text = file.text();
        let pos = if text.starts_with('\u{feff}') { 3 } else { 0 };
        Self { file, text, pos }
    }

    /// The file being read.
    pub fn file(&self) -> &Arc<SourceFile> {
        &self.file
    }

    fn loc(&self, offset: usize) -> Loc {
        Loc::new(&self.file, offset)
    }

    /// The next token, or `None` at the end of the file.
    pub fn next_token(&mut self) -> Result<Option<Token>> {
        let text: &str = &self.text;
        let mut rest = &text[self.pos..];
        // Most tokens follow a single space: step over it before asking the general parser.
        if rest.as_bytes().first() == Some(&b' ') {
            rest = &rest[1..];
        }
        if rest
            .as_bytes()
            .first()
            .is_some_and(|b| b.is_ascii_whitespace() || *b == b'#')
        {
            // skip_blank cannot fail: many0_count accepts zero repetitions.
            rest = skip_blank(rest).map_or(rest, |(r, ())| r);
        }
        let start = text.len() - rest.len();
        let Some(first) = rest.chars().next() else {
            self.pos = start;
            return Ok(None);
        };
        let (kind, len) = match first {
            '[' => (TokenKind::Open, 1),
            ']' => (TokenKind::Close, 1),
            '"' => self.string(rest, start)?,
            _ => {
                let (after, word) = bare(rest).map_err(|_| {
                    Error::at(&self.loc(start), format!("unexpected character {first:?}"))
                })?;
                let len = rest.len() - after.len();
                let starts_number = matches!(first, '0'..='9' | '-' | '+' | '.');
                if starts_number {
                    (TokenKind::Number(self.number(word, start)?), len)
                } else {
                    (TokenKind::Word(word.to_owned()), len)
                }
            }
        };
        self.pos = start + len;
        Ok(Some(Token {
            kind,
            offset: start,
        }))
    }

    fn number(&self, word: &str, start: usize) -> Result<f64> {
        // Integers (mesh indices) are half of a typical scene's numbers: read them directly.
        if let Some(v) = small_integer(word) {
            return Ok(v);
        }
        match word.parse::<f64>() {
            Ok(v) if v.is_finite() => Ok(v),
            Ok(_) => Err(Error::at(
                &self.loc(start),
                format!("number {word} is out of range"),
            )),
            Err(_) => Err(Error::at(
                &self.loc(start),
                format!("invalid number {word:?}"),
            )),
        }
    }

    /// A quoted string starting at `rest` (which begins with the quote); returns its value and
    /// the length of its text including quotes.
    fn string(&self, rest: &str, start: usize) -> Result<(TokenKind, usize)> {
        let mut value = String::new();
        let mut input = &rest[1..];
        loop {
            let (after, run) =
                plain_run(input).map_err(|_| Error::at(&self.loc(start), "unterminated string"))?;
            value.push_str(run);
            let mut chars = after.chars();
            match chars.next() {
                Some('"') => {
                    let len = rest.len() - after.len() + 1;
                    return Ok((TokenKind::Str(value), len));
                }
                Some('\\') => {
                    let escaped = match chars.next() {
                        Some('n') => '\n',
                        Some('t') => '\t',
                        Some('r') => '\r',
                        Some('b') => '\u{8}',
                        Some('f') => '\u{c}',
                        Some(c @ ('\\' | '"' | '\'')) => c,
                        Some(c) => {
                            let at = start + rest.len() - after.len();
                            return Err(Error::at(
                                &self.loc(at),
                                format!("unknown escape sequence \\{c} in string"),
                            ));
                        }
                        None => return Err(Error::at(&self.loc(start), "unterminated string")),
                    };
                    value.push(escaped);
                    input = chars.as_str();
                }
                // A line break or the end of the file before the closing quote.
                _ => return Err(Error::at(&self.loc(start), "unterminated string")),
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tokens(text: &str) -> Result<Vec<TokenKind>> {
        let mut t = Tokenizer::new(SourceFile::new("t.pbrt", text));
        let mut out = Vec::new();
        while let Some(tok) = t.next_token()? {
            out.push(tok.kind);
        }
        Ok(out)
    }

    #[test]
    fn words_numbers_strings_brackets() {
        use TokenKind::*;
        let got = tokens("Shape \"sphere\" \"float radius\" [.5 -1e3 +2]# c\n").unwrap();
        assert_eq!(
            got,
            vec![
                Word("Shape".into()),
                Str("sphere".into()),
                Str("float radius".into()),
                Open,
                Number(0.5),
                Number(-1000.0),
                Number(2.0),
                Close
            ]
        );
    }

    #[test]
    fn integers_read_exactly() {
        for (text, v) in [
            ("0", 0.0),
            ("-12", -12.0),
            ("123456789012345", 123456789012345.0),
        ] {
            assert_eq!(tokens(text).unwrap(), vec![TokenKind::Number(v)]);
        }
        assert_eq!(tokens("-0").unwrap(), vec![TokenKind::Number(-0.0)]);
        assert_eq!(
            tokens("1234567890123456789").unwrap(),
            vec![TokenKind::Number(1234567890123456789.0)]
        );
    }

    #[test]
    fn escapes() {
        let got = tokens(r#""a\"b\\c\nd""#).unwrap();
        assert_eq!(got, vec![TokenKind::Str("a\"b\\c\nd".into())]);
    }

    #[test]
    fn offsets() {
        let mut t = Tokenizer::new(SourceFile::new("t.pbrt", "  # x\n [ 1"));
        assert_eq!(t.next_token().unwrap().unwrap().offset, 7);
        assert_eq!(t.next_token().unwrap().unwrap().offset, 9);
        assert!(t.next_token().unwrap().is_none());
    }

    #[test]
    fn errors() {
        for (text, msg) in [
            ("\"abc", "unterminated string"),
            ("\"ab\nc\"", "unterminated string"),
            ("1.2.3", "invalid number"),
            ("1e999", "out of range"),
            ("\"a\\q\"", "unknown escape"),
        ] {
            let err = tokens(text).unwrap_err();
            assert!(err.to_string().contains(msg), "{text}: {err}");
        }
    }
}
