//! Images: the linear-RGB film both renderers write into, its encoders (saved through
//! `atomic`), and loading images back. Comparing two images is `compare`'s.
//!
//! Colour handling follows the shading spec: pixels are linear RGB; 8-bit formats (PNG, PPM,
//! BMP) clamp to [0, 1] and round to the nearest of 256 levels; EXR keeps the unclamped
//! linear floats. There is no gamma curve anywhere.

mod encode;

use std::path::Path;

#[cfg(feature = "native")]
use rayon::prelude::*;

pub use encode::Format;

use image::{ColorType, DynamicImage, ImageDecoder, ImageFormat, RgbImage};

use crate::gpu_types::{AOV_COST, AOV_DEPTH};
use crate::util::limits::MAX_IMAGE_SIDE;
use crate::{Error, Result};

/// A rendered image: linear RGB, row-major, top row first.
///
/// Invariant: `pixels.len() == width * height`.
#[derive(Debug, Clone, PartialEq)]
pub struct Film {
    pub width: u32,
    pub height: u32,
    pub pixels: Vec<[f32; 3]>,
}

impl Film {
    /// A black film. Its zeros are the allocator's: the kernel maps a page only when it is
    /// first touched, so a huge film holds memory only as rows are traced. A page first
    /// read, though, is mapped to the kernel's shared zero page, and the write after it
    /// copies that page and flushes the TLB of every thread of the process: the renderers
    /// write the sums of a pass that starts at sample 0 instead of adding them
    /// (`Accumulator::holds_nothing`).
    pub fn new(width: u32, height: u32) -> Self {
        Film {
            width,
            height,
            pixels: vec![[0.0; 3]; width as usize * height as usize],
        }
    }

    fn index(&self, x: u32, y: u32) -> usize {
        assert!(
            x < self.width && y < self.height,
            "pixel ({x}, {y}) outside {}x{} film",
            self.width,
            self.height
        );
        y as usize * self.width as usize + x as usize
    }

    /// The pixel at column `x`, row `y` (row 0 is the top). Panics when out of range.
    pub fn get(&self, x: u32, y: u32) -> [f32; 3] {
        self.pixels[self.index(x, y)]
    }

    /// Sets the pixel at column `x`, row `y` (row 0 is the top). Panics when out of range.
    pub fn set(&mut self, x: u32, y: u32, rgb: [f32; 3]) {
        let i = self.index(x, y);
        self.pixels[i] = rgb;
    }

    /// The 8-bit image the spec defines: each channel through [`quantize`].
    pub fn to_rgb8(&self) -> RgbImage {
        let raw = self.pixels.iter().flatten().map(|&c| quantize(c)).collect();
        RgbImage::from_raw(self.width, self.height, raw)
            .expect("Film::pixels must hold width * height entries")
    }

    /// Writes the film to `path`, choosing the format from the extension: `png`, `ppm`
    /// (binary P6), `bmp` are 8-bit through [`quantize`]; `exr` is 32-bit float RGB with
    /// the unclamped linear values. Rows go to the encoder one at a time (`encode`): no
    /// copy of the film is made.
    ///
    /// The write is atomic (see [`crate::util::atomic::write_atomic`]): on any error no partial file is left and an
    /// existing file at `path` is untouched.
    pub fn save(&self, path: &Path) -> Result<()> {
        self.save_mapped(path, Format::from_path(path)?, |p| p)
    }

    /// `save` of each pixel through `map` (which 8-bit formats then quantise).
    fn save_mapped(
        &self,
        path: &Path,
        format: Format,
        map: impl Fn([f32; 3]) -> [f32; 3] + Sync,
    ) -> Result<()> {
        let w = self.width as usize;
        if format.is_float() {
            // Stays float: the EXR is the lossless record of the render.
            return encode::write_exr(path, self.width, self.height, |x, y| {
                map(self.pixels[y * w + x])
            });
        }
        encode::write_rgb8_rows(path, format, self.width, self.height, |y, row| {
            let pixels = &self.pixels[y as usize * w..][..w];
            for (out, p) in row.chunks_exact_mut(3).zip(pixels) {
                out.copy_from_slice(&map(*p).map(quantize));
            }
        })
    }

