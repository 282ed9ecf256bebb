//! The CPU reference renderer: the model the GPU must match, and the fallback where no
//! adapter exists. It reads only `SceneBuffers` and `GpuGlobals`, never the scene tree,
//! so it checks the packing and BVH layout as much as the shader.
//!
//! One module per WGSL file, same function names, same order of operations:
//! `types`, `intersect`, `traverse`, `shade`, `main`; and `wide`, the CPU's own walk of
//! the same tree eight children at a time, which finds the same hits.

mod coherent;
pub mod intersect;
pub mod main;
pub mod packet;
pub mod shade;
pub mod tracer;
pub mod traverse;
pub mod types;
pub mod wide;

use std::ops::Range;
use std::sync::atomic::{AtomicBool, Ordering};

use glam::Vec3;

use rayon::prelude::*;

use crate::error::{Error, Result};
use crate::film::{Accumulator, Film};
use crate::gpu_types::GpuGlobals;
use crate::pack::SceneBuffers;
use types::Bindings;
pub use types::RayCounts;

/// Side of the square tiles rendered in parallel.
pub const TILE: u32 = 16;

/// Renders the whole image. `progress` is called with the number of pixels finished by
/// each tile; `cancel` stops the render early with `Error::Interrupted`.
pub fn render(
    buffers: &SceneBuffers,
    globals: &GpuGlobals,
    progress: &(dyn Fn(u64) + Sync),
    cancel: &AtomicBool,
) -> Result<(Film, RayCounts)> {
    let mut accum = Accumulator::new(globals.width, globals.height);
    let counts = render_samples(
        buffers,
        globals,
        0..globals.spp,
        &mut accum,
        progress,
        cancel,
    )?;
    Ok((accum.into_film(), counts))
}

/// Traces samples `samples` of every pixel and adds them to `accum`, which must hold
/// samples `0..samples.start` of the same frame: progressive rendering, whose result is
/// the one-step image to the bit.
pub fn render_samples(
    buffers: &SceneBuffers,
    globals: &GpuGlobals,
    samples: Range<u32>,
    accum: &mut Accumulator,
    progress: &(dyn Fn(u64) + Sync),
    cancel: &AtomicBool,
) -> Result<RayCounts> {
    let rows = 0..globals.height;
    render_rows(buffers, globals, rows, samples, accum, progress, cancel)
}

/// `render_samples` for the image rows `rows` only (a shard of the image): the other
/// rows of `accum` stay as they are. A pixel's value never depends on which others are
/// traced with it. Coherent rays go in packets with the kernels `GPURT_SIMD` picks
/// (`packet::Kernels::from_env`: by default the widest this processor runs).
pub fn render_rows(
    buffers: &SceneBuffers,
    globals: &GpuGlobals,
    rows: Range<u32>,
    samples: Range<u32>,
    accum: &mut Accumulator,
    progress: &(dyn Fn(u64) + Sync),
    cancel: &AtomicBool,
) -> Result<RayCounts> {
    let kernels = packet::Kernels::from_env()?;
    let k = kernels.as_ref();
    render_rows_with(buffers, globals, k, rows, samples, accum, progress, cancel)
}

/// `render_rows` with coherent rays in packets of `kernels`, or every ray alone for
/// `None`: the same image to the bit, and the same rays counted (but the packets').
#[allow(clippy::too_many_arguments)]
pub fn render_rows_with(
    buffers: &SceneBuffers,
    globals: &GpuGlobals,
    kernels: Option<&packet::Kernels>,
    rows: Range<u32>,
    samples: Range<u32>,
    accum: &mut Accumulator,
    progress: &(dyn Fn(u64) + Sync),
    cancel: &AtomicBool,
) -> Result<RayCounts> {
    let (w, h) = (globals.width, globals.height);
    accum.check(w, h, globals.spp, &samples)?;
    let rows = rows.start.min(h)..rows.end.min(h);
    let b = Bindings::new(buffers, globals);
    // Packets need the eight-wide tree (the `cost` AOV walks the GPU's instead).
    let kernels = kernels.filter(|_| b.wide.is_some());
    // Tiles of TILE x TILE pixels, clipped to `rows`: (x0, y0, y1).
    let tiles: Vec<(u32, u32, u32)> = (0..h.div_ceil(TILE))
        .flat_map(|ty| (0..w.div_ceil(TILE)).map(move |tx| (tx * TILE, ty * TILE)))
        .filter_map(|(x0, y0)| {
            let (lo, hi) = (y0.max(rows.start), (y0 + TILE).min(h).min(rows.end));
            (lo < hi).then_some((x0, lo, hi))
        })
        .collect();
    let old = &accum.sums;
    let done: Vec<Option<(Vec<[f32; 3]>, RayCounts)>> = tiles
        .par_iter()
        .map(|&(x0, y0, y1)| {
            if cancel.load(Ordering::Relaxed) {
                return None;
            }
            let mut counts = RayCounts::default();
            let x1 = (x0 + TILE).min(w);
            let mut px: Vec<Vec3> = (y0..y1)
                .flat_map(|y| (x0..x1).map(move |x| Vec3::from(old.get(x, y))))
                .collect();
            match kernels {
                Some(k) => {
                    let (xs, ys) = ((x0, x1), y0..y1);
                    coherent::render_tile(&b, k, xs, ys, samples.clone(), &mut px, &mut counts);
                }
                None => {
                    let pixels = (y0..y1).flat_map(|y| (x0..x1).map(move |x| (x, y)));
                    for ((x, y), sum) in pixels.zip(&mut px) {
                        *sum = main::sample_sum(&b, x, y, samples.clone(), *sum, &mut counts);
                    }
                }
            }
            progress(px.len() as u64);
            Some((px.iter().map(|p| p.to_array()).collect::<Vec<_>>(), counts))
        })
        .collect();
    let mut total = RayCounts::default();
    // Tiles covering every pixel need no copy of the old sums.
    let mut sums = if rows == (0..h) {
        Film::new(w, h)
    } else {
        accum.sums.clone()
    };
    for (&(x0, y0, _), tile) in tiles.iter().zip(done) {
        let (px, counts) = tile.ok_or(Error::Interrupted)?;
        total.add(&counts);
        let tw = (x0 + TILE).min(w) - x0;
        for (i, p) in px.into_iter().enumerate() {
            let (x, y) = (x0 + i as u32 % tw, y0 + i as u32 / tw);
            sums.pixels[(y * w + x) as usize] = p;
        }
    }
    // Only a finished pass changes the accumulator.
    accum.sums = sums;
    accum.samples = samples.end;
    Ok(total)
}
