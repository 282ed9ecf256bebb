//! Reading a scene file's bytes: which reader a file is for (`FileKind`, from its
//! extension), and the file opened as a stream (`open`), decompressed as it is read when
//! it is gzip. The readers pull from that stream through a buffer of fixed size
//! (`lex::Lexer`, the binary STL reader), so that no file is ever held whole: memory
//! grows with what the scene holds, not with the file. Apart from the readers, which
//! know nothing of files.

use std::io::{self, BufRead, BufReader, Read};
use std::path::{Component, Path, PathBuf};

use crate::util::error::{Error, Result};
use crate::util::limits::MAX_FILE_BYTES;

/// What a file holds, from its extension (after stripping `.gz`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FileKind {
    Nff,
    Stl,
    Obj,
    Ply,
    Gltf,
}

impl FileKind {
    pub fn of(path: &Path) -> FileKind {
        let name = path
            .file_name()
            .map(|n| n.to_string_lossy().to_ascii_lowercase())
            .unwrap_or_default();
        let name = name.strip_suffix(".gz").unwrap_or(&name);
        if name.ends_with(".stl") {
            FileKind::Stl
        } else if name.ends_with(".obj") {
            FileKind::Obj
        } else if name.ends_with(".ply") {
            FileKind::Ply
        } else if name.ends_with(".gltf") || name.ends_with(".glb") {
            FileKind::Gltf
        } else {
            FileKind::Nff
        }
    }
}

/// A file's bytes as a stream, decompressed when the file is gzip, and their number when
/// it is known before reading (a plain file's size, the length of bytes in memory; not a
/// gzip file's, whose trailer may lie).
pub struct Input<'a> {
    pub reader: Box<dyn Read + 'a>,
    pub len: Option<u64>,
}

impl<'a> Input<'a> {
    /// Bytes already in memory, read as a file with those contents would be: decompressed
    /// when they start with the gzip magic bytes.
    pub fn bytes(bytes: &'a [u8]) -> Input<'a> {
        if bytes.starts_with(&GZIP_MAGIC) {
            Input {
                reader: Box::new(Gunzip::new(bytes, MAX_FILE_BYTES)),
                len: None,
            }
        } else {
            Input {
                reader: Box::new(bytes),
                len: Some(bytes.len() as u64),
            }
        }
    }
}

const GZIP_MAGIC: [u8; 2] = [0x1f, 0x8b];

/// Opens a scene file for reading, through a gzip decoder when it starts with the gzip
/// magic bytes (every member, as gzip does). Refuses what is not a regular file.
pub fn open(path: &Path) -> Result<Input<'static>> {
    let not_a_file = |what: &str| Error::Scene {
        file: path.display().to_string(),
        msg: format!("is {what}, not a regular file"),
    };
    // Checked before opening: opening a fifo waits for a writer, and a device such as
    // /dev/zero never ends.
    let meta = std::fs::metadata(path).map_err(|e| Error::io(path, e))?;
    if meta.is_dir() {
        return Err(not_a_file("a directory"));
    }
    if !meta.is_file() {
        return Err(not_a_file("a device, fifo or socket"));
    }
    let file = std::fs::File::open(path).map_err(|e| Error::io(path, e))?;
    // Small: the readers have their own buffers, and reads larger than this one go
    // around it.
    let mut file = BufReader::with_capacity(64 << 10, file);
    let head = file.fill_buf().map_err(|e| Error::io(path, e))?;
    Ok(if head.starts_with(&GZIP_MAGIC) {
        Input {
            reader: Box::new(Gunzip::new(file, MAX_FILE_BYTES)),
            len: None,
        }
    } else {
        Input {
            reader: Box::new(file),
            len: Some(meta.len()),
        }
    })
}

/// The error a reader reports when reading `name`'s bytes failed: the file's own
/// (`Error::Io`), or its decompressed size past the limit (`Error::Scene`).
pub fn read_error(name: &str, e: io::Error) -> Error {
    match e
        .get_ref()
        .and_then(|inner| inner.downcast_ref::<TooLarge>())
    {
        Some(TooLarge(limit)) => {
            let msg = if *limit >= 1 << 30 && limit.is_multiple_of(1 << 30) {
                format!("decompresses to more than {} GiB", limit >> 30)
            } else {
                format!("decompresses to more than {limit} bytes")
            };
            Error::Scene {
                file: name.to_string(),
                msg,
            }
        }
        None => Error::io(PathBuf::from(name), e),
    }
}

