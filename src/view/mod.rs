//! The interactive viewer, `gpurt view`. Everything but the window knows nothing of
//! winit, so it is tested without one: the orbit camera (`camera`), the keys and modes
//! (`controls`), input scripts (`script`), progressive accumulation on a worker thread
//! (`progressive`) and the wireframe that shares the ray tracer's camera (`wireframe`).
//! `window` joins them to a winit window and a wgpu surface.

pub mod camera;
pub mod controls;
pub mod progressive;
pub mod readback;
pub mod script;
pub mod window;
pub mod wireframe;