    /// What an 8-bit image shows of an AOV: depth as grey scaled by the largest finite
    /// distance, cost as a heat ramp scaled by the largest count; colour and normals as
    /// they are.
    pub fn for_display(&self, aov: u32) -> Film {
        let map = self.display_map(aov);
        Film {
            width: self.width,
            height: self.height,
            pixels: self.pixels.iter().map(|&p| map(p)).collect(),
        }
    }

    /// The pixel mapping of `for_display`, for this film's values.
    fn display_map(&self, aov: u32) -> impl Fn([f32; 3]) -> [f32; 3] + Sync + use<> {
        let scaled = aov == AOV_DEPTH || aov == AOV_COST;
        let max = if scaled {
            self.pixels
                .iter()
                .map(|p| p[0])
                .filter(|v| v.is_finite())
                .fold(0.0f32, f32::max)
                .max(1e-30)
        } else {
            1.0
        };
        move |p: [f32; 3]| {
            if !scaled {
                return p;
            }
            let v = (p[0] / max).clamp(0.0, 1.0);
            if aov == AOV_DEPTH {
                [v; 3]
            } else {
                heat_ramp(v)
            }
        }
    }

    /// Writes a render of `aov`: float formats (EXR) keep the raw values, 8-bit ones
    /// get [`Film::for_display`]'s, converted row by row as they are written.
    pub fn save_aov(&self, path: &Path, aov: u32) -> Result<()> {
        let format = Format::from_path(path)?;
        if format.is_float() {
            self.save_mapped(path, format, |p| p)
        } else {
            self.save_mapped(path, format, self.display_map(aov))
        }
    }

    /// Reads any supported image back as linear RGB: 8-bit images become `value / 255`,
    /// float images (EXR) keep their values, including those outside [0, 1].
    pub fn load(path: &Path) -> Result<Film> {
        let img = decode(path)?.into_rgb32f();
        let pixels = img.pixels().map(|p| p.0).collect();
        Ok(Film {
            width: img.width(),
            height: img.height(),
            pixels,
        })
    }
}

/// Running sums of a frame's samples, for rendering it in steps (progressive rendering):
/// tracing samples `0..k` and then `k..n` into one accumulator gives the image of `0..n`.
#[derive(Clone, Debug, PartialEq)]
pub struct Accumulator {
    /// Per pixel, the sum of the samples traced so far.
    pub sums: Film,
    /// How many samples every pixel holds.
    pub samples: u32,
}

impl Accumulator {
    pub fn new(width: u32, height: u32) -> Self {
        Accumulator {
            sums: Film::new(width, height),
            samples: 0,
        }
    }

    /// The image so far: each sum divided by the number of samples, one f32 division as
    /// the reference does it (so all n samples give the one-step image to the bit).
    pub fn film(&self) -> Film {
        let n = self.samples.max(1) as f32;
        Film {
            width: self.sums.width,
            height: self.sums.height,
            pixels: self.sums.pixels.iter().map(|p| p.map(|c| c / n)).collect(),
        }
    }

    /// `film`, for an accumulator that is done: divides in place rather than copying
    /// (a 4K film is 100 MB), in parallel.
    pub fn into_film(self) -> Film {
        let n = self.samples.max(1) as f32;
        let mut film = self.sums;
        let divide = |chunk: &mut [[f32; 3]]| chunk.iter_mut().for_each(|p| *p = p.map(|c| c / n));
        // One thread in the browser (no `native`): the same division, in order.
        #[cfg(feature = "native")]
        film.pixels.par_chunks_mut(1 << 14).for_each(divide);
        #[cfg(not(feature = "native"))]
        film.pixels.chunks_mut(1 << 14).for_each(divide);
        film
    }

