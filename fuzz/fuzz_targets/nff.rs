//! The NFF reader must return Ok or Err on any bytes, never panic or hang.
#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    // `mesh` paths resolve against a directory that does not exist, so inputs cannot make the
    // reader load files from the fuzzing machine (absolute paths aside).
    let _ = gpurt::scene::nff::parse(data, "fuzz.nff", Path::new("/nonexistent-gpurt-fuzz"));
});
