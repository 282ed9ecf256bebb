//! The pipeline the command line drives: load -> pack -> render -> displayable film.

use std::path::Path;
use std::sync::atomic::AtomicBool;
use std::time::{Duration, Instant};

use glam::Vec3;

use image::RgbImage;

use crate::compare::{self, Thresholds};
use crate::error::Result;
use crate::film::Film;
use crate::gpu_types::{AOV_COST, AOV_DEPTH, GpuGlobals};
use crate::pack::{self, SceneBuffers};
use crate::scene;

/// A scene read and flattened, with the time each step took and the reader's warnings.
pub struct Prepared {
    pub buffers: SceneBuffers,
    pub warnings: Vec<String>,
    pub parse_time: Duration,
    pub build_time: Duration,
}

pub fn prepare(path: &Path) -> Result<Prepared> {
    let t0 = Instant::now();
    let mut scene = scene::load(path)?;
    let t1 = Instant::now();
    let warnings = std::mem::take(&mut scene.warnings);
    let buffers = pack::pack(scene)?;
    Ok(Prepared {
        buffers,
        warnings,
        parse_time: t1 - t0,
        build_time: t1.elapsed(),
    })
}

/// Maps raw AOV values to something an 8-bit image can show: depth as grey scaled by
/// the largest distance, cost as a heat ramp scaled by the largest count. Colour and
/// normals pass through. Float formats (EXR) are written from the raw film instead.
pub fn display_film(film: &Film, aov: u32) -> Film {
    if aov != AOV_DEPTH && aov != AOV_COST {
        return film.clone();
    }
    let max = film
        .pixels
        .iter()
        .map(|p| p[0])
        .filter(|v| v.is_finite())
        .fold(0.0f32, f32::max)
        .max(1e-30);
    let mut out = film.clone();
    for p in &mut out.pixels {
        let v = (p[0] / max).clamp(0.0, 1.0);
        *p = if aov == AOV_DEPTH {
            [v; 3]
        } else {
            heat(v).to_array()
        };
    }
    out
}

/// Black -> blue -> red -> yellow -> white.
fn heat(v: f32) -> Vec3 {
    const STOPS: [Vec3; 5] = [
        Vec3::new(0.0, 0.0, 0.0),
        Vec3::new(0.0, 0.0, 1.0),
        Vec3::new(1.0, 0.0, 0.0),
        Vec3::new(1.0, 1.0, 0.0),
        Vec3::new(1.0, 1.0, 1.0),
    ];
    let x = v * 4.0;
    let i = (x.floor() as usize).min(3);
    STOPS[i].lerp(STOPS[i + 1], x - i as f32)
}

/// The fraction of pixels the CPU reference itself changes by more than the tolerance
/// when its eye point moves by one ulp, along each axis and along all three: the largest
/// of the four (see `Thresholds::check_with_noise_floor`). `cpu` is the displayed image of
/// the render `globals` describes. Scenes of sub-pixel mirror spheres (balls-4 at 128x128)
/// change on 0.4% to 1.2% of their pixels; most scenes on none.
pub fn noise_floor(buffers: &SceneBuffers, globals: &GpuGlobals, cpu: &RgbImage) -> Result<f64> {
    let up = |v: f32| f32::from_bits(v.to_bits() + 1);
    let never = AtomicBool::new(false);
    (0..4)
        .map(|axis| {
            let mut g = *globals;
            g.cam_pos = match axis {
                3 => g.cam_pos.map(up),
                _ => {
                    let mut p = g.cam_pos;
                    p[axis] = up(p[axis]);
                    p
                }
            };
            let (nudged, _) = crate::cpu::render(buffers, &g, &|_| {}, &never)?;
            let nudged = display_film(&nudged, globals.aov).to_rgb8();
            Ok(compare::diff(cpu, &nudged, Thresholds::GPU_VS_CPU.tolerance_255)?.frac_over)
        })
        .try_fold(0.0, |a: f64, b: Result<f64>| Ok(a.max(b?)))
}

/// How a GPU image agrees with the CPU reference of the same render.
pub struct Agreement {
    pub stats: compare::DiffStats,
    /// The reference's one-ulp noise floor, measured only when the plain limits fail.
    pub noise_floor: Option<f64>,
    /// `Err` says which limit was exceeded.
    pub verdict: std::result::Result<(), String>,
}

/// Compares the GPU film of a render with the CPU film of the same render under
/// `Thresholds::GPU_VS_CPU`, allowing the CPU's own noise floor where the plain limits
/// fail (`Thresholds::check_allowing_noise`).
pub fn agreement(
    buffers: &SceneBuffers,
    globals: &GpuGlobals,
    cpu: &Film,
    gpu: &Film,
) -> Result<Agreement> {
    let cpu = display_film(cpu, globals.aov).to_rgb8();
    let gpu = display_film(gpu, globals.aov).to_rgb8();
    let stats = compare::diff(&cpu, &gpu, Thresholds::GPU_VS_CPU.tolerance_255)?;
    let (noise_floor, verdict) = Thresholds::GPU_VS_CPU
        .check_allowing_noise(&stats, || noise_floor(buffers, globals, &cpu))?;
    Ok(Agreement {
        stats,
        noise_floor,
        verdict,
    })
}

/// Peak resident memory of this process in bytes (Linux; `None` elsewhere).
pub fn peak_memory() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}