    /// Whether the sums are all zero: no sample accumulated yet. A pass's sums are then
    /// written as `0.0 + sum` (the value an addition to zero gives, to the bit), not
    /// added to what the film holds, so a new film's pages are never read before they are
    /// written (`Film::new`). Adding them to the film's pages ran 5 times slower on 2
    /// cores (235 against 39 ms for a 4K frame's sums), and the GPU's readback of a 4K
    /// frame on an H200 took 63 ms instead of 18.
    pub fn holds_nothing(&self) -> bool {
        self.samples == 0
    }

    /// Refuses to add `samples` of a `width` x `height` frame of `spp` samples unless they
    /// continue where this accumulator left off, within the frame's samples.
    pub fn check(
        &self,
        width: u32,
        height: u32,
        spp: u32,
        samples: &std::ops::Range<u32>,
    ) -> Result<()> {
        if (self.sums.width, self.sums.height) != (width, height) {
            return Err(Error::Render(format!(
                "the accumulator is {}x{}, the frame {width}x{height}",
                self.sums.width, self.sums.height
            )));
        }
        if samples.start != self.samples || samples.end <= samples.start || samples.end > spp {
            return Err(Error::Render(format!(
                "samples {samples:?} do not continue the {} already accumulated within the frame's {spp}",
                self.samples
            )));
        }
        Ok(())
    }
}

/// Quantises one linear channel to 8 bits as the spec says: clamp to [0, 1], scale by 255,
/// round to nearest (halves away from zero). NaN becomes 0 (Rust's float-to-int cast
/// saturates and maps NaN to 0), so a stray NaN shows as black rather than aborting a save.
pub fn quantize(c: f32) -> u8 {
    let v = c.clamp(0.0, 1.0) * 255.0;
    // `v.round()`, which on x86-64's baseline is a call into the C library, six million of
    // them a 1080p image: the whole part, and one more where the rest is at least a half.
    // Exact, since both parts of a float below 2^23 are; NaN's whole part casts to 0 and
    // its rest compares false.
    let whole = v as u8;
    whole + u8::from(v - f32::from(whole) >= 0.5)
}

/// An 8-bit image as the bytes of a PNG file, for callers that show or send it rather
/// than write it (the Python module's notebook display, the browser page).
pub fn encode_png(img: &RgbImage) -> Result<Vec<u8>> {
    let mut out = std::io::Cursor::new(Vec::new());
    img.write_to(&mut out, ImageFormat::Png)
        .map_err(|e| Error::Image(format!("PNG encoding: {e}")))?;
    Ok(out.into_inner())
}

/// Writes an 8-bit image to `path` atomically, format chosen from the extension as in
/// [`Film::save`] (an `exr` holds the values divided by 255). Used for heat maps.
pub fn save_rgb8(img: &RgbImage, path: &Path) -> Result<()> {
    let format = Format::from_path(path)?;
    let (w, h) = img.dimensions();
    if format.is_float() {
        return encode::write_exr(path, w, h, |x, y| {
            img.get_pixel(x as u32, y as u32)
                .0
                .map(|c| f32::from(c) / 255.0)
        });
    }
    let row_len = w as usize * 3;
    encode::write_rgb8_rows(path, format, w, h, |y, row| {
        row.copy_from_slice(&img.as_raw()[y as usize * row_len..][..row_len]);
    })
}

/// The colour ramp of every heat map gpurt draws (the cost AOV, `gpurt diff`'s
/// difference panel): black -> red -> yellow -> white as `v` goes from 0 to 1, each
/// channel rising in its own third.
pub fn heat_ramp(v: f32) -> [f32; 3] {
    let x = v.clamp(0.0, 1.0) * 3.0;
    [0.0, 1.0, 2.0].map(|lo| (x - lo).clamp(0.0, 1.0))
}

