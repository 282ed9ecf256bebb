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

pub mod bvh;
pub mod commands;
#[cfg(feature = "native")]
pub mod compare;
pub mod counters;
#[cfg(feature = "native")]
pub mod cpu;
pub mod film;
pub mod frame;
pub mod gpu;
pub mod gpu_types;
pub mod pack;
pub mod scene;
#[cfg(feature = "native")]
pub mod session;
pub mod util;
pub mod view;

// The layers' modules under their old names, for the Python module, the browser page,
// the benches, the examples and the tests.
pub use commands::info;
#[cfg(feature = "native")]
pub use commands::{batch, bench, run, shard, tune};
#[cfg(feature = "native")]
pub use compare::agreement;
pub use util::error::{Error, Result};
pub use util::{atomic, bounded, console, error, fault, limits};
