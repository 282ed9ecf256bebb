//! The wavefront path's dispatches: a band's tiles, one wave each (a path per pixel
//! sample of the tile's pass). A wave starts its paths (`wf_generate`), runs a round per
//! depth, each of advance, extend, scan, shade, advance the shadows, shadow and gather
//! (the kernels over rays dispatched indirectly, sized on the device), and adds its paths
//! to their pixels (`wf_finish`). Nothing is read back between rounds (but a clock's
//! timestamps, when the kernels are timed): a round past the last ray dispatches
//! nothing. Pixels whose work was cut short are flagged in the output
//! as `main` flags them, and `resume` takes them as before.

use std::ops::Range;

use super::cut::Cut;
use super::device::Gpu;
use super::scene::{Bound, GpuScene};
use super::wavefront::kernel::{
    ADVANCE, ADVANCE_SHADOWS, EXTEND, FINISH, GATHER, GENERATE, SCAN, SHADE, SHADOW,
};
use super::wavefront::{Clock, SHADOW_ARGS, Wave, wave_passes};
use crate::gpu_types::{GpuTile, WORKGROUP_INVOCATIONS};
use crate::util::error::Result;

/// `trace::submit_band` for the wavefront path: the band's tiles at row `y0` for
/// `samples`, as `cut` cuts them, a submission per tile (each tile's record is written to
/// the tile buffer before its submission). Returns the encoder of the last, left open for
/// the band's readback, and the dispatches made. With a clock (`GpuScene::time_kernels`)
/// each tile's passes are timed, and read back before the next tile.
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
    let rounds = wave.rounds();
    let per_tile = wave_passes(rounds);
    let clock = wave.clock.as_ref().filter(|c| c.passes == per_tile);
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
        let mut passes = Passes {
            bound,
            wave,
            clock,
            kinds: Vec::new(),
        };
        passes.direct(&mut enc, GENERATE, pixels * tile.sample_count);
        for _ in 0..rounds {
            passes.round(&mut enc);
        }
        passes.direct(&mut enc, FINISH, pixels);
        dispatches += per_tile;
        if let Some(c) = clock {
            passes.read_clock(gpu, enc, c)?;
            enc = gpu.encoder();
        } else if tiles.peek().is_some() {
            gpu.run(enc);
            enc = gpu.encoder();
        }
    }
    Ok((enc, dispatches))
}

/// A tile's compute passes as they are encoded: which kernel each runs, for the clock.
struct Passes<'a> {
    bound: &'a Bound,
    wave: &'a Wave,
    clock: Option<&'a Clock>,
    kinds: Vec<usize>,
}

impl Passes<'_> {
    /// Begins a pass for kernel `kind`, timed when there is a clock. Each dispatch is a
    /// compute pass of its own: with several indirect dispatches in one pass, wgpu 30 on
    /// lavapipe ran the first and none after it (wgpu validates an indirect dispatch with
    /// a dispatch of its own, then binds the pass's state again).
    fn begin<'e>(
        &mut self,
        enc: &'e mut wgpu::CommandEncoder,
        kind: usize,
    ) -> wgpu::ComputePass<'e> {
        let i = self.kinds.len() as u32;
        self.kinds.push(kind);
        let timestamp_writes = self.clock.map(|c| wgpu::ComputePassTimestampWrites {
            query_set: &c.queries,
            beginning_of_pass_write_index: Some(2 * i),
            end_of_pass_write_index: Some(2 * i + 1),
        });
        let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: None,
            timestamp_writes,
        });
        pass.set_pipeline(&self.wave.kernels[kind]);
        pass.set_bind_group(2, &self.wave.group, &[]);
        if matches!(kind, ADVANCE | ADVANCE_SHADOWS) {
            pass.set_bind_group(3, &self.wave.args_group, &[]);
        } else {
            pass.set_bind_group(0, &self.bound.bind_group, &[0]);
        }
        pass
    }

    /// A dispatch of kernel `kind` over `invocations`.
    fn direct(&mut self, enc: &mut wgpu::CommandEncoder, kind: usize, invocations: u32) {
        let mut pass = self.begin(enc, kind);
        pass.dispatch_workgroups(invocations.div_ceil(WORKGROUP_INVOCATIONS), 1, 1);
    }

    /// A dispatch of kernel `kind` sized on the device, at `offset` in the wave's args.
    fn indirect(&mut self, enc: &mut wgpu::CommandEncoder, kind: usize, offset: u64) {
        let mut pass = self.begin(enc, kind);
        pass.dispatch_workgroups_indirect(&self.wave.args, offset);
    }

    /// One round: advance, extend, scan, shade, advance the shadows, shadow, gather.
    fn round(&mut self, enc: &mut wgpu::CommandEncoder) {
        self.direct(enc, ADVANCE, 1);
        self.indirect(enc, EXTEND, 0);
        self.direct(enc, SCAN, WORKGROUP_INVOCATIONS);
        self.indirect(enc, SHADE, 0);
        self.direct(enc, ADVANCE_SHADOWS, 1);
        self.indirect(enc, SHADOW, SHADOW_ARGS);
        self.indirect(enc, GATHER, 0);
    }

    /// Submits the tile with its timestamps resolved, reads them back, and adds each
    /// pass's time to its kernel's.
    fn read_clock(&self, gpu: &Gpu, mut enc: wgpu::CommandEncoder, clock: &Clock) -> Result<()> {
        let queries = 2 * self.kinds.len() as u32;
        let bytes = 8 * u64::from(queries);
        enc.resolve_query_set(&clock.queries, 0..queries, &clock.resolve, 0);
        enc.copy_buffer_to_buffer(&clock.resolve, 0, &clock.readback, 0, bytes);
        gpu.run(enc);
        let tick = f64::from(gpu.timestamp_period()) * 1e-9;
        gpu.read(&clock.readback, bytes, |b| {
            let ticks: Vec<u64> = b
                .chunks_exact(8)
                .map(bytemuck::pod_read_unaligned)
                .collect();
            let mut seconds = clock.seconds.lock().expect("clock lock");
            for (p, &kind) in self.kinds.iter().enumerate() {
                seconds[kind] += ticks[2 * p + 1].saturating_sub(ticks[2 * p]) as f64 * tick;
            }
        })
    }
}
