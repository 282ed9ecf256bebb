//! Comparing two 8-bit images (a GPU render against the CPU reference, or any two files):
//! difference statistics, FLIP, the heat map, and the acceptance thresholds.

pub mod agreement;

use image::RgbImage;

use crate::{Error, Result};

/// How two 8-bit images differ. A is the reference (the CPU render), B the test (the GPU
/// render). Channel differences are in 1/255 units, i.e. 1.0 is one 8-bit level.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DiffStats {
    pub width: u32,
    pub height: u32,
    /// Largest |B - A| over all channels of all pixels, in 1/255 units (0..=255).
    pub max_abs: f32,
    /// Mean |B - A| over all channels, in 1/255 units.
    pub mean_abs: f64,
    /// Mean (B - A) over all channels, in 1/255 units: a systematic brightness bias.
    pub mean_signed: f64,
    /// Peak signal-to-noise ratio with peak 255; `f64::INFINITY` when identical.
    pub psnr_db: f64,
    /// The tolerance `pixels_over` and `frac_over` were counted with, in 1/255 units.
    pub tolerance_255: u8,
    /// Pixels whose largest channel |B - A| exceeds `tolerance_255`.
    pub pixels_over: u64,
    /// `pixels_over` as a fraction of all pixels.
    pub frac_over: f64,
    /// NVIDIA FLIP mean error (0 = identical, 1 = maximal), at FLIP's default 67 pixels
    /// per degree. FLIP assumes sRGB-encoded input; our files store linear values with no
    /// curve, which is also how a viewer displays them, so FLIP judges what a person sees.
    pub flip_mean: f64,
}

impl std::fmt::Display for DiffStats {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{}x{}: max |diff| {}/255, mean |diff| {:.3}/255, mean signed {:+.3}/255, \
             PSNR {:.2} dB, {} pixels ({:.3}%) over {}/255, FLIP mean {:.4}",
            self.width,
            self.height,
            self.max_abs,
            self.mean_abs,
            self.mean_signed,
            self.psnr_db,
            self.pixels_over,
            self.frac_over * 100.0,
            self.tolerance_255,
            self.flip_mean
        )
    }
}

fn check_same_size(a: &RgbImage, b: &RgbImage) -> Result<()> {
    if a.dimensions() != b.dimensions() {
        return Err(Error::Image(format!(
            "image sizes differ: {}x{} vs {}x{}",
            a.width(),
            a.height(),
            b.width(),
            b.height()
        )));
    }
    if a.width() == 0 || a.height() == 0 {
        return Err(Error::Image("cannot compare empty images".to_string()));
    }
    Ok(())
}

/// Compares reference `a` with test `b`; pixels differing by more than `tolerance_255`
/// (in 1/255 units, in any channel) count towards `frac_over`. Sizes must match and be
/// non-empty.
pub fn diff(a: &RgbImage, b: &RgbImage, tolerance_255: u8) -> Result<DiffStats> {
    check_same_size(a, b)?;
    let (mut max_abs, mut sum_abs, mut sum_signed, mut sum_sq) = (0u8, 0u64, 0i64, 0u64);
    let mut pixels_over = 0u64;
    for (pa, pb) in a.pixels().zip(b.pixels()) {
        let mut pixel_max = 0u8;
        for (&ca, &cb) in pa.0.iter().zip(&pb.0) {
            let d = i64::from(cb) - i64::from(ca);
            let abs = ca.abs_diff(cb);
            pixel_max = pixel_max.max(abs);
            sum_abs += u64::from(abs);
            sum_signed += d;
            sum_sq += (d * d) as u64;
        }
        max_abs = max_abs.max(pixel_max);
        pixels_over += u64::from(pixel_max > tolerance_255);
    }
    let pixels = u64::from(a.width()) * u64::from(a.height());
    let samples = (pixels * 3) as f64;
    let mse = sum_sq as f64 / samples;
    let psnr_db = if sum_sq == 0 {
        f64::INFINITY
    } else {
        10.0 * (255.0 * 255.0 / mse).log10()
    };
    Ok(DiffStats {
        width: a.width(),
        height: a.height(),
        max_abs: f32::from(max_abs),
        mean_abs: sum_abs as f64 / samples,
        mean_signed: sum_signed as f64 / samples,
        psnr_db,
        tolerance_255,
        pixels_over,
        frac_over: pixels_over as f64 / pixels as f64,
        // Equal images have a FLIP error of zero, and FLIP is the costly part of a diff.
        flip_mean: if sum_sq == 0 { 0.0 } else { flip_mean(a, b) },
    })
}

