//! The GPU against the CPU reference: one device and compiled pipeline for the whole test
//! binary, both renders of a frame, and their comparison under `Thresholds::GPU_VS_CPU`
//! with the CPU's noise floor; every variant a scene gets (samples per pixel, each AOV);
//! and the features scene, which has every light and primitive kind.
//!
//! Without an adapter the tests skip with a message, unless `GPURT_REQUIRE_GPU=1`, where
//! they fail. Failures write the CPU image, the GPU image and a heat map to
//! `target/gpu-vs-cpu/`.

use std::path::{Path, PathBuf};
use std::sync::OnceLock;
use std::sync::atomic::AtomicBool;

use gpurt::agreement::noise_floor;
use gpurt::compare::{self, DiffStats, Thresholds};
use gpurt::film::{self, Film};
use gpurt::frame::{self, RenderOptions, Shading};
use gpurt::gpu::{GpuContext, GpuRenderer, GpuScene};
use gpurt::gpu_types::*;
use gpurt::pack::{self, SceneBuffers};
use gpurt::scene::Scene;
use image::RgbImage;

/// Side of the comparison renders.
pub const SIZE: u32 = 128;

pub struct Gpu {
    pub ctx: GpuContext,
    pub renderer: GpuRenderer,
}

/// One device and compiled pipeline for the whole test binary.
pub fn gpu() -> Option<&'static Gpu> {
    static GPU: OnceLock<Result<Gpu, String>> = OnceLock::new();
    let gpu = GPU.get_or_init(|| {
        let required = std::env::var("GPURT_REQUIRE_GPU").is_ok_and(|v| v == "1");
        match gpurt::gpu::open(None) {
            Ok(ctx) => {
                let renderer = GpuRenderer::new(&ctx.device, None).expect("shader compiles");
                Ok(Gpu { ctx, renderer })
            }
            Err(e) if required => panic!("GPURT_REQUIRE_GPU=1 but: {e}"),
            Err(e) => Err(e.to_string()),
        }
    });
    match gpu {
        Ok(g) => {
            println!("GPU tests run on {}", g.ctx.describe());
            Some(g)
        }
        // Every GPU test says it skips, not only the first.
        Err(e) => {
            crate::common::skip(&format!("no GPU adapter: {e}"));
            None
        }
    }
}

/// The frame `globals` of `buffers` on the CPU, or on the GPU given one.
pub fn render_on(buffers: &SceneBuffers, globals: &GpuGlobals, gpu: Option<&Gpu>) -> Film {
    let never = AtomicBool::new(false);
    match gpu {
        None => gpurt::cpu::render(buffers, globals, &|_| {}, &never).map(|r| r.0),
        Some(g) => g
            .renderer
            .render(
                &g.ctx.device,
                &g.ctx.queue,
                buffers,
                globals,
                &|_| {},
                &never,
            )
            .map(|r| r.0),
    }
    .expect("renders")
}

pub fn render_both(
    g: &Gpu,
    scene: &Scene,
    buffers: &SceneBuffers,
    globals: &GpuGlobals,
) -> (Film, Film) {
    let (cpu, gpu, _) = render_both_resumed(g, scene, buffers, globals);
    (cpu, gpu)
}

/// `render_both`, and the pixels the GPU finished in `resume` (`GpuScene::resumed`).
pub fn render_both_resumed(
    g: &Gpu,
    scene: &Scene,
    buffers: &SceneBuffers,
    globals: &GpuGlobals,
) -> (Film, Film, u64) {
    let never = AtomicBool::new(false);
    let (cpu, _) = gpurt::cpu::render(buffers, globals, &|_| {}, &never).expect("CPU renders");
    let (gpu, _, up) = trace_on(g, &g.renderer, buffers, globals)
        .unwrap_or_else(|e| panic!("{}: GPU render failed: {e}", scene.name));
    (cpu, gpu, up.resumed())
}

