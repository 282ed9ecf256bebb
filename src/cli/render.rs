//! `gpurt SCENE`: one scene into one image, on the backend chosen (or both, compared),
//! with the wireframe drawn over it or alone when asked, and the timings with `--stats`.

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use gpurt::commands::run::{self, Prepared};
use gpurt::gpu_types::GpuGlobals;
use gpurt::session::{self, Backend, CpuRenderer, GpuSession, Missing, Probe, Renderer};
use gpurt::view::wireframe::{self, Wireframe};
use gpurt::{agreement, atomic, film, frame};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

use super::args::{Aov, Overlay, RenderArgs};
use super::{cancel_on_signals, print_note, print_threads, print_warnings};

/// `gpurt SCENE [-o OUT]`.
pub fn render(args: RenderArgs) -> gpurt::Result<ExitCode> {
    let scene_path = match &args.scenes[..] {
        [one] => one.as_path(),
        [] => {
            eprintln!("gpurt: no scene given; try `gpurt --help`");
            return Ok(ExitCode::from(2));
        }
        many => {
            eprintln!(
                "gpurt: {}: {} scenes, but one is rendered at a time; give --out-dir DIR to render them all",
                many.iter()
                    .map(|p| p.display().to_string())
                    .collect::<Vec<_>>()
                    .join(", "),
                many.len()
            );
            return Ok(ExitCode::from(2));
        }
    };
    let output = args
        .output
        .clone()
        .unwrap_or_else(|| default_output(scene_path));
    // Checked before rendering, so a long render never ends in "unknown format".
    film::Format::from_path(&output)?;
    atomic::check_writable(&output)?;
    let start = Instant::now();
    let cancel = cancel_on_signals();
    // Looking for an adapter (and opening its device) takes 50 ms or more: it runs while
    // the scene is read and its BVH built.
    let wireframe_only = args.aov == Aov::Wireframe;
    let probe = (!wireframe_only && args.backend != Backend::Cpu)
        .then(|| Probe::start(args.backend, args.adapter.clone(), Missing::Cpu));
    let Prepared {
        buffers,
        warnings,
        parse_time,
        mut build_time,
    } = {
        let read =
            run::read(scene_path, args.view.as_deref(), &args.read_options())?.still(args.time)?;
        let samples = args.options(read.camera()).samples();
        run::pack(read, samples)?
    };
    print_warnings(&warnings);
    let opts = args.options(&buffers.camera);
    // `--stats` counts rays and node fetches by kind as the frame renders.
    let globals = GpuGlobals {
        counters: u32::from(args.stats),
        ..frame::globals(&buffers, &opts)
    };
    let mut buffers = buffers;

    // The GPU's context, when one renders: found while the scene was read.
    let mut gpu = None;
    if !wireframe_only {
        let found = match probe {
            Some(probe) => probe.join()?,
            None => session::Found {
                gpu: None,
                note: None,
            },
        };
        print_note(&found, args.verbose || args.stats);
        print_threads(args.verbose || args.stats);
        gpu = found.gpu;
    }
    // A frame that only the CPU's own walk traces frees the binary tree (the GPU's, which
    // the wireframe and the `cost` AOV also read) before it renders.
    if gpu.is_none() && !wireframe_only && args.overlay.is_none() {
        // Its eight-wide tree and blocks are built here, counted with the BVH.
        let t = Instant::now();
        buffers.for_cpu_alone(opts.aov);
        build_time += t.elapsed();
    }
    let buffers = Arc::new(buffers);
    let _copy = (gpurt::util::fault::Fault::from_env()?
        == Some(gpurt::util::fault::Fault::KeepPrimitives))
    .then(|| buffers.prims.clone());

    // The renderers to run, in order: the CPU first, so that with `both` the GPU's
    // image is compared against it.
    let mut renderers: Vec<(&str, Box<dyn Renderer>)> = Vec::new();
    // The GPU renderer's device, which also draws the wireframe when one is asked for.
    let mut device = None;
    let cpu =
        || -> (&str, Box<dyn Renderer>) { ("cpu", Box::new(CpuRenderer::new(buffers.clone()))) };
    if args.backend == Backend::Both {
        renderers.push(cpu());
    }
    if !wireframe_only {
        match gpu {
            Some(ctx) => {
                device = Some(ctx.clone());
                renderers.push(("gpu", Box::new(GpuSession::new(ctx, buffers.clone())?)));
            }
            None if args.backend != Backend::Both => renderers.push(cpu()),
            None => {}
        }
    }
    // The GPU's frame (its BVH walk) where one renders, so that `both` compares the same
    // frame, node costs included.
    let globals = match renderers.last() {
        Some((_, r)) => r.frame(&globals),
        None => globals,
    };
    let mut report = Vec::new();
    let mut films = Vec::new();
    for (name, renderer) in &mut renderers {
        if args.verbose || args.stats {
            eprintln!("{name:<11} {}", renderer.describe());
            if let Some(strategy) = renderer.strategy() {
                eprintln!("strategy    {strategy}");
            }
        }
        let progress = Progress::new(u64::from(opts.width) * u64::from(opts.height));
        let result = run::render_frame(
            renderer.as_mut(),
            &globals,
            &|n| progress.advance(n),
            &cancel,
        );
        progress.finish();
        let r = result?;
        if !r.compile.is_zero() {
            report.push(format!(
                "shader      {:.3} s (module, pipeline and first-dispatch compilation)",
                r.compile.as_secs_f64()
            ));
        }
        report.push(format!(
            "{name:<11} {:.3} s, {} rays, {:.2} Mrays/s",
            r.trace.as_secs_f64(),
            r.rays,
            r.mrays_per_s()
        ));
        if let Some(k) = r.kinds {
            report.push(format!(
                "rays        eye {} ({} in packets), shadow {} ({}), reflected {} ({}), refracted {} ({})",
                k.eye,
                k.eye_packed,
                k.shadow,
                k.shadow_packed,
                k.reflected,
                k.reflected_packed,
                k.refracted,
                k.refracted_packed
            ));
        }
        if let Some(counted) = renderer.counters() {
            report.extend(counted.report(name));
        }
        films.push(r.film);
    }
    if let [cpu, gpu] = &films[..] {
        let agreement = agreement::agreement(&buffers, &globals, cpu, gpu)?;
        eprintln!("cpu vs gpu  {}", agreement.stats);
        if let Some(floor) = agreement.noise_floor {
            eprintln!(
                "cpu noise   {:.3}% of pixels change when the eye moves by one ulp",
                floor * 100.0
            );
        }
        if let Err(why) = agreement.verdict {
            eprintln!("gpurt: the GPU and CPU images differ: {why}; no image written");
            return Ok(ExitCode::from(1));
        }
    }
    if wireframe_only || args.overlay == Some(Overlay::Wireframe) {
        let ctx = match device {
            Some(ctx) => ctx,
            None => gpurt::gpu::open(args.adapter.as_deref())?,
        };
        let wire = Wireframe::new(&ctx.device, &buffers, wireframe::IMAGE_FORMAT)?;
        let under = films.pop().map(|f| f.for_display(opts.aov).to_rgb8());
        let image = wire.draw_image(&ctx.device, &ctx.queue, &globals, under.as_ref())?;
        film::save_rgb8(&image, &output)?;
    } else {
        let film = films.pop().expect("one renderer ran");
        film.save_aov(&output, opts.aov)?;
    }
    if args.stats {
        eprintln!(
            "image       {}x{}, {} spp, depth {}, {} shading",
            opts.width,
            opts.height,
            opts.spp,
            opts.max_depth,
            opts.shading.name()
        );
        eprintln!(
            "scene       {} prims in BVH{} ({} nodes, depth {}), {} planes, {} lights",
            buffers.prims.len(),
            match buffers.copies {
                0 => String::new(),
                n => format!(", {n} of them copies by spatial splits"),
            },
            buffers.node_count(),
            buffers.bvh_depth,
            buffers.planes.len(),
            buffers.lights.len()
        );
        if !buffers.textures.is_empty() {
            eprintln!(
                "textures    {} ({} texels, {:.1} MiB)",
                buffers.textures.len(),
                buffers.texels.len(),
                size_of_val(&buffers.texels[..]) as f64 / (1 << 20) as f64
            );
        }
        eprintln!("parse       {:.3} s", parse_time.as_secs_f64());
        eprintln!(
            "build       {:.3} s (BVH, {} quality, + packing)",
            build_time.as_secs_f64(),
            buffers.bvh_quality.name()
        );
        for line in &report {
            eprintln!("{line}");
        }
        eprintln!("total       {:.3} s", start.elapsed().as_secs_f64());
        if let Some(m) = run::peak_memory() {
            eprintln!("peak memory {:.1} MiB", m as f64 / (1 << 20) as f64);
        }
    }
    Ok(ExitCode::SUCCESS)
}

