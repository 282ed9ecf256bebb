//! The GPU's traversals: each walk its adapter does not use by default matches the CPU
//! too, a scene deeper than the traversal stack renders, nodes and primitives spread
//! over several texture layers are walked as in one, and read from storage buffers
//! rather than textures (or the other way round) give the same images to the bit.

use std::path::Path;
use std::sync::OnceLock;

use gpurt::film::Film;
use gpurt::frame;
use gpurt::frame::RenderOptions;
use gpurt::gpu::GpuRenderer;
use gpurt::gpu::shaders::Fetch;
use gpurt::gpu_types::*;
use gpurt::pack;
use gpurt::scene;

use crate::common::versus::{
    Gpu, check_all, check_scene, check_variants, features_scene, gpu, opts,
};
use crate::common::{files_with, own_scenes, shared_scenes};

/// The same GPU with each traversal its adapter does not use by default (four of single,
/// pairs, wide, cwide and qwide), so that every walk is checked against the CPU on every
/// adapter the suite runs on.
fn other_traversals() -> &'static [Gpu] {
    static OTHERS: OnceLock<Vec<Gpu>> = OnceLock::new();
    OTHERS.get_or_init(|| {
        let Some(g) = gpu() else {
            return Vec::new();
        };
        [
            TRAVERSAL_SINGLE,
            TRAVERSAL_PAIRS,
            TRAVERSAL_WIDE,
            TRAVERSAL_CWIDE,
            TRAVERSAL_QWIDE,
        ]
        .into_iter()
        .filter(|&t| t != g.renderer.traversal())
        .map(|t| Gpu {
            ctx: g.ctx.clone(),
            renderer: GpuRenderer::new(&g.ctx.device, None)
                .expect("shader compiles")
                .with_traversal(t),
        })
        .collect()
    })
}

/// The other traversals find the same images and, walking the tree as the CPU twin of
/// each does, the same node costs: on the features scene, the bundled scenes and three
/// SPD scenes of thousands of primitives.
#[test]
fn the_other_traversals_match_cpu_too() {
    let mut cases = Vec::new();
    for g in other_traversals() {
        let walk = TRAVERSAL_NAMES[g.renderer.traversal() as usize];
        cases.extend(check_variants(
            g,
            &format!("features ({walk})"),
            &features_scene(""),
        ));
        for f in files_with(&own_scenes(), &[".nff"]) {
            let scene = scene::load(&f).expect("own scene loads");
            let name = format!("{} ({walk})", f.display());
            cases.extend(check_variants(g, &name, &scene));
        }
        if let Some(root) = shared_scenes() {
            for name in ["spd/balls-3.nff", "spd/mount-5.nff", "spd/teapot-6.nff"] {
                let scene = scene::load(&root.join(name)).expect("shared scene loads");
                cases.extend(check_variants(g, &format!("{name} ({walk})"), &scene));
            }
        }
    }
    check_all(cases);
}

/// Spheres each 1.5 times as far out as the last chain obvhs' clustering into a tree
/// deeper than the traversal stack (`bvh::tests` shows it); the scene is built by median
/// splits instead (depth log2(n / 4) + 2) and renders the same on both backends, seen
/// along the chain.
#[test]
fn a_scene_deeper_than_the_traversal_stack_renders_and_matches_cpu() {
    let Some(g) = gpu() else {
        return;
    };
    let mut src = String::from(
        "v from -4 3 2 at 40 0 0 up 0 0 1 angle 60 hither 0.01 resolution 96 64\n\
         b 0.1 0.1 0.2\nl -10 10 10\nf 1 0.5 0.2 0.7 0.3 20 0 1\n",
    );
    for k in 0..200 {
        let x = 1.5f64.powi(k);
        src.push_str(&format!("s {x} 0 0 {}\n", x * 0.3));
    }
    let scene = scene::nff::parse(src.as_bytes(), "chain", Path::new(".")).expect("parses");
    let buffers = pack::pack(scene.clone()).expect("packs");
    assert!(
        buffers.bvh_depth <= 7,
        "median depth, got {}",
        buffers.bvh_depth
    );
    check_all([check_scene(g, "chain", &scene, &opts(&scene))]);
}

