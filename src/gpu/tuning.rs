//! What `gpurt tune` measured fastest on an adapter (a `policy::Strategy`: the walk of the
//! BVH, the kernels of a colour frame, how the shaders read the scene), kept as a small
//! text file an adapter in the cache directory and taken by every renderer made for that
//! adapter in place of `policy::defaults`; the variables of the environment still
//! override it. A file written by another version of gpurt, or for another driver, is
//! passed over: its figures were another shader's, or another compiler's.
//!
//! The file, as `gpurt tune` writes it (`key = value` lines; `#` starts a comment):
//!
//! ```text
//! # gpurt tune: ...
//! gpurt = 0.1.0
//! adapter = NVIDIA H100 80GB HBM3 (Vulkan, NVIDIA 580.159.04)
//! kernels = pooled
//! walk = qwide
//! fetch = buffers
//! measured = 3 scenes at 1920x1080, 1 spp, depth 5: 0.81 of the defaults' time
//! ```

use std::path::{Path, PathBuf};

use super::cache::cache_dir;
use super::policy::{Kernels, Strategy};
use super::shaders::Fetch;
use crate::gpu_types::TRAVERSAL_NAMES;
use crate::util::error::{Error, Result};

/// What a tuning file holds.
#[derive(Clone, Debug, PartialEq)]
pub struct Tuning {
    pub strategy: Strategy,
    /// What it was measured on and what it gained, as `gpurt tune` put it.
    pub measured: String,
    /// Where it is kept.
    pub file: PathBuf,
}

/// The file kept for `info`'s adapter, where there is a cache directory (`cache_dir`):
/// one a backend, vendor and device.
pub fn file(info: &wgpu::AdapterInfo) -> Option<PathBuf> {
    let backend = format!("{:?}", info.backend).to_lowercase();
    let name = format!("tuning-{backend}-{:x}-{:x}.txt", info.vendor, info.device);
    Some(cache_dir()?.join(name))
}

/// How the file names the adapter and driver it was measured on: a file naming another
/// is passed over.
fn adapter(info: &wgpu::AdapterInfo) -> String {
    format!(
        "{} ({:?}, {} {})",
        info.name, info.backend, info.driver, info.driver_info
    )
}

/// The most a tuning file is read of: `save` writes a few hundred bytes.
const MAX_BYTES: u64 = 64 << 10;

/// The version of gpurt that reads and writes the files.
const VERSION: &str = env!("CARGO_PKG_VERSION");

/// The tuning kept for `info`'s adapter: `None` where there is no file, no cache
/// directory, or a file for another version of gpurt or another driver. A file that
/// cannot be read, or says something else than `save` writes, is an error naming its
/// line and column, so that an edited file is not silently ignored.
pub fn load(info: &wgpu::AdapterInfo) -> Result<Option<Tuning>> {
    let Some(path) = file(info) else {
        return Ok(None);
    };
    // Read up to a bound: whatever the cache directory holds, no unbounded allocation.
    let bytes = match crate::util::bounded::read(&path, MAX_BYTES) {
        Ok(Some(bytes)) => bytes,
        Ok(None) => {
            return Err(Error::Scene {
                file: path.display().to_string(),
                msg: format!("longer than a tuning file can be ({MAX_BYTES} bytes); delete it"),
            });
        }
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
        Err(e) => return Err(Error::io(&path, e)),
    };
    parse(&String::from_utf8_lossy(&bytes), &path, &adapter(info))
}

/// Writes `strategy` as the tuning of `info`'s adapter, `measured` saying what it was
/// measured on (one line). Returns the file written, or `None` where there is no cache
/// directory.
pub fn save(
    info: &wgpu::AdapterInfo,
    strategy: Strategy,
    measured: &str,
) -> Result<Option<PathBuf>> {
    let Some(path) = file(info) else {
        return Ok(None);
    };
    if let Some(dir) = path.parent() {
        std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    }
    let text = format(strategy, &adapter(info), measured);
    crate::util::atomic::write_atomic(&path, text.as_bytes())?;
    Ok(Some(path))
}

/// The file's text.
fn format(strategy: Strategy, adapter: &str, measured: &str) -> String {
    format!(
        "# gpurt tune: the walk, kernels and fetch measured fastest on this adapter, taken by\n\
         # every render on it (GPURT_TRAVERSAL, GPURT_KERNELS and GPURT_FETCH still override\n\
         # them). Delete the file to go back to the defaults, or run gpurt tune again.\n\
         gpurt = {VERSION}\n\
         adapter = {adapter}\n\
         kernels = {}\n\
         walk = {}\n\
         fetch = {}\n\
         measured = {}\n",
        strategy.kernels.name(),
        TRAVERSAL_NAMES[strategy.traversal as usize],
        strategy.fetch.name(),
        measured.replace('\n', " "),
    )
}

