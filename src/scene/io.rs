//! Reading a scene file's bytes: which reader a file is for (`FileKind`, from its
//! extension), the whole file read with a size limit, and gzip decompression that refuses
//! bombs while holding little of them. Apart from the readers, which take bytes and know
//! nothing of files; `load` and the NFF `mesh` include call it.

use std::path::Path;

use crate::error::{Error, Result};
use crate::limits::{HELD_BYTES, MAX_FILE_BYTES};

/// What a file holds, from its extension (after stripping `.gz`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FileKind {
    Nff,
    Stl,
    Obj,
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
        } else {
            FileKind::Nff
        }
    }
}

/// Reads a file whole, decompressing it when it starts with the gzip magic bytes.
pub fn read_file(path: &Path) -> Result<Vec<u8>> {
    use std::io::Read;
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
    let mut raw = Vec::with_capacity(meta.len().min(MAX_FILE_BYTES) as usize);
    // Bounded even so: a file that grows while it is read stops at the limit.
    std::fs::File::open(path)
        .and_then(|f| f.take(MAX_FILE_BYTES + 1).read_to_end(&mut raw))
        .map_err(|e| Error::io(path, e))?;
    if raw.len() as u64 > MAX_FILE_BYTES {
        return Err(Error::Scene {
            file: path.display().to_string(),
            msg: format!("is larger than {} GiB", MAX_FILE_BYTES >> 30),
        });
    }
    decompress(raw, path, MAX_FILE_BYTES)
}

/// `raw` as `read_file` returns it for a file at `path`: decompressed when it starts with
/// the gzip magic bytes (every member, as gzip does), unchanged otherwise. A file that
/// decompresses to more than `limit` bytes is an error (`read_file` uses `MAX_FILE_BYTES`),
/// found holding at most `HELD_BYTES` of it.
pub fn decompress(raw: Vec<u8>, path: &Path, limit: u64) -> Result<Vec<u8>> {
    if !raw.starts_with(&[0x1f, 0x8b]) {
        return Ok(raw);
    }
    let io = |e| Error::io(path, e);
    // The gzip trailer ends with the decompressed size mod 2^32 (ISIZE): exact for the usual
    // one-member file, so the output is allocated once instead of doubling its way up (which
    // would hold up to twice the scene's bytes at the peak). Deflate cannot expand more than
    // about 1032:1, which bounds a lying trailer.
    let isize = raw.len().checked_sub(4).map_or(0, |i| {
        u32::from_le_bytes(raw[i..].try_into().unwrap()) as u64
    });
    let held = limit.min(HELD_BYTES);
    let hint = isize.min(raw.len() as u64 * 1032).min(held);
    let mut out = Vec::with_capacity(hint as usize + 64);
    let mut total = inflate(&raw, &mut out, held + 1).map_err(io)?;
    if total > held {
        // Larger than is held before the size is known: count it all first.
        total = inflate(&raw, &mut std::io::sink(), limit + 1).map_err(io)?;
        if total <= limit {
            out = Vec::with_capacity(total as usize);
            inflate(&raw, &mut out, total).map_err(io)?;
        }
    }
    if total > limit {
        let msg = if limit >= 1 << 30 && limit.is_multiple_of(1 << 30) {
            format!("decompresses to more than {} GiB", limit >> 30)
        } else {
            format!("decompresses to more than {limit} bytes")
        };
        return Err(Error::Scene {
            file: path.display().to_string(),
            msg,
        });
    }
    Ok(out)
}

/// Writes the gzip members of `raw` to `out`, member after member as gzip does, stopping
/// after `room` bytes; returns the bytes written. Zero bytes after the last member are
/// padding (tape blocks, `dd`), which `gzip -t` accepts too.
fn inflate(raw: &[u8], out: &mut impl std::io::Write, room: u64) -> std::io::Result<u64> {
    use std::io::Read;
    let (mut rest, mut written) = (raw, 0);
    while written < room && !rest.iter().all(|&b| b == 0) {
        let mut member = flate2::bufread::GzDecoder::new(rest);
        written += std::io::copy(&mut (&mut member).take(room - written), out)?;
        rest = member.into_inner();
    }
    Ok(written)
}
