//! gpurt's integration tests: one binary, one module (or directory) a subject, each file
//! under 800 lines, sharing the helpers of `common`; `architecture` checks the library's
//! module graph.

mod architecture;
mod bvh;
mod cli;
mod common;
mod cpu;
mod fuzzed;
mod gallery;
mod gpu;
mod hostile;
mod layout;
mod parse;
mod session;
mod shading;
mod spd;
/// The SPD generator example, for `spd`'s tests (its `main` goes unused here).
#[path = "../../examples/spd.rs"]
#[allow(dead_code)]
mod spd_example;
mod view;
mod window;
