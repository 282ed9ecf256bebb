//! The images textures are made of (OBJ's `map_Kd`, glTF's `baseColorTexture`): decoded
//! with `image` (PNG, JPEG, TGA, BMP) once the header's size is checked against the
//! bound, so that a header declaring 100000 x 100000 allocates nothing; decoded from sRGB
//! to linear here, once, so that neither renderer converts a texel per sample; and the
//! scene's textures held to `MAX_TEXELS` together by halving the largest, with a warning
//! (a model renders, a little blurrier, rather than not at all).
//!
//! A texture that cannot be had (missing, outside the model's folder, corrupt, too
//! large) is a warning naming the image and the material, whose surfaces keep their
//! colour: as for an unknown material or an unreadable `.mtl`, the model's geometry and
//! lighting stay right without it.

use std::io::Cursor;

use glam::Vec3;
use image::{DynamicImage, ImageReader, Limits};

use super::model::{Texture, Wrap};
use crate::util::limits::{MAX_IMAGE_BYTES, MAX_TEXELS};

/// Decodes an image's bytes into a texture named `name`, or says why not.
pub fn decode(bytes: &[u8], name: &str, wrap: [Wrap; 2]) -> Result<Texture, String> {
    let reader = || {
        ImageReader::new(Cursor::new(bytes))
            .with_guessed_format()
            .map_err(|e| e.to_string())
    };
    if reader()?.format().is_none() {
        return Err("not an image gpurt reads (PNG, JPEG, TGA or BMP)".into());
    }
    let (width, height) = reader()?.into_dimensions().map_err(|e| e.to_string())?;
    let texels = u64::from(width) * u64::from(height);
    if texels == 0 || texels > MAX_TEXELS {
        return Err(format!(
            "its header declares {width} x {height} texels (at most {MAX_TEXELS} are read)"
        ));
    }
    let mut limits = Limits::default();
    limits.max_image_width = Some(width);
    limits.max_image_height = Some(height);
    limits.max_alloc = Some(MAX_IMAGE_BYTES);
    let mut r = reader()?;
    r.limits(limits);
    let image = r.decode().map_err(|e| e.to_string())?;
    Ok(Texture {
        name: name.to_string(),
        width,
        height,
        texels: linear(image),
        wrap,
    })
}

/// The image's texels as linear RGB, row by row from the top (alpha is not read). Eight-
/// and sixteen-bit images are sRGB, as textures of colour are (glTF says so; OBJ's
/// libraries are painted so); float images are linear already.
fn linear(image: DynamicImage) -> Vec<Vec3> {
    match image {
        DynamicImage::ImageRgb32F(_) | DynamicImage::ImageRgba32F(_) => image
            .to_rgb32f()
            .pixels()
            .map(|p| Vec3::from(p.0))
            .collect(),
        DynamicImage::ImageLuma8(_)
        | DynamicImage::ImageLumaA8(_)
        | DynamicImage::ImageRgb8(_)
        | DynamicImage::ImageRgba8(_) => {
            let table: [f32; 256] = std::array::from_fn(|i| srgb_to_linear(i as f32 / 255.0));
            image
                .to_rgb8()
                .pixels()
                .map(|p| Vec3::from(p.0.map(|c| table[c as usize])))
                .collect()
        }
        _ => image
            .to_rgb32f()
            .pixels()
            .map(|p| Vec3::from(p.0.map(srgb_to_linear)))
            .collect(),
    }
}

/// The sRGB transfer function undone (IEC 61966-2-1).
pub fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// The index of the texture already read from `name` with `wrap`, if any: materials that
/// share an image share its texels.
pub fn find(textures: &[Texture], name: &str, wrap: [Wrap; 2]) -> Option<u32> {
    textures
        .iter()
        .position(|t| t.name == name && t.wrap == wrap)
        .map(|i| i as u32)
}

/// Adds `t` to the scene's `textures` and gives its index. While they hold more than
/// `MAX_TEXELS` together, the largest is halved in each direction (a box filter of 2 x 2
/// texels), with a warning each time.
pub fn add(textures: &mut Vec<Texture>, t: Texture, warnings: &mut Vec<String>) -> u32 {
    add_within(textures, t, warnings, MAX_TEXELS)
}

fn add_within(
    textures: &mut Vec<Texture>,
    t: Texture,
    warnings: &mut Vec<String>,
    bound: u64,
) -> u32 {
    textures.push(t);
    let total = |textures: &[Texture]| textures.iter().map(|t| t.texels.len() as u64).sum::<u64>();
    while total(textures) > bound {
        let largest = textures
            .iter_mut()
            .max_by_key(|t| t.texels.len())
            .expect("one at least");
        let (w, h) = (largest.width, largest.height);
        halve(largest);
        warnings.push(format!(
            "texture '{}' halved from {w} x {h} to {} x {} texels: the scene's textures would hold more than {bound} together",
            largest.name, largest.width, largest.height
        ));
    }
    textures.len() as u32 - 1
}

/// `t` at half its width and height (at least one texel each), each texel the mean of
/// the two by two it replaces (of the one or two at an odd edge).
fn halve(t: &mut Texture) {
    let (w, h) = (t.width.div_ceil(2).max(1), t.height.div_ceil(2).max(1));
    let at =
        |x: u32, y: u32| t.texels[(y.min(t.height - 1) * t.width + x.min(t.width - 1)) as usize];
    let mut texels = Vec::with_capacity((w * h) as usize);
    for y in 0..h {
        for x in 0..w {
            let (x0, y0) = (2 * x, 2 * y);
            texels.push(0.25 * (at(x0, y0) + at(x0 + 1, y0) + at(x0, y0 + 1) + at(x0 + 1, y0 + 1)));
        }
    }
    (t.width, t.height, t.texels) = (w, h, texels);
}