/// `scene.nff.gz` -> `scene.png` (in the current directory).
fn default_output(scene: &Path) -> PathBuf {
    PathBuf::from(format!(
        "{}.png",
        gpurt::commands::batch::output_stem(scene)
    ))
}

/// A progress bar that appears only once a render has run for a second, and only on a
/// terminal (indicatif draws nothing to a non-terminal stderr).
struct Progress {
    bar: ProgressBar,
    start: Instant,
    shown: AtomicBool,
}

impl Progress {
    fn new(total: u64) -> Self {
        let bar = ProgressBar::with_draw_target(Some(total), ProgressDrawTarget::hidden());
        bar.set_style(
            ProgressStyle::with_template("{elapsed_precise} [{wide_bar}] {percent}% ETA {eta}")
                .expect("valid template"),
        );
        Progress {
            bar,
            start: Instant::now(),
            shown: AtomicBool::new(false),
        }
    }
    fn advance(&self, n: u64) {
        self.bar.inc(n);
        if self.start.elapsed() > Duration::from_secs(1)
            && !self.shown.swap(true, Ordering::Relaxed)
        {
            self.bar.set_draw_target(ProgressDrawTarget::stderr());
        }
    }
    fn finish(&self) {
        self.bar.finish_and_clear();
    }
}