/// Rows beyond a band that FLIP is given on each side, so that every pixel of the band
/// gets the error it gets in the whole image: FLIP's filters reach 10 rows at its
/// default 67 pixels per degree (the colour filter ceil(3 sqrt(0.04 / 2 pi^2) 67), the
/// feature filter ceil(3 x 0.5 x 0.082 x 67) = 9), and clamp at the image's edges. (With
/// 9 the test below fails, with 10 it passes.)
const FLIP_MARGIN: u32 = 16;

/// Bytes of FLIP's working memory a band may take: FLIP holds about 80 bytes a pixel
/// while it runs (0.6 GB for a whole 3840x2160 image).
const FLIP_BAND_BYTES: u64 = 64 << 20;
const FLIP_BYTES_PER_PIXEL: u64 = 80;

/// The rows of each band FLIP runs on for images `width` pixels wide: what
/// `FLIP_BAND_BYTES` holds with the margins, at least 64 so that the margins stay a
/// small part (so a band of a 16384-wide image takes 126 MB).
fn flip_band_rows(width: u32) -> u32 {
    let rows = FLIP_BAND_BYTES / (FLIP_BYTES_PER_PIXEL * u64::from(width.max(1)));
    (rows as u32).saturating_sub(2 * FLIP_MARGIN).max(64)
}

/// FLIP's mean error over the image, computed in bands of `flip_band_rows` rows on all
/// cores: FLIP itself runs on one core and holds its working memory for the whole image
/// at once (20 GB at 16384x16384). Each band is given `FLIP_MARGIN` rows more on each
/// side, so that its pixels' errors are those of the whole image, bit for bit (tested);
/// the bands' sums are added in order, so the mean does not depend on the cores. The
/// sums are in f64: FLIP's own pool (`FlipPool::mean`) sums in f32, which at 7680x4320
/// read 0.00822 for a mean of 0.00838.
fn flip_mean(a: &RgbImage, b: &RgbImage) -> f64 {
    flip_mean_in_bands(a, b, flip_band_rows(a.width()))
}

/// `flip_mean` with bands of `rows` rows.
fn flip_mean_in_bands(a: &RgbImage, b: &RgbImage, rows: u32) -> f64 {
    use rayon::prelude::*;
    let (w, h) = a.dimensions();
    let bands: Vec<u32> = (0..h).step_by(rows as usize).collect();
    let sums: Vec<f64> = bands
        .par_iter()
        .map(|&y0| {
            let errors = flip_errors(a, b, y0, (y0 + rows).min(h));
            errors.iter().map(|&e| f64::from(e)).sum::<f64>()
        })
        .collect();
    sums.iter().sum::<f64>() / (f64::from(w) * f64::from(h))
}

/// FLIP's error at each pixel of rows `y0..y1`, from a band of `a` and `b` with
/// `FLIP_MARGIN` rows more on each side where the image has them.
fn flip_errors(a: &RgbImage, b: &RgbImage, y0: u32, y1: u32) -> Vec<f32> {
    let (w, h) = a.dimensions();
    let (top, bottom) = (y0.saturating_sub(FLIP_MARGIN), (y1 + FLIP_MARGIN).min(h));
    let row = w as usize * 3;
    let band = top as usize * row..bottom as usize * row;
    let reference = nv_flip::FlipImageRgb8::with_data(w, bottom - top, &a.as_raw()[band.clone()]);
    let test = nv_flip::FlipImageRgb8::with_data(w, bottom - top, &b.as_raw()[band]);
    let errors = nv_flip::flip(reference, test, nv_flip::DEFAULT_PIXELS_PER_DEGREE).to_vec();
    errors[(y0 - top) as usize * w as usize..(y1 - top) as usize * w as usize].to_vec()
}

/// How much a per-pixel difference is magnified in the heat map's third panel.
pub const HEAT_MAP_GAIN: u32 = 16;