#[cfg(test)]
mod tests {
    use super::*;

    fn png(w: u32, h: u32, texels: &[[u8; 3]]) -> Vec<u8> {
        let mut out = Cursor::new(Vec::new());
        image::RgbImage::from_fn(w, h, |x, y| image::Rgb(texels[(y * w + x) as usize]))
            .write_to(&mut out, image::ImageFormat::Png)
            .unwrap();
        out.into_inner()
    }

    #[test]
    fn srgb_is_decoded_to_linear_once() {
        let t = decode(
            &png(2, 1, &[[255, 0, 188], [128, 10, 55]]),
            "a.png",
            [Wrap::Repeat; 2],
        )
        .unwrap();
        assert_eq!((t.width, t.height), (2, 1));
        // 188/255 and 128/255 of sRGB: 0.5029 and 0.2158 of linear light.
        let want = [
            Vec3::new(1.0, 0.0, 0.50289),
            Vec3::new(0.21586, 0.003035, 0.038204),
        ];
        for (got, want) in t.texels.iter().zip(want) {
            assert!((*got - want).abs().max_element() < 1e-4, "{got} {want}");
        }
    }

    #[test]
    fn jpeg_is_read() {
        let mut out = Cursor::new(Vec::new());
        image::RgbImage::from_pixel(16, 8, image::Rgb([188, 188, 188]))
            .write_to(&mut out, image::ImageFormat::Jpeg)
            .unwrap();
        let t = decode(out.get_ref(), "a.jpg", [Wrap::Repeat; 2]).unwrap();
        assert_eq!((t.width, t.height, t.texels.len()), (16, 8, 128));
        // Lossy, but a flat grey stays within a level of itself.
        let want = srgb_to_linear(188.0 / 255.0);
        let (lo, hi) = (srgb_to_linear(187.0 / 255.0), srgb_to_linear(189.0 / 255.0));
        assert!(
            t.texels
                .iter()
                .all(|c| c.min_element() >= lo && c.max_element() <= hi),
            "{want}"
        );
    }

    #[test]
    fn a_header_declaring_too_much_is_refused_before_decoding() {
        // A PNG whose header says 100000 x 100000 (its checksum made right), and whose one
        // texel of data follows.
        let mut bytes = png(1, 1, &[[0, 0, 0]]);
        bytes[16..20].copy_from_slice(&100_000u32.to_be_bytes());
        bytes[20..24].copy_from_slice(&100_000u32.to_be_bytes());
        let mut crc = flate2::Crc::new();
        crc.update(&bytes[12..29]);
        let crc = crc.sum();
        bytes[29..33].copy_from_slice(&crc.to_be_bytes());
        let e = decode(&bytes, "big.png", [Wrap::Repeat; 2]).unwrap_err();
        assert!(e.contains("100000 x 100000"), "{e}");
    }

    #[test]
    fn corrupt_and_truncated_images_are_errors() {
        let good = png(8, 8, &[[200, 100, 50]; 64]);
        assert!(decode(&good[..good.len() - 30], "cut.png", [Wrap::Repeat; 2]).is_err());
        assert!(decode(b"not an image at all", "x.png", [Wrap::Repeat; 2]).is_err());
        let mut bad = good.clone();
        let n = bad.len();
        bad[n / 2..n - 12].fill(0xa5);
        assert!(decode(&bad, "bad.png", [Wrap::Repeat; 2]).is_err());
    }

    #[test]
    fn textures_beyond_the_bound_halve_the_largest() {
        let tex = |name: &str, w: u32, h: u32| Texture {
            name: name.into(),
            width: w,
            height: h,
            texels: vec![Vec3::ONE; (w * h) as usize],
            wrap: [Wrap::Repeat; 2],
        };
        let (mut textures, mut warnings) = (Vec::new(), Vec::new());
        add_within(&mut textures, tex("a", 8, 8), &mut warnings, 160);
        add_within(&mut textures, tex("b", 8, 8), &mut warnings, 160);
        assert!(warnings.is_empty());
        // 128 + 81 texels: c, the largest, is halved to 5 x 5, and 153 fit.
        add_within(&mut textures, tex("c", 9, 9), &mut warnings, 160);
        assert_eq!((textures[2].width, textures[2].height), (5, 5));
        assert_eq!(warnings.len(), 1, "{warnings:?}");
        assert!(warnings[0].starts_with("texture 'c' halved from 9 x 9 to 5 x 5"));
        // Then the largest, an 8 x 8, halves while the total is over.
        add_within(&mut textures, tex("d", 6, 6), &mut warnings, 160);
        let total: u64 = textures.iter().map(|t| t.texels.len() as u64).sum::<u64>();
        assert!(total <= 160, "{total}");
        let sizes: Vec<_> = textures.iter().map(|t| (t.width, t.height)).collect();
        assert!(
            sizes[..2].contains(&(4, 4)) && sizes[..2].contains(&(8, 8)),
            "{sizes:?}"
        );
        assert_eq!(warnings.len(), 2, "{warnings:?}");
        assert!(
            textures
                .iter()
                .all(|t| t.texels.iter().all(|&c| c == Vec3::ONE))
        );
        assert_eq!(find(&textures, "b", [Wrap::Repeat; 2]), Some(1));
        assert_eq!(find(&textures, "b", [Wrap::Clamp; 2]), None);
    }
}
