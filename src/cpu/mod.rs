//! The CPU reference renderer: the model the GPU must match, and the fallback where no
//! adapter exists. It reads only `SceneBuffers` and `GpuGlobals`, never the scene tree,
//! so it checks the packing and BVH layout as much as the shader.
//!
//! One module per WGSL file, same function names, same order of operations:
//! `types`, `intersect`, `walk` (where a traversal stands), `cwide` (the compressed
//! tree's walk), `traverse`, `shade`, `main`, `wavefront` (the wavefront kernels' steps over queues of pixels); and `wide`, the CPU's own walk of the same
//! tree eight children at a time, which finds the same hits.

pub mod cwide;
pub mod intersect;
pub mod main;
pub mod shade;
pub mod traverse;
pub mod types;
pub mod walk;
pub mod wavefront;
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
/// traced with it.
pub fn render_rows(
    buffers: &SceneBuffers,
    globals: &GpuGlobals,
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
    // Tiles of TILE x TILE pixels, clipped to `rows`: (x0, y0, y1).
    let tiles: Vec<(u32, u32, u32)> = (0..h.div_ceil(TILE))
        .flat_map(|ty| (0..w.div_ceil(TILE)).map(move |tx| (tx * TILE, ty * TILE)))
        .filter_map(|(x0, y0)| {
            let (lo, hi) = (y0.max(rows.start), (y0 + TILE).min(h).min(rows.end));
            (lo < hi).then_some((x0, lo, hi))
        })
        .collect();
    let done: Vec<Option<(Vec<[f32; 3]>, RayCounts)>> = tiles
        .par_iter()
        .map(|&(x0, y0, y1)| {
            if cancel.load(Ordering::Relaxed) {
                return None;
            }
            let mut counts = RayCounts::default();
            let mut px = Vec::with_capacity((TILE * TILE) as usize);
            for y in y0..y1 {
                for x in x0..(x0 + TILE).min(w) {
                    let sum = Vec3::from(accum.sums.get(x, y));
                    let sum = main::sample_sum(&b, x, y, samples.clone(), sum, &mut counts);
                    px.push(sum.to_array());
                }
            }
            progress(px.len() as u64);
            Some((px, counts))
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
