//! The `gpurt` command line: argument parsing, calling the library, printing errors.
//! Exit codes: 0 success, 1 `diff` over its thresholds, 2 bad input or failure,
//! 130 interrupted.

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use clap::{Parser, Subcommand, ValueEnum};
use glam::Vec3;
use gpurt::compare::{self, Thresholds};
use gpurt::frame::{self, RenderOptions};
use gpurt::gpu_types as gt;
use gpurt::limits::{
    DEFAULT_AMBIENT, DEFAULT_DEPTH, DEFAULT_SPP, MAX_DEPTH, MAX_IMAGE_SIDE, MAX_SPP,
};
use gpurt::run::{self, Prepared};
use gpurt::session::{CpuRenderer, GpuSession, Renderer};
use gpurt::view::wireframe::{self, Wireframe};
use gpurt::{Error, out, outln};
use gpurt::{agreement, atomic, film};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

#[derive(Parser)]
#[command(
    name = "gpurt",
    version,
    about = "Whitted ray tracer for NFF/SPD scenes and STL/OBJ meshes",
    args_conflicts_with_subcommands = true
)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
    #[command(flatten)]
    render: RenderArgs,
}

#[derive(Subcommand)]
enum Command {
    /// Print what a scene holds: camera, bounds, primitive counts, lights, materials, warnings.
    Info {
        scene: PathBuf,
        /// One JSON object instead of text.
        #[arg(long)]
        json: bool,
    },
    /// Compare two images: max/mean difference, PSNR, pixels over 2/255, FLIP mean.
    /// Exits 1 when they differ beyond the limits (by default the GPU-vs-CPU ones: at most
    /// 0.5% of pixels over 2/255, FLIP mean 0.01, no bias of 0.5/255), 2 on bad input.
    Diff {
        a: PathBuf,
        b: PathBuf,
        /// Write a heat map (A | B | magnified difference) here.
        #[arg(short, long)]
        output: Option<PathBuf>,
        /// Largest acceptable FLIP mean (default 0.01).
        #[arg(long, value_parser = parse_limit)]
        max_flip: Option<f64>,
        /// Largest acceptable fraction of pixels differing by more than 2/255 (default 0.005).
        #[arg(long, value_parser = parse_limit)]
        max_bad: Option<f64>,
    },
    /// Assemble an image from the shards `gpurt SCENE --shard I/N -o DIR` wrote into DIR,
    /// after checking that all N are there and belong to one render.
    Merge {
        dir: PathBuf,
        /// The image to write; the format follows the extension.
        #[arg(short, long)]
        output: PathBuf,
    },
    /// Open a window on a scene: ray traced progressively, with a wireframe preview that
    /// shares the ray tracer's camera. Without a display, says so and exits 2.
    #[command(after_help = gpurt::view::controls::key_help())]
    View(ViewArgs),
    /// Time frames on the GPU and the CPU over scenes, sizes and sample counts; prints a
    /// markdown table (Mrays/s by ray kind, upload and compile apart, GPU memory).
    Bench {
        /// Scenes to render.
        #[arg(required = true)]
        scenes: Vec<PathBuf>,
        /// Image sizes, WxH, comma-separated.
        #[arg(long, default_value = "1920x1080", value_delimiter = ',', value_parser = parse_size)]
        sizes: Vec<(u32, u32)>,
        /// Samples per pixel, comma-separated.
        #[arg(long, default_value = "1", value_delimiter = ',', value_parser = clap::value_parser!(u32).range(1..=MAX_SPP as i64))]
        spp: Vec<u32>,
        /// Maximum ray depth.
        #[arg(long, default_value_t = DEFAULT_DEPTH, value_parser = clap::value_parser!(u32).range(1..=MAX_DEPTH as i64))]
        depth: u32,
        /// Timed GPU frames per pass; the median is reported.
        #[arg(long, default_value_t = 5, value_parser = clap::value_parser!(u32).range(1..=1000))]
        frames: u32,
        /// Which backends to time.
        #[arg(long, value_enum, default_value_t = BenchBackend::Both)]
        backend: BenchBackend,
        /// Use the first GPU adapter whose name contains this (also GPURT_ADAPTER).
        #[arg(long)]
        adapter: Option<String>,
    },
}