/// A scene larger than one texture layer is split over several, as many as it needs
/// (read from textures whatever the adapter's default):
/// with layers cut to 2 and 1 rows here (balls-4's 7383 primitives take 6 rows, its
/// nodes 3), the images and costs still match the CPU's.
#[test]
fn scenes_over_several_texture_layers_match_cpu() {
    let (Some(g), Some(root)) = (gpu(), shared_scenes()) else {
        return;
    };
    let scene = scene::load(&root.join("spd/balls-4.nff")).expect("balls-4 loads");
    let mut cases = Vec::new();
    for rows in [2, 1] {
        let layered = Gpu {
            ctx: g.ctx.clone(),
            renderer: GpuRenderer::fetching(&g.ctx.device, None, Fetch::Textures)
                .expect("shader compiles")
                .with_layer_rows(rows),
        };
        let base = opts(&scene);
        for (name, aov) in [("", AOV_COLOR), ("cost", AOV_COST)] {
            let o = RenderOptions {
                aov,
                ..base.clone()
            };
            let label = format!("balls-4 in layers of {rows} rows {name}");
            cases.push(check_scene(&layered, &label, &scene, &o));
        }
    }
    check_all(cases);
}

/// Where two films differ first, by bits: the size, a pixel's channel, or the rays traced.
fn same_to_the_bit(a: &(Film, u64), b: &(Film, u64)) -> Result<(), String> {
    if (a.0.width, a.0.height) != (b.0.width, b.0.height) {
        return Err(format!(
            "{}x{} against {}x{}",
            a.0.width, a.0.height, b.0.width, b.0.height
        ));
    }
    let pixels = a.0.pixels.iter().zip(&b.0.pixels).enumerate();
    for (i, (p, q)) in pixels {
        if p.map(f32::to_bits) != q.map(f32::to_bits) {
            return Err(format!("pixel {i}: {p:?} against {q:?}"));
        }
    }
    match a.1 == b.1 {
        true => Ok(()),
        false => Err(format!("{} rays against {}", a.1, b.1)),
    }
}

/// The comparison above fails a film one pixel's channel one step of f32 away, and one
/// ray short.
#[test]
fn the_bitwise_film_comparison_fails_a_perturbed_film() {
    let mut film = Film::new(3, 2);
    film.pixels[4] = [0.25, 0.5, 1.0];
    let a = (film.clone(), 10);
    assert!(same_to_the_bit(&a, &a.clone()).is_ok());
    let mut nudged = a.clone();
    nudged.0.pixels[4][1] = f32::from_bits(0.5f32.to_bits() + 1);
    assert!(same_to_the_bit(&a, &nudged).is_err());
    assert!(same_to_the_bit(&a, &(film, 9)).is_err());
}

/// The way of reading the scene's arrays the adapter does not use by default (storage
/// buffers on lavapipe, textures on a hardware GPU) gives the same films to the bit, and
/// the same rays, as the default: colour at 4 samples per pixel, the cost AOV (the nodes
/// each pixel's walk visited) and the normals, on the features scene, the bundled scenes
/// and three SPD scenes. The default is checked against the CPU by every other test.
#[test]
fn the_other_way_of_fetching_the_scene_gives_the_same_images() {
    let Some(g) = gpu() else {
        return;
    };
    let other = match g.renderer.fetch() {
        Fetch::Textures => Fetch::Buffers,
        Fetch::Buffers => Fetch::Textures,
    };
    let fetching = GpuRenderer::fetching(&g.ctx.device, None, other).expect("shader compiles");
    let mut scenes = vec![("features".to_string(), features_scene(""))];
    for f in files_with(&own_scenes(), &[".nff"]) {
        let scene = scene::load(&f).expect("own scene loads");
        scenes.push((f.display().to_string(), scene));
    }
    if let Some(root) = shared_scenes() {
        for name in ["spd/balls-3.nff", "spd/mount-5.nff", "spd/teapot-6.nff"] {
            let scene = scene::load(&root.join(name)).expect("shared scene loads");
            scenes.push((name.to_string(), scene));
        }
    }
    let never = std::sync::atomic::AtomicBool::new(false);
    let mut differ = Vec::new();
    for (name, scene) in &scenes {
        let buffers = pack::pack(scene.clone()).expect("scene packs");
        for (what, spp, aov) in [
            ("colour", 4, AOV_COLOR),
            ("cost", 1, AOV_COST),
            ("normal", 1, AOV_NORMAL),
        ] {
            let o = RenderOptions {
                spp,
                aov,
                ..opts(scene)
            };
            let globals = g.renderer.frame(&buffers, &frame::globals(&buffers, &o));
            let [a, b] = [&g.renderer, &fetching].map(|r| {
                r.render(
                    &g.ctx.device,
                    &g.ctx.queue,
                    &buffers,
                    &globals,
                    &|_| {},
                    &never,
                )
                .unwrap_or_else(|e| panic!("{name} {what}: GPU render failed: {e}"))
            });
            if let Err(e) = same_to_the_bit(&a, &b) {
                differ.push(format!("{name} {what} ({}): {e}", other.name()));
            }
        }
    }
    assert!(differ.is_empty(), "{}", differ.join("\n"));
}
