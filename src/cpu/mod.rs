//! The CPU reference renderer: the model the GPU must match, and the fallback where no
//! adapter exists. It reads only `SceneBuffers` and `GpuGlobals`, never the scene tree,
//! so it checks the packing and BVH layout as much as the shader.
//!
//! Two rooms. Here, the twins: one module per WGSL file, same function names, same order
//! of operations: `types`, `intersect`, `walk` (where a traversal stands), `cwide` (the
//! compressed tree's walk), `traverse`, `texture` (what a hit's texture gives its
//! material), `shade`, `pixel` (a pixel's camera rays),
//! `wave` (a wave's records) and `wavefront` (the wavefront kernels' steps over queues of
//! pixels). In `fast/`, what
//! only the CPU has, which finds the same hits faster: its eight-wide walk, coherent rays
//! in SIMD packets, and where the shading gets its rays' answers (`fast/mod.rs`).

pub mod cwide;
pub mod fast;
pub mod intersect;
pub mod pixel;
pub mod shade;
pub mod texture;
pub mod traverse;
pub mod types;
pub mod walk;
pub mod wave;
pub mod wavefront;

pub use fast::{packet, tracer, wide};

use std::ops::Range;
use std::sync::atomic::{AtomicBool, Ordering};

use glam::Vec3;

use rayon::prelude::*;

use crate::film::{Accumulator, Film};
use crate::gpu_types::GpuGlobals;
use crate::pack::SceneBuffers;
use crate::util::error::{Error, Result};
use types::Bindings;
pub use types::RayCounts;

/// Side of the square tiles rendered in parallel.
pub const TILE: u32 = 16;

/// A row of a tile: the image row and its pixels' sums.
type RowPiece<'a> = (u32, &'a mut [[f32; 3]]);

/// Renders the whole image. `progress` is called with the number of pixels finished by
/// each tile; `cancel` stops the render early with `Error::Interrupted`.
pub fn render(
    buffers: &SceneBuffers,
    globals: &GpuGlobals,
    progress: &(dyn Fn(u64) + Sync),
    cancel: &AtomicBool,
) -> Result<(Film, RayCounts)> {
    let mut accum = Accumulator::new(globals.width, globals.height);
    let counts = render_rows(
        buffers,
        globals,
        0..globals.height,
        0..globals.spp,
        &mut accum,
        progress,
        cancel,
    )?;
    Ok((accum.into_film(), counts))
}

/// Traces samples `samples` of the pixels of image rows `rows` (all of them, or a shard
/// of the image) and adds them to `accum`, which must hold samples `0..samples.start` of
/// the same frame: progressive rendering, whose result is the one-step image to the bit.
/// The other rows of `accum` stay as they are. A pixel's value never depends on which others are
/// traced with it. Coherent rays go in packets with the kernels `GPURT_SIMD` picks
/// (`packet::Kernels::from_env`: by default the widest this processor runs).
///
/// Each pixel's sum is traced in place in `accum`, in tiles of TILE x TILE pixels, so a
/// frame costs no memory beyond its accumulator (at 16384 x 16384, 3 GiB; a second
/// buffer of the tiles' results would double it). Only a finished pass counts: when
/// cancelled, the rows traced are put back as they were, from a copy kept of them unless
/// they held nothing: then only the tiles finished are zeroed, which needs no copy and
/// leaves the pages of a huge film that no tile reached untouched (zeroing all of a
/// 16384 x 16384 film would take seconds after Ctrl-C).
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
    if globals.aov == crate::gpu_types::AOV_COST && buffers.is_cpu_only() {
        return Err(Error::Render(
            "internal error: the cost AOV walks the binary tree, which was dropped".into(),
        ));
    }
    let b = Bindings::new(buffers, globals);
    // Packets need the eight-wide tree (the `cost` AOV walks the GPU's instead).
    let kernels = kernels.filter(|_| b.wide.is_some());
    let span = rows.start as usize * w as usize..rows.end as usize * w as usize;
    // A pass from zero sums writes them without reading them first (`Film::new`).
    let fresh = accum.holds_nothing();
    let held = &accum.sums.pixels[span.clone()];
    let before = (!fresh && held.iter().any(|p| *p != [0.0; 3])).then(|| held.to_vec());
    let band = (TILE * w) as usize;
    let columns = w.div_ceil(TILE) as usize;
    // Which tiles were traced, by band and column: the tiles to zero when cancelled.
    let finished: Vec<AtomicBool> = (0..h.div_ceil(TILE) as usize * columns)
        .map(|_| AtomicBool::new(false))
        .collect();
    let traced: Option<RayCounts> = accum
        .sums
        .pixels
        .par_chunks_mut(band.max(1))
        .enumerate()
        .flat_map(|(band_index, pixels)| {
            let y0 = band_index as u32 * TILE;
            // The band's rows, cut into the TILE-wide pieces of each tile column.
            let mut columns: Vec<Vec<RowPiece>> =
                (0..w.div_ceil(TILE)).map(|_| Vec::new()).collect();
            for (dy, row) in pixels.chunks_mut(w as usize).enumerate() {
                let y = y0 + dy as u32;
                if rows.contains(&y) {
                    for (piece, column) in row.chunks_mut(TILE as usize).zip(&mut columns) {
                        column.push((y, piece));
                    }
                }
            }
            columns
                .into_par_iter()
                .enumerate()
                .filter(|(_, c)| !c.is_empty())
                .map(move |(tx, tile)| (band_index, tx, tile))
        })
        .map(|(band_index, tx, tile)| {
            if cancel.load(Ordering::Relaxed) {
                return None;
            }
            let mut counts = RayCounts::default();
            let n = match kernels {
                Some(k) => {
                    // The tile's rows are consecutive (`rows` is a range): trace them
                    // as one block, then write the sums back into the accumulator.
                    let x0 = tx as u32 * TILE;
                    let x1 = x0 + tile[0].1.len() as u32;
                    let ys = tile[0].0..tile[0].0 + tile.len() as u32;
                    let mut px: Vec<Vec3> = if fresh {
                        vec![Vec3::ZERO; tile.iter().map(|(_, p)| p.len()).sum()]
                    } else {
                        tile.iter()
                            .flat_map(|(_, p)| p.iter().map(|&s| Vec3::from(s)))
                            .collect()
                    };
                    fast::coherent::render_tile(
                        &b,
                        k,
                        (x0, x1),
                        ys,
                        samples.clone(),
                        &mut px,
                        &mut counts,
                    );
                    let sums = px.chunks(tile[0].1.len());
                    for ((_, piece), row) in tile.into_iter().zip(sums) {
                        for (out, sum) in piece.iter_mut().zip(row) {
                            *out = sum.to_array();
                        }
                    }
                    px.len() as u64
                }
                None => {
                    let mut n = 0;
                    for (y, piece) in tile {
                        for (dx, px) in piece.iter_mut().enumerate() {
                            let x = tx as u32 * TILE + dx as u32;
                            let sum = pixel::sample_sum(
                                &b,
                                &mut fast::tracer::Alone,
                                (x, y),
                                samples.clone(),
                                if fresh { Vec3::ZERO } else { Vec3::from(*px) },
                                &mut counts,
                            );
                            *px = sum.to_array();
                            n += 1;
                        }
                    }
                    n
                }
            };
            finished[band_index * columns + tx].store(true, Ordering::Relaxed);
            progress(n);
            Some(counts)
        })
        // Any tile left untraced (None) leaves the pass unfinished.
        .reduce(
            || Some(RayCounts::default()),
            |a, b| {
                let (mut a, b) = (a?, b?);
                a.add(&b);
                Some(a)
            },
        );
    let Some(total) = traced else {
        let restored = &mut accum.sums.pixels[span];
        match before {
            Some(old) => restored.copy_from_slice(&old),
            None => {
                for (i, row) in restored.chunks_mut((w as usize).max(1)).enumerate() {
                    let band_index = (rows.start as usize + i) / TILE as usize;
                    for (tx, piece) in row.chunks_mut(TILE as usize).enumerate() {
                        if finished[band_index * columns + tx].load(Ordering::Relaxed) {
                            piece.fill([0.0; 3]);
                        }
                    }
                }
            }
        }
        return Err(Error::Interrupted);
    };
    accum.samples = samples.end;
    Ok(total)
}

