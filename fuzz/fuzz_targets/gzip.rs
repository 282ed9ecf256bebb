//! The gzip layer the loader reads every file through (`scene::io::decompress`, as `read_file`
//! calls it) must return Ok or Err on any bytes, never panic, hang or allocate past its
//! limit; what it returns is parsed as NFF, as `load` would.
#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;

/// Far below the loader's 4 GiB, so that a gzip bomb costs a millisecond, not the run.
const LIMIT: u64 = 1 << 20;

fuzz_target!(|data: &[u8]| {
    let gzipped = data.starts_with(&[0x1f, 0x8b]);
    match gpurt::scene::io::decompress(data.to_vec(), Path::new("fuzz.nff.gz"), LIMIT) {
        Ok(bytes) => {
            assert!(bytes.len() as u64 <= LIMIT, "output past the limit");
            if !gzipped {
                assert_eq!(bytes, data, "plain input must pass through unchanged");
            }
            let _ =
                gpurt::scene::nff::parse(&bytes, "fuzz.nff", Path::new("/nonexistent-gpurt-fuzz"));
        }
        Err(_) => assert!(gzipped, "plain input must never fail"),
    }
});
