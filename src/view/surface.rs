//! The window's wgpu surface: the device that draws into it (on an adapter that can
//! present to the window), the surface's format and size, and one frame drawn: the
//! ray-traced image written straight into the surface texture, the wireframe drawn over it
//! (`Wireframe::encode`), and the texture read back for a screenshot. The window decides
//! what a frame shows; this module only knows wgpu.

use std::path::Path;
use std::sync::Arc;

use image::RgbImage;
use winit::window::Window;

use super::readback::TextureReadback;
use super::wireframe::Wireframe;
use crate::film;
use crate::gpu::device::Gpu;
use crate::gpu::{self, GpuContext};
use crate::gpu_types::GpuGlobals;
use crate::pack::SceneBuffers;
use crate::util::error::{Error, Result};

/// A window's surface and the device that draws into it.
pub struct Surface {
    surface: wgpu::Surface<'static>,
    config: wgpu::SurfaceConfiguration,
    /// The surface format without sRGB encoding: the image's bytes are shown as they are,
    /// as the PNG of the same view stores them.
    view_format: wgpu::TextureFormat,
    ctx: GpuContext,
    wireframe: Wireframe,
}

/// What `Surface::draw` did.
pub enum Drawn {
    /// The frame was shown.
    Shown,
    /// No frame could be drawn now; the window should ask for another.
    Later,
}

impl Surface {
    /// The surface of `window`, on the adapter whose name contains `adapter` (else the
    /// best) among those that can present to it, with the scene's wireframe ready to
    /// draw. `readable`: the surface must be read back (`--screenshot`).
    pub fn new(
        window: &Arc<Window>,
        adapter: Option<&str>,
        readable: bool,
        buffers: &SceneBuffers,
    ) -> Result<Surface> {
        let on = |instance: wgpu::Instance| -> Result<(wgpu::Surface<'static>, GpuContext)> {
            let surface = instance
                .create_surface(window.clone())
                .map_err(|e| Error::Gpu(format!("cannot draw into the window: {e}")))?;
            let ctx = gpu::open_on(&instance, adapter, Some(&surface))?;
            Ok((surface, ctx))
        };
        let (surface, ctx) = gpu::on_any_backend(on)?;
        let caps = surface.get_capabilities(&ctx.adapter);
        // 8-bit formats only: the image's bytes go into the surface texture unchanged.
        let format = caps
            .formats
            .iter()
            .copied()
            .find(|f| {
                matches!(
                    f.remove_srgb_suffix(),
                    wgpu::TextureFormat::Bgra8Unorm | wgpu::TextureFormat::Rgba8Unorm
                )
            })
            .ok_or_else(|| {
                Error::Gpu(format!(
                    "the window offers no 8-bit RGBA or BGRA format (only {:?})",
                    caps.formats
                ))
            })?;
        let mut usage = wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_DST;
        if caps.usages.contains(wgpu::TextureUsages::COPY_SRC) {
            usage |= wgpu::TextureUsages::COPY_SRC;
        }
        if !caps.usages.contains(usage) {
            return Err(Error::Gpu(format!(
                "the window's surface cannot be copied into (it allows {:?})",
                caps.usages
            )));
        }
        if readable && !usage.contains(wgpu::TextureUsages::COPY_SRC) {
            return Err(Error::Gpu(
                "the window's surface cannot be read back for --screenshot".into(),
            ));
        }
        let view_format = format.remove_srgb_suffix();
        let size = window.inner_size();
        let config = wgpu::SurfaceConfiguration {
            usage,
            format,
            width: size.width.max(1),
            height: size.height.max(1),
            present_mode: wgpu::PresentMode::AutoVsync,
            desired_maximum_frame_latency: 2,
            alpha_mode: caps.alpha_modes[0],
            color_space: wgpu::SurfaceColorSpace::Auto,
            view_formats: if view_format == format {
                vec![]
            } else {
                vec![view_format]
            },
        };
        surface.configure(&ctx.device, &config);
        let wireframe = Wireframe::new(&ctx.device, buffers, view_format)?;
        Ok(Surface {
            surface,
            config,
            view_format,
            ctx,
            wireframe,
        })
    }

