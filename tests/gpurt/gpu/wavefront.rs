//! The wavefront kernels (`shaders/wavefront.wgsl`): the images of the one `main` kernel,
//! to the bit on a software adapter (the same steps in the same order, only other pixels
//! beside them), the same rays and counts, and agreement with the CPU on the scenes with
//! the most secondary rays, many samples, every walk, and pixels too heavy for one
//! invocation; and the kernels' CPU twin against the CPU renderer.

use std::sync::atomic::AtomicBool;

use glam::Vec3;
use gpurt::cpu::RayCounts;
use gpurt::cpu::main::sample_sum;
use gpurt::cpu::types::Bindings;
use gpurt::cpu::wavefront::wave_sums;
use gpurt::film::Film;
use gpurt::frame::{self, RenderOptions};
use gpurt::gpu::GpuRenderer;
use gpurt::gpu_types::*;
use gpurt::pack::{self, SceneBuffers};
use gpurt::scene::{self, Scene};

use crate::common::own_scenes;
use crate::common::versus::{Gpu, check_all, check_scene, features_scene, gpu};

/// The same device with renderers taking the wavefront kernels and the one kernel.
fn both(g: &Gpu, traversal: u32) -> [Gpu; 2] {
    [true, false].map(|wavefront| Gpu {
        ctx: g.ctx.clone(),
        renderer: GpuRenderer::new(&g.ctx.device, None)
            .expect("shader compiles")
            .with_traversal(traversal)
            .with_wavefront(wavefront),
    })
}

/// The image, rays and counts of a counting frame on `g`.
fn render(g: &Gpu, buffers: &SceneBuffers, opts: &RenderOptions) -> (Film, u64, GpuGlobals) {
    let globals = GpuGlobals {
        counters: 1,
        ..g.renderer.frame(buffers, &frame::globals(buffers, opts))
    };
    let (device, queue) = (&g.ctx.device, &g.ctx.queue);
    let scene = g
        .renderer
        .upload(device, queue, buffers, &globals)
        .expect("uploads");
    let never = AtomicBool::new(false);
    let (film, rays) = gpurt::gpu::trace(device, queue, &scene, &|_| {}, &never).expect("traces");
    let counted = scene.counters().expect("counts");
    assert_eq!(counted.total_rays(), rays, "the kinds add up");
    (film, rays, globals)
}

/// Scenes with glass and mirrors, at depth 5 and 4 samples a pixel, and the features
/// scene's every light and primitive kind.
fn scenes() -> Vec<(String, Scene, RenderOptions)> {
    let mut out = Vec::new();
    for name in ["glass.nff", "mirrors.nff"] {
        let scene = scene::load(&own_scenes().join(name)).expect("loads");
        let opts = RenderOptions {
            width: 64,
            height: 48,
            spp: 4,
            max_depth: 5,
            ..RenderOptions::for_camera(&scene.camera)
        };
        out.push((name.to_string(), scene, opts));
    }
    let features = features_scene("");
    let opts = RenderOptions {
        width: 40,
        height: 40,
        spp: 2,
        max_depth: 6,
        ..RenderOptions::for_camera(&features.camera)
    };
    out.push(("features".to_string(), features, opts));
    out
}

/// On every walk the wavefront kernels trace what `main` traces: the same rays by kind,
/// the same node fetches, and on a software adapter the same image to the bit; on a GPU,
/// whose compiler may fuse arithmetic differently in each kernel, images within the
/// GPU-vs-CPU limits of the CPU's.
#[test]
fn the_wavefront_kernels_trace_what_the_main_kernel_traces() {
    let Some(g) = gpu() else {
        return;
    };
    let software = gpurt::gpu::is_software(&g.ctx.info);
    let mut cases = Vec::new();
    for traversal in [TRAVERSAL_WIDE, TRAVERSAL_CWIDE, TRAVERSAL_PAIRS] {
        let [wave, main] = both(g, traversal);
        for (name, scene, opts) in scenes() {
            let buffers = pack::pack(scene.clone()).expect("packs");
            let label = format!("{name} ({})", TRAVERSAL_NAMES[traversal as usize]);
            let (wave_film, wave_rays, wave_frame) = render(&wave, &buffers, &opts);
            let (main_film, main_rays, main_frame) = render(&main, &buffers, &opts);
            assert_eq!(
                (wave_frame.wavefront, main_frame.wavefront),
                (1, 0),
                "{label}"
            );
            assert_eq!(wave_rays, main_rays, "{label}: rays");
            if software {
                assert!(wave_film == main_film, "{label}: the images differ");
            }
            cases.push(check_scene(&wave, &label, &scene, &opts));
        }
    }
    check_all(cases);
}