/// A side-by-side picture for a person: `A | B | difference`, three panels of the image's
/// size in one row. The difference panel shows each pixel's largest channel |B - A|
/// multiplied by [`HEAT_MAP_GAIN`] on a black -> red -> yellow -> white ramp: one level of
/// difference is a faint red, about 16 levels full red, 32 yellow, 48 and more white. The
/// gain is high because the differences worth seeing between two renderers are a few levels.
/// Sizes must match and be non-empty.
pub fn heat_map(a: &RgbImage, b: &RgbImage) -> Result<RgbImage> {
    check_same_size(a, b)?;
    let (w, h) = a.dimensions();
    Ok(RgbImage::from_fn(w * 3, h, |x, y| match x / w {
        0 => *a.get_pixel(x, y),
        1 => *b.get_pixel(x - w, y),
        _ => {
            let (pa, pb) = (a.get_pixel(x - 2 * w, y).0, b.get_pixel(x - 2 * w, y).0);
            let d = (0..3).map(|c| pa[c].abs_diff(pb[c])).max().unwrap_or(0);
            image::Rgb(heat_ramp(d))
        }
    }))
}

/// The colour of a difference `d` in 1/255 units: `film::heat_ramp` after the gain, so
/// that 3 * 255 / `HEAT_MAP_GAIN` levels and more are white.
fn heat_ramp(d: u8) -> [u8; 3] {
    let v = (u32::from(d) * HEAT_MAP_GAIN) as f32 / (3.0 * 255.0);
    crate::film::heat_ramp(v).map(crate::film::quantize)
}

/// Acceptance limits for a [`DiffStats`]. A comparison passes when `frac_over <=
/// max_frac_over`, `flip_mean <= max_flip_mean` and `|mean_signed| <
/// max_abs_mean_signed_255`, with the stats counted at `tolerance_255`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Thresholds {
    /// Largest allowed fraction of pixels differing by more than `tolerance_255`.
    pub max_frac_over: f64,
    /// Largest allowed FLIP mean.
    pub max_flip_mean: f64,
    /// |mean signed difference| must stay below this, in 1/255 units.
    pub max_abs_mean_signed_255: f64,
    /// Per-channel tolerance, in 1/255 units, to pass to [`diff`].
    pub tolerance_255: u8,
}

impl Thresholds {
    /// The acceptance values for comparing a GPU render against the CPU reference: 99.5% of
    /// pixels within 2/255 in every channel, FLIP mean at most 0.01, and no overall
    /// brightness bias of 0.5/255 or more. What forces each value: the GPU's division,
    /// square root and normalisation may be a few ulps off (Vulkan allows it) and it may
    /// fuse multiply-adds, so rays that graze a silhouette can hit on one renderer and miss
    /// on the other; such pixels are few but can differ completely. On lavapipe the worst
    /// of the 190 comparisons in `tests/gpurt/gpu/agreement.rs` (every scene, 1 and 4 samples, each
    /// AOV) is 0.45% of pixels over 2/255 (p3d/balls_high at 4 samples, thousands of small
    /// mirror spheres), FLIP mean 0.0018 and mean signed difference 0.003/255. A bias or a
    /// moved feature, which is what a real bug looks like, fails by a wide margin (see the
    /// self-tests).
    pub const GPU_VS_CPU: Thresholds = Thresholds {
        max_frac_over: 0.005,
        max_flip_mean: 0.01,
        max_abs_mean_signed_255: 0.5,
        tolerance_255: 2,
    };

    /// How many times the reference's own noise floor a comparison may differ on.
    pub const NOISE_FACTOR: f64 = 2.0;

    /// `check`, with the pixel-count limit raised to `NOISE_FACTOR` times `noise_floor`
    /// where that is larger. `noise_floor` is the fraction of pixels over the tolerance
    /// between the reference and the reference re-rendered with its eye point moved by
    /// one ulp: the pixels whose value no float renderer can pin down (rays grazing
    /// sub-pixel mirror spheres, whose reflections go anywhere). A GPU that fuses
    /// multiply-adds moves every ray by about that much, so it may differ on those pixels
    /// and no others. The FLIP and bias limits stay as they are, and a moved feature
    /// still fails: it changes whole regions, far above any floor.
    pub fn check_with_noise_floor(
        &self,
        stats: &DiffStats,
        noise_floor: f64,
    ) -> std::result::Result<(), String> {
        Thresholds {
            max_frac_over: self.max_frac_over.max(Self::NOISE_FACTOR * noise_floor),
            ..*self
        }
        .check(stats)
    }

