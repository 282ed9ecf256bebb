//! gpurt's integration tests: one binary, one module (or directory) a subject, each file
//! under 800 lines, sharing the helpers of `common`; `architecture` checks the library's
//! module graph.

mod architecture;
mod bare;
mod bvh;
mod cli;
mod common;
mod cpu;
/// The generated scenes of the memory benchmarks, for `memory`'s guard (its `main` goes
/// unused here).
#[path = "../../examples/field.rs"]
#[allow(dead_code)]
mod field_example;
mod fuzzed;
mod gallery;
mod gpu;
mod hostile;
mod layout;
mod memory;
mod packet;
mod parse;
mod session;
mod shading;
mod spd;
/// The SPD generator example, for `spd`'s tests (its `main` goes unused here).
#[path = "../../examples/spd.rs"]
#[allow(dead_code)]
mod spd_example;
mod texture;
mod texture_files;
mod view;
mod window;
