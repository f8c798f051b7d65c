//! Source files and byte-offset locations, resolved to line:column only when reported.

use std::fmt;
use std::path::{Path, PathBuf};
use std::sync::{Arc, OnceLock};

/// One scene file's text, kept so that any later diagnostic can quote its line.
#[derive(Debug)]
pub struct SourceFile {
    /// The path as the user (or the including file) named it.
    pub path: PathBuf,
    /// The whole text of the file.
    pub text: Arc<str>,
    /// Where each line starts, built on the first location resolved: counting lines from the
    /// start of the file for every location printed was quadratic (`acr parse` of a 30 MB
    /// scene spent 98% of 18 to 97 s there).
    lines: OnceLock<LineIndex>,
}

/// The byte offset each line starts at, and whether it is all ASCII (its columns are then
/// byte differences, with no need to count characters along a line that may hold a mesh).
#[derive(Debug)]
struct LineIndex {
    starts: Vec<u32>,
    ascii: Vec<bool>,
}

impl LineIndex {
    fn new(text: &str) -> Self {
        let bytes = text.as_bytes();
        let mut starts = vec![0u32];
        starts.extend(
            bytes
                .iter()
                .enumerate()
                .filter(|&(_, &b)| b == b'\n')
                .map(|(i, _)| (i + 1).min(u32::MAX as usize) as u32),
        );
        let ascii = (0..starts.len())
            .map(|k| {
                let from = starts[k] as usize;
                let to = starts.get(k + 1).map_or(bytes.len(), |&e| e as usize);
                bytes[from.min(to)..to].is_ascii()
            })
            .collect();
        Self { starts, ascii }
    }

    /// 0-based line of byte `offset`, by binary search.
    fn line_of(&self, offset: u32) -> usize {
        self.starts.partition_point(|&s| s <= offset) - 1
    }
}

impl SourceFile {
    /// Wraps a file's text under the given path.
    pub fn new(path: impl Into<PathBuf>, text: impl Into<Arc<str>>) -> Arc<Self> {
        Arc::new(Self {
            path: path.into(),
            text: text.into(),
            lines: OnceLock::new(),
        })
    }

    fn lines(&self) -> &LineIndex {
        self.lines.get_or_init(|| LineIndex::new(&self.text))
    }

    /// The directory holding this file, against which relative names inside it resolve.
    pub fn dir(&self) -> &Path {
        self.path.parent().unwrap_or_else(|| Path::new(""))
    }
}

/// A place in a source file: a byte offset, turned into line and column on demand.
///
/// Columns are computed only when reporting, because computing them per token is quadratic on
/// pbrt's long one-line arrays.
#[derive(Clone)]
pub struct Loc {
    /// The file the location is in.
    pub file: Arc<SourceFile>,
    /// Byte offset from the start of the file.
    pub offset: u32,
}

impl Loc {
    /// A location at `offset` bytes into `file`.
    pub fn new(file: &Arc<SourceFile>, offset: usize) -> Self {
        Self {
            file: Arc::clone(file),
            offset: offset.min(u32::MAX as usize) as u32,
        }
    }

    /// 1-based line and column (in characters) of this location.
    pub fn line_col(&self) -> (usize, usize) {
        let text = &self.file.text;
        let offset = (self.offset as usize).min(text.len());
        let index = self.file.lines();
        let line = index.line_of(offset as u32);
        let start = index.starts[line] as usize;
        let col = if index.ascii[line] {
            offset - start
        } else {
            String::from_utf8_lossy(&text.as_bytes()[start..offset])
                .chars()
                .count()
        };
        (line + 1, col + 1)
    }

    /// The text of the line holding this location, without its line break, shortened around
    /// the column when very long (pbrt files often hold a whole mesh on one line).
    pub fn snippet(&self) -> String {
        const MAX: usize = 120;
        let text = &self.file.text;
        let offset = (self.offset as usize).min(text.len());
        let bytes = text.as_bytes();
        let start = bytes[..offset]
            .iter()
            .rposition(|&b| b == b'\n')
            .map_or(0, |p| p + 1);
        let end = bytes[offset..]
            .iter()
            .position(|&b| b == b'\n')
            .map_or(bytes.len(), |p| offset + p);
        let line = String::from_utf8_lossy(&bytes[start..end]);
        let line = line.trim_end_matches('\r');
        let chars: Vec<char> = line
            .chars()
            // Tabs as spaces keep the caret aligned; other control characters (from a binary
            // file given as a scene) would move the terminal's cursor or ring its bell.
            .map(|c| match c {
                '\t' => ' ',
                c if c.is_control() => '?',
                c => c,
            })
            .collect();
        let col = String::from_utf8_lossy(&bytes[start..offset])
            .chars()
            .count();
        let (from, prefix) = if col > MAX / 2 {
            (col - MAX / 2, "...")
        } else {
            (0, "")
        };
        let to = (from + MAX).min(chars.len());
        let suffix = if to < chars.len() { "..." } else { "" };
        let shown: String = chars[from.min(to)..to].iter().collect();
        let caret_at = prefix.len() + col - from;
        format!("{prefix}{shown}{suffix}\n{:width$}^", "", width = caret_at)
    }
}

impl fmt::Display for Loc {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let (line, col) = self.line_col();
        write!(f, "{}:{line}:{col}", self.file.path.display())
    }
}

impl fmt::Debug for Loc {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        fmt::Display::fmt(self, f)
    }
}

/// Reads a whole file named in a scene, refusing devices and sockets (`/dev/zero` would never
/// end) with an `InvalidInput` error before reading anything.
pub fn read_file(path: &Path) -> std::io::Result<Vec<u8>> {
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        let t = std::fs::metadata(path)?.file_type();
        if t.is_char_device() || t.is_block_device() || t.is_socket() {
            return Err(std::io::Error::new(
                std::io::ErrorKind::InvalidInput,
                "not a regular file but a device or socket",
            ));
        }
    }
    std::fs::read(path)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Line and column counted from the start of the file, as before the line index.
    fn counted(text: &str, offset: usize) -> (usize, usize) {
        let before = &text.as_bytes()[..offset.min(text.len())];
        let line = before.iter().filter(|&&b| b == b'\n').count() + 1;
        let start = before
            .iter()
            .rposition(|&b| b == b'\n')
            .map_or(0, |p| p + 1);
        let col = String::from_utf8_lossy(&before[start..]).chars().count() + 1;
        (line, col)
    }

    #[test]
    fn the_line_index_gives_the_counted_line_and_column_everywhere() {
        let texts = [
            "",
            "\n",
            "Shape \"sphere\"\n",
            "a\nbc\r\nd\n\n\ne",
            "# héllo wörld\nShape \"sphère\" [1 2]\n  é\n",
            "no newline at the end",
        ];
        for text in texts {
            let file = SourceFile::new("t.pbrt", text);
            for offset in 0..=text.len() + 2 {
                let got = Loc::new(&file, offset).line_col();
                assert_eq!(got, counted(text, offset), "{text:?} at {offset}");
            }
        }
    }
}
