//! `gpurt bench`: frame times and ray rates of both backends over scenes, image sizes and
//! sample counts, printed as a markdown table.
//!
//! Per scene and setting, on the GPU: the pipeline compile and the upload are timed apart
//! from the frames, then each of three passes is traced `frames` times after a quarter of
//! a second of warm-up frames and its median time kept, once reading the image back into a film and once on the
//! device alone (the time the rates are computed from):
//! - `eye`: the depth AOV, which traces the eye rays and nothing else;
//! - `shaded`: colour with depth 1 and no shadow rays (every light reaching every surface
//!   facing it: `GpuRenderer::with_shadow_rays`), the eye rays with their hits shaded;
//! - `direct`: colour with depth 1, adding the eye rays' shadow rays;
//! - `full`: colour with the requested depth, adding reflected and refracted rays and
//!   their shadow rays.
//!
//! The differences between passes give each kind's rate: the shading of the eye rays'
//! hits takes `shaded - eye`, shadow rays `direct - shaded`, secondary rays (with their
//! hits' shading and their own shadow rays) `full - direct`. (A frame on the wavefront
//! kernels, which trace every shadow ray, has no `shaded` pass: its shadow rays take
//! `direct - eye`, shading included.) The CPU
//! renders the `full` pass once per setting, with its own count of rays by kind, which
//! should equal the GPU's total: a mismatch is reported as a warning.
//!
//! The `full` pass is then traced once more, untimed, counting (`GpuGlobals::counters`):
//! the BVH nodes fetched per ray of each kind and the bytes they read, on the GPU's walk
//! (on the CPU's own walk where only the CPU is timed). Where the frame takes the
//! wavefront kernels and the device has timestamps, once more with each kernel's
//! dispatches timed on the device, printed to stderr.

use std::path::PathBuf;
use std::sync::atomic::AtomicBool;
use std::time::{Duration, Instant};

mod table;

use table::{CpuRow, GpuRow, Pass, Row};

use crate::bvh::{self, wide::WideNode};
use crate::commands::run;
use crate::frame::{self, Overrides, RenderOptions, Shading};
use crate::gpu::{self, GpuContext, GpuRenderer};
use crate::gpu_types::{
    AOV_COLOR, AOV_DEPTH, GpuGlobals, TRAVERSAL_NAMES, TRAVERSAL_QWIDE, TRAVERSAL_WIDE,
};
use crate::pack;
use crate::scene::{Camera, ReadOptions};
use crate::session::{self, Backend, Missing};
use crate::util::error::{Error, Result};

/// What to measure.
pub struct BenchConfig {
    pub scenes: Vec<PathBuf>,
    pub sizes: Vec<(u32, u32)>,
    pub spps: Vec<u32>,
    pub depth: u32,
    /// The highlight's model of every frame.
    pub shading: Shading,
    /// Timed GPU frames per pass (after one warm-up frame).
    pub frames: u32,
    /// Which backends to time: `Gpu` needs an adapter, `Both` times both, `Auto` the one
    /// `session::choose` picks.
    pub backend: Backend,
    pub adapter: Option<String>,
    /// How every scene is read (`--lenient`).
    pub read: ReadOptions,
}

fn median(mut times: Vec<Duration>) -> Duration {
    times.sort();
    times[times.len() / 2]
}

/// Traces frames of `scene` on the device for a quarter of a second, before timing: a
/// GPU idle for a while (the CPU rows run in between) clocks down.
pub(crate) fn warm_up(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    scene: &gpu::GpuScene,
) -> Result<()> {
    let warm = Instant::now();
    while warm.elapsed() < Duration::from_millis(250) {
        gpu::trace_on_device(device, queue, scene)?;
    }
    Ok(())
}

/// The median time of `frames` frames (at least one) of `scene` on the device alone,
/// after `warm_up`.
fn time_frames(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    scene: &gpu::GpuScene,
    frames: u32,
) -> Result<Duration> {
    warm_up(device, queue, scene)?;
    let on_device = (0..frames.max(1))
        .map(|_| {
            let t = Instant::now();
            gpu::trace_on_device(device, queue, scene).map(|()| t.elapsed())
        })
        .collect::<Result<Vec<_>>>()?;
    Ok(median(on_device))
}

