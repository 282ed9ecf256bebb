//! Reading the small files gpurt keeps or is handed beside a scene (a tuning, a shard
//! manifest, a viewer script, the pipeline cache) no further than a bound: a file's
//! length says nothing of a pipe or a device such as /dev/zero, so the bound is kept
//! while reading, and no such file costs more memory than its bound.

use std::io::Read;
use std::path::Path;

/// The bytes of the file at `path`, or `None` where it holds more than `max` bytes (of
/// which no more than `max + 1` are read).
pub fn read(path: &Path, max: u64) -> std::io::Result<Option<Vec<u8>>> {
    let mut bytes = Vec::new();
    std::fs::File::open(path)?
        .take(max + 1)
        .read_to_end(&mut bytes)?;
    Ok((bytes.len() as u64 <= max).then_some(bytes))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A file within its bound is read whole; one past it, or a device that never ends,
    /// is `None` after `max + 1` bytes.
    #[test]
    fn files_are_read_up_to_their_bound() {
        let path = std::env::temp_dir().join(format!("gpurt-bounded-{}", std::process::id()));
        std::fs::write(&path, b"four").unwrap();
        assert_eq!(read(&path, 4).unwrap().as_deref(), Some(&b"four"[..]));
        assert_eq!(read(&path, 3).unwrap(), None);
        std::fs::remove_file(&path).unwrap();
        if Path::new("/dev/zero").exists() {
            assert_eq!(read(Path::new("/dev/zero"), 1 << 10).unwrap(), None);
        }
    }
}
