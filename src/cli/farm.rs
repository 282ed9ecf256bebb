//! Many renders of one kind: `gpurt SCENE... --out-dir DIR` (a batch on one device),
//! `gpurt SCENE --shard I/N -o DIR` (one process's share of an image) and `gpurt merge`
//! (the shards assembled). Batches and shards are what a job array runs: they render on
//! one backend and print only what goes wrong unless asked.

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::Arc;
use std::time::Instant;

use gpurt::commands::batch::{self, BatchOptions};
use gpurt::commands::run::{self, Prepared};
use gpurt::commands::shard::{self, Manifest, Shard};
use gpurt::session::{self, Backend, CpuRenderer, GpuSession, Missing, Renderer};
use gpurt::{Error, atomic, film, frame};
use indicatif::{ProgressBar, ProgressStyle};

use super::args::{Aov, RenderArgs, ShardBy};
use super::{cancel_on_signals, print_note, print_threads, print_warnings};

/// `gpurt SCENE... --out-dir DIR`: every scene into DIR, one device, failures skipped.
pub fn batch(args: &RenderArgs, dir: &Path) -> gpurt::Result<ExitCode> {
    if args.scenes.is_empty() {
        eprintln!("gpurt: no scene given; try `gpurt --help`");
        return Ok(ExitCode::from(2));
    }
    if !one_backend_no_wireframe(args, "a batch") {
        return Ok(ExitCode::from(2));
    }
    // Names are checked over the whole list, so that no two shards write one file.
    let outputs = batch::outputs(&args.scenes, dir, args.format.format())?;
    let (scenes, outputs): (Vec<PathBuf>, Vec<PathBuf>) = match args.shard {
        Some(shard) => {
            let pairs: Vec<(PathBuf, PathBuf)> = args.scenes.iter().cloned().zip(outputs).collect();
            shard.take(&pairs).into_iter().cloned().unzip()
        }
        None => (args.scenes.clone(), outputs),
    };
    std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    for out in &outputs {
        atomic::check_writable(out)?;
    }
    let cancel = cancel_on_signals();
    let found = session::choose(args.backend, args.adapter.as_deref(), Missing::Cpu)?;
    print_note(&found, args.verbose || args.stats);
    print_threads(args.verbose || args.stats);
    let bar = ProgressBar::new(scenes.len() as u64);
    bar.set_style(
        ProgressStyle::with_template("{elapsed_precise} [{wide_bar}] {pos}/{len} {msg}")
            .expect("valid template"),
    );
    let start = Instant::now();
    let outcome = batch::run(
        &scenes,
        &outputs,
        &BatchOptions {
            overrides: args.overrides(),
            view: args.view.clone(),
            read: args.read_options(),
        },
        found.gpu,
        &|scene| {
            bar.set_message(scene.display().to_string());
            bar.inc(1);
        },
        &cancel,
    );
    bar.finish_and_clear();
    let outcome = outcome?;
    print_warnings(&outcome.warnings);
    for (scene, e) in &outcome.failed {
        // Most errors start with the scene's name already; the others get it.
        let named = e.to_string().starts_with(&scene.display().to_string());
        if named {
            super::report::print_error(e, " (skipped)");
        } else {
            eprintln!("gpurt: {}: {e} (skipped)", scene.display());
        }
    }
    if args.verbose || args.stats || !outcome.failed.is_empty() {
        let secs = start.elapsed().as_secs_f64();
        eprintln!(
            "batch       {} of {} scenes rendered into {} in {secs:.2} s ({:.1} scenes/s, {:.2} Mrays/s)",
            outcome.rendered,
            scenes.len(),
            dir.display(),
            outcome.rendered as f64 / secs.max(1e-9),
            outcome.rays as f64 / secs.max(1e-9) / 1e6
        );
    }
    Ok(if outcome.failed.is_empty() {
        ExitCode::SUCCESS
    } else {
        ExitCode::from(2)
    })
}

