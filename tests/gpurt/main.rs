//! gpurt's integration tests: one binary, one module per area.

mod bvh;
mod cli;
mod common;
mod cpu;
mod fuzzed;
mod gallery;
mod gpu;
mod layout;
mod parse;
mod session;
mod view;
mod window;
