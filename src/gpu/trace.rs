//! The dispatch loop: tiled dispatch and readback of an uploaded scene.
//!
//! A frame is cut (`Cut`) into tiles, one bounded dispatch each, so that no dispatch runs
//! long enough to trip a driver watchdog, and the tiles into bands of rows, one submission
//! and one readback each, so that the host does not wait on the GPU per tile. On a GPU,
//! bands whose dispatches took longer than `DISPATCH_BUDGET` make the rest cut finer.
//! Pixels whose work does not fit one invocation are finished by `resume`.

use std::ops::Range;
use std::sync::atomic::{AtomicBool, Ordering};
use web_time::Instant;

#[cfg(feature = "native")]
use rayon::prelude::*;

use super::cut::{Cut, PIXEL_BYTES};
use super::device::Gpu;
use super::resume::resume;
use super::scene::{Bound, GpuScene};
#[cfg(feature = "native")]
use super::waves;
use crate::counters::Counters;
use crate::film::{Accumulator, Film};
use crate::gpu_types::{GpuPixelCounts, GpuTile, PIXEL_CUT_SHORT, RESUME_X_MASK, RESUME_Y_SHIFT};
use crate::util::error::{Error, Result};

/// Bytes of a pixel's counts (`GpuPixelCounts`).
const COUNT_BYTES: u64 = size_of::<GpuPixelCounts>() as u64;

/// Traces an uploaded scene's image. Returns the film and the number of rays traced.
#[cfg(feature = "native")]
pub fn trace(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    scene: &GpuScene,
    progress: &dyn Fn(u64),
    cancel: &AtomicBool,
) -> Result<(Film, u64)> {
    let mut accum = Accumulator::new(scene.cut.width, scene.cut.height);
    let (rows, samples) = (0..scene.cut.height, 0..scene.cut.spp);
    let gpu = Gpu::new(device, queue);
    let trace = trace_band_rows(&gpu, scene, rows, samples, &mut accum, progress, cancel);
    let rays = pollster::block_on(trace)?;
    Ok((accum.into_film(), rays))
}

/// Traces samples `samples` of the pixels of image rows `rows` (all of them, or a shard
/// of the image) of an uploaded scene and adds them to `accum`, which must hold samples
/// `0..samples.start` of the same frame (progressive rendering); the other rows of
/// `accum` stay as they are. Returns the rays traced.
#[allow(clippy::too_many_arguments)]
#[cfg(feature = "native")]
pub fn trace_rows(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    scene: &GpuScene,
    rows: Range<u32>,
    samples: Range<u32>,
    accum: &mut Accumulator,
    progress: &dyn Fn(u64),
    cancel: &AtomicBool,
) -> Result<u64> {
    let trace = trace_rows_async(device, queue, scene, rows, samples, accum, progress, cancel);
    pollster::block_on(trace)
}

/// `trace_rows` as a future, for the browser (`web/`), which may not block: it awaits
/// each band's readback, giving way to the page's event loop. Natively every await
/// returns at once, so `trace_rows` blocks on this.
#[allow(clippy::too_many_arguments)]
pub async fn trace_rows_async(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    scene: &GpuScene,
    rows: Range<u32>,
    samples: Range<u32>,
    accum: &mut Accumulator,
    progress: &dyn Fn(u64),
    cancel: &AtomicBool,
) -> Result<u64> {
    let gpu = Gpu::new(device, queue);
    trace_band_rows(&gpu, scene, rows, samples, accum, progress, cancel).await
}

