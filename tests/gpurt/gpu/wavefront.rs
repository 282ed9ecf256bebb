//! The wavefront kernels (`shaders/wavefront.wgsl`): the same rays and node fetches as the
//! one `main` kernel, by kind; on a software adapter the image of their CPU twin to the
//! bit; agreement with the CPU renderer on the scenes with the most secondary rays, many
//! samples, every walk, and paths whose rays do not fit a wave; and the twin against the
//! CPU renderer.

use std::sync::atomic::AtomicBool;

use glam::Vec3;
use gpurt::counters::Counters;
use gpurt::cpu::RayCounts;
use gpurt::cpu::pixel::sample_sum;
use gpurt::cpu::tracer::Alone;
use gpurt::cpu::types::Bindings;
use gpurt::cpu::wavefront::wave_sums;
use gpurt::film::Film;
use gpurt::frame::{self, RenderOptions};
use gpurt::gpu::{GpuRenderer, GpuScene};
use gpurt::gpu_types::*;
use gpurt::pack::{self, SceneBuffers};
use gpurt::scene::{self, Light, Scene};

use crate::common::own_scenes;
use crate::common::versus::{
    Gpu, check_all, check_scene, check_scene_resumed, features_scene, gpu,
};

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

/// `buffers` on `g`'s device for a frame of `opts` (counting where `counters` is 1), and
/// the frame.
fn upload(
    g: &Gpu,
    buffers: &SceneBuffers,
    opts: &RenderOptions,
    counters: u32,
) -> (GpuScene, GpuGlobals) {
    let globals = GpuGlobals {
        counters,
        ..g.renderer.frame(buffers, &frame::globals(buffers, opts))
    };
    let scene = g
        .renderer
        .upload(&g.ctx.device, &g.ctx.queue, buffers, &globals)
        .expect("uploads");
    (scene, globals)
}

/// The image, rays, counts and frame of a counting frame on `g`.
fn render(
    g: &Gpu,
    buffers: &SceneBuffers,
    opts: &RenderOptions,
) -> (Film, u64, Counters, GpuGlobals) {
    let (scene, globals) = upload(g, buffers, opts, 1);
    let (device, queue) = (&g.ctx.device, &g.ctx.queue);
    let never = AtomicBool::new(false);
    let (film, rays) = gpurt::gpu::trace(device, queue, &scene, &|_| {}, &never).expect("traces");
    let counted = scene.counters().expect("counts");
    assert_eq!(counted.total_rays(), rays, "the kinds add up");
    (film, rays, counted, globals)
}

/// The features scene without its area light (whose frames take the one kernel).
fn features_without_area_lights() -> Scene {
    let mut scene = features_scene("");
    scene.lights.retain(|l| !matches!(l, Light::Area { .. }));
    scene
}

/// Scenes with glass and mirrors, at depth 5 and 4 samples a pixel, and the features
/// scene's every primitive and every light kind but the area light.
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
    let features = features_without_area_lights();
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

/// The film the CPU twin of the kernels gives for a whole frame (one tile, every sample,
/// the room a GPU's wave of its paths has): its sums divided by the samples, as the GPU's
/// host divides them, and how many pixels had paths cut short.
fn twin_film(buffers: &SceneBuffers, globals: &GpuGlobals) -> (Film, usize) {
    let b = Bindings::gpu_walk(buffers, globals);
    let (w, h) = (globals.width, globals.height);
    let tile = GpuTile {
        width: w,
        height: h,
        out_stride: w,
        sample_count: globals.spp,
        ..Default::default()
    };
    let room = w * h * globals.spp * WAVE_RAYS_PER_PATH as u32;
    let sums = wave_sums(&b, &tile, room, (w * h) as usize);
    let mut film = Film::new(w, h);
    let n = globals.spp as f32;
    let mut cut = 0;
    for (i, (sum, rays, _)) in sums.iter().enumerate() {
        film.set(i as u32 % w, i as u32 / w, (*sum / n).to_array());
        cut += usize::from(rays & PIXEL_CUT_SHORT != 0);
    }
    (film, cut)
}

/// On every walk the wavefront kernels trace what `main` traces: the same rays and node
/// fetches by kind; on a software adapter the image of the kernels' CPU twin within
/// rounding in every pixel (lavapipe's arithmetic is not the CPU's to the bit: `pow` and
/// square roots round otherwise); on any adapter, images within the GPU-vs-CPU limits of
/// the CPU's.
#[test]
fn the_wavefront_kernels_trace_what_the_main_kernel_traces() {
    let Some(g) = gpu() else {
        return;
    };
    let software = gpurt::gpu::is_software(&g.ctx.info);
    let mut cases = Vec::new();
    for traversal in [
        TRAVERSAL_WIDE,
        TRAVERSAL_QWIDE,
        TRAVERSAL_CWIDE,
        TRAVERSAL_PAIRS,
    ] {
        let [wave, main] = both(g, traversal);
        for (name, scene, opts) in scenes() {
            let buffers = pack::pack(scene.clone()).expect("packs");
            let label = format!("{name} ({})", TRAVERSAL_NAMES[traversal as usize]);
            let (wave_film, wave_rays, wave_counts, wave_frame) = render(&wave, &buffers, &opts);
            let (_, main_rays, main_counts, main_frame) = render(&main, &buffers, &opts);
            assert_eq!(
                (wave_frame.wavefront, main_frame.wavefront),
                (1, 0),
                "{label}"
            );
            assert_eq!(wave_rays, main_rays, "{label}: rays");
            assert_eq!(wave_counts, main_counts, "{label}: rays and nodes by kind");
            if software {
                let (twin, cut) = twin_film(&buffers, &wave_frame);
                assert_eq!(cut, 0, "{label}: every path fits the twin's wave");
                for (i, (a, b)) in wave_film.pixels.iter().zip(&twin.pixels).enumerate() {
                    let (a, b) = (Vec3::from(*a), Vec3::from(*b));
                    assert!(
                        rounding_apart(a, b),
                        "{label}: pixel {i}: {a} against the twin's {b}"
                    );
                }
            }
            cases.push(check_scene(&wave, &label, &scene, &opts));
        }
    }
    check_all(cases);
}

