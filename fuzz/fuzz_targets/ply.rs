//! The PLY reader (ASCII and binary of either byte order) must return Ok or Err on any
//! bytes, never panic.
#![no_main]

use std::path::Path;

use gpurt::scene::io::FileKind;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = gpurt::scene::parse(data, FileKind::Ply, "fuzz.ply", Path::new("/nonexistent"));
});
