//! Dispatch: work too long for one invocation (many samples per pixel, deep glass, a
//! thousand lights) is cut into passes and continued across dispatches, agreeing with the
//! CPU ray for ray; what cannot be finished is an error; dispatches over the time budget
//! cut the rest of the frame finer, and a GPU's cut (strips, several samples a pass)
//! traces the same frames, without changing a bit.

use std::path::Path;
use std::sync::atomic::AtomicBool;

use gpurt::compare::DiffStats;
use gpurt::frame::{self, RenderOptions, Shading};
use gpurt::gpu::GpuRenderer;
use gpurt::gpu_types::*;
use gpurt::pack;
use gpurt::scene::{self, Scene};

use crate::common::versus::{
    Gpu, Outcome, check_all, expect_resumed, features_scene, gpu, opts, trace_on,
};
use crate::common::{own_scenes, shared_scenes};

/// Renders on both backends and checks agreement (with the noise floor) and ray counts:
/// equal within one in 10^4, the drift that lights grazing a surface give (lavapipe's
/// normalize and sqrt are not the CPU's; 47 of 2.65 million shadow rays in the thousand
/// lights case), where dropped samples or bounces lose a tenth or more.
fn check_heavy(g: &Gpu, label: &str, scene: &Scene, opts: &RenderOptions) -> Outcome {
    check_heavy_resumed(g, label, scene, opts).map(|(outcome, _)| outcome)
}

/// `check_heavy`, and the pixels the GPU finished in `resume` (`GpuScene::resumed`).
fn check_heavy_resumed(
    g: &Gpu,
    label: &str,
    scene: &Scene,
    opts: &RenderOptions,
) -> Result<((String, DiffStats), u64), String> {
    let buffers = pack::pack(scene.clone()).expect("scene packs");
    let globals = g.renderer.frame(&buffers, &frame::globals(&buffers, opts));
    let never = AtomicBool::new(false);
    let (cpu, counts) =
        gpurt::cpu::render(&buffers, &globals, &|_| {}, &never).expect("CPU renders");
    let (gpu, rays, up) = trace_on(g, &g.renderer, &buffers, &globals)
        .map_err(|e| format!("{label}: GPU render failed: {e}"))?;
    let a = gpurt::agreement::agreement(&buffers, &globals, &cpu, &gpu).expect("compares");
    a.verdict
        .map_err(|why| format!("{label}: {why} ({})", a.stats))?;
    let drift = rays.abs_diff(counts.total()) as f64 / counts.total() as f64;
    if drift > 1e-4 {
        return Err(format!(
            "{label}: the GPU traced {rays} rays, the CPU {}",
            counts.total()
        ));
    }
    Ok(((label.to_string(), a.stats), up.resumed()))
}

/// An 8x8 area light over a glass sphere and a box: 64 shadow rays per hit.
const AREA_GLASS: &str = "
b 0.05 0.05 0.07
v
from 0 -9 4.5
at 0 0 0.8
up 0 0 1
angle 36
hither 0.01
resolution 64 64
al -1 -1 5 2 0 0 0 2 0 0.85 0.85 0.8 8 8
f 0.85 0.85 0.85 0.85 0 1 0 1
p 4
-10 -10 0
10 -10 0
10 10 0
-10 10 0
f 1 1 1 0.1 0.3 60 0.8 1.5
s -1 0 1.2 1.2
f 0.3 0.45 0.9 0.8 0.1 30 0 1
aabb 0.6 2.4 -0.6 1.2 0 1.4
";

/// Many samples per pixel, which one invocation could not all trace on lavapipe (it ends
/// every loop once an invocation has run 65535 loop iterations): traced a pass of samples
/// at a time, they agree with the CPU, rays counted alike.
#[test]
fn many_samples_per_pixel_match_cpu() {
    let Some(g) = gpu() else {
        return;
    };
    let area = gpurt::scene::nff::parse(AREA_GLASS.as_bytes(), "area-glass.nff", Path::new("."))
        .expect("parses");
    let mut cases = vec![check_heavy(
        g,
        "area light and glass, 64 spp",
        &area,
        &RenderOptions {
            spp: 64,
            ..RenderOptions::for_camera(&area.camera)
        },
    )];
    if let Some(root) = shared_scenes() {
        for (name, side, spp) in [
            ("gears-4", 64, 32),
            ("teapot-6", 48, 64),
            ("mount-5", 48, 64),
        ] {
            let scene = scene::load(&root.join(format!("spd/{name}.nff"))).expect("loads");
            let opts = RenderOptions {
                width: side,
                height: side,
                spp,
                ..RenderOptions::for_camera(&scene.camera)
            };
            cases.push(check_heavy(g, &format!("{name} {spp} spp"), &scene, &opts));
        }
    }
    check_all(cases);
}

