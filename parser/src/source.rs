//! Source files and byte-offset locations, resolved to line:column only when reported.

use std::fmt;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex, OnceLock};

/// One scene file's text, kept so that any later diagnostic can quote its line. Once the
/// scene is parsed the text may be released ([`SourceFile::release_text`]): a diagnostic after
/// that reads the file again.
#[derive(Debug)]
pub struct SourceFile {
    /// The path as the user (or the including file) named it.
    pub path: PathBuf,
    /// The whole text of the file, until released.
    text: Mutex<Option<Arc<String>>>,
    /// The text's length in bytes (a file read again must have it, or it changed).
    len: usize,
    /// Whether the text came from the file at `path` (and can be read again from there).
    on_disk: bool,
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
    /// Wraps a text under the given path (the text is its own: it cannot be released).
    pub fn new(path: impl Into<PathBuf>, text: impl Into<String>) -> Arc<Self> {
        Self::with_origin(path.into(), text.into(), false)
    }

    /// Wraps the text just read from the file at `path`: it can be released once parsed and
    /// read again for a diagnostic.
    pub fn read_from(path: impl Into<PathBuf>, text: String) -> Arc<Self> {
        Self::with_origin(path.into(), text, true)
    }

    fn with_origin(path: PathBuf, text: String, on_disk: bool) -> Arc<Self> {
        Arc::new(Self {
            path,
            len: text.len(),
            // An Arc of the String keeps its buffer: an `Arc<str>` would copy the whole file.
            text: Mutex::new(Some(Arc::new(text))),
            on_disk,
            lines: OnceLock::new(),
        })
    }

    /// The file's text: the one parsed, or once released, the file read again (empty if it
    /// cannot be read or its length changed).
    pub fn text(&self) -> Arc<String> {
        let kept = self.text.lock().map_or(None, |t| t.clone());
        kept.unwrap_or_else(|| {
            let again = read_file(&self.path, FileKind::Scene)
                .ok()
                .and_then(|bytes| String::from_utf8(bytes).ok())
                .filter(|t| t.len() == self.len);
            Arc::new(again.unwrap_or_default())
        })
    }