/// Numbers in [-1, 1) from a xorshift stream seeded with `state`: the CPU tests' random
/// cases (rays, triangles, cones, boxes), the same stream on every machine.
#[cfg(test)]
pub(crate) fn xorshift(mut state: u64) -> impl FnMut() -> f32 {
    move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 40) as f32 / (1u64 << 24) as f32 * 2.0 - 1.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::frame::{RenderOptions, globals};
    use crate::pack::pack;
    use crate::scene::nff;

    /// A pass cancelled half way leaves the accumulator as it was, whether it held earlier
    /// samples (restored from the copy) or none (zeroed), though tiles were traced in place.
    #[test]
    fn a_cancelled_pass_leaves_the_accumulator_as_it_was() {
        let src = b"v from 0 -5 1 at 0 0 0 up 0 0 1 angle 40 resolution 64 48
            l 1 -2 3  f 1 0.5 0.2 0.8 0.2 10 0 1  s 0 0 0 1";
        let scene = nff::parse(src, "t.nff", std::path::Path::new(".")).unwrap();
        let b = pack(scene.clone()).unwrap();
        let opts = RenderOptions {
            spp: 3,
            ..RenderOptions::for_camera(&scene.camera)
        };
        let g = globals(&b, &opts);
        let never = AtomicBool::new(false);
        // Cancelled once the first tile is done: the others are skipped or finish.
        let cancel_after_one = |start: u32, accum: &mut Accumulator| {
            let cancel = AtomicBool::new(false);
            let stop = |_| cancel.store(true, Ordering::Relaxed);
            render_rows(&b, &g, 0..48, start..start + 1, accum, &stop, &cancel)
        };
        let mut fresh = Accumulator::new(64, 48);
        assert!(matches!(
            cancel_after_one(0, &mut fresh),
            Err(Error::Interrupted)
        ));
        assert_eq!(fresh, Accumulator::new(64, 48));

        let mut accum = Accumulator::new(64, 48);
        render_rows(&b, &g, 0..48, 0..1, &mut accum, &|_| {}, &never).unwrap();
        let before = accum.clone();
        assert!(before.sums.pixels.iter().any(|p| *p != [0.0; 3]));
        assert!(matches!(
            cancel_after_one(1, &mut accum),
            Err(Error::Interrupted)
        ));
        assert_eq!(accum, before);
        // And the pass then runs as if never tried: the one-step image to the bit.
        render_rows(&b, &g, 0..48, 1..3, &mut accum, &|_| {}, &never).unwrap();
        let (whole, _) = render(&b, &g, &|_| {}, &never).unwrap();
        assert_eq!(accum.into_film(), whole);
    }
}