/// Runs the benchmark, printing each row as it is measured (header first) to stdout.
pub fn run(config: &BenchConfig) -> Result<()> {
    let ctx = session::choose(config.backend, config.adapter.as_deref(), Missing::Error)?.gpu;
    if let Some(ctx) = &ctx {
        eprintln!("adapter     {}", ctx.describe());
        eprintln!("features    {}", ctx.capabilities());
    }
    // The CPU is timed beside the GPU, or in its place.
    let time_cpu = config.backend == Backend::Both || ctx.is_none();
    // The second renderer traces the `shaded` pass: its pipelines are compiled once for
    // the whole run, as the first's are.
    let renderers = match &ctx {
        Some(c) => Some((
            GpuRenderer::new(&c.device, None)?,
            GpuRenderer::new(&c.device, None)?.with_shadow_rays(false),
        )),
        None => None,
    };
    let renderer = renderers.as_ref().map(|(r, _)| r);
    if let Some(r) = renderer {
        let t = r.traversal();
        let fallback = if t == TRAVERSAL_WIDE || t == TRAVERSAL_QWIDE {
            " (pairs where a scene's wide tree does not fit the stack)"
        } else {
            ""
        };
        eprintln!(
            "traversal   {}{fallback} (GPURT_TRAVERSAL={} to choose)",
            TRAVERSAL_NAMES[t as usize],
            TRAVERSAL_NAMES.join("|")
        );
        let stack = match r.stack_floor() {
            0 => "as each scene's tree needs".to_string(),
            n => format!("at least {n} entries"),
        };
        eprintln!("stack       {stack} (GPURT_STACK=N for at least N)");
        eprintln!(
            "scene data  {} (GPURT_FETCH=textures|buffers to choose)",
            r.fetch().name()
        );
    }
    let bvh = match bvh::Quality::forced().map_err(Error::Render)? {
        Some(q) => q.name(),
        None => "as a render of each row's samples gets it",
    };
    eprintln!("bvh         {bvh} (GPURT_BVH=medium|high to choose)");
    if time_cpu {
        eprintln!("cpu         {} threads", rayon::current_num_threads());
    }
    eprintln!("shading     {}", config.shading.name());
    // The table's header waits for its first row, so that a scene that cannot be read
    // is an error alone, not a header and then an error.
    let mut header = true;
    for path in &config.scenes {
        // Each row traces the tree a render of its size and samples would get: one build
        // per BVH quality the rows need.
        let mut builds: Vec<run::Prepared> = Vec::new();
        let name = path
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        let name = name.split('.').next().unwrap_or_default().to_string();
        for &(width, height) in &config.sizes {
            for &spp in &config.spps {
                let overrides = Overrides {
                    width: Some(width),
                    height: Some(height),
                    spp: Some(spp),
                    max_depth: Some(config.depth),
                    shading: Some(config.shading),
                    ..Overrides::default()
                };
                let with_camera =
                    |camera: &Camera| RenderOptions::for_camera(camera).with_overrides(&overrides);
                let wanted = |b: &run::Prepared| {
                    let samples = with_camera(&b.buffers.camera).samples();
                    bvh::Quality::chosen(b.buffers.prims.len(), samples)
                        .is_ok_and(|q| q == b.buffers.bvh_quality)
                };
                let prepared = match builds.iter().position(wanted) {
                    Some(i) => &builds[i],
                    None => {
                        let read = run::read(path, None, &config.read)?.still(None)?;
                        let samples = with_camera(read.camera()).samples();
                        let b = run::pack(read, samples)?;
                        eprintln!(
                            "  {name}: BVH built at {} quality for {width}x{height}, {spp} spp",
                            b.buffers.bvh_quality.name()
                        );
                        builds.push(b);
                        &builds[builds.len() - 1]
                    }
                };
                let opts = with_camera(&prepared.buffers.camera);
                let globals = frame::globals(&prepared.buffers, &opts);
                if let Some(r) = renderer {
                    let kernels = r.kernels(&prepared.buffers, &globals);
                    eprintln!("  {name}: {width}x{height}, {spp} spp, kernels: {kernels}");
                }
                let gpu = match (&ctx, &renderers) {
                    (Some(c), Some((r, unshadowed))) => Some(gpu_row(
                        c,
                        r,
                        unshadowed,
                        &prepared.buffers,
                        &globals,
                        config,
                    )?),
                    _ => None,
                };
                let cpu = time_cpu
                    .then(|| cpu_row(&prepared.buffers, &globals))
                    .transpose()?;
                if let (Some(g), Some(c)) = (&gpu, &cpu)
                    && g.full.rays != c.rays
                {
                    eprintln!(
                        "gpurt: warning: {name} {width}x{height} {spp} spp: the GPU traced {} rays, the CPU {}",
                        g.full.rays, c.rays
                    );
                }
                if std::mem::take(&mut header) {
                    table::print_header();
                }
                table::print_row(&Row {
                    scene: name.clone(),
                    prims: prepared.buffers.prims.len() + prepared.buffers.planes.len(),
                    width,
                    height,
                    spp,
                    gpu,
                    cpu,
                });
            }
        }
    }
    Ok(())
}

