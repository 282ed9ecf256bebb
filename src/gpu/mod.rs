//! The GPU renderer: WGSL compute through wgpu on the same `SceneBuffers` the CPU
//! reference traverses. `context` finds an adapter and a device, `shaders` assembles and
//! validates the WGSL, `specialization` picks the pipeline a scene needs, `upload` puts a
//! scene's arrays on the device, `cut` cuts a frame into bounded dispatches, `render`
//! binds, dispatches band by band and reads back, and `resume` finishes the pixels whose
//! work did not fit one invocation.

pub mod context;
mod cut;
pub(crate) mod device;
mod pipeline;
pub mod render;
mod resume;
mod scene;
pub mod shaders;
pub mod specialization;
mod trace;
mod upload;

pub use context::{Choice, GpuContext, choose, is_software, open, open_on};
pub use render::{GpuRenderer, render_gpu};
pub use scene::GpuScene;
pub use trace::{trace, trace_on_device, trace_rows, trace_samples};
