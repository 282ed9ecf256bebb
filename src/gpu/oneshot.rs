//! One render from packed buffers to a film, blocking: the convenience the tests, the
//! examples and `gpurt bench` use (natively; the browser awaits `trace_rows_async`).

use std::sync::atomic::AtomicBool;

use super::renderer::GpuRenderer;
use super::trace::trace;
use crate::film::Film;
use crate::gpu_types::GpuGlobals;
use crate::pack::SceneBuffers;
use crate::util::error::Result;

impl GpuRenderer {
    /// Renders the image described by `globals` on `device`. Returns the film and the
    /// number of rays traced.
    pub fn render(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        scene: &SceneBuffers,
        globals: &GpuGlobals,
        progress: &dyn Fn(u64),
        cancel: &AtomicBool,
    ) -> Result<(Film, u64)> {
        let uploaded = self.upload(device, queue, scene, globals)?;
        trace(device, queue, &uploaded, progress, cancel)
    }
}

/// Convenience for one render: compiles the pipeline (no disk cache) and renders.
pub fn render_gpu(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    scene: &SceneBuffers,
    globals: &GpuGlobals,
) -> Result<(Film, u64)> {
    let r = GpuRenderer::new(device, None)?;
    r.render(
        device,
        queue,
        scene,
        globals,
        &|_| {},
        &AtomicBool::new(false),
    )
}