fn image_error(path: &Path, e: image::ImageError) -> Error {
    Error::Image(format!("{}: {e}", path.display()))
}

/// Bytes a decoder may allocate for each pixel an image's header declares: four float
/// channels (an EXR with alpha), the most any format gpurt reads decodes to.
const DECODED_BYTES_PER_PIXEL: u64 = 16;

/// Reads and decodes an image, recognising the format by content (falling back to the
/// extension). Any image gpurt writes is read, up to `MAX_IMAGE_SIDE` a side (the image
/// crate's own default limit, 512 MiB, refused a 10000x10000 EXR gpurt had written); a
/// larger one is refused by its header before anything is decoded, and a decoder may
/// take no more memory than the size its header declares.
fn decode(path: &Path) -> Result<DynamicImage> {
    let mut reader = image::ImageReader::open(path)
        .map_err(|e| Error::io(path, e))?
        .with_guessed_format()
        .map_err(|e| Error::io(path, e))?;
    if reader.format().is_none() {
        let supported: Vec<_> = Format::ALL.iter().map(|f| f.extension()).collect();
        return Err(Error::Image(format!(
            "{}: not an image by its content nor by its extension (images: {})",
            path.display(),
            supported.join(", ")
        )));
    }
    // The decoder reads the header; its limits are set from what the header declares.
    reader.no_limits();
    let mut decoder = reader.into_decoder().map_err(|e| image_error(path, e))?;
    let (w, h) = decoder.dimensions();
    if w > MAX_IMAGE_SIDE || h > MAX_IMAGE_SIDE {
        return Err(Error::Image(format!(
            "{}: {w}x{h} pixels, larger than any image gpurt reads or writes \
             (at most {MAX_IMAGE_SIDE} a side)",
            path.display()
        )));
    }
    let mut limits = image::Limits::default();
    limits.max_alloc = Some(u64::from(w) * u64::from(h) * DECODED_BYTES_PER_PIXEL + (64 << 20));
    // As `ImageReader::decode` does: the image's buffer counts against the limit too.
    limits
        .reserve(decoder.total_bytes())
        .and_then(|()| decoder.set_limits(limits))
        .and_then(|()| DynamicImage::from_decoder(decoder))
        .map_err(|e| image_error(path, e))
}