/// The frame `globals` of `buffers` uploaded by `renderer` to `g`'s device and traced:
/// the film, the rays, and the uploaded scene, whose record of the trace (`counters`,
/// `resumed`) the caller reads.
pub fn trace_on(
    g: &Gpu,
    renderer: &GpuRenderer,
    buffers: &SceneBuffers,
    globals: &GpuGlobals,
) -> gpurt::Result<(Film, u64, GpuScene)> {
    let (device, queue) = (&g.ctx.device, &g.ctx.queue);
    let up = renderer.upload(device, queue, buffers, globals)?;
    let (film, rays) = gpurt::gpu::trace(device, queue, &up, &|_| {}, &AtomicBool::new(false))?;
    Ok((film, rays, up))
}

/// Checks that `resume` finished some of a frame's pixels (`resumed` of them) where the
/// adapter cuts long shader loops short: a software rasteriser (lavapipe, whose every
/// loop ends after 65535 iterations; CI's adapter). Elsewhere (a GPU has no such limit)
/// it says that the frame did not exercise `resume`.
pub fn expect_resumed(g: &Gpu, label: &str, resumed: u64) {
    let software = g.ctx.adapter.get_info().device_type == wgpu::DeviceType::Cpu;
    if software {
        assert!(resumed > 0, "{label}: no pixel was finished by resume");
    } else if resumed == 0 {
        crate::common::skip(&format!(
            "{label}: this adapter finished every pixel at once; resume was not exercised"
        ));
    }
}

pub fn failure_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("target/gpu-vs-cpu")
}

/// Compares GPU and CPU images under `Thresholds::GPU_VS_CPU`, with the pixel-count limit
/// raised to the CPU's own noise floor where the plain limits fail (see
/// `Thresholds::check_allowing_noise`); on failure writes the images and returns a
/// message.
pub fn compare(
    label: &str,
    cpu: &RgbImage,
    gpu: &RgbImage,
    floor: impl FnOnce() -> gpurt::Result<f64>,
) -> Result<DiffStats, String> {
    let stats = compare::diff(cpu, gpu, Thresholds::GPU_VS_CPU.tolerance_255)
        .map_err(|e| format!("{label}: {e}"))?;
    let (floor, verdict) = Thresholds::GPU_VS_CPU
        .check_allowing_noise(&stats, floor)
        .map_err(|e| format!("{label}: {e}"))?;
    verdict
        .map_err(|why| match floor {
            Some(f) => format!(
                "{why}; the CPU's own one-ulp noise floor is {:.3}%",
                f * 100.0
            ),
            None => why,
        })
        .map(|()| stats)
        .map_err(|why| {
            let dir = failure_dir();
            let _ = std::fs::create_dir_all(&dir);
            let stem = label.trim().replace(['/', ' ', '.'], "_");
            let path = |suffix: &str| dir.join(format!("{stem}-{suffix}.png"));
            let _ = film::save_rgb8(cpu, &path("cpu"));
            let _ = film::save_rgb8(gpu, &path("actual"));
            if let Ok(heat) = compare::heat_map(cpu, gpu) {
                let _ = film::save_rgb8(&heat, &path("difference"));
            }
            format!("{label}: {why} ({stats}); images in {}", dir.display())
        })
}

/// One comparison's outcome: its label and statistics, or why it failed.
pub type Outcome = Result<(String, DiffStats), String>;

pub fn check_scene(g: &Gpu, label: &str, scene: &Scene, opts: &RenderOptions) -> Outcome {
    check_scene_resumed(g, label, scene, opts).0
}

/// `check_scene`, and the pixels the GPU finished in `resume`.
pub fn check_scene_resumed(
    g: &Gpu,
    label: &str,
    scene: &Scene,
    opts: &RenderOptions,
) -> (Outcome, u64) {
    let buffers = pack::pack(scene.clone()).expect("scene packs");
    // The CPU walks the BVH as the GPU renderer does, so costs match node for node.
    let globals = g.renderer.frame(&buffers, &frame::globals(&buffers, opts));
    let (cpu, gpu, resumed) = render_both_resumed(g, scene, &buffers, &globals);
    (
        check_films(label, opts, &buffers, &globals, cpu, gpu),
        resumed,
    )
}

/// The CPU's film against the GPU's, as `check_scene` compares them.
fn check_films(
    label: &str,
    opts: &RenderOptions,
    buffers: &SceneBuffers,
    globals: &GpuGlobals,
    cpu: Film,
    gpu: Film,
) -> Outcome {
    if cpu.pixels.iter().flatten().any(|v| !v.is_finite()) {
        return Err(format!("{label}: CPU image has non-finite values"));
    }
    let cpu = cpu.for_display(opts.aov).to_rgb8();
    let stats = compare(label, &cpu, &gpu.for_display(opts.aov).to_rgb8(), || {
        noise_floor(buffers, globals, &cpu)
    })?;
    Ok((label.to_string(), stats))
}