    /// The text's length in bytes.
    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether the text is empty.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Frees the text of a file read from disk (its lines indexed first, so that locations
    /// still resolve to line and column without it); a diagnostic that quotes a line reads
    /// the file again. A text given in memory is kept.
    pub fn release_text(&self) {
        if !self.on_disk {
            return;
        }
        if let Ok(mut t) = self.text.lock() {
            if let Some(text) = t.as_ref() {
                self.lines.get_or_init(|| LineIndex::new(text));
            }
            *t = None;
        }
    }

    fn lines(&self) -> &LineIndex {
        self.lines.get_or_init(|| LineIndex::new(&self.text()))
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
        let offset = (self.offset as usize).min(self.file.len());
        let index = self.file.lines();
        let line = index.line_of(offset as u32);
        let start = index.starts[line] as usize;
        let col = if index.ascii[line] {
            offset - start
        } else {
            let text = self.file.text();
            let bytes = text.as_bytes();
            String::from_utf8_lossy(&bytes[start.min(bytes.len())..offset.min(bytes.len())])
                .chars()
                .count()
        };
        (line + 1, col + 1)
    }

    /// The text of the line holding this location, without its line break, shortened around
    /// the column when very long (pbrt files often hold a whole mesh on one line).
    pub fn snippet(&self) -> String {
        const MAX: usize = 120;
        let text = self.file.text();
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

/// What a file named in a scene holds, which bounds the size it may have.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FileKind {
    /// A scene file, the main one or an `Include`d one.
    Scene,
    /// A `plymesh` file.
    Ply,
    /// An image: a texture, an image light's map, an `acr merge` or `acr diff` input.
    Image,
    /// A `fourier` material's `bsdffile` table.
    BsdfTable,
    /// A spectrum (`.spd`) file.
    Spectrum,
}

impl FileKind {
    /// The most bytes a file of this kind may have: far above any real one, so that only a
    /// wrong or hostile name (a disk image, a log that grows) is refused before it fills memory.
    pub const fn max_bytes(self) -> u64 {
        match self {
            // Locations are 32-bit byte offsets.
            FileKind::Scene => u32::MAX as u64,
            FileKind::Ply => 16 << 30,
            // 16384 x 16384 RGBA float pixels (the most an image may have) and headers.
            FileKind::Image => 5 << 30,
            // pbrt-v3's tables are a few MB; layerlab's largest some hundred.
            FileKind::BsdfTable => 1 << 30,
            FileKind::Spectrum => 16 << 20,
        }
    }

    /// The kind in words, for messages.
    pub const fn name(self) -> &'static str {
        match self {
            FileKind::Scene => "scene file",
            FileKind::Ply => "PLY file",
            FileKind::Image => "image",
            FileKind::BsdfTable => "BSDF table",
            FileKind::Spectrum => "spectrum file",
        }
    }
}

/// Opens a file named in a scene (every such file is opened here, most through
/// [`read_file`]): a regular file, at most [`FileKind::max_bytes`] long. Folders, devices
/// (`/dev/zero` would never end), pipes (whose opening waits for a writer) and sockets are
/// refused before opening, and so is a file too long. Errors are `InvalidInput` with a message
/// that says which check failed; the caller adds where the file was named. Gives the file and
/// its length.
pub fn open_file(path: &Path, kind: FileKind) -> std::io::Result<(std::fs::File, u64)> {
    let check = |meta: &std::fs::Metadata| {
        if meta.is_dir() {
            Err(refused("a folder, not a file".to_owned()))
        } else if !meta.is_file() {
            Err(refused(
                "not a regular file but a device, pipe or socket".to_owned(),
            ))
        } else if meta.len() > kind.max_bytes() {
            Err(too_long(meta.len(), kind))
        } else {
            Ok(meta.len())
        }
    };
    check(&std::fs::metadata(path)?)?;
    let file = std::fs::File::open(path)?;
    // Again on what was opened, in case the name changed meanwhile.
    let len = check(&file.metadata()?)?;
    Ok((file, len))
}

/// Reads a whole file named in a scene, checked as [`open_file`] checks it; the read is
/// bounded again in case the file grows meanwhile. A name ending in `.gz` (any case) is
/// decompressed, as pbrt-v4 reads `.pbrt.gz` and `.ply.gz`; the limit then bounds the
/// decompressed bytes too, so that a small file cannot expand without end.
pub fn read_file(path: &Path, kind: FileKind) -> std::io::Result<Vec<u8>> {
    use std::io::Read;
    let (file, len) = open_file(path, kind)?;
    let limit = kind.max_bytes();
    let mut bytes = read_halves(&file, len)?;
    file.take(limit + 1 - bytes.len() as u64)
        .read_to_end(&mut bytes)?;
    if bytes.len() as u64 > limit {
        return Err(too_long(bytes.len() as u64, kind));
    }
    if !is_gzip_name(path) {
        return Ok(bytes);
    }
    let mut text = Vec::with_capacity(bytes.len().saturating_mul(4));
    flate2::read::MultiGzDecoder::new(bytes.as_slice())
        .take(limit + 1)
        .read_to_end(&mut text)
        .map_err(|e| refused(format!("not a readable gzip file: {e}")))?;
    if text.len() as u64 > limit {
        return Err(refused(format!(
            "more than {limit} bytes once decompressed, more than a {} may have",
            kind.name()
        )));
    }
    Ok(text)
}

/// Files of at least this many bytes are read in two halves at once.
const HALVES_MIN: u64 = 1 << 22;

/// The first `len` bytes of `file` (its length when opened, at most its kind's limit), the
/// file's position left at their end. A large file is read in two halves at once, each on its
/// own thread: the copy into fresh pages was most of reading a 24 MB mesh
/// (docs/BENCHMARKS.md). A file that has shrunk meanwhile gives what it still holds.
fn read_halves(file: &std::fs::File, len: u64) -> std::io::Result<Vec<u8>> {
    use std::io::{Read, Seek};
    let n = usize::try_from(len).unwrap_or(0);
    #[cfg(unix)]
    if len >= HALVES_MIN {
        use std::os::unix::fs::FileExt;
        // Zeroed by the allocator's fresh mapping, so that each thread faults its own half in.
        let mut bytes = vec![0u8; n];
        let (a, b) = bytes.split_at_mut(n / 2);
        let half = a.len() as u64;
        let (ra, rb) = std::thread::scope(|s| {
            let second = s.spawn(|| file.read_exact_at(b, half));
            (file.read_exact_at(a, 0), second.join())
        });
        if let (Ok(()), Ok(Ok(()))) = (ra, rb) {
            let mut f = file;
            f.seek(std::io::SeekFrom::Start(len))?;
            return Ok(bytes);
        }
    }
    let mut bytes = Vec::with_capacity(n);
    let mut f = file;
    f.seek(std::io::SeekFrom::Start(0))?;
    f.take(len).read_to_end(&mut bytes)?;
    Ok(bytes)
}

/// Whether `path` names a gzip-compressed file (`.gz`, any case).
pub fn is_gzip_name(path: &Path) -> bool {
    path.extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("gz"))
}