/// `trace_rows`, band by band.
async fn trace_band_rows(
    gpu: &Gpu<'_>,
    scene: &GpuScene,
    rows: Range<u32>,
    samples: Range<u32>,
    accum: &mut Accumulator,
    progress: &dyn Fn(u64),
    cancel: &AtomicBool,
) -> Result<u64> {
    let cut = scene.cut;
    accum.check(cut.width, cut.height, cut.spp, &samples)?;
    let (mut rays, mut cut_short) = (0u64, 0u64);
    // Pixels whose work did not fit one invocation, finished by `resume`.
    let mut unfinished = Vec::new();
    // The bands, clipped to `rows`.
    let bands = cut.bands().filter_map(|(y0, n)| {
        let (lo, hi) = (y0.max(rows.start), (y0 + n).min(rows.end));
        (lo < hi).then(|| (lo, hi - lo))
    });
    let mut tracing = scene.tracing_cut();
    let all = u64::from(samples.end - samples.start).max(1);
    let mut counted = scene
        .bound
        .counting
        .then(|| Counters::new(scene.node_bytes));
    for (y0, rows) in bands {
        let pixels = u64::from(cut.width) * u64::from(rows);
        let bytes = pixels * PIXEL_BYTES;
        // Progress is in pixels: a submission of part of the samples reports its share.
        let mut reported = 0;
        for run in cut.submissions(&samples) {
            if cancel.load(Ordering::Relaxed) {
                return Err(Error::Interrupted);
            }
            let last = run.end == samples.end;
            let start = Instant::now();
            let dispatches = gpu.scoped("tracing a band", || -> Result<u32> {
                let first = run.start == samples.start;
                let (mut enc, dispatches) =
                    submit_band(gpu, scene, &tracing, y0, rows, &run, first)?;
                if last {
                    let (output, readback) = (&scene.bound.output, &scene.bound.readback);
                    enc.copy_buffer_to_buffer(output, 0, readback, 0, bytes);
                    if counted.is_some() {
                        let (counts, back) = (&scene.bound.counts, &scene.bound.counts_back);
                        enc.copy_buffer_to_buffer(counts, 0, back, 0, pixels * COUNT_BYTES);
                    }
                }
                gpu.run(enc);
                Ok(dispatches)
            })??;
            if last {
                let fresh = accum.holds_nothing();
                let (band_rays, band_cut) = read_band(
                    gpu,
                    &scene.bound.readback,
                    bytes,
                    y0,
                    &mut accum.sums,
                    fresh,
                )
                .await?;
                if let Some(counted) = &mut counted {
                    let first = u64::from(y0) * u64::from(cut.width);
                    read_counts(gpu, scene, pixels, first, &band_cut, counted).await?;
                }
                rays += band_rays;
                unfinished.extend(band_cut);
            } else {
                // One submission at a time, so that Ctrl-C is seen within one.
                gpu.wait()?;
            }
            if let Some(budget) = scene.dispatch_budget {
                // The time includes the band's readback after its last submission: the
                // mean dispatch is overestimated, on the safe side.
                let mean = start.elapsed().as_secs_f64() / f64::from(dispatches.max(1));
                if mean > budget.as_secs_f64() {
                    tracing = tracing.finer(2.0 * mean / budget.as_secs_f64());
                    *scene.finer.lock().expect("cut lock") = Some(tracing);
                }
            }
            let done = pixels * u64::from(run.end - samples.start) / all;
            progress(done - reported);
            reported = done;
        }
    }
    if !unfinished.is_empty() {
        let (sums, counts) = (&mut accum.sums, counted.as_mut());
        let resumed = resume(gpu, scene, &unfinished, &samples, sums, counts, cancel);
        let (more_rays, cut) = resumed.await?;
        rays += more_rays;
        cut_short += cut;
    }
    if cut_short > 0 {
        return Err(Error::Gpu(format!(
            "{cut_short} of {} pixels could not finish on {}: the driver ended a shader loop \
             before its end (lavapipe stops every loop once one invocation has run 65535 \
             loop iterations, and a single ray of these pixels needs more, crossing too \
             many surfaces); render with --backend cpu",
            u64::from(cut.width) * u64::from(cut.height),
            gpu.adapter_name()
        )));
    }
    accum.samples = samples.end;
    *scene.counted.lock().expect("counts lock") = counted;
    scene
        .resumed
        .store(unfinished.len() as u64, Ordering::Relaxed);
    Ok(rays)
}