/// The file `rel` names below the model's folder `dir`, read whole: a relative path with
/// no `..`, root, drive or scheme (a model's file may name only what travels with it, not
/// whatever the machine that renders it holds), and a regular file of at most `limit`
/// bytes. Why not, in words for a message.
pub fn read_inside(dir: &Path, rel: &str, limit: u64) -> std::result::Result<Vec<u8>, String> {
    let path = Path::new(rel);
    let inside = !rel.contains(':')
        && path
            .components()
            .all(|c| matches!(c, Component::Normal(_) | Component::CurDir));
    if !inside {
        return Err(format!(
            "'{rel}' is outside the model's folder (only relative paths below it are read)"
        ));
    }
    let full = dir.join(path);
    let meta = std::fs::metadata(&full).map_err(|e| format!("cannot read '{rel}': {e}"))?;
    if !meta.is_file() || meta.len() > limit {
        return Err(format!(
            "'{rel}' is not a regular file of at most {} MiB",
            limit >> 20
        ));
    }
    std::fs::read(&full).map_err(|e| format!("cannot read '{rel}': {e}"))
}

/// Reads a file whole, decompressed. For tools and tests: the renderer itself streams.
pub fn read_file(path: &Path) -> Result<Vec<u8>> {
    let mut input = open(path)?;
    let mut out = Vec::with_capacity(input.len.unwrap_or(0) as usize);
    input
        .reader
        .read_to_end(&mut out)
        .map_err(|e| read_error(&path.display().to_string(), e))?;
    Ok(out)
}

/// `raw` as `read_file` returns it for a file at `path` with those contents: decompressed
/// when it starts with the gzip magic bytes, unchanged otherwise. A file that decompresses
/// to more than `limit` bytes is an error (files are held to `MAX_FILE_BYTES`).
pub fn decompress(raw: Vec<u8>, path: &Path, limit: u64) -> Result<Vec<u8>> {
    if !raw.starts_with(&GZIP_MAGIC) {
        return Ok(raw);
    }
    let mut out = Vec::new();
    Gunzip::new(&raw[..], limit)
        .read_to_end(&mut out)
        .map_err(|e| read_error(&path.display().to_string(), e))?;
    Ok(out)
}

/// The payload of the error `Gunzip` returns past its limit (`read_error` names it).
#[derive(Debug)]
struct TooLarge(u64);

impl std::fmt::Display for TooLarge {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "decompresses to more than {} bytes", self.0)
    }
}

impl std::error::Error for TooLarge {}

/// Every gzip member of a stream, one after another as gzip reads them, stopping with an
/// error past `limit` decompressed bytes: a gzip bomb no longer costs memory (nothing is
/// held), but it would cost time. Zero bytes after the last member are padding (tape
/// blocks, `dd`), which `gzip -t` accepts too.
struct Gunzip<R: BufRead> {
    /// The member being read; `None` once the stream has ended.
    member: Option<flate2::bufread::GzDecoder<R>>,
    total: u64,
    limit: u64,
}

impl<R: BufRead> Gunzip<R> {
    fn new(raw: R, limit: u64) -> Self {
        Gunzip {
            member: Some(flate2::bufread::GzDecoder::new(raw)),
            total: 0,
            limit,
        }
    }
}

impl<R: BufRead> Read for Gunzip<R> {
    fn read(&mut self, out: &mut [u8]) -> io::Result<usize> {
        while let Some(member) = &mut self.member {
            let n = member.read(out)?;
            if n > 0 || out.is_empty() {
                self.total += n as u64;
                if self.total > self.limit {
                    return Err(io::Error::other(TooLarge(self.limit)));
                }
                return Ok(n);
            }
            // The member ended: another follows, or padding, or nothing.
            let mut raw = self.member.take().expect("a member").into_inner();
            let mut padded = false;
            loop {
                let rest = raw.fill_buf()?;
                match rest.iter().position(|&b| b != 0) {
                    None if rest.is_empty() => return Ok(0),
                    None => {
                        let n = rest.len();
                        raw.consume(n);
                        padded = true;
                    }
                    Some(0) if !padded => {
                        self.member = Some(flate2::bufread::GzDecoder::new(raw));
                        break;
                    }
                    Some(_) => {
                        return Err(io::Error::new(
                            io::ErrorKind::InvalidData,
                            "invalid gzip header (bytes after the zero padding)",
                        ));
                    }
                }
            }
        }
        Ok(0)
    }
}
