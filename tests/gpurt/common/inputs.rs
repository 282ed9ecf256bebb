//! Scene inputs the tests write: a valid NFF view to put entities after, the NFF reader
//! run on a string, meshes in each format, and files, gzip-compressed or not.

use std::io::Write;
use std::path::Path;

use glam::Vec3;
use gpurt::Error;
use gpurt::scene::{MaterialId, Scene, Triangle, nff};

/// A valid view on lines 1-5; entities after it start on line 6.
pub const VIEW: &str = "v\nfrom 0 -5 0\nat 0 0 0\nup 0 0 1\nangle 45\n";

pub fn parse_nff(src: &str) -> Result<Scene, Error> {
    nff::parse(src.as_bytes(), "t.nff", Path::new("."))
}

/// The position and message of the parse error `src` must give. Its excerpt is the text
/// of that line of `src`, the span at the column.
pub fn parse_error(src: &str) -> (u32, u32, String) {
    match parse_nff(src) {
        Err(e @ Error::Parse { .. }) => {
            let shown = e.to_string();
            let Error::Parse {
                file,
                line,
                col,
                msg,
                excerpt,
            } = e
            else {
                unreachable!()
            };
            assert_eq!(file, "t.nff");
            assert_eq!(shown, format!("t.nff:{line}:{col}: {msg}"), "error display");
            let x = excerpt.expect("a parse error carries its line");
            // The sources here are printable ASCII and short: the excerpt is the line, the
            // span starting at the column, tabs shown as spaces.
            let text = src
                .split(['\n', '\r'])
                .nth(line as usize - 1)
                .unwrap_or("")
                .replace('\t', " ");
            if src.is_ascii() && !src.contains('\r') && text.len() < 100 {
                assert_eq!(
                    x.text,
                    text.trim_start_matches('\u{feff}'),
                    "excerpt of {src:?}"
                );
                assert_eq!(x.span.start, col as usize - 1, "caret of {src:?}");
            }
            (line, col, msg)
        }
        other => panic!("expected a parse error for {src:?}, got {other:?}"),
    }
}

/// Asserts the error's line and column and that its message mentions every `words`.
#[track_caller]
pub fn assert_error(src: &str, line: u32, col: u32, words: &[&str]) {
    let (l, c, msg) = parse_error(src);
    assert_eq!((l, c), (line, col), "position of error {msg:?} in {src:?}");
    for w in words {
        assert!(msg.contains(w), "{msg:?} mentions {w:?}");
    }
}

pub fn parse_ok(src: &str) -> Scene {
    parse_nff(src).unwrap_or_else(|e| panic!("{src:?} should parse: {e}"))
}

pub fn tri(v: [[f32; 3]; 3], n: Option<[f32; 3]>) -> Triangle {
    Triangle {
        v: v.map(Vec3::from),
        n: n.map(|n| Box::new([Vec3::from(n); 3])),
        material: MaterialId(0),
        uv: None,
    }
}

/// A tetrahedron with unit facet normals, one facet without a normal.
pub fn tetra() -> Vec<Triangle> {
    let (o, x, y, z) = ([0., 0., 0.], [1., 0., 0.], [0., 1., 0.], [0., 0., 1.]);
    vec![
        tri([o, y, x], Some([0., 0., -1.])),
        tri([o, x, z], Some([0., -1., 0.])),
        tri([o, z, y], Some([-1., 0., 0.])),
        tri([x, y, z], None),
        // One more, far away, so bounds are not symmetric.
        tri(
            [[2., 3., 4.], [2.5, 3., 4.], [2., 3.5, 4.25]],
            Some([0., 0., 1.]),
        ),
    ]
}

pub fn ascii_stl(tris: &[Triangle]) -> String {
    let mut s = String::from("solid test part\n");
    for t in tris {
        let n = t.n.as_ref().map_or(Vec3::ZERO, |n| n[0]);
        // `{}` prints the shortest text that reads back as the same f32.
        s += &format!("  facet normal {} {} {}\n    outer loop\n", n.x, n.y, n.z);
        for v in t.v {
            s += &format!("      vertex {} {} {}\n", v.x, v.y, v.z);
        }
        s += "    endloop\n  endfacet\n";
    }
    s + "endsolid test part\n"
}

pub fn header(text: &[u8]) -> [u8; 80] {
    let mut h = [b' '; 80];
    h[..text.len()].copy_from_slice(text);
    h
}

/// A `.glb` of glTF JSON `json` and binary chunk `bin`, each padded to four bytes.
pub fn glb(json: &[u8], bin: &[u8]) -> Vec<u8> {
    let pad = |b: &[u8], with: u8| {
        let mut b = b.to_vec();
        b.resize(b.len().next_multiple_of(4), with);
        b
    };
    let (json, bin) = (pad(json, b' '), pad(bin, 0));
    let mut out = b"glTF".to_vec();
    for x in [
        2,
        28 + json.len() as u32 + bin.len() as u32,
        json.len() as u32,
    ] {
        out.extend(x.to_le_bytes());
    }
    out.extend(b"JSON");
    out.extend(json);
    out.extend((bin.len() as u32).to_le_bytes());
    out.extend(b"BIN\0");
    out.extend(bin);
    out
}

pub fn gzip(bytes: &[u8]) -> Vec<u8> {
    let mut e = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
    e.write_all(bytes).unwrap();
    e.finish().unwrap()
}

pub fn write(path: &Path, bytes: &[u8]) {
    std::fs::write(path, bytes).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
}

/// A white quad under ambient light 1 whose right edge runs through the centres of pixel
/// column 100 (x = 0.013465 on the plane, 200x200, 30 degrees): every sample count
/// covers half of that column, on average, within 0.02 (a k x ceil(n/k) grid with empty
/// cells gave 0.667 at 3 spp and 0.568 at 7). One sample sits on the edge itself, so its
/// value there is 0 or 1 by construction; it is checked on the columns beside it.
pub const HALF_COLUMN: &str = "v\nfrom 0 0 10\nat 0 0 0\nup 0 1 0\nangle 30\nresolution 200 200\n\
am 1 1 1\nb 0 0 0\nf 1 1 1 1 0 1 0 1\np 4\n-10 -10 0\n0.013465 -10 0\n0.013465 10 0\n-10 10 0\n";

/// A lit ball at 32 x 32: the scene the command line's tests render.
pub const SCENE: &str = "b 0.1 0.2 0.3
v
from 0 -4 1
at 0 0 0
up 0 0 1
angle 40
resolution 32 32
l 2 -3 4
f 1 0.5 0.2 0.8 0.2 20 0 1
s 0 0 0 1
";
