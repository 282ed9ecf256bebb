//! The command line's arguments: the clap definitions of every command (rendering's
//! here, the other commands' in `tools`) and their value parsers (`values`). What each
//! command does is in its own module; these only say what it accepts (the flags, their
//! limits and defaults, and the `--help` text).

use std::path::PathBuf;

use clap::{Parser, Subcommand, ValueEnum};
use gpurt::film;
use gpurt::frame::{Overrides, RenderOptions};
use gpurt::gpu_types as gt;
use gpurt::scene::{Camera, ReadOptions};
use gpurt::session::Backend;
use gpurt::util::limits::{
    DEFAULT_DEPTH, DEFAULT_SPP, MAX_DEPTH, MAX_IMAGE_SIDE, MAX_SPP, MAX_THREADS,
};

mod shade;
mod tools;
mod values;

pub use shade::ShadeArgs;
pub use tools::{BenchArgs, DiffArgs, TuneArgs, ViewArgs};
use values::backends;

#[derive(Parser)]
#[command(
    name = "gpurt",
    version,
    about = "Whitted ray tracer for NFF/SPD scenes, STL/OBJ/PLY meshes and glTF models",
    args_conflicts_with_subcommands = true,
    // `--spp -1` is a value out of range, not an unknown flag `-1`.
    allow_negative_numbers = true
)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Option<Command>,
    #[command(flatten)]
    pub render: RenderArgs,
    /// Threads that trace on the CPU and build BVHs, for renders, batches, the viewer's CPU
    /// path and bench (default: one a core, or RAYON_NUM_THREADS). `-v` says how many.
    #[arg(short = 'j', long, global = true, value_name = "N",
          value_parser = clap::value_parser!(u32).range(1..=MAX_THREADS as i64))]
    pub threads: Option<u32>,
}

#[derive(Subcommand)]
pub enum Command {
    /// Print what a scene holds: camera, bounds, primitive counts, lights, materials, warnings.
    Info {
        scene: PathBuf,
        /// One JSON object instead of text.
        #[arg(long)]
        json: bool,
        /// Skip NFF keywords gpurt does not know (other tracers' dialects: `Q`, `fp`, `obj`)
        /// with what follows each up to the next known keyword, warning of each, instead of
        /// refusing the file.
        #[arg(long)]
        lenient: bool,
    },
    /// Compare two images: max/mean difference, PSNR, pixels over 2/255, FLIP mean.
    /// Exits 1 when they differ beyond the limits (by default the GPU-vs-CPU ones: at most
    /// 0.5% of pixels over 2/255, FLIP mean 0.01, no bias of 0.5/255), 2 on bad input.
    Diff(DiffArgs),
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
    #[command(after_help = gpurt::view::controls::key_help(), allow_negative_numbers = true)]
    View(ViewArgs),
    /// Time frames on the GPU and the CPU over scenes, sizes and sample counts; prints a
    /// markdown table (Mrays/s by ray kind, upload and compile apart, GPU memory).
    #[command(allow_negative_numbers = true)]
    Bench(BenchArgs),
    /// Measure which walk of the BVH, kernels and way of reading the scene trace the given
    /// scenes fastest on the GPU adapter, and keep the fastest for every later render on
    /// that adapter (in the cache directory; GPURT_CACHE_DIR= measures without keeping).
    /// Prints a markdown table and the choice.
    Tune(TuneArgs),
    /// Print the completion script for a shell, e.g. `gpurt completions bash >
    /// ~/.local/share/bash-completion/completions/gpurt` (see the README for each shell).
    Completions { shell: clap_complete::Shell },
    /// Print the manual page (roff), e.g. `gpurt man > ~/.local/share/man/man1/gpurt.1`.
    Man,
}

#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum ShardBy {
    Tiles,
    Samples,
}

#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum ImageFormat {
    Png,
    Ppm,
    Bmp,
    Exr,
}

impl ImageFormat {
    pub fn format(self) -> film::Format {
        match self {
            ImageFormat::Png => film::Format::Png,
            ImageFormat::Ppm => film::Format::Ppm,
            ImageFormat::Bmp => film::Format::Bmp,
            ImageFormat::Exr => film::Format::Exr,
        }
    }
}

#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Aov {
    /// The shaded image (the default).
    Color,
    /// The surface normal at the first hit, each axis mapped from [-1, 1] to [0, 1].
    Normal,
    /// The distance to the first hit, nearest light, farthest dark.
    Depth,
    /// The BVH nodes the GPU's walk tests a pixel, as a heat map.
    Cost,
    /// The texture coordinates at the first hit, u in red and v in green (none: black).
    Uv,
    /// The wireframe alone (drawn by the GPU), as `gpurt view` shows it.
    Wireframe,
}

impl Aov {
    /// The shader's AOV; the wireframe traces no rays.
    pub fn code(self) -> Option<u32> {
        match self {
            Aov::Color => Some(gt::AOV_COLOR),
            Aov::Normal => Some(gt::AOV_NORMAL),
            Aov::Depth => Some(gt::AOV_DEPTH),
            Aov::Cost => Some(gt::AOV_COST),
            Aov::Uv => Some(gt::AOV_UV),
            Aov::Wireframe => None,
        }
    }
}

