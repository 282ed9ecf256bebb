//! The counters (`GpuGlobals::counters`, for `--stats` and `gpurt bench`): the rays and BVH
//! node fetches the GPU counts by kind of ray, on every walk, against what the CPU twin of
//! that walk counts on the same frame, in all and warp by warp; a walk's counts do not
//! pass for another walk's; counting changes no pixel; and pixels continued across
//! dispatches are counted too.

use glam::Vec3;
use gpurt::counters::{Counters, KINDS, gpu_node_bytes};
use gpurt::cpu::RayCounts;
use gpurt::cpu::pixel::sample_sum;
use gpurt::cpu::tracer::Alone;
use gpurt::cpu::types::Bindings;
use gpurt::film::Film;
use gpurt::frame::{self, RenderOptions};
use gpurt::gpu::GpuRenderer;
use gpurt::gpu_types::*;
use gpurt::pack::{self, SceneBuffers};
use gpurt::scene::{self, Scene};

use crate::common::versus::{Gpu, expect_resumed, features_scene, gpu, trace_on};
use crate::common::{own_scenes, shared_scenes};

/// What the CPU twin of the GPU's walk `globals.traversal` counts on the frame, its
/// pixels grouped into the GPU's warps as the host groups the GPU's (`add_band`).
fn twin(buffers: &SceneBuffers, globals: &GpuGlobals) -> Counters {
    let b = Bindings::gpu_walk(buffers, globals);
    let mut counts = RayCounts::default();
    let mut pixels = Vec::new();
    for y in 0..globals.height {
        for x in 0..globals.width {
            let mut pixel = RayCounts::default();
            sample_sum(
                &b,
                &mut Alone,
                (x, y),
                0..globals.spp,
                Vec3::ZERO,
                &mut pixel,
            );
            counts.add(&pixel);
            let k = pixel.counters(0);
            let n = |v: u64| u32::try_from(v).expect("a pixel's count fits");
            pixels.push(GpuPixelCounts {
                eye_rays: n(k.rays[0]),
                eye_nodes: n(k.nodes[0]),
                shadow_rays: n(k.rays[1]),
                shadow_nodes: n(k.nodes[1]),
                secondary_rays: n(k.rays[2]),
                secondary_nodes: n(k.nodes[2]),
                _pad: [0; 2],
            });
        }
    }
    let mut warps = Counters::default();
    warps.add_band(&pixels, globals.width as usize, &[]);
    Counters {
        warp_nodes: warps.warp_nodes,
        warp_room: warps.warp_room,
        warp_room_all: warps.warp_room_all,
        pool_room: warps.pool_room,
        ..counts.counters(gpu_node_bytes(globals.traversal))
    }
}

/// The GPU's image, rays and counts of the frame, on `renderer`.
fn on_gpu(
    g: &Gpu,
    renderer: &GpuRenderer,
    buffers: &SceneBuffers,
    globals: &GpuGlobals,
) -> (Film, u64, Option<Counters>) {
    let (film, rays, up) = trace_on(g, renderer, buffers, globals).expect("traces");
    (film, rays, up.counters())
}

