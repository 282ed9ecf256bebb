//! How a frame is cut into GPU work: tiles (one bounded dispatch each, in passes of
//! samples), bands of full-width rows (one readback each), and a band's samples in
//! submissions of bounded work; and the time a dispatch may take (`DISPATCH_BUDGET`),
//! past which the cut is made finer.

use std::ops::Range;
use std::time::Duration;

use crate::gpu_types::{GpuTile, WORKGROUP_SIDE};

/// Bytes per traced pixel: `PixelOut` (rgb + ray count).
pub(super) const PIXEL_BYTES: u64 = 16;

/// Largest output buffer a band of rows writes on a software adapter: far below the 128
/// MiB storage binding of lavapipe, large enough that a 4K frame at one sample takes two
/// submissions. (GPUs take larger bands: `Shape::band_bytes`.)
pub(super) const BAND_BYTES: u64 = 64 << 20;

/// Time one dispatch may take on a GPU, an eighth of the shortest common driver watchdog
/// (Windows' two seconds): the mean dispatch of a band is what is measured, and one tile
/// may take several times the mean. A band whose dispatches took longer on average makes
/// the rest of the frame, and the frames after it, cut finer (`Cut::finer`), to half the
/// budget.
pub const DISPATCH_BUDGET: Duration = Duration::from_millis(250);

/// How much work one dispatch and one submission take on an adapter
/// (`policy::shape_for`); with the frame's size and the device's limits it makes a `Cut`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Shape {
    /// Samples of a pixel one dispatch traces at most.
    pub(super) pass_samples: u32,
    /// Pixel samples one dispatch traces at most (its tile's pixels times its pass's
    /// samples): sets the tile's side.
    pub(super) dispatch_samples: u64,
    /// Pixel samples one submission traces at most.
    pub(super) band_samples: u64,
    /// Pixels a side of a wavefront frame's waves at most, and the bytes a wave's
    /// records may take (`policy::cut_for`).
    pub(super) wave_side: u32,
    pub(super) wave_bytes: u64,
    /// Whether each dispatch scatters its workgroups over its tile (`scatter`): for
    /// drivers that split a dispatch's workgroups into one contiguous run per thread.
    pub(super) spread: bool,
    /// Whether a tile is a strip as wide as the frame (else a square): the fewest
    /// dispatches for the work each may take, all of one size but the last.
    pub(super) strips: bool,
    /// Bytes of output a band holds at most (the device's storage binding limit may hold
    /// it to less).
    pub(super) band_bytes: u64,
    /// Pixels a side of the square a workgroup of `pooled` traces (`POOL_SIDE`).
    pub(super) pool_side: u32,
}

/// How a frame is cut into work. Each tile is traced in passes of `pass_samples` samples
/// per pixel, one dispatch each, whose work is bounded by the tile's size and the pass's
/// samples (so that no dispatch runs long enough to trip a driver watchdog, and no
/// invocation runs into lavapipe's loop limit for want of splitting); each band of
/// full-width rows has one readback, its output fitting `BAND_BYTES`, and is submitted
/// in runs of `submit_samples` samples, so that one submission's work fits
/// `band_samples` (the host checks for Ctrl-C and reports progress between them).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Cut {
    pub(super) width: u32,
    pub(super) height: u32,
    pub(super) spp: u32,
    pub(super) pass_samples: u32,
    /// A tile's pixels across (the frame's width for strips) and rows.
    pub(super) tile_width: u32,
    pub(super) tile_rows: u32,
    pub(super) band_rows: u32,
    /// Samples of a band's pixels one submission traces: a multiple of `pass_samples`.
    pub(super) submit_samples: u32,
    /// Whether each dispatch scatters its workgroups over its tile (`Shape::spread`).
    pub(super) spread: bool,
    /// Pixels a side of the square one workgroup traces (`GpuTile::group_side`).
    pub(super) group_side: u32,
}

