//! The interactive viewer, `gpurt view`. Everything but the window's edge knows nothing of
//! winit, so it is tested without one: the orbit camera (`camera`), the keys and modes
//! (`controls`), input scripts (`script`), progressive accumulation on a worker thread
//! (`progressive`), an animated scene's frames (`playback`), the wireframe that shares the ray tracer's camera (`wireframe`) and
//! the `--stats` figures (`stats`). At the edge, `window` runs the winit window and its
//! events, `input` turns winit's input into `controls::Action`s, and `surface` draws
//! frames into the window's wgpu surface (`readback` reads one back for a screenshot).
//! Data flows one way: `window` uses the others, none of them uses `window`.
//!
//! The camera and the controls are also the browser page's (`web/`), so they build
//! without the `native` feature; the rest needs threads or a window.

pub mod camera;
pub mod controls;
#[cfg(feature = "native")]
pub mod input;
#[cfg(feature = "native")]
pub mod playback;
#[cfg(feature = "native")]
pub mod progressive;
#[cfg(feature = "native")]
pub mod readback;
#[cfg(feature = "native")]
pub mod script;
#[cfg(feature = "native")]
pub mod stats;
#[cfg(feature = "native")]
pub mod surface;
#[cfg(feature = "native")]
pub mod window;
#[cfg(feature = "native")]
pub mod wireframe;
