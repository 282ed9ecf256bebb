//! Helpers shared by the test modules.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU32, Ordering};

/// Whether missing prerequisites (shared scenes, a GPU adapter) must fail tests rather
/// than skip them.
pub fn in_ci() -> bool {
    std::env::var("CI").is_ok_and(|v| v == "true")
}

/// Says that a test skips, and why, on standard error itself: the test harness captures
/// `eprintln!` of passing tests, which would hide the skip. Under `CI=true` (shared scenes)
/// and `GPURT_REQUIRE_GPU=1` (an adapter) the callers fail instead of skipping.
pub fn skip(why: &str) {
    use std::io::Write;
    let test = std::thread::current()
        .name()
        .unwrap_or("a test")
        .to_string();
    let _ = writeln!(std::io::stderr(), "SKIPPED {test}: {why}");
}

/// A device for the tests that need one. Without an adapter they skip with a message,
/// except under `GPURT_REQUIRE_GPU=1`, where they fail.
pub fn gpu_context() -> Option<gpurt::gpu::GpuContext> {
    match gpurt::gpu::open(None) {
        Ok(ctx) => Some(ctx),
        Err(e) if std::env::var("GPURT_REQUIRE_GPU").is_ok_and(|v| v == "1") => {
            panic!("GPURT_REQUIRE_GPU=1 but: {e}")
        }
        Err(e) => {
            skip(&format!("no GPU adapter: {e}"));
            None
        }
    }
}

/// `../shared/scenes` next to the checkout. When it is missing, tests skip with a message,
/// except under `CI=true`, where they fail.
pub fn shared_scenes() -> Option<PathBuf> {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared/scenes");
    if dir.is_dir() {
        Some(dir)
    } else if in_ci() {
        panic!("{} is missing (required under CI=true)", dir.display());
    } else {
        skip(&format!("{} is missing", dir.display()));
        None
    }
}

/// The project's own `scenes/` directory.
pub fn own_scenes() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scenes")
}

/// Files under `dir` (recursively) whose names end with one of `suffixes`, sorted: the
/// one walker every test that lists scene files uses. A directory that cannot be read
/// fails the test rather than shrinking the list.
pub fn files_with(dir: &Path, suffixes: &[&str]) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        let entries = std::fs::read_dir(&d).unwrap_or_else(|e| panic!("{}: {e}", d.display()));
        for e in entries {
            let p = e.expect("directory entry").path();
            if p.is_dir() {
                stack.push(p);
            } else if suffixes.iter().any(|s| p.to_string_lossy().ends_with(s)) {
                out.push(p);
            }
        }
    }
    out.sort();
    out
}

/// A new empty directory for one test's files, under cargo's per-target temporary
/// directory (inside `target/`), unique per call so parallel tests never collide.
pub fn temp_dir(tag: &str) -> PathBuf {
    static N: AtomicU32 = AtomicU32::new(0);
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!(
        "{tag}-{}-{}",
        std::process::id(),
        N.fetch_add(1, Ordering::Relaxed)
    ));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("temporary directory can be created");
    dir
}
