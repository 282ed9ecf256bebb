//! BVH build time on the two largest shared SPD scenes (`bvh::build` on primitive bounds,
//! at both qualities, and the whole `pack::pack`, which adds the primitive reordering and
//! buffer filling), and CPU render throughput in rays per second on small scenes.
//! `cargo bench --bench render`; shared scenes are skipped when ../shared is missing.

use std::hint::black_box;
use std::path::Path;
use std::sync::atomic::AtomicBool;
use std::time::Duration;

use criterion::{
    BatchSize, BenchmarkId, Criterion, SamplingMode, Throughput, criterion_group, criterion_main,
};
use gpurt::frame::{self, RenderOptions};
use gpurt::pack;
use gpurt::scene::{self, Scene};
use obvhs::aabb::Aabb;

const BUILD_SCENES: [&str; 2] = ["mount-9.nff.gz", "balls-6.nff.gz"];

/// Small scenes for render throughput: our default scene and two SPD scenes of different
/// character (a deep sphere hierarchy with mirrors; triangles with glass).
const RENDER_SCENES: [&str; 3] = [
    "scenes/spheres.nff",
    "../shared/scenes/spd/balls-3.nff",
    "../shared/scenes/spd/mount-5.nff",
];

/// Side of the throughput renders: big enough to amortise thread start-up.
const RENDER_SIZE: u32 = 128;

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

fn load(path: &Path) -> Option<Scene> {
    if !path.exists() {
        eprintln!("skipping: {} not found", path.display());
        return None;
    }
    Some(scene::load(path).expect("scene loads"))
}

/// The bounds `pack` builds over, in the same order.
fn prim_bounds(s: &Scene) -> Vec<Aabb> {
    s.bounded_prims()
        .map(|p| gpurt::bvh::aabb(p.bounds()))
        .collect()
}

fn bvh_build(c: &mut Criterion) {
    let dir = root().join("../shared/scenes/spd");
    let mut g = c.benchmark_group("bvh_build");
    // A build of half a million primitives takes about half a second: few flat samples.
    g.sampling_mode(SamplingMode::Flat)
        .sample_size(10)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(5));
    for name in BUILD_SCENES {
        let Some(scene) = load(&dir.join(name)) else {
            continue;
        };
        let bounds = prim_bounds(&scene);
        g.throughput(Throughput::Elements(bounds.len() as u64));
        for quality in [gpurt::bvh::Quality::Medium, gpurt::bvh::Quality::High] {
            let id = format!("bvh::build {}", quality.name());
            g.bench_function(BenchmarkId::new(id, name), |b| {
                b.iter(|| gpurt::bvh::build(black_box(&bounds), quality))
            });
        }
        g.bench_function(BenchmarkId::new("pack::pack", name), |b| {
            b.iter_batched(
                || scene.clone(),
                |s| pack::pack(s).expect("scene packs"),
                BatchSize::LargeInput,
            )
        });
    }
    g.finish();
}

fn cpu_render(c: &mut Criterion) {
    let mut g = c.benchmark_group("cpu_render");
    g.sampling_mode(SamplingMode::Flat)
        .sample_size(10)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(3));
    let never = AtomicBool::new(false);
    for rel in RENDER_SCENES {
        let Some(scene) = load(&root().join(rel)) else {
            continue;
        };
        let buffers = pack::pack(scene.clone()).expect("scene packs");
        let mut opts = RenderOptions::for_camera(&scene.camera);
        (opts.width, opts.height) = (RENDER_SIZE, RENDER_SIZE);
        let globals = frame::globals(&buffers, &opts);
        let render = || gpurt::cpu::render(&buffers, &globals, &|_| {}, &never).expect("renders");
        // Every render traces the same rays: report rays per second.
        let (_, counts) = render();
        g.throughput(Throughput::Elements(counts.total()));
        let name = Path::new(rel).file_name().unwrap().to_string_lossy();
        g.bench_function(BenchmarkId::new("rays", name), |b| {
            b.iter(|| black_box(render()))
        });
    }
    g.finish();
}

criterion_group!(benches, bvh_build, cpu_render);
criterion_main!(benches);