#[derive(clap::Args)]
struct ViewArgs {
    /// Scene to view (as for rendering).
    scene: PathBuf,
    /// Window width (default: the scene's resolution).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=MAX_IMAGE_SIDE as i64))]
    width: Option<u32>,
    /// Window height.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=MAX_IMAGE_SIDE as i64))]
    height: Option<u32>,
    /// Stop accumulating after this many samples per pixel (default: the most a frame may
    /// have, MAX_SPP).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=MAX_SPP as i64))]
    spp: Option<u32>,
    /// Maximum ray depth, the eye ray counting as 1.
    #[arg(long, default_value_t = DEFAULT_DEPTH, value_parser = clap::value_parser!(u32).range(1..=MAX_DEPTH as i64))]
    depth: u32,
    #[arg(long, value_parser = parse_colour, help = format!(
        "Ambient light: one grey level or r,g,b (default: the scene's `am`, else {DEFAULT_AMBIENT})"
    ))]
    ambient: Option<Vec3>,
    /// Seed of the sample hash.
    #[arg(long, default_value_t = 0)]
    seed: u32,
    /// Which renderer traces the rays (the window is drawn on the GPU adapter either way).
    #[arg(long, value_enum, default_value_t = ViewBackend::Auto)]
    backend: ViewBackend,
    /// Use the first GPU adapter whose name contains this (also GPURT_ADAPTER).
    #[arg(long)]
    adapter: Option<String>,
    /// Start from this file's NFF `v` block instead of the scene's camera.
    #[arg(long, value_name = "FILE")]
    view: Option<PathBuf>,
    /// Replay the input events in this file (drag, pan, wheel, key, wait; see
    /// docs/viewer.md).
    #[arg(long, value_name = "EVENTS")]
    script: Option<PathBuf>,
    /// After the script (and, with --spp, once the view has its samples), write what the
    /// window shows to this file and exit.
    #[arg(long, value_name = "OUT.png", requires = "script")]
    screenshot: Option<PathBuf>,
    /// On exit, print the time to the first picture, frame times and tracing rates.
    #[arg(long)]
    stats: bool,
}

#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
enum ShardBy {
    Tiles,
    Samples,
}

#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
enum ImageFormat {
    Png,
    Ppm,
    Bmp,
    Exr,
}

impl ImageFormat {
    fn format(self) -> film::Format {
        match self {
            ImageFormat::Png => film::Format::Png,
            ImageFormat::Ppm => film::Format::Ppm,
            ImageFormat::Bmp => film::Format::Bmp,
            ImageFormat::Exr => film::Format::Exr,
        }
    }
}

#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
enum BenchBackend {
    Gpu,
    Cpu,
    Both,
}

#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
enum ViewBackend {
    /// The GPU when there is a hardware adapter, else the CPU.
    Auto,
    /// WGSL compute through wgpu, on any adapter.
    Gpu,
    /// The CPU reference renderer.
    Cpu,
}

#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
enum Backend {
    /// The GPU when there is a hardware adapter, else the CPU (faster than a software
    /// rasteriser such as lavapipe on the same cores); `-v` says which and why.
    Auto,
    /// WGSL compute through wgpu, on any adapter, software ones included; falls back to
    /// the CPU when no adapter exists.
    Gpu,
    /// The CPU reference renderer.
    Cpu,
    /// Both, reporting how much their images differ; the GPU image is written if they
    /// agree, otherwise nothing is and the exit code is 1.
    Both,
}

#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
enum Aov {
    Color,
    Normal,
    Depth,
    Cost,
    /// The wireframe alone (drawn by the GPU), as `gpurt view` shows it.
    Wireframe,
}

