//! The wavefront path's dispatches: a band's tiles, one wave each (a path per pixel
//! sample of the tile's pass). A wave starts its paths (`wf_generate`), runs a round per
//! depth, each of advance, extend, scan, shade, advance the shadows, shadow and gather
//! (the kernels over rays dispatched indirectly, sized on the device), and adds its paths
//! to their pixels (`wf_finish`). Nothing is read back between rounds: a round past the
//! last ray dispatches nothing. Pixels whose work was cut short are flagged in the output
//! as `main` flags them, and `resume` takes them as before.

use std::ops::Range;

use super::cut::Cut;
use super::device::Gpu;
use super::scene::{Bound, GpuScene};
use super::wavefront::{SHADOW_ARGS, Wave};
use crate::error::Result;
use crate::gpu_types::{GpuTile, WORKGROUP_INVOCATIONS};

/// `trace::submit_band` for the wavefront path: the band's tiles at row `y0` for
/// `samples`, as `cut` cuts them, a submission per tile (each tile's record is written to
/// the tile buffer before its submission). Returns the encoder of the last, left open for
/// the band's readback, and the dispatches made.
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
    let depth = wave.depth.max(1);
    let mut dispatches = 0;
    let mut tiles = cut.tiles(y0, rows, samples).into_iter().peekable();
    while let Some(tile) = tiles.next() {
        let pixels = tile.width * tile.height;
        debug_assert!(pixels * tile.sample_count <= wave.capacity);
        let mut record = vec![0u8; bound.tile_stride as usize];
        record[..size_of::<GpuTile>()].copy_from_slice(bytemuck::bytes_of(&tile));
        // Queue order: the tile lands after the submissions of the tile before.
        gpu.write(&bound.tile_buf, 0, &record);
        enc.clear_buffer(&wave.counts, 0, None);
        let k = &wave.kernels;
        let direct = |enc: &mut wgpu::CommandEncoder, pipeline, invocations: u32| {
            let mut pass = enc.begin_compute_pass(&Default::default());
            pass.set_pipeline(pipeline);
            pass.set_bind_group(0, &bound.bind_group, &[0]);
            pass.set_bind_group(2, &wave.group, &[]);
            pass.dispatch_workgroups(invocations.div_ceil(WORKGROUP_INVOCATIONS), 1, 1);
        };
        direct(&mut enc, &k.generate, pixels * tile.sample_count);
        for _ in 0..depth {
            encode_round(&mut enc, bound, wave);
        }
        direct(&mut enc, &k.finish, pixels);
        dispatches += 2 + 7 * depth;
        if tiles.peek().is_some() {
            gpu.run(enc);
            enc = gpu.encoder();
        }
    }
    Ok((enc, dispatches))
}

/// Encodes one round: advance, extend, scan, shade, advance the shadows, shadow, gather.
/// Each dispatch is a compute pass of its own: with several indirect dispatches in one
/// pass, wgpu 30 on lavapipe ran the first and none after it (wgpu validates an indirect
/// dispatch with a dispatch of its own, then binds the pass's state again).
fn encode_round(enc: &mut wgpu::CommandEncoder, bound: &Bound, wave: &Wave) {
    let k = &wave.kernels;
    let advance = |enc: &mut wgpu::CommandEncoder, pipeline| {
        let mut pass = enc.begin_compute_pass(&Default::default());
        pass.set_pipeline(pipeline);
        pass.set_bind_group(2, &wave.group, &[]);
        pass.set_bind_group(3, &wave.args_group, &[]);
        pass.dispatch_workgroups(1, 1, 1);
    };
    let run = |enc: &mut wgpu::CommandEncoder, pipeline, args: Option<u64>| {
        let mut pass = enc.begin_compute_pass(&Default::default());
        pass.set_pipeline(pipeline);
        pass.set_bind_group(0, &bound.bind_group, &[0]);
        pass.set_bind_group(2, &wave.group, &[]);
        match args {
            Some(offset) => pass.dispatch_workgroups_indirect(&wave.args, offset),
            None => pass.dispatch_workgroups(1, 1, 1),
        }
    };
    advance(enc, &k.advance);
    run(enc, &k.extend, Some(0));
    run(enc, &k.scan, None);
    run(enc, &k.shade, Some(0));
    advance(enc, &k.advance_shadows);
    run(enc, &k.shadow, Some(SHADOW_ARGS));
    run(enc, &k.gather, Some(0));
}