/// Counts equal kind by kind within one in 10^4 for rays (the drift of lights grazing a
/// surface, as in `dispatch.rs`) and one in 10^3 for node fetches (a ray that moves by an
/// ulp may take another path), in all and by warps (so the GPU's pixels are grouped
/// where they are in the frame; a warp's room is 32 times its busiest pixel's fetches),
/// with the same node size.
fn agree(gpu: &Counters, cpu: &Counters) -> Result<(), String> {
    let near = |a: u64, b: u64, tol: f64| a.abs_diff(b) as f64 <= tol * a.max(b).max(1) as f64;
    for (k, kind) in KINDS.iter().enumerate() {
        if !near(gpu.rays[k], cpu.rays[k], 1e-4) || !near(gpu.nodes[k], cpu.nodes[k], 1e-3) {
            return Err(format!(
                "{kind} rays: the GPU counted {} rays and {} nodes, the CPU twin {} and {}",
                gpu.rays[k], gpu.nodes[k], cpu.rays[k], cpu.nodes[k]
            ));
        }
        // A pixel's node fetch more or less moves its warp's room by up to 32 (the lanes).
        let room = 32.0 * 1e-3 * gpu.warp_nodes[k].max(cpu.warp_nodes[k]).max(1) as f64;
        if !near(gpu.warp_nodes[k], cpu.warp_nodes[k], 1e-3)
            || gpu.warp_room[k].abs_diff(cpu.warp_room[k]) as f64 > room
        {
            return Err(format!(
                "{kind} rays by warps: the GPU counted {} of room for {} nodes, the CPU \
                 twin {} for {}",
                gpu.warp_room[k], gpu.warp_nodes[k], cpu.warp_room[k], cpu.warp_nodes[k]
            ));
        }
    }
    // Every kind together, one pixel a lane and pooled: likewise.
    let nodes = gpu
        .warp_nodes
        .iter()
        .sum::<u64>()
        .max(cpu.warp_nodes.iter().sum());
    let room = 32.0 * 1e-3 * nodes.max(1) as f64;
    for (what, g, c) in [
        ("a pixel a lane", gpu.warp_room_all, cpu.warp_room_all),
        ("pooled", gpu.pool_room, cpu.pool_room),
    ] {
        if g.abs_diff(c) as f64 > room {
            return Err(format!(
                "every ray by warps, {what}: the GPU counted {g} of room, the CPU twin {c}"
            ));
        }
    }
    if gpu.node_bytes != cpu.node_bytes {
        return Err(format!(
            "node sizes {} and {}",
            gpu.node_bytes, cpu.node_bytes
        ));
    }
    Ok(())
}

/// The scenes counted: every primitive and light kind with glass and a mirror (at depth
/// 5 and 4 samples a pixel), and balls-3, whose mirror spheres send many secondary rays.
fn scenes() -> Vec<(String, Scene, RenderOptions)> {
    let features = features_scene("");
    let mut out = vec![(
        "features".to_string(),
        features.clone(),
        RenderOptions {
            width: 64,
            height: 64,
            spp: 4,
            max_depth: 5,
            ..RenderOptions::for_camera(&features.camera)
        },
    )];
    if let Some(root) = shared_scenes() {
        let balls = scene::load(&root.join("spd/balls-3.nff")).expect("loads");
        let opts = RenderOptions {
            width: 48,
            height: 40,
            max_depth: 5,
            ..RenderOptions::for_camera(&balls.camera)
        };
        out.push(("balls-3".to_string(), balls, opts));
    }
    out
}

