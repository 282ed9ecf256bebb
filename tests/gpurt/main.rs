//! gpurt's integration tests: one binary, one module per area.

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
mod spd;
/// The SPD generator example, for `spd`'s tests (its `main` goes unused here).
#[path = "../../examples/spd.rs"]
#[allow(dead_code)]
mod spd_example;
mod view;
mod window;
