//! Helpers shared by the test modules: whether to skip or fail, where the scenes are,
//! temporary directories, a seedable random source, and the `gpurt` binary. Apart:
//! `inputs` (the scene texts and files the tests write), `oracle` (expected values
//! computed independently of the renderer), `whitted` (an independent f64 tracer of the
//! whole model), `versus` (the GPU against the CPU).

pub mod inputs;
pub mod oracle;
pub mod versus;
pub mod whitted;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use glam::Vec3;
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
    if let Ok(mut skipped) = SKIPPED.lock() {
        skipped.push((test, why.to_string()));
    }
}

/// The tests that skipped, and why, for the summary printed after the harness's last line.
static SKIPPED: std::sync::Mutex<Vec<(String, String)>> = std::sync::Mutex::new(Vec::new());

/// After the harness's `test result` line, as the process exits: how many tests skipped
/// and why, the reasons counted, so that a run that skipped says so in the last lines a
/// reader sees rather than only among hundreds of test lines. (Run by the C library's
/// exit, which the harness calls: a function in `.fini_array` on Linux,
/// `__mod_term_func` on macOS; elsewhere the per-test lines stand alone.)
extern "C" fn print_skipped() {
    use std::io::Write;
    let Ok(skipped) = SKIPPED.lock() else { return };
    if skipped.is_empty() {
        return;
    }
    let mut reasons: Vec<(usize, &str)> = Vec::new();
    for (_, why) in skipped.iter() {
        // A reason without its test-specific tail (a path's file name, an error's words).
        let why = why.split(": ").next().unwrap_or(why);
        match reasons.iter_mut().find(|(_, r)| *r == why) {
            Some((n, _)) => *n += 1,
            None => reasons.push((1, why)),
        }
    }
    let mut err = std::io::stderr().lock();
    let n = skipped.len();
    let tests = if n == 1 { "test" } else { "tests" };
    let _ = writeln!(
        err,
        "\n{n} {tests} skipped (their SKIPPED lines above say which):"
    );
    for (n, why) in reasons {
        let _ = writeln!(err, "  {n:4}  {why}");
    }
}

#[cfg(target_os = "linux")]
#[used]
#[unsafe(link_section = ".fini_array")]
static PRINT_SKIPPED: extern "C" fn() = print_skipped;

#[cfg(target_os = "macos")]
#[used]
#[unsafe(link_section = "__DATA,__mod_term_func")]
static PRINT_SKIPPED: extern "C" fn() = print_skipped;

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

/// xorshift64*: deterministic, seedable, good enough to spray rays.
pub struct XorShift(pub u64);

impl XorShift {
    pub fn next_u64(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_f491_4f6c_dd1d)
    }
    /// Uniform in [0, 1).
    pub fn unit(&mut self) -> f32 {
        (self.next_u64() >> 40) as f32 * (1.0 / (1u64 << 24) as f32)
    }
    pub fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.unit()
    }
    pub fn point_in(&mut self, lo: Vec3, hi: Vec3) -> Vec3 {
        Vec3::new(
            self.range(lo.x, hi.x),
            self.range(lo.y, hi.y),
            self.range(lo.z, hi.z),
        )
    }
    /// Uniform on the unit sphere (rejection from the cube).
    pub fn direction(&mut self) -> Vec3 {
        loop {
            let v = self.point_in(Vec3::NEG_ONE, Vec3::ONE);
            let l2 = v.length_squared();
            if l2 > 1e-4 && l2 <= 1.0 {
                return v / l2.sqrt();
            }
        }
    }
}

/// Runs the `gpurt` binary in `dir` (with the pipeline cache off, so that every run
/// compiles as a first run does).
pub fn gpurt(args: &[&str], dir: &Path) -> Output {
    Command::new(env!("CARGO_BIN_EXE_gpurt"))
        .args(args)
        .current_dir(dir)
        .env("GPURT_CACHE_DIR", "")
        .output()
        .expect("gpurt runs")
}

/// A fresh directory under target/ for one test.
pub fn workdir(name: &str) -> PathBuf {
    let d = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("target/cli-tests")
        .join(name);
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// The error output of a finished command, as text.
pub fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}
