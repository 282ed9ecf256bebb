//! The wavefront path's dispatch loop: a band's tiles, one wave each. A wave starts every
//! pixel of its tile (`wf_generate`), then runs rounds (advance, extend, shadow, advance,
//! shade), each kernel dispatched indirectly over the queue the round before filled, a
//! batch of `ROUNDS` to a submission, until no pixel is left in a queue. Pixels whose
//! work was cut short are flagged in the output as `main` flags them, and `resume` takes
//! them as before.

use std::ops::Range;

use super::cut::Cut;
use super::device::Gpu;
use super::scene::{Bound, GpuScene};
use super::wavefront::{COUNT_WORDS, Wave};
use crate::error::Result;
use crate::gpu_types::{GpuTile, WORKGROUP_INVOCATIONS};

/// Rounds encoded between two looks at whether the wave is done: each look waits for the
/// GPU, and a round with empty queues costs five empty dispatches.
const ROUNDS: u32 = 8;

/// `trace::submit_band` for the wavefront path: the band's tiles at row `y0` for
/// `samples`, as `cut` cuts them, each traced to its end (the wave's own submissions are
/// made and waited for here). Returns the encoder of the last, left open for the band's
/// readback, and the dispatches made.
#[allow(clippy::too_many_arguments)]
pub(super) fn submit_band(
    gpu: &Gpu,
    scene: &GpuScene,
    wave: &Wave,
    cut: &Cut,
    y0: u32,
    rows: u32,
    samples: &Range<u32>,
    clear: bool,
) -> Result<(wgpu::CommandEncoder, u32)> {
    let bound = &scene.bound;
    let mut enc = gpu.encoder();
    if clear {
        bound.clear(&mut enc, u64::from(cut.width) * u64::from(rows));
    }
    let mut dispatches = 0;
    for tile in cut.tiles(y0, rows, samples) {
        debug_assert!(tile.width * tile.height <= wave.capacity);
        // Queue order: the tile lands after the submissions of the tile before.
        let mut record = vec![0u8; bound.tile_stride as usize];
        record[..size_of::<GpuTile>()].copy_from_slice(bytemuck::bytes_of(&tile));
        gpu.write(&bound.tile_buf, 0, &record);
        enc.clear_buffer(&wave.counts, 0, None);
        {
            let mut pass = enc.begin_compute_pass(&Default::default());
            pass.set_pipeline(&wave.kernels.generate);
            pass.set_bind_group(0, &bound.bind_group, &[0]);
            pass.set_bind_group(2, &wave.group, &[]);
            let pixels = tile.width * tile.height;
            pass.dispatch_workgroups(pixels.div_ceil(WORKGROUP_INVOCATIONS), 1, 1);
        }
        dispatches += 1;
        loop {
            encode_rounds(&mut enc, bound, wave);
            let bytes = 4 * COUNT_WORDS;
            enc.copy_buffer_to_buffer(&wave.counts, 0, &wave.counts_back, 0, bytes);
            gpu.run(enc);
            dispatches += 5 * ROUNDS;
            // The queues filling for the next round: empty when every pixel is written.
            let left = gpu.read(&wave.counts_back, bytes, |b| {
                let words: &[u32] = bytemuck::cast_slice(b);
                words[6] + words[7] + words[8]
            })?;
            enc = gpu.encoder();
            if left == 0 {
                break;
            }
        }
    }
    Ok((enc, dispatches))
}

/// Encodes `ROUNDS` rounds: the extend and shadow queues advance and their kernels run,
/// then the shade queue advances and the shade kernel runs. Each dispatch is a compute
/// pass of its own: with all of a round's dispatches in one pass, wgpu 30 on lavapipe ran
/// the first indirect dispatch of a pass and none of the dispatches after it (the queue
/// counts read back never moved again, and the frame never ended); wgpu validates an
/// indirect dispatch with a dispatch of its own, then binds the pass's state again.
fn encode_rounds(enc: &mut wgpu::CommandEncoder, bound: &Bound, wave: &Wave) {
    let k = &wave.kernels;
    let advance = |enc: &mut wgpu::CommandEncoder, pipeline| {
        let mut pass = enc.begin_compute_pass(&Default::default());
        pass.set_pipeline(pipeline);
        pass.set_bind_group(2, &wave.group, &[]);
        pass.set_bind_group(3, &wave.args_group, &[]);
        pass.dispatch_workgroups(1, 1, 1);
    };
    let run = |enc: &mut wgpu::CommandEncoder, pipeline, queue: u64| {
        let mut pass = enc.begin_compute_pass(&Default::default());
        pass.set_pipeline(pipeline);
        pass.set_bind_group(0, &bound.bind_group, &[0]);
        pass.set_bind_group(2, &wave.group, &[]);
        pass.dispatch_workgroups_indirect(&wave.args, 12 * queue);
    };
    for _ in 0..ROUNDS {
        advance(enc, &k.advance_rays);
        run(enc, &k.extend, 0);
        run(enc, &k.shadow, 1);
        advance(enc, &k.advance_shade);
        run(enc, &k.shade, 2);
    }
}