impl Aov {
    /// The shader's AOV; the wireframe traces no rays.
    fn code(self) -> Option<u32> {
        match self {
            Aov::Color => Some(gt::AOV_COLOR),
            Aov::Normal => Some(gt::AOV_NORMAL),
            Aov::Depth => Some(gt::AOV_DEPTH),
            Aov::Cost => Some(gt::AOV_COST),
            Aov::Wireframe => None,
        }
    }
}

#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
enum Overlay {
    /// The scene's edges, projected from the ray tracer's camera.
    Wireframe,
}

#[derive(clap::Args)]
struct RenderArgs {
    /// Scene to render: .nff (Haines NFF, IST P3D, gpurt extensions), .stl or .obj, optionally .gz.
    /// One at a time, or any number with --out-dir.
    #[arg(value_name = "SCENE")]
    scenes: Vec<PathBuf>,
    /// Render every scene given into this directory, each image named after its scene,
    /// on one device; a scene that fails is reported and skipped (exit 2 at the end).
    #[arg(long, value_name = "DIR", conflicts_with = "output")]
    out_dir: Option<PathBuf>,
    /// Do this process's share: with --out-dir every N-th scene from the I-th (0-based);
    /// for one scene the I-th of N bands of rows, written with its manifest into the
    /// directory -o names, for `gpurt merge`. `/N` takes I from SLURM_ARRAY_TASK_ID or
    /// JOB_COMPLETION_INDEX (a Slurm job array, a Kubernetes Indexed Job).
    #[arg(long, value_name = "I/N", value_parser = gpurt::batch::Shard::parse)]
    shard: Option<gpurt::batch::Shard>,
    /// How one image is split between shards: bands of rows, or runs of samples (each
    /// shard then stores one image per sample, spp/N of them).
    #[arg(long, value_enum, default_value_t = ShardBy::Tiles, requires = "shard")]
    shard_by: ShardBy,
    /// Image format of the images --out-dir writes.
    #[arg(long, value_enum, default_value_t = ImageFormat::Png, requires = "out_dir")]
    format: ImageFormat,
    /// Output image; the format follows the extension (png, ppm, bmp, exr).
    /// Default: the scene's name with .png, in the current directory.
    #[arg(short, long)]
    output: Option<PathBuf>,
    /// Image width (overrides the scene's resolution; the vertical angle stays).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=MAX_IMAGE_SIDE as i64))]
    width: Option<u32>,
    /// Image height.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=MAX_IMAGE_SIDE as i64))]
    height: Option<u32>,
    /// Maximum ray depth, the eye ray counting as 1.
    #[arg(long, default_value_t = DEFAULT_DEPTH, value_parser = clap::value_parser!(u32).range(1..=MAX_DEPTH as i64))]
    depth: u32,
    /// Samples per pixel (stratified and jittered).
    #[arg(long, default_value_t = DEFAULT_SPP, value_parser = clap::value_parser!(u32).range(1..=MAX_SPP as i64))]
    spp: u32,
    #[arg(long, value_parser = parse_colour, help = format!(
        "Ambient light: one grey level or r,g,b (default: the scene's `am`, else {DEFAULT_AMBIENT})"
    ))]
    ambient: Option<Vec3>,
    /// Seed of the sample hash.
    #[arg(long, default_value_t = 0)]
    seed: u32,
    /// Which renderer traces the rays.
    #[arg(long, value_enum, default_value_t = Backend::Auto)]
    backend: Backend,
    /// Use the first GPU adapter whose name contains this (also GPURT_ADAPTER).
    #[arg(long)]
    adapter: Option<String>,
    /// Say which adapter renders.
    #[arg(short, long)]
    verbose: bool,
    /// Debug output instead of shaded colour.
    #[arg(long, value_enum, default_value_t = Aov::Color)]
    aov: Aov,
    /// Draw this over the image (on the GPU; lavapipe will do).
    #[arg(long, value_enum)]
    overlay: Option<Overlay>,
    /// Take the camera from this file's NFF `v` block (as `gpurt view` prints it with C)
    /// instead of the scene's.
    #[arg(long, value_name = "FILE")]
    view: Option<PathBuf>,
    /// Print timings, rays traced, Mrays/s and peak memory.
    #[arg(long)]
    stats: bool,
}