/// Other frames than colour take the one kernel (an AOV traces eye rays alone), and so
/// do colour frames of a scene with an area light (whose samples draw from a path's
/// random stream depth first); without it, the features scene takes the wavefront.
#[test]
fn aov_and_area_light_frames_keep_the_main_kernel() {
    let Some(g) = gpu() else {
        return;
    };
    let [wave, _] = both(g, TRAVERSAL_WIDE);
    let scene = features_scene("");
    let buffers = pack::pack(scene.clone()).expect("packs");
    let takes = |buffers: &SceneBuffers, aov| {
        let opts = RenderOptions {
            aov,
            ..RenderOptions::for_camera(&scene.camera)
        };
        let frame = wave
            .renderer
            .frame(buffers, &frame::globals(buffers, &opts));
        frame.wavefront
    };
    for aov in [AOV_NORMAL, AOV_DEPTH, AOV_COST, AOV_COLOR] {
        assert_eq!(takes(&buffers, aov), 0, "aov {aov}");
    }
    let without = pack::pack(features_without_area_lights()).expect("packs");
    assert_eq!(takes(&without, AOV_COLOR), 1);
}

/// Glass at depth 16 (each glass hit sends two rays) and many samples a pixel (several
/// passes) on the wavefront kernels agree with the CPU. Paths that outgrow a wave's room
/// are flagged and finished by `resume`; on lavapipe these frames fit their waves and
/// resume none (the test says how many), so the flagging is shown by the CPU twin
/// (`paths_that_outgrow_the_wave_are_flagged_and_the_rest_are_traced`) and `resume`
/// itself by the one kernel's tests (`dispatch.rs`, `counts.rs`), which assert it.
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
    let (deep, resumed) = check_scene_resumed(&wave, "glass at depth 16", &glass, &deep);
    check_all([deep, check_scene(&wave, "glass at 24 spp", &glass, &many)]);
    // None on lavapipe: its wave holds every path's rays here (the CPU twin's test below
    // shows a wave of a GPU's room cutting such paths short and flagging them).
    println!("glass at depth 16: {resumed} pixels finished by resume");
}

/// The bundled glass scene at 24x20 and depth 16, `spp` samples a pixel: paths of many
/// rays a round.
fn deep_glass(spp: u32) -> (Scene, RenderOptions) {
    let glass = scene::load(&own_scenes().join("glass.nff")).expect("loads");
    let opts = RenderOptions {
        width: 24,
        height: 20,
        spp,
        max_depth: 16,
        ..RenderOptions::for_camera(&glass.camera)
    };
    (glass, opts)
}

/// Whether two sums of the same light differ by rounding only: within 2^-16 of the larger
/// channel in each channel.
fn rounding_apart(a: Vec3, b: Vec3) -> bool {
    let scale = a.abs().max(b.abs()).max_element().max(1e-6);
    (a - b).abs().max_element() <= scale / 65536.0
}

/// The CPU twin of the kernels (`cpu::wavefront`) runs the same rounds without a GPU:
/// every pixel's rays and counts are the CPU renderer's exactly and its sum is within
/// rounding of theirs (added a generation at a time, not depth first), on glass and
/// mirrors, the features scene and glass at depth 16, over a tile that starts mid-image at
/// a later sample, with room for every path's rays. A tile started one sample off
/// differs, and so does a sum one part in 10^4 off, so the comparison sees both.
#[test]
fn the_cpu_twin_of_the_kernels_traces_what_the_cpu_traces() {
    let mut cases = scenes();
    let (glass, deep) = deep_glass(3);
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
            group_side: 0,
        };
        let t = tile(1);
        let pixels = (t.width * t.height) as usize;
        // Room for every ray of a round: glass at depth 16 sends many a path.
        let room = 1 << 20;
        let waved = wave_sums(&b, &t, room, pixels);
        let shifted = wave_sums(&b, &tile(0), room, pixels);
        let mut differs = false;
        for (i, &(sum, rays, counts)) in waved.iter().enumerate() {
            let (x, y) = (t.x + i as u32 % t.width, t.y + i as u32 / t.width);
            let mut want = RayCounts::default();
            let samples = t.sample_start..t.sample_start + t.sample_count;
            let expect = sample_sum(&b, &mut Alone, (x, y), samples, Vec3::ZERO, &mut want);
            assert!(
                rounding_apart(sum, expect),
                "{name}: pixel ({x}, {y}): {sum} against {expect}"
            );
            assert!(!rounding_apart(sum * 1.0001, expect) || expect == Vec3::ZERO);
            assert_eq!(counts, want, "{name}: pixel ({x}, {y})");
            assert_eq!(u64::from(rays), want.total(), "{name}: pixel ({x}, {y})");
            differs |= !rounding_apart(shifted[i].0, sum);
        }
        assert!(differs, "{name}: the samples do not show");
    }
}

