//! The render-session API: progressive rendering on both backends, and its guards.

use std::sync::Arc;
use std::sync::atomic::AtomicBool;

use gpurt::compare::{self, Thresholds};
use gpurt::film::Accumulator;
use gpurt::frame::{self, RenderOptions};
use gpurt::gpu_types::GpuGlobals;
use gpurt::pack::{self, SceneBuffers};
use gpurt::session::{CpuRenderer, GpuSession, Renderer};
use gpurt::{Error, scene};

use crate::common::{gpu_context, own_scenes};

/// glass.nff at 64x48 and 8 samples: refraction, reflection, several lights.
fn frame() -> (Arc<SceneBuffers>, GpuGlobals) {
    let scene = scene::load(&own_scenes().join("glass.nff")).expect("loads");
    let buffers = pack::pack(scene.clone()).expect("packs");
    let opts = RenderOptions {
        width: 64,
        height: 48,
        spp: 8,
        ..RenderOptions::for_camera(&scene.camera)
    };
    let globals = frame::globals(&buffers, &opts);
    (Arc::new(buffers), globals)
}

/// Samples in steps (3, then 5) and in one go, on one renderer: the two accumulators'
/// films, and the rays traced by each.
fn in_steps_and_at_once(r: &mut dyn Renderer, g: &GpuGlobals) -> [(Accumulator, u64); 2] {
    let never = AtomicBool::new(false);
    let mut steps = Accumulator::new(g.width, g.height);
    let rays = r
        .render(g, 0..3, &mut steps, &|_| {}, &never)
        .expect("renders")
        + r.render(g, 3..8, &mut steps, &|_| {}, &never)
            .expect("renders");
    let mut once = Accumulator::new(g.width, g.height);
    let rays_once = r
        .render(g, 0..8, &mut once, &|_| {}, &never)
        .expect("renders");
    [(steps, rays), (once, rays_once)]
}

#[test]
fn progressive_cpu_rendering_is_the_one_step_image_to_the_bit() {
    let (buffers, g) = frame();
    let mut cpu = CpuRenderer::new(buffers.clone());
    let [(steps, rays), (once, rays_once)] = in_steps_and_at_once(&mut cpu, &g);
    assert_eq!(steps.samples, 8);
    assert_eq!(steps.film(), once.film());
    assert_eq!(rays, rays_once);
    // And the one-step image is the reference renderer's.
    let never = AtomicBool::new(false);
    let (film, counts) = gpurt::cpu::render(&buffers, &g, &|_| {}, &never).expect("renders");
    assert_eq!(once.film(), film);
    assert_eq!(rays_once, counts.total());
}

#[test]
fn progressive_gpu_rendering_agrees_with_one_step_and_the_cpu() {
    let Some(ctx) = gpu_context() else { return };
    let (buffers, g) = frame();
    let mut gpu = GpuSession::new(ctx, buffers.clone()).expect("session");
    let [(steps, rays), (once, rays_once)] = in_steps_and_at_once(&mut gpu, &g);
    assert_eq!(rays, rays_once);
    let mut cpu = CpuRenderer::new(buffers);
    let mut reference = Accumulator::new(g.width, g.height);
    let never = AtomicBool::new(false);
    let cpu_rays = cpu
        .render(&g, 0..8, &mut reference, &|_| {}, &never)
        .expect("renders");
    assert_eq!(rays, cpu_rays);
    let image = |a: &Accumulator| a.film().to_rgb8();
    for (what, a, b) in [
        ("steps vs at once", &once, &steps),
        ("GPU vs CPU", &reference, &steps),
    ] {
        let stats = compare::diff(&image(a), &image(b), 2).expect("same size");
        Thresholds::GPU_VS_CPU
            .check(&stats)
            .unwrap_or_else(|why| panic!("{what}: {why} ({stats})"));
    }
}