fn parse_colour(s: &str) -> Result<Vec3, String> {
    let v: Vec<f32> = s
        .split(',')
        .map(|p| p.trim().parse::<f32>().map_err(|e| format!("'{p}': {e}")))
        .collect::<Result<_, _>>()?;
    match v[..] {
        [g] if g.is_finite() && g >= 0.0 => Ok(Vec3::splat(g)),
        [r, g, b] if [r, g, b].iter().all(|c| c.is_finite() && *c >= 0.0) => Ok(Vec3::new(r, g, b)),
        _ => Err("expected one non-negative number or three separated by commas".into()),
    }
}

/// Mesa's Vulkan device-select layer connects to a Wayland display to choose a default
/// GPU, and on a headless machine prints "error: XDG_RUNTIME_DIR is invalid or not set"
/// twice although nothing failed. gpurt chooses its adapter itself (`gpu::open`), so the
/// layer is turned off unless the user set `NODEVICE_SELECT` either way.
fn quiet_device_select() {
    if std::env::var_os("NODEVICE_SELECT").is_none() {
        // SAFETY: called first thing in `main`, before any other thread exists.
        unsafe { std::env::set_var("NODEVICE_SELECT", "1") };
    }
}

/// A threshold: a finite number, not negative (NaN would make every comparison pass).
fn parse_limit(s: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(v) if v.is_finite() && v >= 0.0 => Ok(v),
        _ => Err(format!("'{s}': expected a finite number, 0 or more")),
    }
}

/// Whether an adapter was asked for by name (`--adapter` or `GPURT_ADAPTER`).
fn adapter_named(args: &RenderArgs) -> bool {
    args.adapter.is_some() || std::env::var("GPURT_ADAPTER").is_ok_and(|v| !v.is_empty())
}

fn parse_size(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s
        .split_once('x')
        .ok_or_else(|| format!("'{s}': expected WIDTHxHEIGHT"))?;
    let dim = |d: &str| match d.trim().parse::<u32>() {
        Ok(v) if (1..=MAX_IMAGE_SIDE).contains(&v) => Ok(v),
        _ => Err(format!("'{s}': each side must be 1 to {MAX_IMAGE_SIDE}")),
    };
    Ok((dim(w)?, dim(h)?))
}

fn main() -> ExitCode {
    let launch = Instant::now();
    quiet_device_select();
    let cli = Cli::parse();
    let result = match cli.command {
        Some(Command::Info { scene, json }) => info(&scene, json),
        Some(Command::Diff {
            a,
            b,
            output,
            max_flip,
            max_bad,
        }) => diff(&a, &b, output.as_deref(), max_flip, max_bad),
        Some(Command::Bench {
            scenes,
            sizes,
            spp,
            depth,
            frames,
            backend,
            adapter,
        }) => gpurt::bench::run(&gpurt::bench::BenchConfig {
            scenes,
            sizes,
            spps: spp,
            depth,
            frames,
            cpu: backend != BenchBackend::Gpu,
            gpu: backend != BenchBackend::Cpu,
            adapter,
        })
        .map(|()| ExitCode::SUCCESS),
        Some(Command::View(args)) => view(args, launch),
        Some(Command::Merge { dir, output }) => merge(&dir, &output),
        None => render_command(cli.render),
    };
    match result {
        Ok(code) => code,
        Err(Error::Interrupted) => {
            eprintln!("gpurt: interrupted; no image written");
            ExitCode::from(130)
        }
        Err(e) => {
            eprintln!("gpurt: {e}");
            ExitCode::from(2)
        }
    }
}

