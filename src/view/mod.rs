//! What the interactive viewer is made of, apart from its window: the orbit camera
//! (`camera`) and the wireframe that shares the ray tracer's camera (`wireframe`).

pub mod camera;
pub mod wireframe;