/// What `text`, the file at `path`, holds for the adapter `adapter` names.
fn parse(text: &str, path: &Path, adapter: &str) -> Result<Option<Tuning>> {
    let error = |line: usize, col: usize, msg: String| Error::Parse {
        file: path.display().to_string(),
        line: line as u32 + 1,
        col: col as u32 + 1,
        msg,
        excerpt: None,
    };
    let mut version = None;
    let mut kept_for = None;
    let (mut kernels, mut walk, mut fetch, mut measured) = (None, None, None, None);
    for (n, line) in text.lines().enumerate() {
        let trimmed = line.trim_start();
        if trimmed.is_empty() || trimmed.starts_with('#') {
            continue;
        }
        let Some((key, value)) = line.split_once('=') else {
            let col = line.len() - trimmed.len();
            return Err(error(n, col, "expected `key = value`".into()));
        };
        let col = key.len() + 1 + (value.len() - value.trim_start().len());
        let value = value.trim();
        let bad = |what: &str| error(n, col, format!("{what}: `{value}`"));
        match key.trim() {
            "gpurt" => version = Some(value),
            "adapter" => kept_for = Some(value),
            "kernels" => {
                kernels = Some(
                    Kernels::from_name(value)
                        .ok_or_else(|| bad("expected main, wavefront or pooled"))?,
                )
            }
            "walk" => {
                let t = TRAVERSAL_NAMES.iter().position(|&t| t == value);
                let names = TRAVERSAL_NAMES.join(", ");
                walk = Some(t.ok_or_else(|| bad(&format!("expected one of {names}")))? as u32);
            }
            "fetch" => {
                fetch = Some(match value {
                    "textures" => Fetch::Textures,
                    "buffers" => Fetch::Buffers,
                    _ => return Err(bad("expected textures or buffers")),
                })
            }
            "measured" => measured = Some(value.to_string()),
            other => {
                let col = line.len() - trimmed.len();
                return Err(error(n, col, format!("unknown key `{other}`")));
            }
        }
    }
    let lines = text.lines().count();
    let missing = |key: &str| error(lines, 0, format!("no `{key} = ...` line"));
    let version = version.ok_or_else(|| missing("gpurt"))?;
    let kept_for = kept_for.ok_or_else(|| missing("adapter"))?;
    let strategy = Strategy {
        traversal: walk.ok_or_else(|| missing("walk"))?,
        kernels: kernels.ok_or_else(|| missing("kernels"))?,
        fetch: fetch.ok_or_else(|| missing("fetch"))?,
    };
    if version != VERSION || kept_for != adapter {
        return Ok(None);
    }
    Ok(Some(Tuning {
        strategy,
        measured: measured.unwrap_or_default(),
        file: path.to_path_buf(),
    }))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gpu_types::{TRAVERSAL_QWIDE, TRAVERSAL_WIDE};

    const ADAPTER: &str = "llvmpipe (Vulkan, llvmpipe Mesa 22.3.6)";

    /// What `format` writes, `parse` reads back, for every kind of kernels, walk and fetch.
    #[test]
    fn a_file_reads_back_what_was_written() {
        let path = Path::new("tuning.txt");
        for kernels in Kernels::ALL {
            for traversal in 0..TRAVERSAL_NAMES.len() as u32 {
                for fetch in [Fetch::Textures, Fetch::Buffers] {
                    let strategy = Strategy {
                        traversal,
                        kernels,
                        fetch,
                    };
                    let text = format(strategy, ADAPTER, "2 scenes\nat 64x64");
                    let read = parse(&text, path, ADAPTER).unwrap().unwrap();
                    assert_eq!(read.strategy, strategy);
                    assert_eq!(read.measured, "2 scenes at 64x64");
                }
            }
        }
    }

    /// A file for another version or adapter is passed over; one that says anything else
    /// than a tuning file says is an error at its line and column.
    #[test]
    fn a_stale_file_is_passed_over_and_a_broken_one_refused() {
        let path = Path::new("t.txt");
        let strategy = Strategy {
            traversal: TRAVERSAL_QWIDE,
            kernels: Kernels::Pooled,
            fetch: Fetch::Buffers,
        };
        let text = format(strategy, ADAPTER, "m");
        assert_eq!(parse(&text, path, "another GPU").unwrap(), None);
        let older = text.replace(VERSION, "0.0.0-older");
        assert_eq!(parse(&older, path, ADAPTER).unwrap(), None);
        let wide = text.replace("walk = qwide", "walk = wide");
        let read = parse(&wide, path, ADAPTER).unwrap().unwrap();
        assert_eq!(read.strategy.traversal, TRAVERSAL_WIDE);

        let line_of = |key: &str| text.lines().position(|l| l.starts_with(key)).unwrap() + 1;
        for (from, to, line, col, says) in [
            (
                "walk = qwide",
                "walk = quad",
                line_of("walk"),
                8,
                "expected one of",
            ),
            (
                "fetch = buffers",
                "fetch =  buffer",
                line_of("fetch"),
                10,
                "textures or buffers",
            ),
            (
                "kernels = pooled",
                "kernels = mega",
                line_of("kernels"),
                11,
                "main, wavefront or pooled",
            ),
            (
                "walk = qwide",
                "walk qwide",
                line_of("walk"),
                1,
                "key = value",
            ),
            (
                "walk = qwide",
                "  speed = 9",
                line_of("walk"),
                3,
                "unknown key `speed`",
            ),
            (
                "walk = qwide\n",
                "",
                text.lines().count(),
                1,
                "no `walk = ...` line",
            ),
        ] {
            let broken = text.replace(from, to);
            let e = parse(&broken, path, ADAPTER).unwrap_err().to_string();
            assert!(e.starts_with(&format!("t.txt:{line}:{col}: ")), "{e}");
            assert!(e.contains(says), "{e}");
        }
    }
}