    /// `check`, and where that fails, `check_with_noise_floor` with the floor `floor`
    /// measures: measured only then, since it costs renders. Returns the floor when it was
    /// measured, and the verdict.
    pub fn check_allowing_noise<E>(
        &self,
        stats: &DiffStats,
        floor: impl FnOnce() -> std::result::Result<f64, E>,
    ) -> std::result::Result<(Option<f64>, std::result::Result<(), String>), E> {
        match self.check(stats) {
            Ok(()) => Ok((None, Ok(()))),
            Err(_) => {
                let floor = floor()?;
                Ok((Some(floor), self.check_with_noise_floor(stats, floor)))
            }
        }
    }

    /// `Ok` when `stats` is within every limit, otherwise one message naming every limit
    /// exceeded (separated by "; ").
    pub fn check(&self, stats: &DiffStats) -> std::result::Result<(), String> {
        let mut failures = Vec::new();
        if stats.tolerance_255 != self.tolerance_255 {
            failures.push(format!(
                "stats were counted at tolerance {}/255 but the limits need {}/255",
                stats.tolerance_255, self.tolerance_255
            ));
        }
        if stats.frac_over > self.max_frac_over {
            failures.push(format!(
                "{} pixels ({:.3}%) differ by more than {}/255 (limit {:.3}%)",
                stats.pixels_over,
                stats.frac_over * 100.0,
                stats.tolerance_255,
                self.max_frac_over * 100.0
            ));
        }
        if stats.flip_mean > self.max_flip_mean {
            failures.push(format!(
                "FLIP mean {:.4} exceeds {:.4}",
                stats.flip_mean, self.max_flip_mean
            ));
        }
        if stats.mean_signed.abs() >= self.max_abs_mean_signed_255 {
            failures.push(format!(
                "mean signed difference {:+.3}/255 (B - A) is not within ±{}/255",
                stats.mean_signed, self.max_abs_mean_signed_255
            ));
        }
        if failures.is_empty() {
            Ok(())
        } else {
            Err(failures.join("; "))
        }
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::film::tests::scratch_dir;
    use crate::film::{load_rgb8, save_rgb8};
    use std::fs;

    /// Gradients plus hashed noise, so any moved block shows up; channels stay in 0..=253
    /// so a +2 bias never saturates.
    pub(crate) fn textured(w: u32, h: u32) -> RgbImage {
        RgbImage::from_fn(w, h, |x, y| {
            let noise = (x.wrapping_mul(73_856_093) ^ y.wrapping_mul(19_349_663)) % 61;
            image::Rgb([
                ((x * 3 + noise) % 254) as u8,
                ((y * 3 + noise * 2) % 254) as u8,
                ((x + y + noise * 3) % 254) as u8,
            ])
        })
    }

    fn gpu_vs_cpu(a: &RgbImage, b: &RgbImage) -> (DiffStats, std::result::Result<(), String>) {
        let t = Thresholds::GPU_VS_CPU;
        let stats = diff(a, b, t.tolerance_255).unwrap();
        (stats, t.check(&stats))
    }

    #[test]
    fn identical_images_have_zero_stats_and_pass() {
        let a = textured(64, 48);
        let (stats, verdict) = gpu_vs_cpu(&a, &a.clone());
        assert_eq!((stats.width, stats.height), (64, 48));
        assert_eq!(stats.max_abs, 0.0);
        assert_eq!(stats.mean_abs, 0.0);
        assert_eq!(stats.mean_signed, 0.0);
        assert_eq!(stats.psnr_db, f64::INFINITY);
        assert_eq!(stats.pixels_over, 0);
        assert_eq!(stats.frac_over, 0.0);
        assert_eq!(stats.flip_mean, 0.0);
        assert_eq!(verdict, Ok(()));
        // `diff` skips FLIP on equal images; FLIP itself says the same of them.
        assert_eq!(flip_mean(&a, &a.clone()), 0.0);
    }

    /// FLIP in bands gives every pixel the error FLIP gives it in the whole image, bit for
    /// bit, whatever the bands' height (one row, a few, more than the image), on images
    /// of odd sizes with differences everywhere; the mean is the whole image's too. With
    /// too small a margin the pixels beside a band's edge would differ: a band given no
    /// margin does (the self-test of the comparison).
    #[test]
    fn flip_in_bands_is_flip_of_the_whole_image() {
        for (w, h) in [(37u32, 91u32), (130, 47)] {
            let a = textured(w, h);
            let b = RgbImage::from_fn(w, h, |x, y| {
                let p = a.get_pixel(x, y).0;
                let d = ((x * 7 + y * 13) % 9) as u8;
                image::Rgb([p[0].saturating_add(d), p[1], p[2].saturating_sub(d / 2)])
            });
            let whole = flip_errors(&a, &b, 0, h);
            assert!(whole.iter().any(|&e| e > 0.0));
            for rows in [1, 5, 33, h + 10] {
                let banded: Vec<f32> = (0..h)
                    .step_by(rows as usize)
                    .flat_map(|y0| flip_errors(&a, &b, y0, (y0 + rows).min(h)))
                    .collect();
                assert!(
                    banded
                        .iter()
                        .zip(&whole)
                        .all(|(x, y)| x.to_bits() == y.to_bits()),
                    "{w}x{h} in bands of {rows}"
                );
                let whole_mean =
                    whole.iter().map(|&e| f64::from(e)).sum::<f64>() / f64::from(w * h);
                assert!((flip_mean_in_bands(&a, &b, rows) - whole_mean).abs() < 1e-12);
            }
            // A band of the middle rows given alone, without the rows around it.
            let (y0, y1) = (h / 3, 2 * h / 3);
            let band =
                |img: &RgbImage| RgbImage::from_fn(w, y1 - y0, |x, y| *img.get_pixel(x, y + y0));
            let alone = flip_errors(&band(&a), &band(&b), 0, y1 - y0);
            let inside = &whole[(y0 * w) as usize..(y1 * w) as usize];
            assert!(
                alone
                    .iter()
                    .zip(inside)
                    .any(|(x, y)| x.to_bits() != y.to_bits())
            );
        }
    }

    #[test]
    fn known_differences_are_measured() {
        let a = RgbImage::from_pixel(4, 4, image::Rgb([100, 100, 100]));
        let mut b = a.clone();
        b.put_pixel(0, 0, image::Rgb([110, 100, 97])); // over a 2/255 tolerance
        b.put_pixel(1, 0, image::Rgb([102, 100, 100])); // exactly at it: not over
        let stats = diff(&a, &b, 2).unwrap();
        assert_eq!(stats.max_abs, 10.0);
        assert!((stats.mean_abs - 15.0 / 48.0).abs() < 1e-12);
        assert!((stats.mean_signed - 9.0 / 48.0).abs() < 1e-12);
        let mse: f64 = (100.0 + 9.0 + 4.0) / 48.0;
        assert!((stats.psnr_db - 10.0 * (65025.0 / mse).log10()).abs() < 1e-9);
        assert_eq!(stats.pixels_over, 1);
        assert_eq!(stats.frac_over, 1.0 / 16.0);
        assert!(stats.flip_mean > 0.0);
    }

    #[test]
    fn shifted_block_fails_gpu_vs_cpu() {
        let a = textured(64, 64);
        let mut b = a.clone();
        // Copy a 16x16 block 4 pixels right and 3 down, as a misplaced object would.
        for y in 20..36 {
            for x in 20..36 {
                b.put_pixel(x + 4, y + 3, *a.get_pixel(x, y));
            }
        }
        let (stats, verdict) = gpu_vs_cpu(&a, &b);
        let msg = verdict.expect_err("a moved block must fail");
        assert!(stats.frac_over > 0.005, "{stats}");
        assert!(msg.contains("differ by more than 2/255"), "{msg}");
    }

    #[test]
    fn uniform_bias_fails_gpu_vs_cpu_on_mean_signed() {
        let a = textured(64, 64);
        let mut b = a.clone();
        for p in b.pixels_mut() {
            p.0 = p.0.map(|c| c + 2);
        }
        let (stats, verdict) = gpu_vs_cpu(&a, &b);
        assert_eq!(stats.mean_signed, 2.0);
        // Each channel is within the 2/255 tolerance, so only the bias check can catch it.
        assert_eq!(stats.pixels_over, 0);
        let msg = verdict.expect_err("a +2/255 bias must fail");
        assert!(msg.contains("mean signed difference +2.000/255"), "{msg}");
    }

    #[test]
    fn single_pixel_change_passes_gpu_vs_cpu() {
        let a = textured(64, 64);
        let mut b = a.clone();
        b.put_pixel(30, 30, image::Rgb([255, 255, 255]));
        let (stats, verdict) = gpu_vs_cpu(&a, &b);
        assert_eq!(stats.pixels_over, 1);
        assert_eq!(verdict, Ok(()), "{stats}");
    }

    #[test]
    fn check_reports_every_exceeded_limit() {
        let stats = DiffStats {
            width: 10,
            height: 10,
            max_abs: 50.0,
            mean_abs: 5.0,
            mean_signed: -1.0,
            psnr_db: 20.0,
            tolerance_255: 2,
            pixels_over: 10,
            frac_over: 0.1,
            flip_mean: 0.2,
        };
        let msg = Thresholds::GPU_VS_CPU.check(&stats).unwrap_err();
        assert_eq!(msg.split("; ").count(), 3, "{msg}");
        assert!(msg.contains("FLIP mean 0.2000"), "{msg}");
        let wrong_tolerance = DiffStats {
            tolerance_255: 5,
            pixels_over: 0,
            frac_over: 0.0,
            flip_mean: 0.0,
            mean_signed: 0.0,
            ..stats
        };
        let msg = Thresholds::GPU_VS_CPU.check(&wrong_tolerance).unwrap_err();
        assert!(msg.contains("tolerance 5/255"), "{msg}");
    }

    #[test]
    fn size_mismatch_and_empty_images_are_errors() {
        let a = textured(8, 8);
        let b = textured(8, 9);
        assert!(
            diff(&a, &b, 2)
                .unwrap_err()
                .to_string()
                .contains("8x8 vs 8x9")
        );
        assert!(heat_map(&a, &b).is_err());
        let empty = RgbImage::new(0, 0);
        assert!(diff(&empty, &empty, 2).is_err());
    }

    #[test]
    fn heat_map_shows_a_b_and_magnified_difference() {
        let a = RgbImage::from_pixel(8, 4, image::Rgb([100, 100, 100]));
        let mut b = a.clone();
        b.put_pixel(1, 1, image::Rgb([101, 100, 100]));
        b.put_pixel(2, 1, image::Rgb([100, 98, 100]));
        b.put_pixel(3, 1, image::Rgb([0, 0, 0]));
        let map = heat_map(&a, &b).unwrap();
        assert_eq!(map.dimensions(), (24, 4));
        assert_eq!(map.get_pixel(5, 2), a.get_pixel(5, 2));
        assert_eq!(map.get_pixel(8 + 1, 1), b.get_pixel(1, 1));
        assert_eq!(map.get_pixel(16, 0).0, [0, 0, 0]);
        assert_eq!(map.get_pixel(16 + 1, 1).0, [16, 0, 0]);
        assert_eq!(map.get_pixel(16 + 2, 1).0, [32, 0, 0]);
        assert_eq!(map.get_pixel(16 + 3, 1).0, [255, 255, 255]);
        assert_eq!(heat_ramp(15), [240, 0, 0]);
        assert_eq!(heat_ramp(16), [255, 1, 0]);
        assert_eq!(heat_ramp(24), [255, 129, 0]);
        assert_eq!(heat_ramp(32), [255, 255, 2]);
        assert_eq!(heat_ramp(255), [255, 255, 255]);
    }

    #[test]
    fn save_rgb8_writes_heat_maps() {
        let dir = scratch_dir("saveheat");
        let a = textured(8, 8);
        let map = heat_map(&a, &a).unwrap();
        let path = dir.join("heat.png");
        save_rgb8(&map, &path).unwrap();
        assert_eq!(load_rgb8(&path).unwrap(), map);
        fs::remove_dir_all(&dir).unwrap();
    }
}