impl Cut {
    pub(super) fn new(width: u32, height: u32, spp: u32, shape: &Shape, max_bytes: u64) -> Cut {
        let pass_samples = shape.pass_samples.clamp(1, spp.max(1));
        let band_bytes = max_bytes.min(shape.band_bytes);
        let (tile_width, tile_rows) = if shape.strips {
            (
                width.max(1),
                strip_rows(width, height, pass_samples, shape, band_bytes),
            )
        } else {
            let side = tile_side(width, pass_samples, shape, band_bytes);
            (side, side)
        };
        let band_samples = shape.band_samples;
        let row_bytes = u64::from(width) * PIXEL_BYTES;
        let row_samples = u64::from(width) * u64::from(spp);
        let rows = (band_bytes / row_bytes).min(band_samples / row_samples);
        // At least one row of tiles; whole rows of tiles, so only the last band is short;
        // no more rows than the frame has.
        let band_rows = (rows as u32 / tile_rows)
            .max(1)
            .saturating_mul(tile_rows)
            .min(height.max(1));
        // Where even one row of tiles holds more samples than a submission should, the
        // band's samples are submitted a run of passes at a time (at least one pass).
        let pass_work = u64::from(width) * u64::from(band_rows) * u64::from(pass_samples);
        let passes = (band_samples / pass_work.max(1)).clamp(1, u64::from(spp)) as u32;
        Cut {
            width,
            height,
            spp,
            pass_samples,
            tile_width,
            tile_rows,
            band_rows,
            submit_samples: passes.saturating_mul(pass_samples).min(spp.max(1)),
            spread: shape.spread && !shape.strips && tile_width <= MAX_SPREAD_SIDE,
            group_side: WORKGROUP_SIDE,
        }
    }

    /// A cut of the same frame and bands whose dispatches each do at most `1 / factor` of
    /// this one's work (pixels x samples of a pass): fewer samples a pass first, down to
    /// one, then tiles of half the side (a strip, half the rows until it is one workgroup
    /// high, then half the width), down to `MIN_TILE_SIDE`, as far as needed or possible.
    /// A band then holds more dispatches than before (`tiles` lists them all, a band's
    /// last row of tiles cut to its rows). The image does not change: each pass adds to
    /// the sums in sample order.
    pub(super) fn finer(&self, factor: f64) -> Cut {
        let mut cut = *self;
        let work =
            |c: &Cut| f64::from(c.tile_width) * f64::from(c.tile_rows) * f64::from(c.pass_samples);
        let goal = work(self) / factor.max(1.0);
        let half = |n: u32| (n / 2).next_multiple_of(MIN_TILE_SIDE).max(MIN_TILE_SIDE);
        while work(&cut) > goal {
            if cut.pass_samples > 1 {
                cut.pass_samples = cut.pass_samples.div_ceil(2);
            } else if cut.tile_rows > MIN_TILE_SIDE {
                // A square's sides halve together.
                let square = cut.tile_rows == cut.tile_width;
                cut.tile_rows = half(cut.tile_rows);
                if square {
                    cut.tile_width = cut.tile_rows;
                }
            } else if cut.tile_width > MIN_TILE_SIDE {
                cut.tile_width = half(cut.tile_width);
            } else {
                break;
            }
        }
        cut
    }

    /// Dispatches per submission: each tile of a band once per pass of the submission.
    pub(super) fn dispatches_per_submission(&self) -> u32 {
        self.width.div_ceil(self.tile_width)
            * self.band_rows.div_ceil(self.tile_rows)
            * self.submit_samples.div_ceil(self.pass_samples)
    }

    /// The samples of `samples` each submission of a band traces, in order.
    pub(super) fn submissions(
        &self,
        samples: &Range<u32>,
    ) -> impl Iterator<Item = Range<u32>> + use<> {
        let (end, step) = (samples.end, self.submit_samples.max(1));
        (samples.start..end)
            .step_by(step as usize)
            .map(move |s| s..s.saturating_add(step).min(end))
    }

    pub(super) fn band_bytes(&self) -> u64 {
        u64::from(self.width) * u64::from(self.band_rows) * PIXEL_BYTES
    }

    /// The first row of each band and its number of rows.
    pub(super) fn bands(&self) -> impl Iterator<Item = (u32, u32)> + use<> {
        let (h, n) = (self.height, self.band_rows);
        (0..h).step_by(n as usize).map(move |y| (y, n.min(h - y)))
    }

