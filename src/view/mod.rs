//! The interactive viewer, `gpurt view`. Everything but the window's edge knows nothing of
//! winit, so it is tested without one: the orbit camera (`camera`), the keys and modes
//! (`controls`), input scripts (`script`), progressive accumulation on a worker thread
//! (`progressive`), the wireframe that shares the ray tracer's camera (`wireframe`) and
//! the `--stats` figures (`stats`). At the edge, `window` runs the winit window and its
//! events, `input` turns winit's input into `controls::Action`s, and `surface` draws
//! frames into the window's wgpu surface (`readback` reads one back for a screenshot).
//! Data flows one way: `window` uses the others, none of them uses `window`.

pub mod camera;
pub mod controls;
pub mod input;
pub mod progressive;
pub mod readback;
pub mod script;
pub mod stats;
pub mod surface;
pub mod window;
pub mod wireframe;
