//! The arguments of the commands besides rendering (`diff`, `bench`, `tune`, `view`),
//! which `cli::tools` runs.

use std::path::PathBuf;

use gpurt::frame::Shading;
use gpurt::scene::ReadOptions;
use gpurt::session::Backend;
use gpurt::util::limits::{DEFAULT_DEPTH, MAX_DEPTH, MAX_IMAGE_SIDE, MAX_SPP};

use super::shade::ShadeArgs;
use super::values::{backends, parse_limit, parse_size, shadings};

#[derive(clap::Args)]
pub struct DiffArgs {
    pub a: PathBuf,
    pub b: PathBuf,
    /// Write a heat map (A | B | magnified difference) here.
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    /// Largest acceptable FLIP mean (default 0.01).
    #[arg(long, value_parser = parse_limit)]
    pub max_flip: Option<f64>,
    /// Largest acceptable fraction of pixels differing by more than 2/255 (default 0.005).
    #[arg(long, value_parser = parse_limit)]
    pub max_bad: Option<f64>,
}

#[derive(clap::Args)]
pub struct BenchArgs {
    /// Scenes to render.
    #[arg(required = true)]
    pub scenes: Vec<PathBuf>,
    /// Image sizes, WxH, comma-separated.
    #[arg(long, default_value = "1920x1080", value_delimiter = ',', value_parser = parse_size)]
    pub sizes: Vec<(u32, u32)>,
    /// Samples per pixel, comma-separated.
    #[arg(long, default_value = "1", value_delimiter = ',', value_parser = clap::value_parser!(u32).range(1..=MAX_SPP as i64))]
    pub spp: Vec<u32>,
    /// Maximum ray depth.
    #[arg(long, default_value_t = DEFAULT_DEPTH, value_parser = clap::value_parser!(u32).range(1..=MAX_DEPTH as i64))]
    pub depth: u32,
    /// Model of the specular highlight; everything else is shaded alike.
    #[arg(long, default_value = "phong", value_parser = shadings())]
    pub shading: Shading,
    /// Timed GPU frames per pass; the median is reported.
    #[arg(long, default_value_t = 5, value_parser = clap::value_parser!(u32).range(1..=1000))]
    pub frames: u32,
    /// Which backends to time.
    #[arg(long, default_value = "both", value_parser = backends(&[
        (Backend::Gpu, None),
        (Backend::Cpu, None),
        (Backend::Both, None),
    ]))]
    pub backend: Backend,
    /// Use the first GPU adapter whose name contains this (also GPURT_ADAPTER).
    #[arg(long)]
    pub adapter: Option<String>,
    /// Skip NFF keywords gpurt does not know (other tracers' dialects: `Q`, `fp`, `obj`)
    /// with what follows each up to the next known keyword, warning of each, instead of
    /// refusing the file.
    #[arg(long)]
    pub lenient: bool,
}

#[derive(clap::Args)]
pub struct TuneArgs {
    /// Scenes to measure on: the kind of scenes the adapter will render.
    #[arg(required = true)]
    pub scenes: Vec<PathBuf>,
    /// Image size, WxH: that of the renders the adapter will make (frames of a few
    /// milliseconds time noisily).
    #[arg(long, default_value = "1920x1080", value_parser = parse_size)]
    pub size: (u32, u32),
    /// Samples per pixel.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=MAX_SPP as i64))]
    pub spp: u32,
    /// Maximum ray depth.
    #[arg(long, default_value_t = DEFAULT_DEPTH, value_parser = clap::value_parser!(u32).range(1..=MAX_DEPTH as i64))]
    pub depth: u32,
    /// Timed rounds per scene, each one frame of every candidate; a candidate's time on
    /// the scene is the median over the rounds of its time over the defaults'.
    #[arg(long, default_value_t = 5, value_parser = clap::value_parser!(u32).range(1..=1000))]
    pub frames: u32,
    /// Use the first GPU adapter whose name contains this (also GPURT_ADAPTER).
    #[arg(long)]
    pub adapter: Option<String>,
    /// Skip NFF keywords gpurt does not know, warning of each, instead of refusing the
    /// file (as for rendering).
    #[arg(long)]
    pub lenient: bool,
}

#[derive(clap::Args)]
pub struct ViewArgs {
    /// Scene to view (as for rendering).
    pub scene: PathBuf,
    /// Window width (default: the scene's resolution).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=MAX_IMAGE_SIDE as i64))]
    pub width: Option<u32>,
    /// Window height.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=MAX_IMAGE_SIDE as i64))]
    pub height: Option<u32>,
    /// Stop accumulating after this many samples per pixel (default: the most a frame may
    /// have, MAX_SPP).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=MAX_SPP as i64))]
    pub spp: Option<u32>,
    /// Maximum ray depth, the eye ray counting as 1.
    #[arg(long, default_value_t = DEFAULT_DEPTH, value_parser = clap::value_parser!(u32).range(1..=MAX_DEPTH as i64))]
    pub depth: u32,
    #[command(flatten)]
    pub shade: ShadeArgs,
    /// Which renderer traces the rays (the window is drawn on the GPU adapter either way).
    #[arg(long, default_value = "auto", value_parser = backends(&[
        (Backend::Auto, Some("The GPU when there is a hardware adapter, else the CPU")),
        (Backend::Gpu, Some("WGSL compute through wgpu, on any adapter")),
        (Backend::Cpu, Some("The CPU reference renderer")),
    ]))]
    pub backend: Backend,
    /// Use the first GPU adapter whose name contains this (also GPURT_ADAPTER).
    #[arg(long)]
    pub adapter: Option<String>,
    /// Start from this file's NFF `v` block instead of the scene's camera.
    #[arg(long, value_name = "FILE")]
    pub view: Option<PathBuf>,
    /// Replay the input events in this file (drag, pan, wheel, key, wait; see
    /// docs/viewer.md).
    #[arg(long, value_name = "EVENTS")]
    pub script: Option<PathBuf>,
    /// After the script (and, with --spp, once the view has its samples), write what the
    /// window shows to this file and exit.
    #[arg(long, value_name = "OUT.png", requires = "script")]
    pub screenshot: Option<PathBuf>,
    /// On exit, print the time to the first picture, frame times and tracing rates.
    #[arg(long)]
    pub stats: bool,
    /// Skip NFF keywords gpurt does not know (other tracers' dialects: `Q`, `fp`, `obj`)
    /// with what follows each up to the next known keyword, warning of each, instead of
    /// refusing the file.
    #[arg(long)]
    pub lenient: bool,
}

impl ViewArgs {
    /// How the scene is read.
    pub fn read_options(&self) -> ReadOptions {
        ReadOptions {
            lenient: self.lenient,
            ..ReadOptions::default()
        }
    }
}