/// Traces an uploaded scene's image and waits for the GPU, reading nothing back: the
/// GPU's own time for a frame, as a viewer that displays on the device would see it.
pub fn trace_on_device(device: &wgpu::Device, queue: &wgpu::Queue, scene: &GpuScene) -> Result<()> {
    let gpu = Gpu::new(device, queue);
    let cut = scene.tracing_cut();
    for (y0, rows) in cut.bands() {
        for run in cut.submissions(&(0..cut.spp)) {
            gpu.scoped("tracing a band", || -> Result<()> {
                let first = run.start == 0;
                let (enc, _) = submit_band(&gpu, scene, &cut, y0, rows, &run, first)?;
                gpu.run(enc);
                Ok(())
            })??;
        }
    }
    gpu.wait()
}

/// Traces the band at row `y0` for `samples` as `cut` cuts it, after the clearing of the
/// band's output when `clear` (the first samples of the band: each pass adds to what the
/// passes before left): through the `main` kernel, or the wavefront kernels where the
/// frame takes them (`waves`, which waits on the device between rounds: never in the
/// browser). Returns the encoder of the last submission, still open, and the dispatches.
#[allow(clippy::too_many_arguments)]
fn submit_band(
    gpu: &Gpu<'_>,
    scene: &GpuScene,
    cut: &Cut,
    y0: u32,
    rows: u32,
    samples: &Range<u32>,
    clear: bool,
) -> Result<(wgpu::CommandEncoder, u32)> {
    match &scene.wave {
        #[cfg(feature = "native")]
        Some(wave) => waves::submit_band(gpu, scene, wave, cut, y0, rows, samples, clear),
        _ => Ok(submit_main_band(gpu, scene, cut, y0, rows, samples, clear)),
    }
}

/// Writes the tiles of the band at row `y0` for `samples` as `cut` cuts it and encodes
/// their dispatches of `main`, after the clearing of the band's output when `clear`. A
/// finer cut than the one the tile buffer was made for has more tiles than slots: all but
/// the last buffer-full are submitted here. Returns the encoder of the last, and the
/// dispatches.
fn submit_main_band(
    gpu: &Gpu<'_>,
    scene: &GpuScene,
    cut: &Cut,
    y0: u32,
    rows: u32,
    samples: &Range<u32>,
    clear: bool,
) -> (wgpu::CommandEncoder, u32) {
    let tiles = cut.tiles(y0, rows, samples);
    let stride = scene.bound.tile_stride as usize;
    let band_bytes = u64::from(cut.width) * u64::from(rows) * PIXEL_BYTES;
    let mut enc = gpu.encoder();
    if clear {
        scene.bound.clear(&mut enc, band_bytes / PIXEL_BYTES);
    }
    // `tile_buf` holds the dispatches of a submission of the frame's own cut (`bind`).
    let slots = scene.cut.dispatches_per_submission().max(1) as usize;
    let mut groups = tiles.chunks(slots).peekable();
    while let Some(group) = groups.next() {
        let mut bytes = vec![0u8; group.len() * stride];
        for (chunk, tile) in bytes.chunks_mut(stride).zip(group) {
            chunk[..size_of::<GpuTile>()].copy_from_slice(bytemuck::bytes_of(tile));
        }
        // Queue order: this write lands after the submissions before it have run.
        gpu.write(&scene.bound.tile_buf, 0, &bytes);
        encode_band(&mut enc, &scene.pipeline, &scene.bound, group);
        if groups.peek().is_some() {
            gpu.run(enc);
            enc = gpu.encoder();
        }
    }
    (enc, tiles.len() as u32)
}

/// Encodes one compute pass with a dispatch per tile, each tile read from its slot of the
/// tile buffer (written beforehand, in the same order).
pub(super) fn encode_band(
    enc: &mut wgpu::CommandEncoder,
    pipeline: &wgpu::ComputePipeline,
    bound: &Bound,
    tiles: &[GpuTile],
) {
    {
        let mut pass = enc.begin_compute_pass(&Default::default());
        pass.set_pipeline(pipeline);
        for (i, tile) in tiles.iter().enumerate() {
            pass.set_bind_group(0, &bound.bind_group, &[i as u32 * bound.tile_stride]);
            let groups = tile.workgroups();
            pass.dispatch_workgroups(groups[0], groups[1], 1);
        }
    }
}