/// `gpurt SCENE --shard I/N -o DIR`: this process's band of rows of one image, with its
/// manifest, into DIR.
pub fn shard(args: &RenderArgs, shard: Shard) -> gpurt::Result<ExitCode> {
    let [scene] = &args.scenes[..] else {
        eprintln!("gpurt: --shard splits one scene's image, or a batch with --out-dir");
        return Ok(ExitCode::from(2));
    };
    let Some(dir) = &args.output else {
        eprintln!("gpurt: --shard needs -o DIR, the directory the shards of the image go to");
        return Ok(ExitCode::from(2));
    };
    let by = match args.shard_by {
        ShardBy::Tiles => shard::By::Tiles,
        ShardBy::Samples => shard::By::Samples,
    };
    if by == shard::By::Samples && shard.count > args.spp {
        eprintln!(
            "gpurt: {} shards of {} samples per pixel would leave some empty; use at most {} (or --shard-by tiles)",
            shard.count, args.spp, args.spp
        );
        return Ok(ExitCode::from(2));
    }
    if !one_backend_no_wireframe(args, "a shard") {
        return Ok(ExitCode::from(2));
    }
    let cancel = cancel_on_signals();
    let Prepared {
        buffers, warnings, ..
    } = {
        let read =
            run::read(scene, args.view.as_deref(), &args.read_options())?.still(args.time)?;
        let samples = args.options(read.camera()).samples() / u64::from(shard.count);
        run::pack(read, samples)?
    };
    print_warnings(&warnings);
    let mut buffers = buffers;
    let opts = args.options(&buffers.camera);
    let globals = frame::globals(&buffers, &opts);
    let found = session::choose(args.backend, args.adapter.as_deref(), Missing::Cpu)?;
    if found.gpu.is_none() {
        buffers.for_cpu_alone(opts.aov);
    }
    let buffers = Arc::new(buffers);
    let backend = if found.gpu.is_some() { "gpu" } else { "cpu" };
    let mut renderer: Box<dyn Renderer> = match found.gpu {
        Some(ctx) => Box::new(GpuSession::new(ctx, buffers.clone())?),
        None => Box::new(CpuRenderer::new(buffers.clone())),
    };
    // The shading model is named only when it is not Phong, so that a Phong shard's
    // settings (and digest) are those of a gpurt that had no other model: shards from
    // both merge.
    let shading = match opts.shading {
        frame::Shading::Phong => String::new(),
        other => format!(", {} shading", other.name()),
    };
    let settings = format!(
        "{}x{}, {} spp, depth {}, ambient {:?}, seed {}, aov {}{shading}, {backend}",
        opts.width, opts.height, opts.spp, opts.max_depth, globals.ambient, opts.seed, opts.aov
    );
    let (rows, samples) = match by {
        shard::By::Tiles => (shard::rows(shard, opts.height), 0..opts.spp),
        shard::By::Samples => (0..opts.height, shard::samples(shard, opts.spp)),
    };
    let manifest = Manifest {
        shard,
        by,
        digest: shard::digest(scene, args.view.as_deref(), &settings)?,
        settings,
        scene: scene.display().to_string(),
        width: opts.width,
        height: opts.height,
        spp: opts.spp,
        aov: opts.aov,
        shading: opts.shading,
        rows: rows.clone(),
        samples: samples.clone(),
    };
    renderer.prepare(&globals)?;
    match by {
        shard::By::Tiles => {
            let mut accum = film::Accumulator::new(opts.width, opts.height);
            renderer.render_rows(&globals, rows, samples, &mut accum, &|_| {}, &cancel)?;
            shard::write_tiles(dir, &manifest, &accum)?;
        }
        shard::By::Samples => {
            // Each sample alone, added to zero sums: the merge adds these in sample order.
            let mut images = Vec::with_capacity(samples.len());
            for s in samples {
                let mut accum = film::Accumulator {
                    sums: film::Film::new(opts.width, opts.height),
                    samples: s,
                };
                renderer.render(&globals, s..s + 1, &mut accum, &|_| {}, &cancel)?;
                images.push(accum.sums);
            }
            shard::write_samples(dir, &manifest, &images)?;
        }
    }
    Ok(ExitCode::SUCCESS)
}

/// `gpurt merge DIR -o OUT`.
pub fn merge(dir: &Path, output: &Path) -> gpurt::Result<ExitCode> {
    film::Format::from_path(output)?;
    atomic::check_writable(output)?;
    let (accum, aov) = gpurt::commands::shard::merge(dir)?;
    accum.into_film().save_aov(output, aov)?;
    Ok(ExitCode::SUCCESS)
}

/// Batches and shards render on one backend and draw no wireframe; says so and returns
/// false when asked otherwise.
pub(super) fn one_backend_no_wireframe(args: &RenderArgs, what: &str) -> bool {
    let ok = args.backend != Backend::Both && args.overlay.is_none() && args.aov != Aov::Wireframe;
    if !ok {
        eprintln!(
            "gpurt: {what} renders on one backend, without wireframes: drop --backend both, \
             --overlay and --aov wireframe, or render the scene on its own"
        );
    }
    ok
}
