//! Formats told by their first bytes as well as their names: PLY and glTF read as such
//! whatever the name, and what gpurt does not read named as what it is, before any reader
//! sees it.

use std::path::Path;

use gpurt::scene::io::FileKind;
use gpurt::scene::{self, load};

use super::ply::{Format, mesh, write};
use crate::common::temp_dir;

#[test]
fn a_ply_file_is_read_as_ply_whatever_its_name_and_gzip_too() {
    let dir = temp_dir("sniff-ply");
    let bytes = write(&mesh(), Format::Little, false);
    std::fs::write(dir.join("m.ply"), &bytes).unwrap();
    std::fs::write(dir.join("scan.nff"), &bytes).unwrap();
    std::fs::write(dir.join("scan.ply.gz"), crate::common::inputs::gzip(&bytes)).unwrap();
    let want = load(&dir.join("m.ply")).expect("reads").triangles;
    assert!(!want.is_empty());
    for name in ["scan.nff", "scan.ply.gz"] {
        assert_eq!(
            load(&dir.join(name)).expect("reads").triangles,
            want,
            "{name}"
        );
    }
    // Bytes in memory, given as another kind.
    let s = scene::parse(&bytes, FileKind::Nff, "s", Path::new(".")).expect("reads");
    assert_eq!(s.triangles, want);
}

#[test]
fn formats_gpurt_does_not_read_are_named() {
    let reads = "gpurt reads NFF, STL, OBJ, PLY and glTF";
    for (name, bytes, what) in [
        ("x.nff", &b"\x89PNG\r\n\x1a\n...."[..], "a PNG image"),
        ("m.nff", b"  {\"a\": 1}", "a JSON file"),
        ("m.zip", b"PK\x03\x04rest", "a zip archive"),
        ("m.fbx", b"Kaydara FBX Binary  \0", "an FBX file"),
        ("m.fbx", b"anything", "an FBX file"),
        ("m.3ds", b"MM\0\0", "a 3DS file"),
        ("m.blend.gz", b"whatever", "a Blender file"),
    ] {
        let e = scene::parse(bytes, FileKind::Nff, name, Path::new("."))
            .expect_err(name)
            .to_string();
        assert_eq!(e, format!("{name}: {what}; {reads}"));
    }
    // glTF by its JSON or its magic, whatever the name; a .gltf whose "asset" key comes
    // late is still glTF.
    for (name, bytes) in [
        ("duck.nff", &b"{\"asset\":{\"version\":\"2.0\"}}"[..]),
        ("duck.bin", b"glTF\x02\0\0\0"),
        ("late.gltf", b"{\"scenes\": []}"),
    ] {
        let e = scene::parse(bytes, FileKind::of(Path::new(name)), name, Path::new("."))
            .expect_err(name)
            .to_string();
        assert!(
            !e.contains(reads) && !e.contains("entity keyword"),
            "{name}: {e}"
        );
    }
    // An NFF file is not mistaken for anything.
    let nff =
        b"v\nfrom 0 0 5\nat 0 0 0\nup 0 1 0\nangle 40\nl 1 1 1\nf 1 0 0 1 0 0 0 0\ns 0 0 0 1\n";
    assert!(scene::parse(nff, FileKind::Nff, "s.nff", Path::new(".")).is_ok());
}