/// The GPU's passes of one row on `renderer`, the `shaded` one on `unshadowed` (the same
/// renderer tracing no shadow rays).
fn gpu_row(
    ctx: &GpuContext,
    renderer: &GpuRenderer,
    unshadowed: &GpuRenderer,
    buffers: &pack::SceneBuffers,
    globals: &GpuGlobals,
    config: &BenchConfig,
) -> Result<GpuRow> {
    let (device, queue) = (&ctx.device, &ctx.queue);
    let pass =
        |renderer: &GpuRenderer, globals: &GpuGlobals| -> Result<(Pass, Duration, Duration, u64)> {
            let before = renderer.compile_time();
            renderer.prepare(device, queue, buffers, globals)?;
            let compile = renderer.compile_time() - before;
            let t = Instant::now();
            let scene = renderer.upload(device, queue, buffers, globals)?;
            let upload = t.elapsed();
            let never = AtomicBool::new(false);
            let (_, rays) = gpu::trace(device, queue, &scene, &|_| {}, &never)?;
            let time = time_frames(device, queue, &scene, config.frames)?;
            let with_readback = (0..config.frames.max(1))
                .map(|_| {
                    let t = Instant::now();
                    gpu::trace(device, queue, &scene, &|_| {}, &never).map(|_| t.elapsed())
                })
                .collect::<Result<Vec<_>>>()?;
            let pass = Pass {
                time,
                with_readback: median(with_readback),
                rays,
            };
            Ok((pass, compile, upload, scene.device_bytes()))
        };
    // The full pass first, so that its compile time is its own.
    let (full, compile, upload, device_bytes) = pass(renderer, globals)?;
    let (eye, ..) = pass(
        renderer,
        &GpuGlobals {
            aov: AOV_DEPTH,
            ..*globals
        },
    )?;
    let depth_1 = GpuGlobals {
        aov: AOV_COLOR,
        max_depth: 1,
        ..*globals
    };
    let (direct, ..) = pass(renderer, &depth_1)?;
    let shaded = match renderer.frame(buffers, &depth_1).wavefront {
        0 => Some(pass(unshadowed, &depth_1)?.0),
        _ => None,
    };
    let counting = GpuGlobals {
        counters: 1,
        ..renderer.frame(buffers, globals)
    };
    let scene = renderer.upload(device, queue, buffers, &counting)?;
    gpu::trace(device, queue, &scene, &|_| {}, &AtomicBool::new(false))?;
    let counted = scene.counters().expect("a counting frame has counts");
    // One more `full` frame, untimed, with each wavefront kernel timed on the device.
    let mut kernels = None;
    if renderer.frame(buffers, globals).wavefront != 0 {
        let mut scene = renderer.upload(device, queue, buffers, globals)?;
        if scene.time_kernels(device) {
            gpu::trace(device, queue, &scene, &|_| {}, &AtomicBool::new(false))?;
            kernels = scene.kernel_times();
        }
    }
    Ok(GpuRow {
        compile,
        upload,
        device_bytes,
        eye,
        shaded,
        direct,
        full,
        counted,
        kernels,
    })
}

fn cpu_row(buffers: &pack::SceneBuffers, globals: &GpuGlobals) -> Result<CpuRow> {
    let never = AtomicBool::new(false);
    let t = Instant::now();
    let (_, counts) = crate::cpu::render(buffers, globals, &|_| {}, &never)?;
    Ok(CpuRow {
        time: t.elapsed(),
        rays: counts.total(),
        counted: counts.counters(size_of::<WideNode>() as u64),
    })
}
