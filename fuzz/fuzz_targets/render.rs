//! The whole path of `gpurt render` on the CPU: bytes -> scene (as `scene::load` makes it:
//! an NFF scene, or else a bare STL or OBJ mesh with its automatic camera, light and
//! ground) -> `pack` -> the buffer checks the GPU relies on -> an 8 x 8 render at 1 sample
//! per pixel. A scene a reader accepts must pack, pass `SceneBuffers::check` and render to
//! finite, non-negative pixels; reader errors are fine.
#![no_main]

use std::path::Path;
use std::sync::OnceLock;
use std::sync::atomic::AtomicBool;

use libfuzzer_sys::fuzz_target;

use gpurt::frame::{self, RenderOptions};
use gpurt::scene::io::FileKind;
use gpurt::scene::{Light, Scene, auto, mesh, nff};

/// Inputs and scenes past these are skipped (not failed): they are valid, but would make
/// one execution cost milliseconds instead of microseconds.
const MAX_INPUT: usize = 16 << 10;
const MAX_PRIMS: usize = 64;
const MAX_PLANES: usize = 8;
const MAX_LIGHTS: usize = 8;
const MAX_AREA_SAMPLES: u32 = 64;
const SIDE: u32 = 8;
const DEPTH: u32 = 4;

/// The CPU renderer runs on rayon; one thread keeps a run on one core and deterministic.
fn pool() -> &'static rayon::ThreadPool {
    static POOL: OnceLock<rayon::ThreadPool> = OnceLock::new();
    POOL.get_or_init(|| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap()
    })
}

/// The scene `data` makes as NFF, or failing that as a bare STL, or as a bare OBJ.
fn read(data: &[u8]) -> Option<Scene> {
    // `mesh` paths resolve against a directory that does not exist.
    let nowhere = Path::new("/nonexistent-gpurt-fuzz");
    if let Ok(scene) = nff::parse(data, "fuzz.nff", nowhere) {
        return Some(scene);
    }
    [(FileKind::Stl, "fuzz.stl"), (FileKind::Obj, "fuzz.obj")]
        .into_iter()
        .find_map(|(kind, name)| {
            let tris = mesh::parse_mesh(data, kind, name).ok()?.triangles;
            // Checked before the automatic scene is made: a big mesh is skipped, not built.
            if tris.len() > MAX_PRIMS {
                return None;
            }
            auto::scene_for_mesh(name, tris).ok()
        })
}

fuzz_target!(|data: &[u8]| {
    if data.len() > MAX_INPUT {
        return;
    }
    let Some(scene) = read(data) else {
        return;
    };
    let area_samples = |l: &Light| match l {
        Light::Area { samples, .. } => samples[0] * samples[1],
        _ => 1,
    };
    if scene.bounded_count() > MAX_PRIMS
        || scene.planes.len() > MAX_PLANES
        || scene.lights.len() > MAX_LIGHTS
        || scene.lights.iter().map(area_samples).sum::<u32>() > MAX_AREA_SAMPLES
    {
        return;
    }
    let mut opts = RenderOptions::for_camera(&scene.camera);
    (opts.width, opts.height, opts.max_depth) = (SIDE, SIDE, DEPTH);
    let buffers = gpurt::pack::pack(scene).expect("an accepted scene packs");
    let globals = frame::globals(&buffers, &opts);
    buffers
        .check(&globals)
        .expect("packed buffers pass the GPU's checks");
    let never = AtomicBool::new(false);
    let (film, _) = pool()
        .install(|| gpurt::cpu::render(&buffers, &globals, &|_| {}, &never))
        .expect("an accepted scene renders");
    for (i, p) in film.pixels.iter().enumerate() {
        assert!(
            p.iter().all(|c| c.is_finite() && *c >= 0.0),
            "pixel ({}, {}) is {p:?}",
            i as u32 % SIDE,
            i as u32 / SIDE
        );
    }
});
