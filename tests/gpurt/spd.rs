//! The SPD generator of `examples/spd.rs` (mount and balls at any size) against the shared
//! SPD files: the same text, byte for byte, including mount beyond size 7, where the
//! original hash shifts by a negative count.

use std::io::Read;

use crate::common::shared_scenes;
use crate::spd_example::{Model, write_nff};

/// Generates `model` at `size` and compares it with `file` under the shared SPD folder
/// (gzip when it ends in `.gz`).
fn same_as_shared(model: Model, size: u32, file: &str) {
    let Some(dir) = shared_scenes() else { return };
    let path = dir.join("spd").join(file);
    let raw = std::fs::read(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let want = if file.ends_with(".gz") {
        let mut text = Vec::new();
        flate2::read::GzDecoder::new(raw.as_slice())
            .read_to_end(&mut text)
            .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        text
    } else {
        raw
    };
    let mut got = Vec::new();
    write_nff(model, size, &mut got).unwrap();
    if got != want {
        let line = |t: &[u8], n: usize| {
            String::from_utf8_lossy(t.split(|&b| b == b'\n').nth(n).unwrap_or(b"<end>"))
                .into_owned()
        };
        let n = got
            .split(|&b| b == b'\n')
            .zip(want.split(|&b| b == b'\n'))
            .position(|(a, b)| a != b)
            .unwrap_or_else(|| got.len().min(want.len()));
        panic!(
            "{file}: line {} differs: generated {:?}, shared {:?} ({} against {} bytes)",
            n + 1,
            line(&got, n),
            line(&want, n),
            got.len(),
            want.len()
        );
    }
}

#[test]
fn mount_3_matches_shared() {
    same_as_shared(Model::Mount, 3, "mount-3.nff");
}

/// Size 8 is the first where the hash's `A << (7 - size)` shifts by a negative count.
#[test]
fn mount_8_matches_shared() {
    same_as_shared(Model::Mount, 8, "mount-8.nff.gz");
}

#[test]
fn balls_2_matches_shared() {
    same_as_shared(Model::Balls, 2, "balls-2.nff");
}

#[test]
fn balls_4_matches_shared() {
    same_as_shared(Model::Balls, 4, "balls-4.nff");
}