/// Loads an image as 8-bit RGB for diffing. PNG, PPM and BMP are taken as stored (alpha is
/// dropped); float images (EXR) are quantised exactly like [`Film::to_rgb8`], so an EXR and
/// the PNG of the same render compare equal.
pub fn load_rgb8(path: &Path) -> Result<RgbImage> {
    let img = decode(path)?;
    if matches!(img.color(), ColorType::Rgb32F | ColorType::Rgba32F) {
        let f = img.into_rgb32f();
        let raw = f.as_raw().iter().map(|&c| quantize(c)).collect();
        Ok(RgbImage::from_raw(f.width(), f.height(), raw).expect("same dimensions"))
    } else {
        Ok(img.into_rgb8())
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::compare::tests::textured;
    use std::fs;
    use std::path::PathBuf;

    /// A fresh, empty directory for one test.
    pub(crate) fn scratch_dir(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("gpurt-film-{}-{name}", std::process::id()));
        let _ = fs::remove_dir_all(&dir);
        fs::create_dir_all(&dir).unwrap();
        dir
    }

    pub(crate) fn dir_entries(dir: &Path) -> Vec<String> {
        let mut names: Vec<String> = fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        names
    }

    #[test]
    fn quantize_rounds_clamps_and_zeroes_nan() {
        assert_eq!(quantize(0.0), 0);
        assert_eq!(quantize(0.49 / 255.0), 0);
        assert_eq!(quantize(0.51 / 255.0), 1);
        assert_eq!(quantize(1.49 / 255.0), 1);
        assert_eq!(quantize(1.51 / 255.0), 2);
        assert_eq!(quantize(254.49 / 255.0), 254);
        assert_eq!(quantize(254.51 / 255.0), 255);
        assert_eq!(quantize(1.0), 255);
        assert_eq!(quantize(1.5), 255);
        assert_eq!(quantize(f32::INFINITY), 255);
        assert_eq!(quantize(-0.1), 0);
        assert_eq!(quantize(f32::NEG_INFINITY), 0);
        assert_eq!(quantize(f32::NAN), 0);
        // Every level survives a round trip through its float value.
        for v in 0..=255u8 {
            assert_eq!(quantize(f32::from(v) / 255.0), v);
        }
        // `round`'s answer on every float of [0, 1] a 64th apart in their bits, and on
        // each side of every half-way point.
        let rounded = |c: f32| (c.clamp(0.0, 1.0) * 255.0).round() as u8;
        for bits in (0..=1.0f32.to_bits()).step_by(64) {
            let c = f32::from_bits(bits);
            assert_eq!(quantize(c), rounded(c), "{c:e}");
        }
        for half in 0..255 {
            let c = (half as f32 + 0.5) / 255.0;
            for c in [c.next_down(), c, c.next_up()] {
                assert_eq!(quantize(c), rounded(c), "{c:e}");
            }
        }
    }

    #[test]
    fn film_get_set_and_to_rgb8() {
        let mut film = Film::new(3, 2);
        assert_eq!(film.pixels.len(), 6);
        film.set(2, 1, [1.0, 0.5, -3.0]);
        assert_eq!(film.get(2, 1), [1.0, 0.5, -3.0]);
        assert_eq!(film.pixels[5], [1.0, 0.5, -3.0]); // row-major, top row first
        let img = film.to_rgb8();
        assert_eq!(img.dimensions(), (3, 2));
        assert_eq!(img.get_pixel(2, 1).0, [255, 128, 0]);
        assert_eq!(img.get_pixel(0, 0).0, [0, 0, 0]);
    }

    /// A film whose 8-bit image uses many levels, plus values outside [0, 1].
    fn test_film() -> Film {
        let img = textured(13, 7);
        let mut film = Film::new(13, 7);
        for (x, y, p) in img.enumerate_pixels() {
            film.set(x, y, p.0.map(|c| f32::from(c) / 255.0));
        }
        film.set(0, 0, [4.5, -0.25, 1.0]);
        film
    }

    #[test]
    fn eight_bit_round_trips_are_lossless() {
        let dir = scratch_dir("roundtrip8");
        let film = test_film();
        for ext in ["png", "ppm", "bmp", "PNG"] {
            let path = dir.join(format!("out.{ext}"));
            film.save(&path).unwrap();
            assert_eq!(load_rgb8(&path).unwrap(), film.to_rgb8(), "{ext}");
        }
        // A classic binary PPM (P6), not PAM.
        assert!(fs::read(dir.join("out.ppm")).unwrap().starts_with(b"P6"));
        // Only the outputs: no temporary files left behind.
        assert_eq!(
            dir_entries(&dir),
            ["out.PNG", "out.bmp", "out.png", "out.ppm"]
        );
        fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn exr_keeps_unclamped_values_and_loads_quantised() {
        let dir = scratch_dir("roundtripexr");
        let path = dir.join("out.exr");
        let film = test_film();
        film.save(&path).unwrap();
        let back = Film::load(&path).unwrap();
        assert_eq!(back, film);
        assert_eq!(back.get(0, 0), [4.5, -0.25, 1.0]);
        assert_eq!(load_rgb8(&path).unwrap(), film.to_rgb8());
        fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn unknown_extension_errors_and_writes_nothing() {
        let dir = scratch_dir("badext");
        let film = Film::new(2, 2);
        let err = film.save(&dir.join("out.jpg")).unwrap_err().to_string();
        assert!(err.contains("'.jpg'"), "{err}");
        assert!(err.contains("png, ppm, bmp, exr"), "{err}");
        let err = film.save(&dir.join("out")).unwrap_err().to_string();
        assert!(err.contains("no image file extension"), "{err}");
        assert!(dir_entries(&dir).is_empty());
        fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn missing_directory_errors_and_leaves_nothing() {
        let dir = scratch_dir("nodir");
        let path = dir.join("missing").join("out.png");
        let err = Film::new(2, 2).save(&path).unwrap_err();
        assert!(matches!(err, Error::Io { .. }), "{err}");
        assert!(err.to_string().contains("out.png"), "{err}");
        assert!(dir_entries(&dir).is_empty());
        fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn load_errors_name_the_file() {
        let dir = scratch_dir("loaderr");
        let missing = dir.join("missing.png");
        let err = load_rgb8(&missing).unwrap_err().to_string();
        assert!(err.contains("missing.png"), "{err}");
        let garbage = dir.join("garbage.png");
        fs::write(&garbage, b"not an image").unwrap();
        let err = load_rgb8(&garbage).unwrap_err().to_string();
        assert!(err.contains("garbage.png"), "{err}");
        fs::remove_dir_all(&dir).unwrap();
    }

    /// A PNG declaring `w`x`h` pixels and holding `rows` black rows of them, compressed
    /// as they are made, so that the test never holds the image.
    fn black_png(w: u32, h: u32, rows: u32) -> Vec<u8> {
        use std::io::Write;
        fn chunk(out: &mut Vec<u8>, kind: &[u8; 4], data: &[u8]) {
            let mut crc = flate2::Crc::new();
            crc.update(kind);
            crc.update(data);
            out.extend((data.len() as u32).to_be_bytes());
            out.extend(kind);
            out.extend(data);
            out.extend(crc.sum().to_be_bytes());
        }
        let mut z = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::fast());
        let row = vec![0u8; 1 + 3 * w as usize];
        for _ in 0..rows {
            z.write_all(&row).unwrap();
        }
        let mut ihdr = Vec::from(w.to_be_bytes());
        ihdr.extend(h.to_be_bytes());
        ihdr.extend([8, 2, 0, 0, 0]);
        let mut out = b"\x89PNG\r\n\x1a\n".to_vec();
        chunk(&mut out, b"IHDR", &ihdr);
        chunk(&mut out, b"IDAT", &z.finish().unwrap());
        chunk(&mut out, b"IEND", &[]);
        out
    }

    /// Every image gpurt writes is read back, the ones past the image crate's default
    /// 512 MiB limit too (this one decodes to 588 MB); one whose header declares more
    /// than gpurt's largest side is refused by that header, with its size, at once.
    #[test]
    fn large_images_load_and_larger_headers_are_refused() {
        let dir = scratch_dir("large");
        let large = dir.join("large.png");
        fs::write(&large, black_png(14_000, 14_000, 14_000)).unwrap();
        let img = load_rgb8(&large).unwrap();
        assert_eq!(img.dimensions(), (14_000, 14_000));
        assert!(img.as_raw().iter().all(|&c| c == 0));
        drop(img);
        let bomb = dir.join("bomb.png");
        fs::write(&bomb, black_png(MAX_IMAGE_SIDE + 1, 1, 1)).unwrap();
        let err = load_rgb8(&bomb).unwrap_err().to_string();
        assert!(
            err.contains("bomb.png") && err.contains("16385x1 pixels"),
            "{err}"
        );
        // The header alone decides: of the 60000 rows it declares, one is there.
        fs::write(&bomb, black_png(60_000, 60_000, 1)).unwrap();
        let err = load_rgb8(&bomb).unwrap_err().to_string();
        assert!(err.contains("60000x60000 pixels, larger than"), "{err}");
        fs::remove_dir_all(&dir).unwrap();
    }
}
