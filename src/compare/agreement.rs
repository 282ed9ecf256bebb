//! Whether a GPU image agrees with the CPU reference of the same frame: the comparison
//! under `Thresholds::GPU_VS_CPU`, allowing for the reference's own one-ulp noise floor
//! where the plain limits fail (`Thresholds::check_allowing_noise`).

use std::sync::atomic::AtomicBool;

use image::RgbImage;

use crate::compare::{self, DiffStats, Thresholds};
use crate::film::Film;
use crate::gpu_types::GpuGlobals;
use crate::pack::SceneBuffers;
use crate::util::error::Result;

/// How a GPU image agrees with the CPU reference of the same render.
pub struct Agreement {
    pub stats: DiffStats,
    /// The reference's one-ulp noise floor, measured only when the plain limits fail.
    pub noise_floor: Option<f64>,
    /// `Err` says which limit was exceeded.
    pub verdict: std::result::Result<(), String>,
}

/// Compares the GPU film of a render with the CPU film of the same render (both as an
/// 8-bit image shows them).
pub fn agreement(
    buffers: &SceneBuffers,
    globals: &GpuGlobals,
    cpu: &Film,
    gpu: &Film,
) -> Result<Agreement> {
    let cpu = cpu.for_display(globals.aov).to_rgb8();
    let gpu = gpu.for_display(globals.aov).to_rgb8();
    let stats = compare::diff(&cpu, &gpu, Thresholds::GPU_VS_CPU.tolerance_255)?;
    let (noise_floor, verdict) = Thresholds::GPU_VS_CPU
        .check_allowing_noise(&stats, || noise_floor(buffers, globals, &cpu))?;
    Ok(Agreement {
        stats,
        noise_floor,
        verdict,
    })
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
            let nudged = nudged.for_display(globals.aov).to_rgb8();
            Ok(compare::diff(cpu, &nudged, Thresholds::GPU_VS_CPU.tolerance_255)?.frac_over)
        })
        .try_fold(0.0, |a: f64, b: Result<f64>| Ok(a.max(b?)))
}