/// A band's chunk of sums to add to, and its readback pixels, at its index.
type Chunk<'a> = (usize, (&'a mut [[f32; 3]], &'a [[u32; 4]]));

/// Maps the readback buffer and adds the band's sums (full rows from `y0`) to `sums`
/// (writes them, where `fresh`: `sums` holds nothing yet, `Accumulator::holds_nothing`);
/// returns its ray count and the pixels (x | y << RESUME_Y_SHIFT) whose work was cut short, which are
/// left to `resume` (neither their sums nor their rays are counted).
async fn read_band(
    gpu: &Gpu<'_>,
    readback: &wgpu::Buffer,
    bytes: u64,
    y0: u32,
    sums: &mut Film,
    fresh: bool,
) -> Result<(u64, Vec<u32>)> {
    let width = sums.width as usize;
    // In parallel: a 4K band is 133 MB, and one core takes longer to add it up than the
    // GPU took to trace it.
    const CHUNK: usize = 1 << 14;
    let start = y0 as usize * width;
    // The chunk at `k` of the band: its sums added, its rays and its pixels cut short.
    let add = |(k, (out, px)): Chunk| {
        let (mut rays, mut cut) = (0u64, Vec::new());
        for (i, (out, p)) in out.iter_mut().zip(px).enumerate() {
            if p[3] & PIXEL_CUT_SHORT != 0 {
                let j = start + k * CHUNK + i;
                cut.push((j % width) as u32 | ((j / width) as u32) << RESUME_Y_SHIFT);
            } else {
                let sum = if fresh { [0.0; 3] } else { *out };
                *out = [0, 1, 2].map(|c| sum[c] + f32::from_bits(p[c]));
                rays += u64::from(p[3]);
            }
        }
        (rays, cut)
    };
    let join = |(rays, mut cut): (u64, Vec<u32>), (more, more_cut): (u64, Vec<u32>)| {
        cut.extend(more_cut);
        (rays + more, cut)
    };
    gpu.read_async(readback, bytes, |view| {
        let px: &[[u32; 4]] = bytemuck::cast_slice(view);
        let out = &mut sums.pixels[start..start + px.len()];
        #[cfg(feature = "native")]
        let chunks = out.par_chunks_mut(CHUNK).zip(px.par_chunks(CHUNK));
        // One thread in the browser: the same chunks, in order.
        #[cfg(not(feature = "native"))]
        let chunks = out.chunks_mut(CHUNK).zip(px.chunks(CHUNK));
        let parts = chunks.enumerate().map(add);
        #[cfg(feature = "native")]
        return parts.reduce(|| (0, Vec::new()), join);
        #[cfg(not(feature = "native"))]
        return parts.fold((0, Vec::new()), join);
    })
    .await
}

/// Adds the counts of a band's pixels (`pixels` of them, the first being pixel `first` of
/// the image) to `counted`, but for those cut short (`cut`, as `read_band` lists them),
/// whose counts `resume` gives.
async fn read_counts(
    gpu: &Gpu<'_>,
    scene: &GpuScene,
    pixels: u64,
    first: u64,
    cut: &[u32],
    counted: &mut Counters,
) -> Result<()> {
    let width = u64::from(scene.cut.width);
    let mut skip: Vec<usize> = cut
        .iter()
        .map(|&xy| {
            let (x, y) = (xy & RESUME_X_MASK, xy >> RESUME_Y_SHIFT);
            (u64::from(y) * width + u64::from(x) - first) as usize
        })
        .collect();
    skip.sort_unstable();
    gpu.read_async(&scene.bound.counts_back, pixels * COUNT_BYTES, |view| {
        let px: &[GpuPixelCounts] = bytemuck::cast_slice(view);
        counted.add_band(px, width as usize, &skip);
    })
    .await
}
