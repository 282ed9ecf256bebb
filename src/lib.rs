//! gpurt: a Whitted ray tracer for NFF/SPD scenes and STL/OBJ meshes.
//!
//! Data flows one way: `scene` (readers, plain data) -> `bvh` -> `pack` (flat `#[repr(C)]`
//! buffers) -> a `frame` of it (camera and options) -> a `session::Renderer`: `gpu` (WGSL
//! compute) or `cpu` (the reference) -> `film` (images) -> `compare` (diffs). `run` strings
//! these together for the command line; `docs/api.md` shows the library.

pub mod agreement;
pub mod atomic;
pub mod batch;
pub mod bench;
pub mod bvh;
pub mod compare;
pub mod console;
pub mod counters;
pub mod cpu;
pub mod error;
pub mod fault;
pub mod film;
pub mod frame;
pub mod gpu;
pub mod gpu_types;
pub mod info;
pub mod limits;
pub mod pack;
pub mod run;
pub mod scene;
pub mod session;
pub mod shard;
pub mod view;

pub use error::{Error, Result};