/// Other frames than colour take the one kernel: an AOV traces eye rays alone.
#[test]
fn aov_frames_keep_the_main_kernel() {
    let Some(g) = gpu() else {
        return;
    };
    let [wave, _] = both(g, TRAVERSAL_WIDE);
    let scene = features_scene("");
    let buffers = pack::pack(scene.clone()).expect("packs");
    for aov in [AOV_NORMAL, AOV_DEPTH, AOV_COST] {
        let opts = RenderOptions {
            aov,
            ..RenderOptions::for_camera(&scene.camera)
        };
        let frame = wave
            .renderer
            .frame(&buffers, &frame::globals(&buffers, &opts));
        assert_eq!(frame.wavefront, 0, "aov {aov}");
    }
}

/// Glass at depth 16: pixels too heavy for one invocation on lavapipe are flagged by the
/// wavefront kernels too and finished by `resume`; many samples a pixel take several
/// passes. Both agree with the CPU.
#[test]
fn heavy_pixels_and_many_samples_on_the_wavefront_kernels_match_cpu() {
    let Some(g) = gpu() else {
        return;
    };
    let [wave, _] = both(g, TRAVERSAL_WIDE);
    let glass = scene::load(&own_scenes().join("glass.nff")).expect("loads");
    let deep = RenderOptions {
        width: 48,
        height: 48,
        max_depth: 16,
        ..RenderOptions::for_camera(&glass.camera)
    };
    let many = RenderOptions {
        width: 32,
        height: 32,
        spp: 24,
        ..RenderOptions::for_camera(&glass.camera)
    };
    check_all([
        check_scene(&wave, "glass at depth 16", &glass, &deep),
        check_scene(&wave, "glass at 24 spp", &glass, &many),
    ]);
}

/// The CPU twin of the kernels (`cpu::wavefront`) runs the same queues round by round
/// without a GPU: every pixel's sum, rays and counts are the CPU renderer's to the bit, on
/// glass and mirrors at depths up to 16 and the features scene, over a tile that starts
/// mid-image at a later sample. A tile started one sample off differs, so the comparison
/// sees a pixel's samples.
#[test]
fn the_cpu_twin_of_the_kernels_traces_what_the_cpu_traces() {
    let mut cases = scenes();
    let glass = scene::load(&own_scenes().join("glass.nff")).expect("loads");
    let deep = RenderOptions {
        width: 24,
        height: 20,
        spp: 3,
        max_depth: 16,
        ..RenderOptions::for_camera(&glass.camera)
    };
    cases.push(("glass at depth 16".to_string(), glass, deep));
    for (name, scene, opts) in cases {
        let buffers = pack::pack(scene).expect("packs");
        let globals = frame::globals(&buffers, &opts);
        let b = Bindings::gpu_walk(&buffers, &globals);
        let tile = |sample_start| GpuTile {
            x: 3,
            y: 2,
            width: opts.width - 5,
            height: opts.height - 3,
            out_base: 0,
            out_stride: opts.width - 5,
            sample_start,
            sample_count: opts.spp - 1,
            scatter: 0,
        };
        let t = tile(1);
        let pixels = (t.width * t.height) as usize;
        let waved = wave_sums(&b, &t, pixels);
        let shifted = wave_sums(&b, &tile(0), pixels);
        let mut differs = false;
        for (i, &(sum, rays, counts)) in waved.iter().enumerate() {
            let (x, y) = (t.x + i as u32 % t.width, t.y + i as u32 / t.width);
            let mut want = RayCounts::default();
            let samples = t.sample_start..t.sample_start + t.sample_count;
            let expect = sample_sum(&b, x, y, samples, Vec3::ZERO, &mut want);
            assert_eq!(sum, expect, "{name}: pixel ({x}, {y})");
            assert_eq!(counts, want, "{name}: pixel ({x}, {y})");
            assert_eq!(u64::from(rays), want.total(), "{name}: pixel ({x}, {y})");
            differs |= shifted[i].0 != sum;
        }
        assert!(differs, "{name}: the samples do not show");
    }
}