/// A wave with the room a GPU's wave has (four rays a path in a round) cuts short the
/// paths of glass at depth 16 whose rays outgrow it: their pixels are flagged for
/// `resume`, and every other pixel is still the CPU's, rays and counts exactly.
#[test]
fn paths_that_outgrow_the_wave_are_flagged_and_the_rest_are_traced() {
    let (glass, opts) = deep_glass(2);
    let buffers = pack::pack(glass).expect("packs");
    let globals = frame::globals(&buffers, &opts);
    let b = Bindings::gpu_walk(&buffers, &globals);
    let tile = GpuTile {
        width: opts.width,
        height: opts.height,
        out_stride: opts.width,
        sample_count: opts.spp,
        ..Default::default()
    };
    let room = opts.width * opts.height * opts.spp * WAVE_RAYS_PER_PATH as u32;
    let sums = wave_sums(&b, &tile, room, (opts.width * opts.height) as usize);
    let mut cut = 0;
    for (i, &(sum, rays, counts)) in sums.iter().enumerate() {
        if rays & PIXEL_CUT_SHORT != 0 {
            cut += 1;
            continue;
        }
        let (x, y) = (i as u32 % opts.width, i as u32 / opts.width);
        let mut want = RayCounts::default();
        let expect = sample_sum(&b, &mut Alone, (x, y), 0..opts.spp, Vec3::ZERO, &mut want);
        assert!(rounding_apart(sum, expect), "pixel ({x}, {y})");
        assert_eq!(counts, want, "pixel ({x}, {y})");
        assert_eq!(u64::from(rays), want.total(), "pixel ({x}, {y})");
    }
    assert!(
        cut > 0 && cut < sums.len(),
        "{cut} of {} pixels cut short",
        sums.len()
    );
}

/// Timing the kernels (`GpuScene::time_kernels`, what `gpurt bench` prints for a
/// wavefront frame) changes nothing in the image or the rays; where the device has
/// timestamps each kernel gets its time, and the kernels that trace rays take some; a
/// frame of the one kernel has no kernels to time.
#[test]
fn timing_the_kernels_changes_nothing_and_times_each() {
    let Some(g) = gpu() else {
        return;
    };
    let [wave, main] = both(g, TRAVERSAL_WIDE);
    let (name, scene, opts) = scenes().remove(0);
    let buffers = pack::pack(scene).expect("packs");
    let (device, queue) = (&g.ctx.device, &g.ctx.queue);
    let never = AtomicBool::new(false);
    let (mut up, _) = upload(&wave, &buffers, &opts, 0);
    let plain = gpurt::gpu::trace(device, queue, &up, &|_| {}, &never).expect("traces");
    assert!(up.kernel_times().is_none(), "{name}: not timed yet");
    if !up.time_kernels(device) {
        // Only a device without timestamps may leave the kernels untimed; under CI=true
        // an adapter that offers them must time them (lavapipe does).
        let offered = g
            .ctx
            .adapter
            .features()
            .contains(wgpu::Features::TIMESTAMP_QUERY);
        assert!(
            !(offered && crate::common::in_ci()),
            "{name}: the adapter offers timestamps, yet the kernels were not timed"
        );
        crate::common::skip(&format!(
            "{name}: the device has no timestamps; the kernels are not timed"
        ));
        return;
    }
    let timed = gpurt::gpu::trace(device, queue, &up, &|_| {}, &never).expect("traces");
    assert!(timed == plain, "{name}: timing changed the frame");
    let times = up.kernel_times().expect("timed");
    let names: Vec<_> = times.iter().map(|(n, _)| *n).collect();
    assert_eq!(
        names,
        [
            "wf_generate",
            "wf_advance",
            "wf_extend",
            "wf_scan",
            "wf_shade",
            "wf_advance_shadows",
            "wf_shadow",
            "wf_gather",
            "wf_finish"
        ]
    );
    for (n, s) in &times {
        assert!(s.is_finite() && *s >= 0.0, "{name}: {n} {s}");
    }
    for traces in ["wf_extend", "wf_shadow"] {
        let s = times.iter().find(|(n, _)| *n == traces).expect("named").1;
        assert!(s > 0.0, "{name}: {traces} took no time");
    }
    let (mut one, _) = upload(&main, &buffers, &opts, 0);
    assert!(
        !one.time_kernels(device),
        "the one kernel has no wave to time"
    );
}