#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Overlay {
    /// The scene's edges, projected from the ray tracer's camera.
    Wireframe,
}

#[derive(clap::Args)]
pub struct RenderArgs {
    /// Scene to render: .nff (Haines NFF, IST P3D, gpurt extensions; .aff, BART's animated NFF,
    /// too), .stl, .obj, .ply, .gltf or .glb, optionally .gz.
    /// One at a time, or any number with --out-dir.
    #[arg(value_name = "SCENE")]
    pub scenes: Vec<PathBuf>,
    /// Render every scene given into this directory, each image named after its scene,
    /// on one device; a scene that fails is reported and skipped (exit 2 at the end).
    #[arg(long, value_name = "DIR", conflicts_with = "output")]
    pub out_dir: Option<PathBuf>,
    /// Do this process's share: with --out-dir every N-th scene from the I-th (0-based);
    /// for one scene the I-th of N bands of rows, written with its manifest into the
    /// directory -o names, for `gpurt merge`. `/N` takes I from SLURM_ARRAY_TASK_ID or
    /// JOB_COMPLETION_INDEX (a Slurm job array, a Kubernetes Indexed Job).
    #[arg(long, value_name = "I/N", value_parser = gpurt::commands::shard::Shard::parse)]
    pub shard: Option<gpurt::commands::shard::Shard>,
    /// How one image is split between shards: bands of rows, or runs of samples (each
    /// shard then stores one image per sample, spp/N of them).
    #[arg(long, value_enum, default_value_t = ShardBy::Tiles, requires = "shard")]
    pub shard_by: ShardBy,
    /// Render these frames of an animated (AFF) scene: `A..B` (both included, counted
    /// from 0), `N`, or `all`; -o names each with a printf-style frame number
    /// (`out/frame-%04d.png`). With --shard I/N, every N-th frame from the I-th.
    #[arg(long, value_name = "A..B", value_parser = gpurt::commands::sequence::Frames::parse,
          conflicts_with_all = ["out_dir", "time", "overlay"])]
    pub frames: Option<gpurt::commands::sequence::Frames>,
    /// With --frames: leave out the frames whose image exists already (a farm task
    /// restarted after some were written; each image is written whole or not at all).
    #[arg(long, requires = "frames")]
    pub resume: bool,
    /// Render an animated (AFF) scene as it is at this time, in the animation's units
    /// (default: the start of its range).
    #[arg(long, value_name = "T", allow_negative_numbers = true)]
    pub time: Option<f64>,
    /// Image format of the images --out-dir writes.
    #[arg(long, value_enum, default_value_t = ImageFormat::Png, requires = "out_dir")]
    pub format: ImageFormat,
    /// Output image; the format follows the extension (png, ppm, bmp, exr).
    /// Default: the scene's name with .png, in the current directory.
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    /// Image width (overrides the scene's resolution; the vertical angle stays).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=MAX_IMAGE_SIDE as i64))]
    pub width: Option<u32>,
    /// Image height.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=MAX_IMAGE_SIDE as i64))]
    pub height: Option<u32>,
    /// Maximum ray depth, the eye ray counting as 1.
    #[arg(long, default_value_t = DEFAULT_DEPTH, value_parser = clap::value_parser!(u32).range(1..=MAX_DEPTH as i64))]
    pub depth: u32,
    /// Samples per pixel (stratified and jittered).
    #[arg(long, default_value_t = DEFAULT_SPP, value_parser = clap::value_parser!(u32).range(1..=MAX_SPP as i64))]
    pub spp: u32,
    #[command(flatten)]
    pub shade: ShadeArgs,
    /// Which renderer traces the rays.
    #[arg(long, default_value = "auto", value_parser = backends(&[
        (Backend::Auto, Some(
            "The GPU when there is a hardware adapter, else the CPU (faster than a software \
             rasteriser such as lavapipe on the same cores); `-v` says which and why"
        )),
        (Backend::Gpu, Some(
            "WGSL compute through wgpu, on any adapter, software ones included; falls back to \
             the CPU when no adapter exists"
        )),
        (Backend::Cpu, Some("The CPU reference renderer")),
        (Backend::Both, Some(
            "Both, reporting how much their images differ; the GPU image is written if they \
             agree, otherwise nothing is and the exit code is 1"
        )),
    ]))]
    pub backend: Backend,
    /// Use the first GPU adapter whose name contains this (also GPURT_ADAPTER).
    #[arg(long)]
    pub adapter: Option<String>,
    /// Say which adapter renders.
    #[arg(short, long)]
    pub verbose: bool,
    /// Debug output instead of shaded colour.
    #[arg(long, value_enum, default_value_t = Aov::Color)]
    pub aov: Aov,
    /// Draw this over the image (on the GPU; lavapipe will do).
    #[arg(long, value_enum)]
    pub overlay: Option<Overlay>,
    /// Take the camera from this file's NFF `v` block (as `gpurt view` prints it with C)
    /// instead of the scene's.
    #[arg(long, value_name = "FILE")]
    pub view: Option<PathBuf>,
    /// Print timings, rays traced, Mrays/s and peak memory.
    #[arg(long)]
    pub stats: bool,
    /// Skip NFF keywords gpurt does not know (other tracers' dialects: `Q`, `fp`, `obj`)
    /// with what follows each up to the next known keyword, warning of each, instead of
    /// refusing the file.
    #[arg(long)]
    pub lenient: bool,
}