/// One session renders a frame, then the same scene from another camera, at another
/// size, and at another depth: the scene is uploaded once, and each frame's image is the
/// one a new session renders of it, to the bit (same device, same pipeline).
#[test]
fn a_gpu_session_changes_frames_without_uploading_the_scene_again() {
    let Some(ctx) = gpu_context() else { return };
    let (buffers, first) = frame();
    let mut moved = first;
    moved.cam_pos += moved.cam_right * 0.5;
    let smaller = frame::globals(
        &buffers,
        &RenderOptions {
            width: 40,
            height: 30,
            spp: 8,
            ..RenderOptions::for_camera(&buffers.camera)
        },
    );
    let shallow = GpuGlobals {
        max_depth: 2,
        ..smaller
    };
    let never = AtomicBool::new(false);
    let render = |session: &mut GpuSession, g: &GpuGlobals| {
        let mut accum = Accumulator::new(g.width, g.height);
        session
            .render(g, 0..g.spp, &mut accum, &|_| {}, &never)
            .expect("renders");
        accum.film()
    };
    let mut session = GpuSession::new(ctx, buffers.clone()).expect("session");
    let mut previous = render(&mut session, &first);
    for (what, g) in [("camera", &moved), ("size", &smaller), ("depth", &shallow)] {
        let image = render(&mut session, g);
        assert_ne!(image, previous, "{what}: the frame changes the image");
        let ctx = gpurt::gpu::open(None).expect("a second device");
        let mut fresh = GpuSession::new(ctx, buffers.clone()).expect("session");
        assert_eq!(
            image,
            render(&mut fresh, g),
            "{what}: as a new session renders it"
        );
        previous = image;
    }
    assert_eq!(session.scene_uploads(), 1);
}

/// Samples that do not continue the accumulator, and a depth the stacks cannot hold, are
/// errors on the CPU path too, not panics.
#[test]
fn a_renderer_refuses_what_it_cannot_do() {
    let (buffers, g) = frame();
    let mut cpu = CpuRenderer::new(buffers);
    let never = AtomicBool::new(false);
    let mut accum = Accumulator::new(g.width, g.height);
    for samples in [2..4, 0..9, 0..0] {
        let err = cpu.render(&g, samples.clone(), &mut accum, &|_| {}, &never);
        assert!(matches!(err, Err(Error::Render(_))), "{samples:?}: {err:?}");
    }
    let mut small = Accumulator::new(8, 8);
    assert!(matches!(
        cpu.render(&g, 0..8, &mut small, &|_| {}, &never),
        Err(Error::Render(_))
    ));
    let deep = GpuGlobals {
        max_depth: 1000,
        ..g
    };
    assert!(
        cpu.render(&deep, 0..8, &mut accum, &|_| {}, &never)
            .is_err()
    );
    assert_eq!(
        accum.samples, 0,
        "a refused render leaves the accumulator as it was"
    );
}

/// A batch's session: a second scene of the same kind uploads its own arrays but
/// compiles nothing, and renders what a fresh session renders.
#[test]
fn a_gpu_session_moved_to_another_scene_keeps_its_pipelines() {
    let Some(ctx) = gpu_context() else {
        return;
    };
    let (first, g) = frame();
    // The same kind of scene (same primitive kinds, lights and materials' features),
    // seen from elsewhere.
    let mut moved = scene::load(&own_scenes().join("glass.nff")).expect("loads");
    moved.camera.from.x += 0.7;
    let second = Arc::new(pack::pack(moved).expect("packs"));
    let g2 = frame::globals(
        &second,
        &RenderOptions {
            width: g.width,
            height: g.height,
            spp: g.spp,
            ..RenderOptions::for_camera(&second.camera)
        },
    );
    let never = AtomicBool::new(false);
    let mut session = GpuSession::new(ctx.clone(), first).expect("session");
    session.prepare(&g).expect("compiles");
    let mut a = Accumulator::new(g.width, g.height);
    session
        .render(&g, 0..g.spp, &mut a, &|_| {}, &never)
        .expect("renders");
    let compiled = session.compile_time();
    session.set_scene(second.clone());
    assert!(
        session.prepare(&g2).expect("ready").is_zero(),
        "nothing compiled"
    );
    let mut b = Accumulator::new(g.width, g.height);
    session
        .render(&g2, 0..g.spp, &mut b, &|_| {}, &never)
        .expect("renders");
    assert_eq!(session.compile_time(), compiled);
    assert_eq!(session.scene_uploads(), 2);
    let mut fresh = GpuSession::new(ctx, second).expect("session");
    let mut c = Accumulator::new(g.width, g.height);
    fresh
        .render(&g2, 0..g.spp, &mut c, &|_| {}, &never)
        .expect("renders");
    assert_eq!(b.film(), c.film());
    assert_ne!(a.film(), b.film());
}
