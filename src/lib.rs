//! gpurt: a Whitted ray tracer for NFF/SPD scenes and STL/OBJ meshes.
//!
//! Data flows one way: `scene` (readers, plain data) -> `bvh` -> `pack` (flat `#[repr(C)]`
//! buffers) -> `gpu` (WGSL compute) or `cpu` (the reference) -> `film` (images, diffs).

pub mod atomic;
pub mod bench;
pub mod bvh;
pub mod compare;
pub mod console;
pub mod cpu;
pub mod error;
pub mod film;
pub mod gpu;
pub mod gpu_types;
pub mod info;
pub mod pack;
pub mod render;
pub mod scene;
pub mod session;

pub use error::{Error, Result};