impl RenderArgs {
    /// How the scenes are read.
    pub fn read_options(&self) -> ReadOptions {
        ReadOptions {
            lenient: self.lenient,
            ..ReadOptions::default()
        }
    }

    /// What the flags set over a scene's camera and the defaults.
    pub fn overrides(&self) -> Overrides {
        Overrides {
            width: self.width,
            height: self.height,
            spp: Some(self.spp),
            max_depth: Some(self.depth),
            ambient: self.shade.ambient,
            aov: Some(self.aov.code().unwrap_or(gt::AOV_COLOR)),
            seed: Some(self.shade.seed),
            shading: Some(self.shade.shading),
        }
    }

    /// The frame the flags ask for, seen from `camera` (its resolution unless
    /// --width/--height).
    pub fn options(&self, camera: &Camera) -> RenderOptions {
        RenderOptions::for_camera(camera).with_overrides(&self.overrides())
    }
}

#[cfg(test)]
mod tests {
    use clap::CommandFactory;
    use gpurt::frame::Shading;

    use super::*;

    #[test]
    fn the_arguments_are_consistent() {
        Cli::command().debug_assert();
    }

    /// Each command takes the backends it can use, and no other.
    #[test]
    fn each_command_accepts_its_own_backends() {
        let backend = |args: &[&str]| -> Result<Backend, clap::Error> {
            let cli = Cli::try_parse_from(args)?;
            Ok(match cli.command {
                Some(Command::View(v)) => v.backend,
                Some(Command::Bench(b)) => b.backend,
                _ => cli.render.backend,
            })
        };
        for (args, accepted) in [
            (&["gpurt", "s.nff"][..], &["auto", "gpu", "cpu", "both"][..]),
            (&["gpurt", "view", "s.nff"], &["auto", "gpu", "cpu"]),
            (&["gpurt", "bench", "s.nff"], &["gpu", "cpu", "both"]),
        ] {
            for b in Backend::ALL {
                let mut with = args.to_vec();
                with.extend(["--backend", b.name()]);
                match backend(&with) {
                    Ok(got) => {
                        assert!(accepted.contains(&b.name()), "{with:?}");
                        assert_eq!(got, b);
                    }
                    Err(e) => assert!(!accepted.contains(&b.name()), "{with:?}: {e}"),
                }
            }
        }
        assert_eq!(backend(&["gpurt", "s.nff"]).unwrap(), Backend::Auto);
        assert_eq!(backend(&["gpurt", "view", "s.nff"]).unwrap(), Backend::Auto);
        assert_eq!(
            backend(&["gpurt", "bench", "s.nff"]).unwrap(),
            Backend::Both
        );
    }

    /// `-j`/`--threads` goes before or after any command, and the count is checked.
    #[test]
    fn the_thread_count_is_global() {
        for args in [
            &["gpurt", "-j", "3", "s.nff"][..],
            &["gpurt", "s.nff", "--threads", "3"],
            &["gpurt", "a.nff", "b.nff", "--out-dir", "d", "-j", "3"],
            &["gpurt", "-j", "3", "view", "s.nff"],
            &["gpurt", "view", "s.nff", "-j", "3"],
            &["gpurt", "bench", "s.nff", "--threads", "3"],
        ] {
            let cli = Cli::try_parse_from(args).expect("parses");
            assert_eq!(cli.threads, Some(3), "{args:?}");
        }
        assert_eq!(
            Cli::try_parse_from(["gpurt", "s.nff"]).unwrap().threads,
            None
        );
        for bad in ["0", "-2", "1025", "x"] {
            assert!(
                Cli::try_parse_from(["gpurt", "s.nff", "-j", bad]).is_err(),
                "{bad}"
            );
        }
    }

    /// Renders, batches, shards, the viewer and bench all take `--shading`, Phong unless
    /// told otherwise.
    #[test]
    fn every_command_that_shades_takes_the_model() {
        let shading = |args: &[&str]| -> Shading {
            let cli = Cli::try_parse_from(args).expect("parses");
            match cli.command {
                Some(Command::View(v)) => v.shade.shading,
                Some(Command::Bench(b)) => b.shading,
                _ => cli.render.overrides().shading.expect("always set"),
            }
        };
        for args in [
            &["gpurt", "s.nff"][..],
            &["gpurt", "a.nff", "b.nff", "--out-dir", "d"],
            &["gpurt", "s.nff", "--shard", "0/2", "-o", "d"],
            &["gpurt", "view", "s.nff"],
            &["gpurt", "bench", "s.nff"],
        ] {
            assert_eq!(shading(args), Shading::Phong, "{args:?}");
            for s in Shading::ALL {
                let with = [args, &["--shading", s.name()]].concat();
                assert_eq!(shading(&with), s, "{with:?}");
            }
        }
    }
}
