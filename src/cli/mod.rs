//! The `gpurt` command line, one module per group of commands: `args` (what every
//! command accepts), `render` (one scene), `farm` (many scenes, shards of one image, and
//! their merge), `sequence` (the frames of an animated scene), `tools` (info, diff, view, bench). Each calls the library and prints;
//! what they share (signals, the note about the backend, the readers' warnings) is here.

pub mod args;
pub mod farm;
pub mod render;
pub mod report;
pub mod sequence;
pub mod shell;
pub mod tools;

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

use gpurt::session::Found;

/// Makes rayon's global pool, which every CPU render, BVH build and image conversion
/// runs on, `n` threads (`--threads`); called before anything uses it.
pub fn use_threads(n: u32) -> Result<(), String> {
    rayon::ThreadPoolBuilder::new()
        .num_threads(n as usize)
        .build_global()
        .map_err(|e| e.to_string())
}

/// Prints, with `-v`, how many threads render on the CPU and how that was chosen.
pub fn print_threads(verbose: bool) {
    if verbose {
        let how = if std::env::var_os("RAYON_NUM_THREADS").is_some() {
            "--threads or RAYON_NUM_THREADS"
        } else {
            "--threads/-j to choose; default one a core"
        };
        eprintln!("threads     {} ({how})", rayon::current_num_threads());
    }
}

/// A flag that Ctrl-C (SIGINT), SIGTERM or SIGHUP sets: the render stops and nothing is
/// written. One that comes during a save lets the save finish (it is atomic), so no
/// temporary file is ever left behind.
pub fn cancel_on_signals() -> Arc<AtomicBool> {
    let cancel = Arc::new(AtomicBool::new(false));
    let flag = cancel.clone();
    let _ = ctrlc::set_handler(move || flag.store(true, Ordering::Relaxed));
    cancel
}

/// Prints the line about the choice of backend: always when it is a warning, else when
/// `verbose`.
pub fn print_note(found: &Found, verbose: bool) {
    if let Some(note) = &found.note
        && (note.warning || verbose)
    {
        eprintln!("{}", note.text);
    }
}

/// Prints the readers' warnings about a scene.
pub fn print_warnings(warnings: &[String]) {
    for w in warnings {
        eprintln!("gpurt: warning: {w}");
    }
}
