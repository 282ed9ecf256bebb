//! `gpurt bench`'s table: what one row holds (the passes `super` measures) and its row of
//! markdown per scene, size and sample count, the rates by kind of ray read off the
//! differences between passes, and what goes to stderr beside it.

use std::time::Duration;

use crate::counters::Counters;
use crate::outln;

/// One row of the table: one scene at one size and sample count.
pub(super) struct Row {
    pub(super) scene: String,
    pub(super) prims: usize,
    pub(super) width: u32,
    pub(super) height: u32,
    pub(super) spp: u32,
    pub(super) gpu: Option<GpuRow>,
    pub(super) cpu: Option<CpuRow>,
}

pub(super) struct GpuRow {
    pub(super) compile: Duration,
    pub(super) upload: Duration,
    pub(super) device_bytes: u64,
    pub(super) eye: Pass,
    /// `None` where the frame takes the wavefront kernels.
    pub(super) shaded: Option<Pass>,
    pub(super) direct: Pass,
    pub(super) full: Pass,
    /// The `full` pass's counts.
    pub(super) counted: Counters,
    /// GPU seconds of each wavefront kernel in one `full` frame, where it takes them.
    pub(super) kernels: Option<Vec<(&'static str, f64)>>,
}

/// One timed pass: median frame time on the device, median time with the image read
/// back into a film, and rays traced per frame.
#[derive(Clone, Copy)]
pub(super) struct Pass {
    pub(super) time: Duration,
    pub(super) with_readback: Duration,
    pub(super) rays: u64,
}

pub(super) struct CpuRow {
    pub(super) time: Duration,
    pub(super) rays: u64,
    /// Rays and node fetches by kind, on the CPU's own walk.
    pub(super) counted: Counters,
}

fn mrays(rays: u64, t: Duration) -> f64 {
    rays as f64 / t.as_secs_f64().max(1e-12) / 1e6
}

/// Rays per second of the rays one pass adds over another, in millions; `-` when the
/// difference is within timing noise.
fn rate_between(more: Pass, less: Pass) -> String {
    let rays = more.rays.saturating_sub(less.rays);
    let t = more.time.saturating_sub(less.time);
    if rays == 0 || t < Duration::from_micros(20) {
        "-".into()
    } else {
        rate(mrays(rays, t))
    }
}

/// Mrays/s with three significant digits or more: a software adapter's rates are a few
/// Mrays/s, a GPU's thousands.
fn rate(mrays: f64) -> String {
    match mrays {
        m if m < 10.0 => format!("{m:.2}"),
        m if m < 100.0 => format!("{m:.1}"),
        m => format!("{m:.0}"),
    }
}

fn ms(t: Duration) -> String {
    format!("{:.2}", t.as_secs_f64() * 1e3)
}

/// Nodes fetched and node bytes read per ray of each kind, as cells: `nodes (bytes)`.
fn per_ray(c: &Counters) -> [String; 3] {
    [0, 1, 2].map(|k| match c.rays[k] {
        0 => "-".to_string(),
        _ => format!("{:.1} ({:.0})", c.nodes_per_ray(k), c.bytes_per_ray(k)),
    })
}

pub(super) fn print_header() {
    outln!(
        "| scene | prims | size | spp | rays/px | GPU frame ms | with readback ms | GPU Mrays/s | eye Mrays/s | shading ms | shadow Mrays/s | secondary Mrays/s | upload ms | compile ms | GPU MiB | CPU frame ms | CPU Mrays/s | GPU / CPU | eye nodes/ray (B) | shadow nodes/ray (B) | secondary nodes/ray (B) |"
    );
    outln!(
        "|---|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"
    );
}

pub(super) fn print_row(r: &Row) {
    let pixels = u64::from(r.width) * u64::from(r.height);
    let rays = r
        .gpu
        .as_ref()
        .map(|g| g.full.rays)
        .or(r.cpu.as_ref().map(|c| c.rays))
        .unwrap_or(0);
    let dash = || "-".to_string();
    let (frame, readback, rate, eye, shading, shadow, secondary, upload, compile, mib) =
        match &r.gpu {
            Some(g) => (
                ms(g.full.time),
                ms(g.full.with_readback),
                rate(mrays(g.full.rays, g.full.time)),
                rate(mrays(g.eye.rays, g.eye.time)),
                g.shaded
                    .map_or_else(dash, |s| ms(s.time.saturating_sub(g.eye.time))),
                // The shaded pass traces the eye rays alone: the direct pass's rays over its
                // are the shadow rays.
                rate_between(g.direct, g.shaded.unwrap_or(g.eye)),
                rate_between(g.full, g.direct),
                ms(g.upload),
                ms(g.compile),
                format!("{:.1}", g.device_bytes as f64 / (1 << 20) as f64),
            ),
            None => (
                dash(),
                dash(),
                dash(),
                dash(),
                dash(),
                dash(),
                dash(),
                dash(),
                dash(),
                dash(),
            ),
        };
    let (cpu_frame, cpu_rate) = match &r.cpu {
        Some(c) => (ms(c.time), format!("{:.1}", mrays(c.rays, c.time))),
        None => (dash(), dash()),
    };
    let speedup = match (&r.gpu, &r.cpu) {
        (Some(g), Some(c)) => format!("{:.1}x", c.time.as_secs_f64() / g.full.time.as_secs_f64()),
        _ => dash(),
    };
    // The GPU's walk where the GPU is timed, else the CPU's.
    let counted = r
        .gpu
        .as_ref()
        .map(|g| g.counted)
        .or(r.cpu.as_ref().map(|c| c.counted));
    let [eye_nodes, shadow_nodes, secondary_nodes] = counted
        .as_ref()
        .map_or_else(|| [dash(), dash(), dash()], per_ray);
    outln!(
        "| {} | {} | {}x{} | {} | {:.2} | {frame} | {readback} | {rate} | {eye} | {shading} | {shadow} | {secondary} | {upload} | {compile} | {mib} | {cpu_frame} | {cpu_rate} | {speedup} | {eye_nodes} | {shadow_nodes} | {secondary_nodes} |",
        r.scene,
        r.prims,
        r.width,
        r.height,
        r.spp,
        rays as f64 / pixels as f64,
    );
    if let Some(kernels) = r.gpu.as_ref().and_then(|g| g.kernels.as_ref()) {
        let each: Vec<String> = kernels
            .iter()
            .map(|(name, s)| format!("{} {:.2}", name.trim_start_matches("wf_"), s * 1e3))
            .collect();
        let total: f64 = kernels.iter().map(|(_, s)| s * 1e3).sum();
        eprintln!(
            "  {}: wavefront kernels, GPU ms a frame: {} (sum {total:.2})",
            r.scene,
            each.join(", ")
        );
    }
    if let Some((main, pooled)) = r.gpu.as_ref().and_then(|g| g.counted.lanes_busy_all()) {
        // The model's bound (`Counters::lanes_busy_all`), beside which a measured
        // `main` / `pooled` ratio can be read.
        eprintln!(
            "  {}: at most {:.0}% of a warp's lanes busy, {:.0}% pooled (model)",
            r.scene,
            100.0 * main,
            100.0 * pooled
        );
    }
    if let Some(c) = &r.cpu {
        let [eye, shadow, secondary] = c.counted.rays;
        eprintln!(
            "  {}: rays by kind (CPU count): {eye} eye, {shadow} shadow, {secondary} secondary",
            r.scene
        );
    }
}
