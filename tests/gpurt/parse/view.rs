//! The NFF view block: every option read, the defaults without them, and each way a view
//! can be missing or degenerate reported where it stands.

use glam::Vec3;

use crate::common::inputs::{VIEW, assert_error, parse_ok};

#[test]
fn view_errors() {
    // No `v` at all: reported at the end of the file.
    assert_error("s 0 0 0 1\n", 2, 1, &["view"]);
    assert_error("", 1, 1, &["view"]);
    // Degenerate views are reported at their `v`.
    assert_error(
        "b 0 0 0\nv\nfrom 1 2 3\nat 1 2 3\nup 0 0 1\nangle 45\n",
        2,
        1,
        &["'from' and 'at'"],
    );
    assert_error(
        "v\nfrom 0 0 5\nat 0 0 0\nup 0 0 2\nangle 45\n",
        1,
        1,
        &["parallel"],
    );
    assert_error(
        "v\nfrom 0 0 5\nat 0 0 0\nup 0 0 0\nangle 45\n",
        1,
        1,
        &["'up' is zero"],
    );
    assert_error(
        "v\nfrom 0 0 5\nat 0 0 0\nangle 45\n",
        1,
        1,
        &["missing 'up'"],
    );
    for bad in ["0", "180", "200", "-10"] {
        assert_error(
            &format!("v\nfrom 0 -5 0\nat 0 0 0\nup 0 0 1\nangle {bad}\n"),
            5,
            7,
            &["view angle", bad],
        );
    }
    assert_error(
        &format!("{VIEW}resolution 0 512\n"),
        6,
        12,
        &["resolution", "found 0"],
    );
    assert_error(
        &format!("{VIEW}resolution 512 100000\n"),
        6,
        16,
        &["resolution", "found 100000"],
    );
    assert_error(&format!("{VIEW}focal 0\n"), 6, 7, &["focal"]);
}

#[test]
fn view_with_every_option() {
    let s = parse_ok(
        "v\nfrom 1 -5 2\nat 1 0 2\nup 0 0 1\nangle 30\nhither 0.25\nresolution 640 480\naperture 0.5\nfocal 7\n",
    );
    let c = &s.camera;
    assert_eq!(
        (c.from, c.at, c.up),
        (Vec3::new(1.0, -5.0, 2.0), Vec3::new(1.0, 0.0, 2.0), Vec3::Z)
    );
    assert_eq!(
        (c.angle, c.hither, c.width, c.height),
        (30.0, 0.25, 640, 480)
    );
    assert_eq!((c.aperture, c.focal), (0.5, Some(7.0)));
    // Without them: a pinhole focused at `at`, 512x512.
    let s = parse_ok(VIEW);
    let c = &s.camera;
    assert_eq!(
        (c.aperture, c.focal, c.width, c.height),
        (0.0, None, 512, 512)
    );
    assert_eq!(c.focal_distance(), 5.0);
}