    /// The dispatches of the band starting at row `y0` for `samples`: every tile for the
    /// first pass's samples, then every tile for the next pass's, and so on.
    pub(super) fn tiles(&self, y0: u32, rows: u32, samples: &Range<u32>) -> Vec<GpuTile> {
        let (w, across, down) = (self.width, self.tile_width, self.tile_rows);
        let mut tiles = Vec::new();
        for sample_start in samples.clone().step_by(self.pass_samples as usize) {
            for y in (y0..y0 + rows).step_by(down as usize) {
                for x in (0..w).step_by(across as usize) {
                    let mut tile = GpuTile {
                        x,
                        y,
                        width: across.min(w - x),
                        height: down.min(y0 + rows - y),
                        out_base: (y - y0) * w + x,
                        out_stride: w,
                        sample_start,
                        sample_count: self.pass_samples.min(samples.end - sample_start),
                        scatter: 1,
                        group_side: self.group_side,
                    };
                    if self.spread {
                        let [gx, gy] = tile.workgroups();
                        tile.scatter = scatter(gx * gy);
                    }
                    tiles.push(tile);
                }
            }
        }
        tiles
    }
}

/// A stride coprime with `n` near `n` over the golden ratio: workgroup `i` of a dispatch
/// of `n` traces block `i * stride mod n` of its tile, a permutation that spreads any run
/// of consecutive workgroups evenly over the tile.
///
/// Lavapipe hands each of its threads one contiguous run of a dispatch's workgroups,
/// fixed in advance, and the dispatch ends when the slowest run ends. Unscattered, one
/// thread gets the top of the tile and another the bottom, whose costs differ as much as
/// sky and scene: at 512x512 on two threads the threads were busy 1.3 of 2 cores' time.
/// Scattered, every run samples the whole tile, so the runs cost about the same.
pub(super) fn scatter(n: u32) -> u32 {
    let gcd = |mut a: u32, mut b: u32| {
        while b != 0 {
            (a, b) = (b, a % b);
        }
        a
    };
    let start = ((f64::from(n) * 0.618_033_988_75).round() as u32).max(1);
    (start..n).find(|&s| gcd(s, n) == 1).unwrap_or(1)
}

/// The smallest tile `Cut::finer` makes: one workgroup.
pub(super) const MIN_TILE_SIDE: u32 = crate::gpu_types::WORKGROUP_SIDE;

/// The largest tile a dispatch takes: 256x256 workgroups.
pub(super) const MAX_TILE_SIDE: u32 = 2048;

/// The largest tile whose dispatch scatters its workgroups (a larger one, where the
/// environment asks for it, is traced unscattered): `scatter`'s products stay within the
/// shader's u32 (`scatter_permutes_and_spreads_the_workgroups`).
const MAX_SPREAD_SIDE: u32 = 256;

/// A strip's rows for a frame `width` pixels wide and `height` high: the most, in whole
/// workgroups, whose pass of `pass_samples` traces at most `shape.dispatch_samples`
/// pixel samples and whose output fits `band_bytes`; at least one workgroup, at most the
/// frame's height (and what a dispatch can count in workgroups).
fn strip_rows(width: u32, height: u32, pass_samples: u32, shape: &Shape, band_bytes: u64) -> u32 {
    let row_samples = u64::from(width.max(1)) * u64::from(pass_samples);
    let row_bytes = u64::from(width.max(1)) * PIXEL_BYTES;
    let rows = (shape.dispatch_samples / row_samples).min(band_bytes / row_bytes);
    let most = u64::from(height.max(1)).min(u64::from(u16::MAX) * u64::from(MIN_TILE_SIDE));
    (rows.min(most) as u32 / MIN_TILE_SIDE * MIN_TILE_SIDE).max(MIN_TILE_SIDE)
}

/// A square tile's side: the largest power of two, at most `MAX_TILE_SIDE`, whose pass of
/// `pass_samples` traces at most `shape.dispatch_samples` pixel samples and whose row of
/// tiles, `width` pixels wide, fits `band_bytes` (a band is at least one row of tiles);
/// at least one workgroup.
fn tile_side(width: u32, pass_samples: u32, shape: &Shape, band_bytes: u64) -> u32 {
    let fits = |side: u32| {
        u64::from(side).pow(2) * u64::from(pass_samples) <= shape.dispatch_samples
            && u64::from(width) * u64::from(side) * PIXEL_BYTES <= band_bytes
    };
    let mut side = MAX_TILE_SIDE;
    while side > MIN_TILE_SIDE && !fits(side) {
        side /= 2;
    }
    side
}

#[cfg(test)]
mod tests {
    use super::*;

    fn shape(pass_samples: u32, dispatch_samples: u64, band_samples: u64) -> Shape {
        Shape {
            pass_samples,
            dispatch_samples,
            band_samples,
            wave_side: 128,
            wave_bytes: 512 << 20,
            spread: false,
            strips: false,
            band_bytes: BAND_BYTES,
            pool_side: crate::gpu_types::POOL_SIDE,
        }
    }

