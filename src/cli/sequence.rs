//! `gpurt SCENE.aff --frames A..B -o out/frame-%04d.png`: the frames of an animated
//! scene, each written as soon as it is traced, with a progress bar over frames; with
//! `--shard I/N` a farm task's share of them, and with `--resume` the frames not yet
//! written only.

use std::process::ExitCode;
use std::time::{Duration, Instant};

use gpurt::commands::run;
use gpurt::commands::sequence::{self, FrameReport};
use gpurt::pack::frames::FrameTree;
use gpurt::session::{self, Missing};
use gpurt::{Error, atomic, film};
use indicatif::{ProgressBar, ProgressStyle};

use super::args::RenderArgs;
use super::farm::one_backend_no_wireframe;
use super::{cancel_on_signals, print_note, print_threads, print_warnings};

/// `gpurt SCENE --frames ...`.
pub fn sequence(args: &RenderArgs) -> gpurt::Result<ExitCode> {
    let frames = args.frames.expect("called for --frames");
    let [scene] = &args.scenes[..] else {
        eprintln!("gpurt: --frames renders the frames of one animated scene; give one");
        return Ok(ExitCode::from(2));
    };
    let Some(output) = &args.output else {
        eprintln!(
            "gpurt: --frames needs -o with a frame number in its name (-o out/frame-%04d.png)"
        );
        return Ok(ExitCode::from(2));
    };
    if !one_backend_no_wireframe(args, "a sequence") {
        return Ok(ExitCode::from(2));
    }
    film::Format::from_path(output)?;
    let start = Instant::now();
    let read = run::read(scene, args.view.as_deref(), &args.read_options())?;
    let name = scene.display().to_string();
    let not_animated = |why: &str| Error::Scene {
        file: name.clone(),
        msg: format!("--frames needs an animated scene, and {why}"),
    };
    let range = match read.animation() {
        None => return Err(not_animated("nothing moves in this one")),
        Some(a) => a
            .range
            .ok_or_else(|| not_animated("this one has no time range (no 'a' statement)"))?,
    };
    let frames = frames
        .resolve(&range)
        .map_err(|msg| Error::Scene { file: name, msg })?;
    let mut todo = sequence::outputs(frames, output)?;
    if let Some(shard) = args.shard {
        todo = shard.take(&todo).into_iter().cloned().collect();
    }
    let asked = todo.len();
    if args.resume {
        todo.retain(|(_, out)| !out.exists());
    }
    for (_, out) in &todo {
        if let Some(dir) = out.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
        }
        atomic::check_writable(out)?;
    }
    let cancel = cancel_on_signals();
    let found = session::choose(args.backend, args.adapter.as_deref(), Missing::Cpu)?;
    print_note(&found, args.verbose || args.stats);
    print_threads(args.verbose || args.stats);
    if args.resume && todo.len() < asked {
        eprintln!(
            "gpurt: {} of {asked} frames written already (--resume); rendering {}",
            asked - todo.len(),
            todo.len()
        );
    }
    let bar = ProgressBar::new(todo.len() as u64);
    bar.set_style(
        ProgressStyle::with_template("{elapsed_precise} [{wide_bar}] frame {pos}/{len} {msg}")
            .expect("valid template"),
    );
    let reports = sequence::render(
        &read,
        &todo,
        &args.overrides(),
        found.gpu,
        &|r| {
            bar.set_message(format!("t = {:.3}", r.time));
            bar.inc(1);
        },
        &cancel,
    );
    bar.finish_and_clear();
    let reports = reports?;
    // The reader's warnings once, not once a frame.
    print_warnings(read.warnings());
    if args.verbose || args.stats {
        print_stats(&reports, start.elapsed());
    }
    Ok(ExitCode::SUCCESS)
}

/// How the frames' trees were made: `3 whole`, or `2 rebuilt, 6 refitted (worn to at
/// most 1.12)` (the moving part's; the still part's is built once).
fn describe_trees(reports: &[FrameReport]) -> String {
    let (mut whole, mut rebuilt, mut refitted, mut worn) = (0, 0, 0, 1.0f64);
    for r in reports {
        match r.tree {
            FrameTree::Whole => whole += 1,
            FrameTree::Rebuilt => rebuilt += 1,
            FrameTree::Refitted(w) => {
                refitted += 1;
                worn = worn.max(w);
            }
        }
    }
    let mut parts = Vec::new();
    if whole > 0 {
        parts.push(format!("{whole} whole"));
    }
    if rebuilt > 0 {
        parts.push(format!("{rebuilt} rebuilt"));
    }
    if refitted > 0 {
        parts.push(format!("{refitted} refitted (worn to at most {worn:.2})"));
    }
    parts.join(", ")
}

/// Per frame, on average: building against tracing; and frames a second overall.
fn print_stats(reports: &[FrameReport], total: Duration) {
    let n = reports.len().max(1) as f64;
    let mean = |f: fn(&FrameReport) -> Duration| {
        reports.iter().map(|r| f(r).as_secs_f64()).sum::<f64>() / n
    };
    let rays: u64 = reports.iter().map(|r| r.rays).sum();
    let trace: f64 = reports.iter().map(|r| r.trace.as_secs_f64()).sum();
    eprintln!(
        "frame       {:.4} s place + build, {:.4} s trace, {:.4} s write (mean of {})",
        mean(|r| r.build),
        mean(|r| r.trace),
        mean(|r| r.write),
        reports.len()
    );
    eprintln!(
        "sequence    {} frames in {:.3} s ({:.2} frames/s), {:.2} Mrays/s tracing",
        reports.len(),
        total.as_secs_f64(),
        reports.len() as f64 / total.as_secs_f64().max(1e-9),
        rays as f64 / trace.max(1e-9) / 1e6
    );
    eprintln!("trees       {}", describe_trees(reports));
    if let Some(m) = run::peak_memory() {
        eprintln!("peak memory {:.1} MiB", m as f64 / (1 << 20) as f64);
    }
}
