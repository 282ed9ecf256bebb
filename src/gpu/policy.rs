//! What a frame takes on this adapter: which walk of the BVH and which kernels (the one
//! `main` kernel or the wavefront ones), each chosen per adapter and per scene by what
//! was measured, and overridable from the environment for measuring them side by side;
//! and how the frame is cut into work.

use super::cut::Cut;
use crate::error::{Error, Result};
use crate::gpu_types::{
    AOV_COLOR, GpuGlobals, GpuWaveState, TRAVERSAL_NAMES, TRAVERSAL_WIDE, WORKGROUP_SIDE,
};
use crate::pack::SceneBuffers;

/// The traversal for an adapter: `TRAVERSAL_WIDE` on every adapter (each scene falls back
/// to pairs where its wide tree does not fit the stack). On the H100 a ray's time goes to
/// waiting on node fetches, and the four-wide tree halves the chain of them: 1.2 to 1.5
/// times faster than pairs, which was 1.2 to 1.4 times faster than single. On lavapipe it
/// is 2 to 19% faster than single (docs/gpu.md has the figures). The compressed
/// eight-wide walk (`TRAVERSAL_CWIDE`) fetches 40 to 56% fewer node bytes, yet is 1.3 to
/// 1.7 times slower on the H100 and slower on lavapipe's larger scenes: not the default.
/// `GPURT_TRAVERSAL` (`single`, `pairs`, `wide` or `cwide`: `TRAVERSAL_NAMES`) overrides
/// it, for measuring them on one adapter.
pub(super) fn traversal_from_env() -> Result<u32> {
    match std::env::var("GPURT_TRAVERSAL").as_deref() {
        Err(_) | Ok("") => Ok(TRAVERSAL_WIDE),
        Ok(v) => match TRAVERSAL_NAMES.iter().position(|&n| n == v) {
            Some(t) => Ok(t as u32),
            None => Err(Error::Render(format!(
                "GPURT_TRAVERSAL={v}: expected one of {}",
                TRAVERSAL_NAMES.join(", ")
            ))),
        },
    }
}

/// `GPURT_KERNELS`: `main` (the one kernel) or `wavefront` forces the kernels of every
/// colour frame; unset or empty, `wavefront_for` chooses.
pub(super) fn kernels_from_env() -> Result<Option<bool>> {
    match std::env::var("GPURT_KERNELS").as_deref() {
        Err(_) | Ok("") => Ok(None),
        Ok("main") => Ok(Some(false)),
        Ok("wavefront") => Ok(Some(true)),
        Ok(v) => Err(Error::Render(format!(
            "GPURT_KERNELS={v}: expected main or wavefront"
        ))),
    }
}

/// Whether a frame of `scene` traces through the wavefront kernels: as `forced` says
/// when it says (`GPURT_KERNELS`, `GpuRenderer::with_wavefront`), else by what was
/// measured. Colour frames only: an AOV traces eye rays alone, which one kernel does
/// without idle lanes.
///
/// Measured (docs/gpu.md, "The wavefront kernels"): the one kernel wins everywhere so
/// far, 3.5 to 7 times on lavapipe and 26 to 73 times on the H100, so every adapter keeps
/// it.
pub(super) fn wavefront_for(
    forced: Option<bool>,
    _software: bool,
    _scene: &SceneBuffers,
    globals: &GpuGlobals,
) -> bool {
    globals.aov == AOV_COLOR && forced.unwrap_or(false)
}

/// Pixels a side of a wave's tile at most: a wave holds a `WaveState` per pixel (up to a
/// kilobyte with the longest ray stack), 16 MiB at this side, less where the device's
/// storage bindings are smaller (`cut_for`).
const WAVE_TILE_SIDE: u32 = 128;

/// How a frame of `globals`' size and samples is cut on this device. Software adapters
/// get small bands so that Ctrl-C and the progress bar respond within a second, and one
/// sample per pass: lavapipe ends every loop once an invocation has run 65535 loop
/// iterations in all, and one sample of an ordinary scene needs far fewer. GPUs take up
/// to 16 samples per pass, and a band is the most one submission should hold. The
/// wavefront path's tiles are its waves, at most `WAVE_TILE_SIDE` a side.
pub(super) fn cut_for(limits: &wgpu::Limits, globals: &GpuGlobals, software: bool) -> Cut {
    let (pass_samples, band_samples) = if software {
        (1, 1 << 18)
    } else {
        (16, 1 << 26)
    };
    let mut cut = Cut::new(
        globals.width,
        globals.height,
        globals.spp,
        pass_samples,
        band_samples,
        limits
            .max_storage_buffer_binding_size
            .min(limits.max_buffer_size),
        // Software adapters split a dispatch among their threads in fixed runs; a GPU's
        // own scheduler balances, and neighbouring blocks share its caches.
        software,
    );
    if globals.wavefront != 0 {
        // A wave's states are one storage binding: halve the side (bands stay whole rows
        // of tiles, sides being powers of two) until they fit the device's limit, down
        // to one workgroup's square.
        let limit = limits
            .max_storage_buffer_binding_size
            .min(limits.max_buffer_size);
        let state = size_of::<GpuWaveState>() as u64;
        let mut side = cut.tile_side.min(WAVE_TILE_SIDE);
        while side > WORKGROUP_SIDE && u64::from(side * side) * state > limit {
            side /= 2;
        }
        cut.tile_side = side;
    }
    cut
}
