//! The image files gpurt writes, fed a row at a time, so that saving an image costs a row
//! of memory beside the film instead of a copy of it: at the 16384 x 16384 maximum a copy
//! of the film is 3 GiB and its 8-bit image 0.75 GiB.
//!
//! PNG goes through the `png` crate's stream writer (filtered and compressed as rows
//! arrive, IDAT chunks written as they fill), PPM is its header and the rows, EXR is the
//! `exr` crate reading each pixel from a closure. BMP, stored bottom-up, is assembled as one
//! 8-bit image (3 bytes a pixel) for `image`'s encoder. Every file is written atomically.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::Path;

use image::{ExtendedColorType, ImageEncoder};

use crate::util::atomic::write_atomic_with;
use crate::{Error, Result};

/// The image formats gpurt writes, chosen by file extension (case-insensitive): the one
/// list of them.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Format {
    Png,
    Ppm,
    Bmp,
    Exr,
}

impl Format {
    pub const ALL: [Format; 4] = [Format::Png, Format::Ppm, Format::Bmp, Format::Exr];

    pub fn extension(self) -> &'static str {
        match self {
            Format::Png => "png",
            Format::Ppm => "ppm",
            Format::Bmp => "bmp",
            Format::Exr => "exr",
        }
    }

    /// Whether the format keeps the film's linear floats (unclamped) rather than 8 bits.
    pub fn is_float(self) -> bool {
        self == Format::Exr
    }

    /// The format a path's extension names; an error naming the path and the supported
    /// extensions otherwise (checked before a render, so one never ends in it). A path
    /// that is a directory is named as one, since it cannot be written either way.
    pub fn from_path(path: &Path) -> Result<Format> {
        if path.is_dir() {
            return Err(Error::Image(format!(
                "{}: is a directory; give an image file name (such as {})",
                path.display(),
                path.join("image.png").display()
            )));
        }
        let ext = path.extension().map(|e| e.to_string_lossy().to_lowercase());
        let known = Format::ALL
            .into_iter()
            .find(|f| Some(f.extension()) == ext.as_deref());
        known.ok_or_else(|| {
            let supported: Vec<_> = Format::ALL.iter().map(|f| f.extension()).collect();
            Error::Image(format!(
                "{}: {}; supported: {}",
                path.display(),
                match ext {
                    Some(ext) => format!(
                        "unsupported image extension '.{}'",
                        crate::util::error::escape(ext.as_bytes())
                    ),
                    None => "no image file extension".to_string(),
                },
                supported.join(", ")
            ))
        })
    }
}

/// Writes a `width` x `height` 8-bit RGB image in `format` (not EXR) to `path`: `fill(y,
/// row)` puts row `y` (top first) into `row`, 3 bytes a pixel.
pub fn write_rgb8_rows(
    path: &Path,
    format: Format,
    width: u32,
    height: u32,
    fill: impl Fn(u32, &mut [u8]),
) -> Result<()> {
    let row_len = width as usize * 3;
    let io = |e: std::io::Error| Error::io(path, e);
    write_atomic_with(path, |w| match format {
        Format::Png => {
            // What `image`'s PNG encoder sets: fast compression, adaptive filters.
            let mut encoder = png::Encoder::new(w, width, height);
            encoder.set_color(png::ColorType::Rgb);
            encoder.set_depth(png::BitDepth::Eight);
            encoder.set_compression(png::Compression::Fast);
            encoder.set_filter(png::Filter::Adaptive);
            let png = |e: png::EncodingError| Error::Image(format!("{}: {e}", path.display()));
            let mut writer = encoder.write_header().map_err(png)?;
            let mut stream = writer.stream_writer().map_err(png)?;
            let mut row = vec![0u8; row_len];
            for y in 0..height {
                fill(y, &mut row);
                stream.write_all(&row).map_err(io)?;
            }
            stream.finish().map_err(png)?;
            writer.finish().map_err(png)
        }
        Format::Ppm => {
            // Binary P6, byte for byte the header `image`'s encoder writes (whose default
            // is PAM, which many .ppm readers reject).
            write!(w, "P6\n{width} {height} 255\n").map_err(io)?;
            let mut row = vec![0u8; row_len];
            for y in 0..height {
                fill(y, &mut row);
                w.write_all(&row).map_err(io)?;
            }
            Ok(())
        }
        Format::Bmp => {
            let mut raw = vec![0u8; row_len * height as usize];
            if row_len > 0 {
                for (y, row) in raw.chunks_mut(row_len).enumerate() {
                    fill(y as u32, row);
                }
            }
            image::codecs::bmp::BmpEncoder::new(w)
                .write_image(&raw, width, height, ExtendedColorType::Rgb8)
                .map_err(|e| Error::Image(format!("{}: {e}", path.display())))
        }
        Format::Exr => unreachable!("EXR is written from floats: write_exr"),
    })
}

/// Writes a `width` x `height` EXR of 32-bit float RGB to `path`, pixel `(x, y)` (row 0
/// the top) being `pixel(x, y)`, as `image`'s EXR encoder lays it out.
pub fn write_exr(
    path: &Path,
    width: u32,
    height: u32,
    pixel: impl Fn(usize, usize) -> [f32; 3] + Sync,
) -> Result<()> {
    use exr::prelude::{Image, SpecificChannels, Vec2, WritableImage};
    write_atomic_with(path, |w: &mut BufWriter<File>| {
        Image::from_channels(
            (width as usize, height as usize),
            SpecificChannels::rgb(|p: Vec2<usize>| {
                let [r, g, b] = pixel(p.x(), p.y());
                (r, g, b)
            }),
        )
        .write()
        .to_buffered(w)
        .map_err(|e| Error::Image(format!("{}: {e}", path.display())))
    })
}
