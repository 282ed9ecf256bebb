//! Pixels whose work did not fit one invocation (lavapipe's loop limit) are finished by
//! the `resume` entry point, which keeps each pixel's whole state in storage and goes
//! on from where it stopped, one bounded dispatch after another.

use std::ops::Range;
use std::sync::atomic::{AtomicBool, Ordering};

use super::device::Gpu;
use super::scene::GpuScene;
use crate::counters::Counters;
use crate::film::Film;
use crate::gpu_types::{
    GpuPixelState, GpuTile, PHASE_DONE, RESUME_X_MASK, RESUME_Y_SHIFT, WORKGROUP_INVOCATIONS,
};
use crate::util::error::{Error, Result};

/// Pixels resumed per dispatch (their states take `GpuPixelState`'s 928 bytes each).
pub(super) const RESUME_CHUNK: usize = 16384;

/// Traces `samples` of the pixels (x | y << RESUME_Y_SHIFT) whose work did not fit one invocation,
/// with the `resume` entry point, one dispatch after another until none is left, and adds
/// them to `sums`, and their counts to `counted` when the frame counts. Returns their
/// rays and how many were still cut short.
pub(super) async fn resume(
    gpu: &Gpu<'_>,
    scene: &GpuScene,
    pixels: &[u32],
    samples: &Range<u32>,
    sums: &mut Film,
    mut counted: Option<&mut Counters>,
    cancel: &AtomicBool,
) -> Result<(u64, u64)> {
    let pipeline = &scene.resume.get(gpu, scene.spec)?;
    let (mut rays, mut cut_short) = (0u64, 0u64);
    for chunk in pixels.chunks(RESUME_CHUNK) {
        let n = chunk.len() as u32;
        let state_bytes = u64::from(n) * size_of::<GpuPixelState>() as u64;
        let (state, pending, pending_back, state_back, group) =
            gpu.scoped("resuming pixels", || {
                let list = gpu.read_only_storage("resume pixels", bytemuck::cast_slice(chunk));
                let state = gpu.output("resume state", state_bytes);
                let pending = gpu.output("resume pending", 4);
                let pending_back = gpu.readback("resume pending readback", 4);
                let state_back = gpu.readback("resume state readback", state_bytes);
                let group = gpu.bind_group(
                    "gpurt resume",
                    &scene.resume.layout,
                    [&list, &state, &pending]
                        .map(|b| b.as_entire_binding())
                        .into(),
                );
                (state, pending, pending_back, state_back, group)
            })?;
        for round in 0u32.. {
            if cancel.load(Ordering::Relaxed) {
                return Err(Error::Interrupted);
            }
            let tile = GpuTile {
                x: samples.start,
                y: samples.end,
                width: n,
                sample_start: round,
                ..Default::default()
            };
            gpu.scoped("resuming pixels", || {
                gpu.write(&scene.bound.tile_buf, 0, bytemuck::bytes_of(&tile));
                gpu.write(&pending, 0, &[0; 4]);
                let mut enc = gpu.encoder();
                {
                    let mut pass = enc.begin_compute_pass(&Default::default());
                    pass.set_pipeline(pipeline);
                    pass.set_bind_group(0, &scene.bound.bind_group, &[0]);
                    pass.set_bind_group(1, &group, &[]);
                    pass.dispatch_workgroups(n.div_ceil(WORKGROUP_INVOCATIONS), 1, 1);
                }
                enc.copy_buffer_to_buffer(&pending, 0, &pending_back, 0, 4);
                gpu.run(enc);
            })?;
            let left: u32 = gpu
                .read_async(&pending_back, 4, bytemuck::pod_read_unaligned)
                .await?;
            if left == 0 {
                break;
            }
        }
        gpu.scoped("resuming pixels", || {
            let mut enc = gpu.encoder();
            enc.copy_buffer_to_buffer(&state, 0, &state_back, 0, state_bytes);
            gpu.run(enc);
        })?;
        gpu.read_async(&state_back, state_bytes, |bytes| {
            let states: &[GpuPixelState] = bytemuck::cast_slice(bytes);
            for (&xy, st) in chunk.iter().zip(states) {
                let (x, y) = (xy & RESUME_X_MASK, xy >> RESUME_Y_SHIFT);
                let sum = sums.get(x, y);
                sums.set(x, y, [0, 1, 2].map(|c| sum[c] + st.sum[c]));
                rays += u64::from(st.rays);
                if let Some(c) = counted.as_deref_mut() {
                    c.add_pixel(&st.counts);
                }
                cut_short += u64::from(st.cut != 0 || st.phase != PHASE_DONE);
            }
        })
        .await?;
    }
    Ok((rays, cut_short))
}