/// Every comparison a scene gets: colour at 1 and 4 samples per pixel, colour under
/// Blinn-Phong, and each AOV.
pub fn check_variants(g: &Gpu, label: &str, scene: &Scene) -> Vec<Outcome> {
    let base = opts(scene);
    let variants = [
        ("", base.clone()),
        (
            "spp4",
            RenderOptions {
                spp: 4,
                ..base.clone()
            },
        ),
        (
            "blinn-phong",
            RenderOptions {
                shading: Shading::BlinnPhong,
                ..base.clone()
            },
        ),
        (
            "normal",
            RenderOptions {
                aov: AOV_NORMAL,
                ..base.clone()
            },
        ),
        (
            "depth",
            RenderOptions {
                aov: AOV_DEPTH,
                ..base.clone()
            },
        ),
        (
            "cost",
            RenderOptions {
                aov: AOV_COST,
                ..base.clone()
            },
        ),
        (
            "uv",
            RenderOptions {
                aov: AOV_UV,
                ..base
            },
        ),
    ];
    variants
        .iter()
        .map(|(name, o)| check_scene(g, &format!("{label} {name}"), scene, o))
        .collect()
}

pub fn opts(scene: &Scene) -> RenderOptions {
    RenderOptions {
        width: SIZE,
        height: SIZE,
        ..RenderOptions::for_camera(&scene.camera)
    }
}

/// Fails with every mismatch at once; otherwise reports the worst agreement seen, which is
/// what `Thresholds::GPU_VS_CPU` has to allow.
pub fn check_all(cases: impl IntoIterator<Item = Outcome>) {
    let (passed, failures): (Vec<_>, Vec<_>) = cases.into_iter().partition(Result::is_ok);
    let failures: Vec<String> = failures.into_iter().filter_map(Result::err).collect();
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    let passed: Vec<(String, DiffStats)> = passed.into_iter().filter_map(Result::ok).collect();
    let worst = |key: fn(&DiffStats) -> f64| {
        passed
            .iter()
            .max_by(|a, b| key(&a.1).total_cmp(&key(&b.1)))
            .map(|(label, s)| format!("{:.5} ({label})", key(s)))
            .unwrap_or_default()
    };
    println!(
        "{} comparisons; worst fraction over 2/255 {}, FLIP mean {}, |mean signed| {}",
        passed.len(),
        worst(|s| s.frac_over),
        worst(|s| s.flip_mean),
        worst(|s| s.mean_signed.abs())
    );
}

/// A small scene with every light kind, glass, a mirror, a cone and a box, written here so
/// the test does not depend on files that may change.
pub const FEATURES: &str = "
b 0.2 0.3 0.4
v
from 0 -6 2.5
at 0 0 0.6
up 0 0 1
angle 40
hither 0.01
resolution 128 128
l 4 -4 6
dl -1 1 -2 0.3 0.3 0.3
al -1 -1 5  2 0 0  0 2 0  0.8 0.8 0.7  3 3
f 0.8 0.8 0.8 0.8 0 1 0 1
pl 0 0 0  1 0 0  0 1 0
f 1 0.2 0.2 0.6 0.4 40 0 1
s -1.2 0 0.8 0.8
f 0.9 0.9 1 0.1 0.1 100 0.85 1.5
s 0.6 -1 0.7 0.7
f 0.2 0.8 0.3 0.7 0.2 20 0 1
c 1.6 1 0 0.5  1.6 1 1.5 0.2
f 0.9 0.7 0.2 0.8 0 1 0 1
aabb -0.3 0.5 0.8 1.6 0 0.6
";

pub fn features_scene(extra_view: &str) -> Scene {
    let text = FEATURES.replace(
        "resolution 128 128",
        &format!("resolution 128 128\n{extra_view}"),
    );
    gpurt::scene::nff::parse(text.as_bytes(), "features.nff", Path::new(".")).expect("parses")
}