fn view(args: ViewArgs, launch: Instant) -> gpurt::Result<ExitCode> {
    use gpurt::view::window::{self, Backend as Tracing, ViewOptions};
    if let Some(shot) = &args.screenshot {
        film::Format::from_path(shot)?;
        atomic::check_writable(shot)?;
    }
    let script = args
        .script
        .as_deref()
        .map(gpurt::view::script::load)
        .transpose()?;
    let Prepared {
        buffers, warnings, ..
    } = run::prepare(&args.scene, args.view.as_deref(), |camera| {
        // Quick to the first image: the build that suits one frame at the window's size.
        let (w, h) = (
            args.width.unwrap_or(camera.width),
            args.height.unwrap_or(camera.height),
        );
        u64::from(w) * u64::from(h)
    })?;
    for w in &warnings {
        eprintln!("gpurt: warning: {w}");
    }
    window::run(
        buffers,
        ViewOptions {
            name: args.scene.display().to_string(),
            width: args.width,
            height: args.height,
            spp: args.spp,
            depth: args.depth,
            ambient: args.ambient,
            seed: args.seed,
            backend: match args.backend {
                ViewBackend::Auto => Tracing::Auto,
                ViewBackend::Gpu => Tracing::Gpu,
                ViewBackend::Cpu => Tracing::Cpu,
            },
            adapter: args.adapter,
            script,
            screenshot: args.screenshot,
            stats: args.stats,
            launch,
        },
    )?;
    Ok(ExitCode::SUCCESS)
}

/// A flag that Ctrl-C (SIGINT), SIGTERM or SIGHUP sets: the render stops and nothing is
/// written. One that comes during a save lets the save finish (it is atomic), so no
/// temporary file is ever left behind.
fn cancel_on_signals() -> Arc<AtomicBool> {
    let cancel = Arc::new(AtomicBool::new(false));
    let flag = cancel.clone();
    let _ = ctrlc::set_handler(move || flag.store(true, Ordering::Relaxed));
    cancel
}

/// The frame the render options ask for, seen from `camera` (its resolution unless
/// --width/--height).
fn render_options(args: &RenderArgs, camera: &gpurt::scene::Camera) -> RenderOptions {
    let defaults = RenderOptions::for_camera(camera);
    RenderOptions {
        width: args.width.unwrap_or(defaults.width),
        height: args.height.unwrap_or(defaults.height),
        spp: args.spp,
        max_depth: args.depth,
        ambient: args.ambient,
        aov: args.aov.code().unwrap_or(gt::AOV_COLOR),
        seed: args.seed,
    }
}

/// Batches and shards render on one backend and draw no wireframe; says so and returns
/// false when asked otherwise.
fn one_backend_no_wireframe(args: &RenderArgs, what: &str) -> bool {
    let ok = args.backend != Backend::Both && args.overlay.is_none() && args.aov != Aov::Wireframe;
    if !ok {
        eprintln!(
            "gpurt: {what} renders on one backend, without wireframes: drop --backend both, \
             --overlay and --aov wireframe, or render the scene on its own"
        );
    }
    ok
}

