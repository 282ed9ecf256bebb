//! The STL reader (binary and ASCII) must return Ok or Err on any bytes, never panic.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = gpurt::scene::stl::parse(data, "fuzz.stl");
});
