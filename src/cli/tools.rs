//! The commands around rendering: `gpurt info` (what a scene holds), `gpurt diff` (two
//! images compared under the GPU-vs-CPU limits), `gpurt view` (the window) and `gpurt
//! bench` (frame times and ray rates).

use std::path::Path;
use std::process::ExitCode;
use std::time::Instant;

use gpurt::commands::bench::{self, BenchConfig};
use gpurt::commands::run::{self, Prepared};
use gpurt::commands::tune::{self, TuneConfig};
use gpurt::compare::{self, Thresholds};
use gpurt::scene::ReadOptions;
use gpurt::view::playback::Playback;
use gpurt::view::window::{self, ViewOptions};
use gpurt::{atomic, film, out, outln};

use super::args::{BenchArgs, DiffArgs, TuneArgs, ViewArgs};
use super::{print_threads, print_warnings};

/// `gpurt info SCENE [--json] [--lenient]`.
pub fn info(path: &Path, json: bool, read: &ReadOptions) -> gpurt::Result<ExitCode> {
    let s = gpurt::scene::summary_with(path, read)?;
    if json {
        outln!("{}", gpurt::commands::info::to_json(&s));
    } else {
        out!("{}", gpurt::commands::info::to_text(&s));
    }
    Ok(ExitCode::SUCCESS)
}

/// `gpurt diff A B`: exits 1 when the images differ beyond the limits.
pub fn diff(args: DiffArgs) -> gpurt::Result<ExitCode> {
    let ia = film::load_rgb8(&args.a)?;
    let ib = film::load_rgb8(&args.b)?;
    let stats = compare::diff(&ia, &ib, Thresholds::GPU_VS_CPU.tolerance_255)?;
    outln!("{stats}");
    if let Some(out) = &args.output {
        film::save_rgb8(&compare::heat_map(&ia, &ib)?, out)?;
        outln!("heat map written to {}", out.display());
    }
    // The project's GPU-vs-CPU limits unless loosened or tightened by the flags: a diff in
    // CI must fail on visibly different images without being told how.
    let limits = Thresholds {
        max_flip_mean: args
            .max_flip
            .unwrap_or(Thresholds::GPU_VS_CPU.max_flip_mean),
        max_frac_over: args.max_bad.unwrap_or(Thresholds::GPU_VS_CPU.max_frac_over),
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

/// `gpurt view SCENE`: runs until the window is closed (or the script's screenshot is
/// written).
pub fn view(args: ViewArgs, launch: Instant) -> gpurt::Result<ExitCode> {
    if let Some(shot) = &args.screenshot {
        film::Format::from_path(shot)?;
        atomic::check_writable(shot)?;
    }
    let script = args
        .script
        .as_deref()
        .map(gpurt::view::script::load)
        .transpose()?;
    let read = run::read(&args.scene, args.view.as_deref(), &args.read_options())?;
    // Quick to the first image: the build that suits one frame at the window's size.
    let camera = read.camera();
    let samples = u64::from(args.width.unwrap_or(camera.width))
        * u64::from(args.height.unwrap_or(camera.height));
    // An animated scene plays from its first frame, which is the still image's, packed
    // by the playback's packer (which builds the still part's tree once).
    let frames = read
        .animation()
        .and_then(|a| a.range)
        .map_or(1, |r| r.frames);
    let mut playback = read.frames(samples, frames.into())?.and_then(Playback::new);
    let buffers = match &mut playback {
        Some(p) => {
            print_warnings(read.warnings());
            p.buffers()?
        }
        None => {
            let Prepared {
                buffers, warnings, ..
            } = run::pack(read.still(None)?, samples)?;
            print_warnings(&warnings);
            buffers
        }
    };
    print_threads(args.stats);
    window::run(
        buffers,
        ViewOptions {
            name: args.scene.display().to_string(),
            width: args.width,
            height: args.height,
            spp: args.spp,
            depth: args.depth,
            ambient: args.shade.ambient,
            seed: args.shade.seed,
            shading: args.shade.shading,
            backend: args.backend,
            adapter: args.adapter,
            script,
            screenshot: args.screenshot,
            stats: args.stats,
            launch,
        },
        playback,
    )?;
    Ok(ExitCode::SUCCESS)
}

/// `gpurt tune SCENE...`.
pub fn tune(args: TuneArgs) -> gpurt::Result<ExitCode> {
    let (width, height) = args.size;
    tune::run(&TuneConfig {
        scenes: args.scenes,
        width,
        height,
        spp: args.spp,
        depth: args.depth,
        frames: args.frames,
        adapter: args.adapter,
        read: ReadOptions {
            lenient: args.lenient,
            ..ReadOptions::default()
        },
    })?;
    Ok(ExitCode::SUCCESS)
}

/// `gpurt bench SCENE...`.
pub fn bench(args: BenchArgs) -> gpurt::Result<ExitCode> {
    bench::run(&BenchConfig {
        scenes: args.scenes,
        sizes: args.sizes,
        spps: args.spp,
        depth: args.depth,
        shading: args.shading,
        frames: args.frames,
        backend: args.backend,
        adapter: args.adapter,
        read: ReadOptions {
            lenient: args.lenient,
            ..ReadOptions::default()
        },
    })?;
    Ok(ExitCode::SUCCESS)
}