    /// Every pixel of every band exactly once per sample, in pass order.
    fn coverage(cut: &Cut) -> Vec<u32> {
        let mut seen = vec![0u32; (cut.width * cut.height) as usize];
        for (y0, rows) in cut.bands() {
            let mut last_start = 0;
            for t in cut.tiles(y0, rows, &(0..cut.spp)) {
                assert!(t.sample_start >= last_start, "passes out of order");
                last_start = t.sample_start;
                for y in t.y..t.y + t.height {
                    for x in t.x..t.x + t.width {
                        seen[(y * cut.width + x) as usize] += t.sample_count;
                    }
                }
            }
        }
        seen
    }

    #[test]
    fn a_finer_cut_divides_the_work_and_covers_the_same_samples() {
        let cut = Cut::new(1000, 333, 40, &shape(16, 1 << 18, 1 << 26), 1 << 30);
        assert_eq!((cut.tile_rows, cut.pass_samples), (128, 16));
        let finer = cut.finer(100.0);
        // 16 -> 1 sample a pass (16x), then 128 -> 32 pixels a side (16x more).
        assert_eq!((finer.tile_rows, finer.pass_samples), (32, 1));
        assert_eq!(finer.band_rows, cut.band_rows);
        assert!(coverage(&finer).iter().all(|&n| n == 40));
        assert_eq!(cut.finer(1.0), cut);
        assert_eq!(cut.finer(0.1), cut);
        // No finer than one sample on one workgroup.
        let finest = cut.finer(1e9);
        assert_eq!((finest.tile_rows, finest.pass_samples), (MIN_TILE_SIDE, 1));
        assert!(coverage(&finest).iter().all(|&n| n == 40));
    }

    /// A band of 16384 pixels a row at 4096 samples is submitted a pass at a time (the
    /// least a submission holds), a lighter one a few passes at a time within the work
    /// it was given, and the runs cover the samples once.
    #[test]
    fn a_band_too_heavy_for_one_submission_is_submitted_in_runs_of_passes() {
        let cut = Cut::new(16384, 16384, 4096, &shape(1, 1 << 16, 1 << 18), 1 << 27);
        assert_eq!((cut.tile_rows, cut.band_rows), (256, 256));
        assert_eq!(
            cut.submit_samples, 1,
            "one pass of the band is 16x a submission's work"
        );
        let cut = Cut::new(512, 512, 4096, &shape(1, 1 << 16, 1 << 26), 1 << 27);
        assert_eq!((cut.tile_rows, cut.band_rows), (256, 256));
        let work = 512 * 256 * u64::from(cut.submit_samples);
        assert!(
            work <= 1 << 26 && 2 * work > 1 << 26,
            "{} samples a submission",
            cut.submit_samples
        );
        assert_eq!(cut.dispatches_per_submission(), 2 * cut.submit_samples);
        let runs: Vec<_> = cut.submissions(&(5..4096)).collect();
        assert_eq!(runs.first().unwrap().start, 5);
        assert!(runs.windows(2).all(|w| w[0].end == w[1].start));
        assert_eq!(runs.last().unwrap().end, 4096);
        // A light frame is one submission a band, as before.
        let light = Cut::new(512, 512, 1, &shape(1, 1 << 16, 1 << 18), 1 << 27);
        assert_eq!(light.submissions(&(0..1)).count(), 1);
        assert_eq!(light.band_rows, 512);
    }

