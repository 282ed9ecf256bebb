//! Writing files atomically: a temporary file beside the target, synced, then renamed
//! over it, so a reader sees the old file or the complete new one, never a partial write.

use std::fs::{self, File, OpenOptions};
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

use crate::{Error, Result};

/// Writes `bytes` to `path` atomically: see [`write_atomic_with`].
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    write_atomic_with(path, |w| w.write_all(bytes).map_err(|e| Error::io(path, e)))
}

/// Distinguishes temporary files of concurrent writes from one process (e.g. parallel tests).
static TEMP_COUNTER: AtomicU64 = AtomicU64::new(0);

/// Runs `write` on a fresh temporary file in the target's directory (`.NAME.tmp-PID-N`),
/// syncs it, then renames it over the target. Renaming within one directory is atomic, so
/// readers see either the old file or the complete new one, never a partial write. On any
/// error the temporary file is removed and the target is left as it was.
///
/// The target is `path` with symbolic links followed (`-o latest.png` where `latest.png`
/// links elsewhere writes the file it points to and keeps the link), and an existing
/// target keeps its permissions.
pub fn write_atomic_with(
    path: &Path,
    write: impl FnOnce(&mut BufWriter<File>) -> Result<()>,
) -> Result<()> {
    let target = follow_links(path);
    let path = target.as_path();
    let temp = temp_path(path)?;
    let permissions = fs::metadata(path).ok().map(|m| m.permissions());
    // create_new: never reuse (or clobber) a file we did not create.
    let file = OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(&temp)
        .map_err(|e| Error::io(path, e))?;
    let result = (|| {
        let mut w = BufWriter::new(file);
        write(&mut w)?;
        // The file is closed at the end of this block, before the rename.
        {
            let file = w
                .into_inner()
                .map_err(|e| Error::io(path, e.into_error()))?;
            if let Some(p) = permissions {
                file.set_permissions(p).map_err(|e| Error::io(path, e))?;
            }
            // Without the sync a crash soon after the rename can leave an empty file behind.
            file.sync_all().map_err(|e| Error::io(path, e))?;
        }
        fs::rename(&temp, path).map_err(|e| Error::io(path, e))
    })();
    if result.is_err() {
        // Best effort: the original error is the one worth reporting.
        let _ = fs::remove_file(&temp);
    }
    result
}

/// `path` with symbolic links followed to the file they name (which may not exist yet);
/// `path` itself when it is no link, or after 40 links (a loop: the write then fails on
/// the link as the system reports it).
fn follow_links(path: &Path) -> PathBuf {
    let mut p = path.to_path_buf();
    for _ in 0..40 {
        match fs::read_link(&p) {
            Ok(to) => p = p.parent().unwrap_or(Path::new("")).join(to),
            Err(_) => return p,
        }
    }
    path.to_path_buf()
}

/// Longest file name most file systems take, in bytes.
const NAME_MAX: usize = 255;

fn temp_path(path: &Path) -> Result<PathBuf> {
    let name = path
        .file_name()
        .ok_or_else(|| Error::Image(format!("{}: not a file name to write to", path.display())))?;
    let n = TEMP_COUNTER.fetch_add(1, Ordering::Relaxed);
    let suffix = format!(".tmp-{}-{n}", std::process::id());
    let mut temp_name = std::ffi::OsString::from(".");
    if 1 + name.len() + suffix.len() <= NAME_MAX {
        temp_name.push(name);
    } else {
        // A name near the limit: the temporary one must not be longer.
        temp_name.push("gpurt");
    }
    temp_name.push(suffix);
    Ok(path.with_file_name(temp_name))
}

/// Fails when `path` cannot be written (its directory is missing, or is not writable), so
/// that a render is refused before it starts rather than after it ends. Tries by creating
/// and removing a temporary file where the real one will go.
pub fn check_writable(path: &Path) -> Result<()> {
    let target = follow_links(path);
    let temp = temp_path(&target)?;
    OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(&temp)
        .map_err(
            |e| match target.parent().filter(|d| !d.as_os_str().is_empty()) {
                Some(dir) if e.kind() == std::io::ErrorKind::NotFound && !dir.is_dir() => {
                    Error::io(
                        path,
                        std::io::Error::new(
                            e.kind(),
                            format!("the folder {} does not exist", dir.display()),
                        ),
                    )
                }
                _ => Error::io(path, e),
            },
        )?;
    let _ = fs::remove_file(&temp);
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::film::Film;
    use crate::film::tests::{dir_entries, scratch_dir};

    #[test]
    fn failed_write_keeps_existing_file_and_removes_temp() {
        let dir = scratch_dir("keepold");
        let path = dir.join("out.png");
        fs::write(&path, b"good old image").unwrap();
        // An encoder that fails halfway through, after writing part of its output.
        let err = write_atomic_with(&path, |w| {
            w.write_all(b"partial").unwrap();
            w.flush().unwrap();
            Err(Error::Image("encoder failed".into()))
        })
        .unwrap_err();
        assert_eq!(err.to_string(), "encoder failed");
        // A real encoder failure: a zero-sized image cannot be encoded as PNG.
        assert!(Film::new(0, 0).save(&path).is_err());
        assert_eq!(fs::read(&path).unwrap(), b"good old image");
        assert_eq!(dir_entries(&dir), ["out.png"]);
        // And a successful write does replace it.
        write_atomic(&path, b"new").unwrap();
        assert_eq!(fs::read(&path).unwrap(), b"new");
        assert_eq!(dir_entries(&dir), ["out.png"]);
        fs::remove_dir_all(&dir).unwrap();
    }
}
