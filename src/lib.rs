//! gpurt: a Whitted ray tracer for NFF/SPD scenes and STL/OBJ meshes.
//!
//! Data flows one way: `scene` (readers, plain data) -> `bvh` -> `pack` (flat `#[repr(C)]`
//! buffers) -> a `frame` of it (camera and options) -> a `session::Renderer`: `gpu` (WGSL
//! compute) or `cpu` (the reference) -> `film` (images) -> `compare` (diffs). `run` strings
//! these together for the command line; `docs/api.md` shows the library.

//!
//! Without the default `native` feature (for `wasm32-unknown-unknown`, `web/`) the library
//! is its core: `scene`, `bvh`, `pack`, `frame`, `film`, `info`, `gpu` and the viewer's
//! camera; the CPU renderer, the sessions and the commands need threads and are left out.

#[cfg(feature = "native")]
pub mod agreement;
pub mod atomic;
#[cfg(feature = "native")]
pub mod batch;
#[cfg(feature = "native")]
pub mod bench;
pub mod bounded;
pub mod bvh;
#[cfg(feature = "native")]
pub mod compare;
pub mod console;
pub mod counters;
#[cfg(feature = "native")]
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
#[cfg(feature = "native")]
pub mod run;
pub mod scene;
#[cfg(feature = "native")]
pub mod session;
#[cfg(feature = "native")]
pub mod shard;
#[cfg(feature = "native")]
pub mod tune;
pub mod view;

pub use error::{Error, Result};
