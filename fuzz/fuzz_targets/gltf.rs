//! The glTF reader (JSON and .glb) must return Ok or Err on any bytes, never panic.
#![no_main]

use std::path::Path;

use gpurt::scene::io::FileKind;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = gpurt::scene::parse(data, FileKind::Gltf, "fuzz.gltf", Path::new("/nonexistent"));
});