/// One sample whose work exceeds what one invocation may do on lavapipe (glass at depth
/// 16; a thousand lights): such pixels continue across dispatches and agree with the CPU,
/// under either shading model (the continued pixels sample their lights in `resume`).
#[test]
fn heavy_single_samples_match_cpu() {
    let Some(g) = gpu() else {
        return;
    };
    let glass = scene::load(&own_scenes().join("glass.nff")).expect("loads");
    let mut cases = Vec::new();
    // Each case's label and the pixels `resume` finished.
    let mut resumed = Vec::new();
    let mut heavy = |label: String, scene: &Scene, opts: &RenderOptions| {
        cases.push(
            check_heavy_resumed(g, &label, scene, opts).map(|(outcome, n)| {
                resumed.push((label, n));
                outcome
            }),
        );
    };
    for shading in Shading::ALL {
        heavy(
            format!("glass at depth 16, {}", shading.name()),
            &glass,
            &RenderOptions {
                width: 64,
                height: 64,
                max_depth: 16,
                shading,
                ..RenderOptions::for_camera(&glass.camera)
            },
        );
    }
    if let Some(root) = shared_scenes() {
        let mut src = std::fs::read_to_string(root.join("spd/balls-3.nff")).expect("reads");
        for i in 0..1000 {
            let (x, y) = ((i % 40) as f32 * 0.15 - 3.0, (i / 40) as f32 * 0.25 - 3.0);
            src.push_str(&format!("l {x} {y} 3 0.01 0.01 0.01\n"));
        }
        let lights = gpurt::scene::nff::parse(src.as_bytes(), "balls-3-lights.nff", Path::new("."))
            .expect("parses");
        for shading in Shading::ALL {
            let opts = RenderOptions {
                width: 48,
                height: 48,
                shading,
                ..RenderOptions::for_camera(&lights.camera)
            };
            heavy(
                format!("balls-3 with 1000 lights, {}", shading.name()),
                &lights,
                &opts,
            );
        }
    }
    check_all(cases);
    for (label, n) in resumed {
        println!("{label}: {n} pixels finished by resume");
        expect_resumed(g, &label, n);
    }
}

/// A ray whose one traversal is too long for lavapipe's loop limit cannot be split
/// further: a shadow ray up a column of 40000 overlapping glass spheres visits every one.
/// The GPU either agrees with the CPU or fails naming the cause, never returns a darker
/// image.
#[test]
fn unfinished_pixels_are_an_error_never_a_darker_image() {
    let Some(g) = gpu() else {
        return;
    };
    let mut src = String::from(
        "b 0.2 0.2 0.2\nv\nfrom 4 0 0.3\nat 0 0 0.2\nup 0 0 1\nangle 20\nhither 0.01\n\
         resolution 32 32\nl 0 0 30\nf 0.8 0.8 0.8 0.8 0 1 0 1\n\
         p 4\n-3 -3 0\n3 -3 0\n3 3 0\n-3 3 0\nf 0.9 0.9 1 0.1 0 1 0.9 1\n",
    );
    for i in 0..40_000 {
        src.push_str(&format!("s 0 0 {:.4} 0.5\n", 1.0 + i as f32 * 0.0002));
    }
    let scene =
        gpurt::scene::nff::parse(src.as_bytes(), "column.nff", Path::new(".")).expect("parses");
    let opts = RenderOptions::for_camera(&scene.camera);
    if let Err(e) = check_heavy(g, "a column of 40000 glass spheres", &scene, &opts) {
        assert!(
            e.contains("GPU render failed") && e.contains("could not finish"),
            "{e}"
        );
    }
}

/// Dispatches over the renderer's time budget (kept well inside a driver's watchdog) make
/// the rest of the frame, and the frames after it, cut finer: on lavapipe, which has no
/// watchdog, a budget of a nanosecond forces it. The image and the rays stay the same to
/// the bit, although most tiles are then submitted in several buffer-fulls.
#[test]
fn dispatches_over_the_budget_are_cut_finer_and_change_nothing() {
    let Some(g) = gpu() else {
        return;
    };
    let scene = features_scene("");
    let buffers = pack::pack(scene.clone()).expect("packs");
    // Two bands on a software adapter: 256 rows of 96 pixels at 8 samples fill one.
    let frame = RenderOptions {
        width: 96,
        height: 300,
        spp: 8,
        ..opts(&scene)
    };
    let globals = frame::globals(&buffers, &frame);
    let never = AtomicBool::new(false);
    let (device, queue) = (&g.ctx.device, &g.ctx.queue);
    let trace_twice = |r: &GpuRenderer| {
        let up = r
            .upload(device, queue, &buffers, &globals)
            .expect("uploads");
        let before = up.dispatch_shape();
        let first = gpurt::gpu::trace(device, queue, &up, &|_| {}, &never).expect("traces");
        let after = up.dispatch_shape();
        let second = gpurt::gpu::trace(device, queue, &up, &|_| {}, &never).expect("traces");
        (before, after, first, second)
    };
    // The default budget: none on a software adapter; a frame this small is far inside
    // it on a GPU.
    let (shape, kept, reference, again) = trace_twice(&g.renderer);
    assert_eq!(shape, kept, "the default budget refined a small frame");
    assert_eq!(again, reference);

    let tight = GpuRenderer::new(device, None)
        .expect("shader module")
        .with_dispatch_budget(std::time::Duration::from_nanos(1));
    let (before, after, first, second) = trace_twice(&tight);
    assert_eq!(before, shape);
    assert_eq!(
        after,
        (WORKGROUP_SIDE, 1),
        "cut down to one workgroup, one sample"
    );
    println!("dispatch shape {shape:?} -> {after:?}");
    assert!(
        first == reference,
        "a finer cut changed the image or the rays"
    );
    assert!(second == reference, "the refined cut's next frame changed");
}