/// On every walk the GPU counts the rays of each kind and the node fetches of their
/// walks as the CPU twin of that walk does, and its kinds add up to the rays it reports.
/// The comparison fails the twin's counts with one node fetch in 500 more of one kind,
/// and on balls-3 the twin's counts of another walk: the check tells walks apart.
#[test]
fn the_gpu_counts_what_the_cpu_twin_of_its_walk_counts() {
    let Some(g) = gpu() else {
        return;
    };
    let walks = [
        TRAVERSAL_SINGLE,
        TRAVERSAL_PAIRS,
        TRAVERSAL_WIDE,
        TRAVERSAL_CWIDE,
        TRAVERSAL_QWIDE,
    ];
    let mut failures = Vec::new();
    for (name, scene, opts) in scenes() {
        let buffers = pack::pack(scene).expect("packs");
        let base = GpuGlobals {
            counters: 1,
            ..frame::globals(&buffers, &opts)
        };
        let mut twins = Vec::new();
        for t in walks {
            let renderer = GpuRenderer::new(&g.ctx.device, None)
                .expect("shader compiles")
                .with_traversal(t);
            let globals = renderer.frame(&buffers, &base);
            assert_eq!(globals.traversal, t, "{name} takes every walk");
            let (_, rays, counted) = on_gpu(g, &renderer, &buffers, &globals);
            let counted = counted.expect("a counting frame has counts");
            let label = format!("{name} ({})", TRAVERSAL_NAMES[t as usize]);
            assert_eq!(counted.total_rays(), rays, "{label}: the kinds add up");
            assert_eq!(
                counted.rays[0],
                u64::from(opts.width * opts.height * opts.spp),
                "{label}: one eye ray a sample"
            );
            assert!(counted.rays.iter().all(|&r| r > 0), "{label}: {counted:?}");
            let cpu = twin(&buffers, &globals);
            if let Err(why) = agree(&counted, &cpu) {
                failures.push(format!("{label}: {why}"));
            }
            assert!(
                counted.warp_room_all > 0 && counted.pool_room > 0,
                "{label}: every ray by warps: {counted:?}"
            );
            let mut pooled = cpu;
            pooled.pool_room += 32 * (pooled.warp_nodes.iter().sum::<u64>() / 500 + 1);
            assert!(
                agree(&counted, &pooled).is_err(),
                "{label}: {pooled:?} passes"
            );
            for k in 0..3 {
                let mut more = cpu;
                more.nodes[k] += more.nodes[k] / 500 + 1;
                assert!(agree(&counted, &more).is_err(), "{label}: {more:?} passes");
                let mut roomier = cpu;
                roomier.warp_room[k] += 32 * (roomier.warp_nodes[k] / 500 + 1);
                assert!(
                    agree(&counted, &roomier).is_err(),
                    "{label}: {roomier:?} passes"
                );
            }
            println!("{label}: {}", counted.report("gpu").join("; "));
            twins.push((t, counted, cpu));
        }
        // The features scene is a handful of primitives, one wide node for both wide
        // walks; balls-3's 820 spheres make every walk its own.
        for (t, counted, _) in twins.iter().filter(|_| name == "balls-3") {
            for (other, _, cpu) in &twins {
                assert!(
                    t == other || counted.nodes != cpu.nodes,
                    "{name}: the {} walk's counts pass for the {} walk's",
                    TRAVERSAL_NAMES[*t as usize],
                    TRAVERSAL_NAMES[*other as usize]
                );
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// Counting compiles more into the shader but changes no pixel and no ray count; a frame
/// that does not count has no counts, and one that does has them.
#[test]
fn counting_changes_no_pixel() {
    let Some(g) = gpu() else {
        return;
    };
    let scene = features_scene("");
    let buffers = pack::pack(scene.clone()).expect("packs");
    let opts = RenderOptions {
        width: 48,
        height: 48,
        spp: 2,
        ..RenderOptions::for_camera(&scene.camera)
    };
    let plain = g.renderer.frame(&buffers, &frame::globals(&buffers, &opts));
    let counting = GpuGlobals {
        counters: 1,
        ..plain
    };
    let (film, rays, none) = on_gpu(g, &g.renderer, &buffers, &plain);
    let (counted_film, counted_rays, some) = on_gpu(g, &g.renderer, &buffers, &counting);
    assert!(none.is_none() && some.is_some());
    assert_eq!(rays, counted_rays);
    assert!(film == counted_film, "counting changed the image");
}

/// Glass at depth 16 has pixels too heavy for one invocation on lavapipe, which the
/// `resume` entry point continues across dispatches: their counts are the pixels' whole
/// counts too, so the kinds still add up to every ray traced and agree with the CPU twin.
#[test]
fn pixels_continued_across_dispatches_are_counted() {
    let Some(g) = gpu() else {
        return;
    };
    let glass = scene::load(&own_scenes().join("glass.nff")).expect("loads");
    let buffers = pack::pack(glass.clone()).expect("packs");
    let opts = RenderOptions {
        width: 64,
        height: 64,
        max_depth: 16,
        ..RenderOptions::for_camera(&glass.camera)
    };
    let globals = GpuGlobals {
        counters: 1,
        ..g.renderer.frame(&buffers, &frame::globals(&buffers, &opts))
    };
    let (_, rays, up) = trace_on(g, &g.renderer, &buffers, &globals).expect("traces");
    expect_resumed(g, "glass at depth 16", up.resumed());
    let counted = up.counters().expect("counts");
    assert_eq!(counted.total_rays(), rays, "every ray is counted by kind");
    // Pixels `resume` finishes are counted in all but not by warps (`Counters::add_band`).
    let in_all = |c: Counters| Counters {
        warp_nodes: [0; 3],
        warp_room: [0; 3],
        warp_room_all: 0,
        pool_room: 0,
        ..c
    };
    assert!((0..3).all(|k| counted.warp_nodes[k] <= counted.nodes[k]));
    agree(&in_all(counted), &in_all(twin(&buffers, &globals)))
        .unwrap_or_else(|why| panic!("glass: {why}"));
}

/// With shadow rays off (`GpuRenderer::with_shadow_rays`, `gpurt bench`'s `shaded`
/// pass), every light reaches every surface facing it and no shadow ray is traced: on the
/// bundled spheres (two lights, a floor the spheres shadow, glass and a mirror, at depth
/// 5) every pixel is at least as bright as with shadows, those in shadow brighter, and
/// the frame traces the same eye and secondary rays and no shadow ray, through `main` and
/// through `pooled`; on a lone ball, which nothing shadows, the image is the same to the
/// bit.
#[test]
fn shadow_rays_off_light_every_surface_facing_a_light() {
    let Some(g) = gpu() else {
        return;
    };
    let spheres = scene::load(&own_scenes().join("spheres.nff")).expect("loads");
    let ball = gpurt::scene::nff::parse(
        crate::common::inputs::SCENE.as_bytes(),
        "ball.nff",
        std::path::Path::new("."),
    )
    .expect("parses");
    for (name, scene, shadowed) in [("spheres", spheres, true), ("ball", ball, false)] {
        let buffers = pack::pack(scene.clone()).expect("packs");
        let opts = RenderOptions {
            width: 48,
            height: 40,
            spp: 2,
            max_depth: 5,
            ..RenderOptions::for_camera(&scene.camera)
        };
        let globals = GpuGlobals {
            counters: 1,
            ..frame::globals(&buffers, &opts)
        };
        let new = || GpuRenderer::new(&g.ctx.device, None).expect("shader module");
        let (lit, lit_rays, lit_counts) = on_gpu(g, &new(), &buffers, &globals);
        let lit_counts = lit_counts.expect("counts");
        for pooled in [false, true] {
            let label = format!("{name}, pooled {pooled}");
            let r = new().with_shadow_rays(false).with_pooled(pooled);
            let globals = r.frame(&buffers, &globals);
            assert_eq!(globals.wavefront, 0, "{label}: the one kernel");
            let (film, rays, counts) = on_gpu(g, &r, &buffers, &globals);
            let counts = counts.expect("counts");
            assert_eq!(counts.rays[1], 0, "{label}: no shadow ray");
            assert_eq!(
                (counts.rays[0], counts.rays[2]),
                (lit_counts.rays[0], lit_counts.rays[2]),
                "{label}: the same eye and secondary rays"
            );
            assert_eq!(
                rays,
                lit_rays - lit_counts.rays[1],
                "{label}: the rays traced"
            );
            let diff = |(a, b): (&[f32; 3], &[f32; 3])| [0, 1, 2].map(|c| a[c] - b[c]);
            let brighter: Vec<_> = film.pixels.iter().zip(&lit.pixels).map(diff).collect();
            assert!(
                brighter.iter().flatten().all(|&d| d >= 0.0),
                "{label}: a pixel darker"
            );
            let shadows = brighter
                .iter()
                .filter(|d| d.iter().any(|&d| d > 0.05))
                .count();
            if shadowed {
                assert!(
                    shadows > film.pixels.len() / 50,
                    "{label}: {shadows} pixels in shadow"
                );
            } else {
                assert!(film == lit, "{label}: a lone ball's image changed");
            }
        }
    }
}
