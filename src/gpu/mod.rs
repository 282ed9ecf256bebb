//! The GPU renderer: WGSL compute through wgpu on the same `SceneBuffers` the CPU
//! reference traverses.
//!
//! Each module imports only modules listed before it here, so the arrows run one way:
//! - `context` finds an adapter and opens a device; `cache` says where what is learnt
//!   about an adapter is kept between runs;
//! - `device` is the one door to wgpu's device and queue: `Device` (what is made on the
//!   device, error scopes, waits, readbacks; the viewer uses it too) and `Gpu` (with the
//!   queue: writes and submissions). No other module calls a method of either
//!   (`tests/gpurt/architecture/door.rs`); the public entry points take wgpu's device and
//!   queue and hand them to the door;
//! - `shaders` assembles and validates the WGSL; `specialization` picks the pipeline a
//!   scene needs;
//! - `cut` cuts a frame into bounded dispatches, bands and submissions; `policy` says
//!   which walk and which kernels a frame takes on an adapter, and how it is cut;
//!   `tuning` keeps what `gpurt tune` measured fastest on an adapter, in place of
//!   `policy`'s defaults;
//! - `upload` puts a scene's arrays on the device;
//! - `pipeline` owns the bind group layouts, the shader modules, the compiling of entry
//!   points and the on-disk pipeline cache;
//! - `wavefront` owns the wavefront kernels' pipelines and a scene's wave of paths;
//! - `scene` holds a scene's GPU state (`GpuScene`) and what a frame binds besides it;
//! - `resume` finishes the pixels whose work did not fit one invocation;
//! - `waves` runs a band's tiles through the wavefront kernels, wave by wave;
//! - `trace` is the dispatch loop: band by band, then the readback;
//! - `renderer` (`GpuRenderer`) uploads scenes, moves them to other frames and compiles
//!   and warms up the pipelines they need;
//! - `oneshot` renders a frame from buffers to a film in one blocking call (natively).

mod cache;
pub mod context;
mod cut;
pub(crate) mod device;
#[cfg(feature = "native")]
mod oneshot;
mod pipeline;
mod policy;
mod renderer;
mod resume;
mod scene;
pub mod shaders;
pub mod specialization;
mod trace;
pub mod tuning;
mod upload;
mod wavefront;
#[cfg(feature = "native")]
mod waves;

pub use context::{
    Choice, GpuContext, choose, instance, is_software, on_any_backend, open, open_on,
    quiet_device_select, request,
};
pub use cut::DISPATCH_BUDGET;
#[cfg(feature = "native")]
pub use oneshot::render_gpu;
pub use policy::{Kernels, Strategy, defaults};
pub use renderer::GpuRenderer;
pub use scene::GpuScene;
#[cfg(feature = "native")]
pub use trace::{trace, trace_rows};
pub use trace::{trace_on_device, trace_rows_async};
