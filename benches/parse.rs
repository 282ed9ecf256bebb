//! Scene reading throughput on the two largest shared SPD scenes, in decompressed bytes per
//! second: `nff::parse` on bytes already in memory, `scene::load` from disk (gzip
//! decompression included) into a `Scene`, and `scene::load_flat`, from disk straight into
//! the renderers' records as the command line reads. `cargo bench --bench parse`; skips
//! when ../shared is missing.

use std::hint::black_box;
use std::path::Path;
use std::time::Duration;

use criterion::{
    BenchmarkId, Criterion, SamplingMode, Throughput, criterion_group, criterion_main,
};
use gpurt::scene;

const SCENES: [&str; 2] = ["mount-9.nff.gz", "balls-6.nff.gz"];

fn parse(c: &mut Criterion) {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/scenes/spd");
    let mut g = c.benchmark_group("parse");
    // One parse takes a good fraction of a second: flat sampling with few samples keeps the
    // whole run under a minute.
    g.sampling_mode(SamplingMode::Flat)
        .sample_size(10)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(3));
    for name in SCENES {
        let path = dir.join(name);
        if !path.exists() {
            eprintln!("skipping {name}: {} not found", path.display());
            continue;
        }
        let bytes = scene::io::read_file(&path).expect("shared scene reads");
        g.throughput(Throughput::Bytes(bytes.len() as u64));
        g.bench_function(BenchmarkId::new("nff::parse", name), |b| {
            b.iter(|| scene::nff::parse(black_box(&bytes), name, &dir).expect("scene parses"))
        });
        g.bench_function(BenchmarkId::new("scene::load", name), |b| {
            b.iter(|| scene::load(black_box(&path)).expect("scene loads"))
        });
        g.bench_function(BenchmarkId::new("scene::load_flat", name), |b| {
            b.iter(|| scene::load_flat(black_box(&path)).expect("scene loads"))
        });
    }
    g.finish();
}

criterion_group!(benches, parse);
criterion_main!(benches);