/// A GPU's cut of a frame (strips as wide as the frame, four samples a pass, in
/// `with_gpu_shape`) gives the image, the rays and the counts of a software adapter's
/// (scattered squares, one sample a pass) to the bit: here with strips of 16 to 40 rows
/// and a short last one, on an odd-sized frame of every feature whose samples do not divide
/// into passes, an AOV frame, and glass at depth 16, whose heavy pixels lavapipe's loop
/// limit cuts short and `resume` finishes. So does the `pooled` entry point (a larger
/// square of pixels a workgroup, shared out among its lanes) in both cuts, with squares
/// of 8, 16 and 24 pixels a side (the software cut's scattered as many as it has); an
/// AOV frame keeps `main`.
#[test]
fn a_gpus_strips_trace_the_frame_of_a_software_adapters_squares() {
    let Some(g) = gpu() else {
        return;
    };
    let (device, queue) = (&g.ctx.device, &g.ctx.queue);
    let features = features_scene("");
    let glass = scene::load(&own_scenes().join("glass.nff")).expect("loads");
    let cases = [
        ("features", &features, 97, 61, 5, 5, AOV_COLOR),
        ("features depth", &features, 97, 61, 2, 5, AOV_DEPTH),
        ("glass", &glass, 64, 44, 1, 16, AOV_COLOR),
    ];
    for (label, scene, width, height, spp, max_depth, aov) in cases {
        let buffers = pack::pack(scene.clone()).expect("packs");
        let frame = RenderOptions {
            width,
            height,
            spp,
            max_depth,
            ..opts(scene)
        };
        let globals = GpuGlobals {
            counters: 1,
            aov,
            ..frame::globals(&buffers, &frame)
        };
        let render = |r: GpuRenderer| {
            let up = r
                .upload(device, queue, &buffers, &r.frame(&buffers, &globals))
                .expect("uploads");
            let shape = up.dispatch_shape();
            let never = AtomicBool::new(false);
            let (film, rays) =
                gpurt::gpu::trace(device, queue, &up, &|_| {}, &never).expect("traces");
            (film, rays, up.counters().expect("counts"), shape)
        };
        // The one kernel's cut (the wavefront kernels' tiles are their waves).
        let new = || {
            GpuRenderer::new(device, None)
                .expect("shader module")
                .with_wavefront(false)
        };
        let (film, rays, counts, _) = render(new());
        let strip = u64::from(width) * 16 * 4;
        let (f, r, c, shape) = render(new().with_gpu_shape(strip));
        // Rows for the dispatch's samples at this pass's samples, whole workgroups, each
        // frame in several strips.
        let pass = spp.min(4);
        let rows = (16 * 4 / pass).min(height) / WORKGROUP_SIDE * WORKGROUP_SIDE;
        assert_eq!(shape, (rows, pass), "{label}: the strips");
        assert!(rows < height);
        assert!(rays > u64::from(width * height), "{label}: traced nothing");
        assert_eq!(r, rays, "{label}: the rays");
        assert!(c == counts, "{label}: the counts");
        assert!(f == film, "{label}: the image");
        // Each cut with each workgroup's square of pixels shared out among its lanes.
        let pooled = [
            (new().with_gpu_shape(strip), 16),
            (new().with_gpu_shape(strip), 8),
            (new(), 16),
            (new(), 24),
        ];
        for (r, side) in pooled {
            let pooled = r.with_pooled(true).with_pool_side(side);
            let kernels = pooled.kernels(&buffers, &pooled.frame(&buffers, &globals));
            let want = if aov == AOV_COLOR { "pooled" } else { "main" };
            assert_eq!(kernels, want, "{label}: an AOV frame keeps main");
            let (f, r, c, _) = render(pooled);
            let label = format!("{label}, pooled squares of {side}");
            assert_eq!(r, rays, "{label}: the rays");
            // Rays and node fetches by kind; not the warps' figures, which leave out the
            // pixels `resume` finishes, and a lane of the pool runs longer than one of
            // `main` (lavapipe's loop limit cuts other pixels short).
            assert!(
                (c.rays, c.nodes) == (counts.rays, counts.nodes),
                "{label}: the counts"
            );
            assert!(f == film, "{label}: the image");
        }
    }
}