/// `gpurt SCENE --shard I/N -o DIR`: this process's band of rows of one image, with its
/// manifest, into DIR.
fn render_shard(args: &RenderArgs, shard: gpurt::batch::Shard) -> gpurt::Result<ExitCode> {
    use gpurt::shard::{self, Manifest};
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
    } = run::prepare(scene, args.view.as_deref(), |camera| {
        render_options(args, camera).samples() / u64::from(shard.count)
    })?;
    for w in &warnings {
        eprintln!("gpurt: warning: {w}");
    }
    let buffers = Arc::new(buffers);
    let opts = render_options(args, &buffers.camera);
    let globals = frame::globals(&buffers, &opts);
    let found = find_gpu(args.backend, args.adapter.as_deref(), adapter_named(args))?;
    let backend = if found.gpu.is_some() { "gpu" } else { "cpu" };
    let mut renderer: Box<dyn Renderer> = match found.gpu {
        Some(ctx) => Box::new(GpuSession::new(ctx, buffers.clone())?),
        None => Box::new(CpuRenderer::new(buffers.clone())),
    };
    let settings = format!(
        "{}x{}, {} spp, depth {}, ambient {:?}, seed {}, aov {}, {backend}",
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
fn merge(dir: &Path, output: &Path) -> gpurt::Result<ExitCode> {
    film::Format::from_path(output)?;
    atomic::check_writable(output)?;
    let (accum, aov) = gpurt::shard::merge(dir)?;
    accum.into_film().save_aov(output, aov)?;
    Ok(ExitCode::SUCCESS)
}

/// `gpurt SCENE... --out-dir DIR`: every scene into DIR, one device, failures skipped.
fn render_batch(args: &RenderArgs, dir: &Path) -> gpurt::Result<ExitCode> {
    use gpurt::batch::{self, BatchOptions};
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
    let found = find_gpu(args.backend, args.adapter.as_deref(), adapter_named(args))?;
    if let Some((note, warn)) = &found.note
        && (*warn || args.verbose || args.stats)
    {
        eprintln!("{note}");
    }
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
            width: args.width,
            height: args.height,
            spp: args.spp,
            max_depth: args.depth,
            ambient: args.ambient,
            aov: args.aov.code().unwrap_or(gt::AOV_COLOR),
            seed: args.seed,
            view: args.view.clone(),
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
    for w in &outcome.warnings {
        eprintln!("gpurt: warning: {w}");
    }
    for (scene, e) in &outcome.failed {
        eprintln!("gpurt: {}: skipped: {e}", scene.display());
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

/// What the adapter search found for a backend: the device to render on, if any, and a
/// line about the choice, printed always when it is a warning, else with `-v` or `--stats`.
struct Found {
    gpu: Option<gpurt::gpu::GpuContext>,
    note: Option<(String, bool)>,
}

/// The adapter search, running while the scene is read. Dropped without `join` (the
/// scene failed to read), it still waits for the search to end: a process that exits while
/// another thread is inside the Vulkan driver's start-up can die in the driver (NVIDIA's
/// did: a bad `--view` file exited on a signal instead of with status 2).
struct Probe(Option<std::thread::JoinHandle<gpurt::Result<Found>>>);

impl Probe {
    fn join(mut self) -> gpurt::Result<Found> {
        let search = self.0.take().expect("joined once");
        search.join().expect("the adapter search does not panic")
    }
}

impl Drop for Probe {
    fn drop(&mut self) {
        if let Some(search) = self.0.take() {
            let _ = search.join();
        }
    }
}

fn find_gpu(backend: Backend, filter: Option<&str>, named: bool) -> gpurt::Result<Found> {
    let (gpu, note) = match backend {
        Backend::Cpu => (None, None),
        Backend::Both => (Some(gpurt::gpu::open(filter)?), None),
        Backend::Gpu => match gpurt::gpu::open(filter) {
            Ok(ctx) => (Some(ctx), None),
            // An adapter asked for by name that is missing is an error, not a fallback.
            Err(Error::NoAdapter(why)) if !named => (
                None,
                Some((
                    format!("gpurt: no GPU adapter{why}; rendering on the CPU"),
                    true,
                )),
            ),
            Err(e) => return Err(e),
        },
        Backend::Auto => match gpurt::gpu::choose(filter)? {
            gpurt::gpu::Choice::Gpu(ctx) => {
                let ctx = *ctx;
                let why = if named {
                    "the adapter named"
                } else {
                    "a hardware adapter"
                };
                (Some(ctx), Some((format!("backend     gpu: {why}"), false)))
            }
            gpurt::gpu::Choice::Cpu(why) => (
                None,
                Some((
                    format!("backend     cpu: {why} (--backend gpu forces the GPU path)"),
                    false,
                )),
            ),
        },
    };
    Ok(Found { gpu, note })
}

fn info(path: &Path, json: bool) -> gpurt::Result<ExitCode> {
    let s = gpurt::scene::load(path)?;
    if json {
        outln!("{}", gpurt::info::to_json(&s));
    } else {
        out!("{}", gpurt::info::to_text(&s));
    }
    Ok(ExitCode::SUCCESS)
}

fn diff(
    a: &Path,
    b: &Path,
    output: Option<&Path>,
    max_flip: Option<f64>,
    max_bad: Option<f64>,
) -> gpurt::Result<ExitCode> {
    let ia = film::load_rgb8(a)?;
    let ib = film::load_rgb8(b)?;
    let stats = compare::diff(&ia, &ib, Thresholds::GPU_VS_CPU.tolerance_255)?;
    outln!("{stats}");
    if let Some(out) = output {
        film::save_rgb8(&compare::heat_map(&ia, &ib)?, out)?;
        outln!("heat map written to {}", out.display());
    }
    // The project's GPU-vs-CPU limits unless loosened or tightened by the flags: a diff in
    // CI must fail on visibly different images without being told how.
    let limits = Thresholds {
        max_flip_mean: max_flip.unwrap_or(Thresholds::GPU_VS_CPU.max_flip_mean),
        max_frac_over: max_bad.unwrap_or(Thresholds::GPU_VS_CPU.max_frac_over),
        ..Thresholds::GPU_VS_CPU
    };
    Ok(match limits.check(&stats) {
        Ok(()) => ExitCode::SUCCESS,
        Err(why) => {
            outln!("{why}");
            ExitCode::from(1)
        }
    })
}

/// `scene.nff.gz` -> `scene.png` (in the current directory).
fn default_output(scene: &Path) -> PathBuf {
    PathBuf::from(format!("{}.png", gpurt::batch::output_stem(scene)))
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

fn render_command(args: RenderArgs) -> gpurt::Result<ExitCode> {
    if let Some(dir) = &args.out_dir {
        return render_batch(&args, dir);
    }
    if let Some(shard) = args.shard {
        return render_shard(&args, shard);
    }
    let scene_path = match &args.scenes[..] {
        [one] => one.as_path(),
        [] => {
            eprintln!("gpurt: no scene given; try `gpurt --help`");
            return Ok(ExitCode::from(2));
        }
        many => {
            eprintln!(
                "gpurt: one scene is rendered at a time, but {} were given ({}); give --out-dir DIR to render them all",
                many.len(),
                many.iter()
                    .map(|p| p.display().to_string())
                    .collect::<Vec<_>>()
                    .join(", ")
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
    let probe = (!wireframe_only && args.backend != Backend::Cpu).then(|| {
        let (backend, filter, named) = (args.backend, args.adapter.clone(), adapter_named(&args));
        Probe(Some(std::thread::spawn(move || {
            find_gpu(backend, filter.as_deref(), named)
        })))
    });
    let Prepared {
        buffers,
        warnings,
        parse_time,
        build_time,
    } = run::prepare(scene_path, args.view.as_deref(), |camera| {
        render_options(&args, camera).samples()
    })?;
    for w in &warnings {
        eprintln!("gpurt: warning: {w}");
    }
    let opts = render_options(&args, &buffers.camera);
    let globals = frame::globals(&buffers, &opts);
    let buffers = Arc::new(buffers);

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
        let found = match probe {
            Some(probe) => probe.join()?,
            None => Found {
                gpu: None,
                note: None,
            },
        };
        if let Some((note, warn)) = &found.note
            && (*warn || args.verbose || args.stats)
        {
            eprintln!("{note}");
        }
        match found.gpu {
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
            "image       {}x{}, {} spp, depth {}",
            opts.width, opts.height, opts.spp, opts.max_depth
        );
        eprintln!(
            "scene       {} prims in BVH ({} nodes, depth {}), {} planes, {} lights",
            buffers.prims.len(),
            buffers.nodes.len(),
            buffers.bvh_depth,
            buffers.planes.len(),
            buffers.lights.len()
        );
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