    /// Draws the wireframe of another scene from now on (an animation's next frame).
    pub fn set_scene(&mut self, buffers: &SceneBuffers) -> Result<()> {
        self.wireframe = Wireframe::new(&self.ctx.device, buffers, self.view_format)?;
        Ok(())
    }

    /// The adapter that draws the window.
    pub fn describe(&self) -> String {
        self.ctx.describe()
    }

    /// The surface's size in pixels.
    pub fn size(&self) -> (u32, u32) {
        (self.config.width, self.config.height)
    }

    /// Gives the surface a new size (each side at least 1).
    pub fn resize(&mut self, (w, h): (u32, u32)) {
        if self.size() != (w, h) {
            self.config.width = w;
            self.config.height = h;
            self.surface.configure(&self.ctx.device, &self.config);
        }
    }

    /// An image's pixels in the byte order of the surface (RGBA or BGRA), opaque.
    pub fn bytes(&self, img: &RgbImage) -> Vec<u8> {
        let bgra = self.view_format == wgpu::TextureFormat::Bgra8Unorm;
        img.pixels()
            .flat_map(|p| {
                let [r, g, b] = p.0;
                if bgra { [b, g, r, 255] } else { [r, g, b, 255] }
            })
            .collect()
    }

    /// Draws and presents a frame: `image` (the surface's size, in its byte order, from
    /// `bytes`) or black, with the wireframe of the frame `lines` over it when given.
    /// With `screenshot`, what the frame shows is also written there.
    pub fn draw(
        &mut self,
        image: Option<&[u8]>,
        lines: Option<&GpuGlobals>,
        screenshot: Option<&Path>,
    ) -> Result<Drawn> {
        let frame = match self.surface.get_current_texture() {
            wgpu::CurrentSurfaceTexture::Success(f)
            | wgpu::CurrentSurfaceTexture::Suboptimal(f) => f,
            wgpu::CurrentSurfaceTexture::Timeout | wgpu::CurrentSurfaceTexture::Occluded => {
                return Ok(Drawn::Later);
            }
            wgpu::CurrentSurfaceTexture::Outdated | wgpu::CurrentSurfaceTexture::Lost => {
                self.surface.configure(&self.ctx.device, &self.config);
                return Ok(Drawn::Later);
            }
            wgpu::CurrentSurfaceTexture::Validation => {
                return Err(Error::Gpu("the window's surface texture is invalid".into()));
            }
        };
        let gpu = Gpu::new(&self.ctx.device, &self.ctx.queue);
        let target = frame.texture.create_view(&wgpu::TextureViewDescriptor {
            format: Some(self.view_format),
            ..Default::default()
        });
        let shot = gpu.scoped("drawing the window", || {
            let mut enc = gpu.encoder();
            if let Some(image) = image {
                gpu.write_image(&frame.texture, image);
            } else {
                clear(&mut enc, &target);
            }
            if let Some(globals) = lines {
                self.wireframe.encode(&gpu, &mut enc, &target, globals);
            }
            let shot = screenshot
                .is_some()
                .then(|| TextureReadback::encode(&gpu, &mut enc, &frame.texture));
            gpu.run(enc);
            shot
        })?;
        if let (Some(shot), Some(path)) = (shot, screenshot) {
            let img = shot.read(&gpu, self.view_format)?;
            film::save_rgb8(&img, path)?;
        }
        gpu.show(frame);
        Ok(Drawn::Shown)
    }
}

/// Clears the target to black (the background of the wireframe alone).
fn clear(enc: &mut wgpu::CommandEncoder, target: &wgpu::TextureView) {
    enc.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some("clear"),
        color_attachments: &[Some(wgpu::RenderPassColorAttachment {
            view: target,
            depth_slice: None,
            resolve_target: None,
            ops: wgpu::Operations {
                load: wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                store: wgpu::StoreOp::Store,
            },
        })],
        depth_stencil_attachment: None,
        timestamp_writes: None,
        occlusion_query_set: None,
        multiview_mask: None,
    });
}