    /// A GPU's tiles grow to the work a dispatch may take, as far as a row of them fits a
    /// band's bytes, and still cover every sample once; a scattered tile is at most
    /// `MAX_SPREAD_SIDE` a side.
    #[test]
    fn tiles_grow_to_the_dispatch_work_within_a_band() {
        let gpu = shape(4, 1 << 22, 1 << 26);
        let hd = Cut::new(1920, 1080, 1, &gpu, 1 << 32);
        assert_eq!(
            (hd.tile_rows, hd.band_rows, hd.pass_samples),
            (2048, 1080, 1)
        );
        assert_eq!(hd.dispatches_per_submission(), 1);
        // At 4K a row of 2048-pixel tiles is 126 MB, over BAND_BYTES.
        let uhd = Cut::new(3840, 2160, 16, &gpu, 1 << 32);
        assert_eq!((uhd.tile_rows, uhd.pass_samples), (1024, 4));
        assert!(uhd.band_bytes() <= BAND_BYTES);
        assert!(coverage(&uhd).iter().all(|&n| n == 16));
        // A small device limit shrinks the tiles with the band.
        let small = Cut::new(3840, 2160, 16, &gpu, 1 << 24);
        assert_eq!(small.tile_rows, 256);
        assert!(small.band_bytes() <= 1 << 24);
        let mut spread = gpu;
        spread.spread = true;
        assert!(!Cut::new(3840, 2160, 1, &spread, 1 << 32).spread);
        let lavapipe = Cut::new(3840, 2160, 1, &shape(1, 1 << 16, 1 << 18), 1 << 32);
        assert_eq!(lavapipe.tile_rows, 256);
        let mut lavapipe = shape(1, 1 << 16, 1 << 18);
        lavapipe.spread = true;
        assert!(Cut::new(3840, 2160, 1, &lavapipe, 1 << 32).spread);
    }

    /// A GPU's strips are as wide as the frame and as high as the work a dispatch may
    /// take allows, in whole workgroups: a 4K frame at one sample is one band of two
    /// dispatches, at 16 samples (4 a pass) eight strips a pass; every sample is covered
    /// once, after a finer cut too (fewer rows, then a narrower tile).
    #[test]
    fn strips_span_the_frame_in_the_fewest_dispatches() {
        let gpu = Shape {
            strips: true,
            band_bytes: 256 << 20,
            ..shape(4, 1 << 22, 1 << 26)
        };
        let uhd = Cut::new(3840, 2160, 1, &gpu, 1 << 32);
        assert_eq!(
            (uhd.tile_width, uhd.tile_rows, uhd.band_rows),
            (3840, 1088, 2160)
        );
        assert_eq!(uhd.dispatches_per_submission(), 2);
        assert!(coverage(&uhd).iter().all(|&n| n == 1));
        let many = Cut::new(3840, 2160, 16, &gpu, 1 << 32);
        assert_eq!((many.tile_rows, many.pass_samples), (272, 4));
        assert!(many.tile_rows.is_multiple_of(MIN_TILE_SIDE));
        assert!(many.band_rows.is_multiple_of(many.tile_rows));
        assert!(coverage(&many).iter().all(|&n| n == 16));
        // A frame lower than a strip is one strip; the device's limit holds the band.
        let low = Cut::new(1000, 3, 1, &gpu, 1 << 32);
        assert_eq!((low.tile_width, low.tile_rows, low.band_rows), (1000, 8, 3));
        let held = Cut::new(3840, 2160, 1, &gpu, 1 << 24);
        assert!(held.band_bytes() <= 1 << 24 && held.tile_rows == 272);
        assert!(coverage(&held).iter().all(|&n| n == 1));
        let finer = many.finer(8.0);
        assert_eq!(
            (finer.tile_width, finer.tile_rows, finer.pass_samples),
            (3840, 136, 1)
        );
        assert!(coverage(&finer).iter().all(|&n| n == 16));
        let finest = many.finer(1e9);
        assert_eq!(
            (finest.tile_width, finest.tile_rows),
            (MIN_TILE_SIDE, MIN_TILE_SIDE)
        );
        assert!(coverage(&finest).iter().all(|&n| n == 16));
    }

    /// Every scatter is a permutation of the dispatch's workgroups, and the first half of
    /// them (one thread's run, on two threads) reaches both halves of the tile.
    #[test]
    fn scatter_permutes_and_spreads_the_workgroups() {
        for n in 1..=4096u32 {
            let s = scatter(n);
            let mut seen = vec![false; n as usize];
            for i in 0..n {
                let j = (u64::from(i) * u64::from(s) % u64::from(n)) as usize;
                assert!(!seen[j], "n = {n}: stride {s} repeats block {j}");
                seen[j] = true;
            }
            if n >= 16 {
                let low = (0..n / 2).filter(|&i| i * s % n < n / 2).count() as f64;
                let share = low / f64::from(n / 2);
                assert!(
                    (0.3..0.7).contains(&share),
                    "n = {n}: first half {share} in the top half"
                );
            }
        }
        // Within u32: the largest scattered tile's dispatch, by its stride.
        let n = (MAX_SPREAD_SIDE / crate::gpu_types::WORKGROUP_SIDE).pow(2);
        assert!(u64::from(n) * u64::from(scatter(n)) < u64::from(u32::MAX));
    }
}
