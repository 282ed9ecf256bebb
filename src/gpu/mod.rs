//! The GPU renderer: WGSL compute through wgpu on the same `SceneBuffers` the CPU
//! reference traverses. `context` finds an adapter and a device, `shaders` assembles and
//! validates the WGSL, `render` uploads, dispatches tile by tile and reads back.

pub mod context;
pub mod render;
pub mod shaders;
pub mod specialization;

pub use context::{GpuContext, open};
pub use render::{GpuRenderer, GpuScene, render_gpu, trace, trace_on_device, trace_samples};