/// A refusal by [`open_file`], with its reason.
fn refused(message: String) -> std::io::Error {
    std::io::Error::new(std::io::ErrorKind::InvalidInput, message)
}

/// The refusal of a file of `n` bytes, longer than a `kind` may be.
fn too_long(n: u64, kind: FileKind) -> std::io::Error {
    refused(format!(
        "{n} bytes, more than a {} may have ({})",
        kind.name(),
        kind.max_bytes()
    ))
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

    /// A fresh empty folder under the system's temporary folder.
    fn temp_dir(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("acr-source-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    #[test]
    fn read_file_reads_a_regular_file_and_refuses_folders_and_long_files_before_reading() {
        let dir = temp_dir("read");
        let small = dir.join("small.spd");
        std::fs::write(&small, "400 1\n").unwrap();
        assert_eq!(read_file(&small, FileKind::Spectrum).unwrap(), b"400 1\n");

        let e = read_file(&dir, FileKind::Scene).unwrap_err();
        assert!(e.to_string().contains("a folder, not a file"), "{e}");

        // A sparse file one byte over the limit: refused from its size, nothing read.
        let long = dir.join("long.spd");
        let f = std::fs::File::create(&long).unwrap();
        f.set_len(FileKind::Spectrum.max_bytes() + 1).unwrap();
        let e = read_file(&long, FileKind::Spectrum).unwrap_err();
        assert!(
            e.to_string().contains("more than a spectrum file may have"),
            "{e}"
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn a_large_file_read_in_two_halves_is_the_file() {
        let dir = temp_dir("halves");
        for n in [HALVES_MIN as usize, HALVES_MIN as usize + 7] {
            let path = dir.join(format!("mesh-{n}.ply"));
            let bytes: Vec<u8> = (0..n as u64)
                .map(|i| (i.wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 56) as u8)
                .collect();
            std::fs::write(&path, &bytes).unwrap();
            assert!(
                read_file(&path, FileKind::Ply).unwrap() == bytes,
                "{n} bytes"
            );
        }
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn read_file_decompresses_gz_names_and_refuses_what_is_not_gzip() {
        use std::io::Write;
        let dir = temp_dir("gz");
        let text = b"WorldBegin\nShape \"sphere\"\nWorldEnd\n";
        let gz = dir.join("s.pbrt.GZ");
        let mut enc = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::default());
        enc.write_all(text).unwrap();
        std::fs::write(&gz, enc.finish().unwrap()).unwrap();
        assert_eq!(read_file(&gz, FileKind::Scene).unwrap(), text);
        // Without the suffix the bytes are what they are.
        let raw = dir.join("s.pbrt");
        std::fs::copy(&gz, &raw).unwrap();
        assert_ne!(read_file(&raw, FileKind::Scene).unwrap(), text);
        // A `.gz` that is not gzip, and one cut short, are errors that say so.
        let bad = dir.join("bad.pbrt.gz");
        std::fs::write(&bad, text).unwrap();
        let e = read_file(&bad, FileKind::Scene).unwrap_err();
        assert!(e.to_string().contains("not a readable gzip file"), "{e}");
        let gz_bytes = std::fs::read(&gz).unwrap();
        std::fs::write(&bad, &gz_bytes[..gz_bytes.len() - 6]).unwrap();
        let e = read_file(&bad, FileKind::Scene).unwrap_err();
        assert!(e.to_string().contains("not a readable gzip file"), "{e}");
        // The limit bounds the decompressed bytes: 17 MB of zeros is a small file.
        let mut enc = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::best());
        enc.write_all(&vec![0u8; (17 << 20) as usize]).unwrap();
        let bomb = dir.join("big.spd.gz");
        std::fs::write(&bomb, enc.finish().unwrap()).unwrap();
        assert!(std::fs::metadata(&bomb).unwrap().len() < FileKind::Spectrum.max_bytes());
        let e = read_file(&bomb, FileKind::Spectrum).unwrap_err();
        assert!(e.to_string().contains("once decompressed"), "{e}");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[cfg(unix)]
    #[test]
    fn read_file_refuses_devices_and_pipes_without_reading_or_waiting() {
        for kind in [FileKind::Scene, FileKind::BsdfTable, FileKind::Image] {
            let e = read_file(Path::new("/dev/zero"), kind).unwrap_err();
            assert!(e.to_string().contains("device, pipe or socket"), "{e}");
        }
        let dir = temp_dir("fifo");
        let fifo = dir.join("pipe.pbrt");
        let made = std::process::Command::new("mkfifo").arg(&fifo).status();
        assert!(made.is_ok_and(|s| s.success()), "mkfifo failed");
        // Opening the pipe would wait for a writer forever.
        let e = read_file(&fifo, FileKind::Scene).unwrap_err();
        assert!(e.to_string().contains("device, pipe or socket"), "{e}");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn a_released_text_is_read_again_for_diagnostics_and_locations_do_not_change() {
        let dir = temp_dir("release");
        let path = dir.join("scene.pbrt");
        let text = "# héllo\nShape \"sphère\" \"float radius\" [ -1 ]\n  é\nWorldEnd";
        std::fs::write(&path, text).unwrap();
        let file = SourceFile::read_from(&path, text.to_owned());
        let before: Vec<_> = (0..=text.len())
            .map(|o| (Loc::new(&file, o).line_col(), Loc::new(&file, o).snippet()))
            .collect();
        file.release_text();
        assert!(
            file.text.lock().unwrap().is_none(),
            "the text is still held"
        );
        for (o, b) in before.iter().enumerate() {
            let loc = Loc::new(&file, o);
            assert_eq!(&(loc.line_col(), loc.snippet()), b, "at {o}");
        }
        assert_eq!(file.text().as_str(), text);
        // A file changed since: no quote from the wrong text, nor a panic.
        std::fs::write(&path, "WorldBegin\n").unwrap();
        assert_eq!(file.text().as_str(), "");
        // The line still comes from the index; a column on a non-ASCII line needs the text.
        assert_eq!(Loc::new(&file, 12).line_col().0, 2);
        let _ = Loc::new(&file, 12).snippet();
        // A text given in memory has no file to read again: it is kept.
        let kept = SourceFile::new(&path, "Shape");
        kept.release_text();
        assert_eq!(kept.text().as_str(), "Shape");
        std::fs::remove_dir_all(&dir).unwrap();
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
