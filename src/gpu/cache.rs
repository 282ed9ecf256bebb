//! The directory gpurt keeps what it learns about an adapter in between runs: the
//! pipeline cache (`pipeline::DiskCache`) and what `gpurt tune` measured (`tuning`).

use std::path::PathBuf;

/// `GPURT_CACHE_DIR`, else `$XDG_CACHE_HOME/gpurt`, else `~/.cache/gpurt`.
/// `GPURT_CACHE_DIR=` (empty) turns both off: nothing is read or written.
pub fn cache_dir() -> Option<PathBuf> {
    if let Ok(d) = std::env::var("GPURT_CACHE_DIR") {
        return (!d.is_empty()).then(|| PathBuf::from(d));
    }
    let base = std::env::var_os("XDG_CACHE_HOME")
        .map(PathBuf::from)
        .or_else(|| std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".cache")))?;
    Some(base.join("gpurt"))
}
