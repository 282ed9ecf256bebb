//! Reading an 8-bit texture back to the host as an RGB image: the window's screenshot
//! (the surface texture it presents) and the headless wireframe image.

use image::RgbImage;

use crate::gpu::device::Device;
use crate::util::error::Result;

/// A copy of an 8-bit RGBA or BGRA texture on its way to the host.
pub struct TextureReadback {
    buffer: wgpu::Buffer,
    row: u32,
    width: u32,
    height: u32,
}

impl TextureReadback {
    /// Encodes the copy of `texture` into `enc`; `read` it once `enc` is submitted.
    pub(crate) fn encode(
        device: &Device,
        enc: &mut wgpu::CommandEncoder,
        texture: &wgpu::Texture,
    ) -> Self {
        let (width, height) = (texture.width(), texture.height());
        let row = (4 * width).next_multiple_of(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT);
        let buffer = device.readback("texture readback", u64::from(row) * u64::from(height));
        enc.copy_texture_to_buffer(
            texture.as_image_copy(),
            wgpu::TexelCopyBufferInfo {
                buffer: &buffer,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(row),
                    rows_per_image: Some(height),
                },
            },
            texture.size(),
        );
        TextureReadback {
            buffer,
            row,
            width,
            height,
        }
    }

    /// The copied pixels as RGB, the texture being of `format`.
    pub(crate) fn read(&self, device: &Device, format: wgpu::TextureFormat) -> Result<RgbImage> {
        let bgra = format == wgpu::TextureFormat::Bgra8Unorm;
        let bytes = u64::from(self.row) * u64::from(self.height);
        device.read(&self.buffer, bytes, |view| {
            let mut img = RgbImage::new(self.width, self.height);
            for (y, line) in view.chunks(self.row as usize).enumerate() {
                for x in 0..self.width as usize {
                    let p = &line[4 * x..4 * x + 4];
                    let rgb = if bgra {
                        [p[2], p[1], p[0]]
                    } else {
                        [p[0], p[1], p[2]]
                    };
                    img.put_pixel(x as u32, y as u32, image::Rgb(rgb));
                }
            }
            img
        })
    }
}
