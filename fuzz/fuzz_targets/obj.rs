//! The OBJ reader must return Ok or Err on any bytes, never panic.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = gpurt::scene::obj::parse(data, "fuzz.obj");
});
