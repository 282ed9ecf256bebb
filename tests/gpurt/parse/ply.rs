//! PLY: the same mesh written in ASCII and in binary of either byte order gives the same
//! scene, value by value against the mesh as written; properties and elements gpurt does
//! not read are read past; normals, vertex and face colours; through a tiny buffer and the
//! `mesh` statement; and bad files, each a clear error at its place.

use std::path::Path;

use glam::Vec3;
use gpurt::Error;
use gpurt::scene::io::FileKind;
use gpurt::scene::{self, Material, ReadOptions, Scene};

use crate::common::{gpurt, temp_dir};

#[derive(Clone, Copy, PartialEq)]
pub(super) enum Format {
    Ascii,
    Little,
    Big,
}

/// A small mesh with what a PLY may carry: a 3 x 3 grid of vertices (on a bowl, with
/// normals and colours and a `confidence` gpurt skips) and faces of 3, 4 and 5 corners,
/// one with a colour of its own, each with a texture-coordinate list gpurt skips; an
/// `edge` element between them. Every value is exact in f32 and in decimal.
pub(super) struct Mesh {
    v: Vec<[f32; 3]>,
    n: Vec<[f32; 3]>,
    c: Vec<[u8; 3]>,
    faces: Vec<(Vec<u32>, [u8; 3])>,
}

pub(super) fn mesh() -> Mesh {
    let mut m = Mesh {
        v: Vec::new(),
        n: Vec::new(),
        c: Vec::new(),
        faces: Vec::new(),
    };
    for j in 0..3 {
        for i in 0..3 {
            let (x, y) = (i as f32 - 1.0, j as f32 - 1.0);
            m.v.push([x, y, 0.25 * (x * x + y * y)]);
            m.n.push([-0.5 * x, -0.5 * y, 1.0]);
            m.c.push([40 * i as u8, 100 + 50 * j as u8, 255]);
        }
    }
    // A face colour of 0 0 0 means "none" in `write` (faces carry one all the same).
    m.faces = vec![
        (vec![0, 1, 4], [0, 0, 0]),
        (vec![0, 4, 3], [0, 0, 0]),
        (vec![1, 2, 5, 4], [200, 10, 10]),
        (vec![3, 4, 7, 6], [0, 0, 0]),
        (vec![4, 5, 8, 7], [0, 0, 0]),
        (vec![0, 1, 2, 5, 4], [0, 0, 0]),
    ];
    m
}

/// The PLY of `m` in `format`; with `face_colour`, faces carry `red green blue`.
pub(super) fn write(m: &Mesh, format: Format, face_colour: bool) -> Vec<u8> {
    let name = match format {
        Format::Ascii => "ascii",
        Format::Little => "binary_little_endian",
        Format::Big => "binary_big_endian",
    };
    let mut out = format!(
        "ply\nformat {name} 1.0\ncomment written by the test\nelement vertex {}\n\
         property float x\nproperty float y\nproperty float z\nproperty float confidence\n\
         property float nx\nproperty float ny\nproperty float nz\n\
         property uchar red\nproperty uchar green\nproperty uchar blue\n\
         element face {}\nproperty list uchar int vertex_indices\nproperty list uchar float texcoord\n",
        m.v.len(),
        m.faces.len()
    );
    if face_colour {
        out += "property uchar red\nproperty uchar green\nproperty uchar blue\n";
    }
    out += "element edge 2\nproperty int vertex1\nproperty int vertex2\nend_header\n";
    let mut out = out.into_bytes();
    let big = format == Format::Big;
    let f = |out: &mut Vec<u8>, x: f32| {
        out.extend(if big {
            x.to_be_bytes()
        } else {
            x.to_le_bytes()
        })
    };
    let i = |out: &mut Vec<u8>, x: u32| {
        out.extend(if big {
            x.to_be_bytes()
        } else {
            x.to_le_bytes()
        })
    };
    for k in 0..m.v.len() {
        let (v, n, c) = (m.v[k], m.n[k], m.c[k]);
        if format == Format::Ascii {
            let line = format!(
                "{} {} {} 0.5 {} {} {} {} {} {}\n",
                v[0], v[1], v[2], n[0], n[1], n[2], c[0], c[1], c[2]
            );
            out.extend(line.bytes());
        } else {
            v.iter().for_each(|&x| f(&mut out, x));
            f(&mut out, 0.5);
            n.iter().for_each(|&x| f(&mut out, x));
            out.extend(c);
        }
    }
    for (corners, c) in &m.faces {
        if format == Format::Ascii {
            let ix: Vec<String> = corners.iter().map(u32::to_string).collect();
            let mut line = format!("{} {} 2 0.25 0.75", corners.len(), ix.join(" "));
            if face_colour {
                line += &format!(" {} {} {}", c[0], c[1], c[2]);
            }
            out.extend((line + "\n").bytes());
        } else {
            out.push(corners.len() as u8);
            corners.iter().for_each(|&x| i(&mut out, x));
            out.push(2);
            f(&mut out, 0.25);
            f(&mut out, 0.75);
            if face_colour {
                out.extend(c);
            }
        }
    }
    for e in [[0u32, 1], [1, 2]] {
        if format == Format::Ascii {
            out.extend(format!("{} {}\n", e[0], e[1]).bytes());
        } else {
            e.iter().for_each(|&x| i(&mut out, x));
        }
    }
    out
}

fn parse(bytes: &[u8], window: Option<usize>) -> Result<Scene, Error> {
    let opts = ReadOptions {
        window,
        ..ReadOptions::default()
    };
    scene::parse_with(bytes, FileKind::Ply, "m.ply", Path::new("."), &opts)
}

/// A face's colour as the reader must give it: its own, else its corners' mean.
fn expected_colour(m: &Mesh, face: usize, face_colour: bool) -> Vec3 {
    let (corners, own) = &m.faces[face];
    if face_colour {
        return Vec3::from(own.map(f32::from)) / 255.0;
    }
    let sum: Vec3 = corners
        .iter()
        .map(|&k| Vec3::from(m.c[k as usize].map(f32::from)) / 255.0)
        .sum();
    sum / corners.len() as f32
}

#[test]
fn ascii_and_binary_of_either_order_give_the_mesh_as_written() {
    let m = mesh();
    for face_colour in [false, true] {
        let ascii = parse(&write(&m, Format::Ascii, face_colour), None).expect("ASCII reads");
        for format in [Format::Little, Format::Big] {
            for window in [None, Some(32)] {
                let got = parse(&write(&m, format, face_colour), window).expect("binary reads");
                assert_eq!(got.triangles, ascii.triangles);
                assert_eq!(got.materials, ascii.materials);
            }
        }
        let tiny = parse(&write(&m, Format::Ascii, face_colour), Some(64)).expect("reads");
        assert_eq!(tiny.triangles, ascii.triangles);
        // Value by value against the mesh: every triangle's corners are its face's
        // vertices, with their unit normals, in the face's colour.
        let mut t = ascii.triangles.iter();
        for (f, (corners, _)) in m.faces.iter().enumerate() {
            let want = Material {
                color: expected_colour(&m, f, face_colour),
                ..Material::NEUTRAL_GREY
            };
            let positions: Vec<Vec3> = corners
                .iter()
                .map(|&k| Vec3::from(m.v[k as usize]))
                .collect();
            // An n-gon is n - 2 triangles, each in the face's colour, its corners the
            // face's with their normals made unit.
            for _ in 0..corners.len() - 2 {
                let tri = t.next().expect("a triangle for every ear");
                assert_eq!(ascii.materials[tri.material.0 as usize], want, "face {f}");
                let n = tri.n.as_deref().expect("shading normals");
                for (v, n) in tri.v.iter().zip(n) {
                    let k = positions
                        .iter()
                        .position(|p| p == v)
                        .expect("a corner of the face");
                    let written = Vec3::from(m.n[corners[k] as usize]);
                    assert!((*n - written.normalize()).length() < 1e-6, "face {f}");
                }
            }
        }
        assert!(t.next().is_none(), "no triangle beyond the faces'");
    }
}

/// `write` with the text `from` replaced by `to` (in the header, or an ASCII body).
fn edit(format: Format, from: &str, to: &str) -> Vec<u8> {
    let bytes = write(&mesh(), format, false);
    let at = bytes
        .windows(from.len())
        .position(|w| w == from.as_bytes())
        .unwrap_or_else(|| panic!("no {from:?} in the file"));
    [&bytes[..at], to.as_bytes(), &bytes[at + from.len()..]].concat()
}

fn error(bytes: &[u8]) -> String {
    match parse(bytes, None) {
        Ok(_) => panic!("read without an error"),
        Err(e) => e.to_string(),
    }
}

#[test]
fn bad_files_are_errors_at_their_place() {
    // Counts the rest of the file cannot hold, refused before reading any vertex.
    for format in [Format::Ascii, Format::Little] {
        let e = error(&edit(
            format,
            "element vertex 9",
            "element vertex 4000000000",
        ));
        assert!(
            e.starts_with("m.ply:4:1: 4000000000 'vertex' elements"),
            "{e}"
        );
        assert!(e.contains("more than the rest of the file holds"), "{e}");
    }
    let e = error(&edit(
        Format::Little,
        "element vertex 9",
        "element vertex 1000000000000",
    ));
    assert!(
        e.starts_with(
            "m.ply:4:16: expected the number of 'vertex' elements (an integer below 2^32)"
        ),
        "{e}"
    );
    // A truncated binary body: at the number it cuts, the last face's second texture
    // coordinate (two edges of 8 bytes after it).
    let whole = write(&mesh(), Format::Little, false);
    let e = error(&whole[..whole.len() - 18]);
    let at = whole.len() - 20;
    let want = format!("m.ply: at byte {at}: the file ends inside a 'face' element ('texcoord')");
    assert!(e.starts_with(&want), "{e}");
    // A face corner past the vertices: the index's line and column (21 header lines,
    // 9 vertices, the fifth face), or its byte (31 bytes a vertex).
    let e = error(&edit(Format::Ascii, "\n4 4 5 8 7", "\n4 4 5 9 7"));
    assert!(
        e.starts_with("m.ply:35:7: face 4 refers to vertex 9; the file has 9 before it"),
        "{e}"
    );
    let mut far = whole.clone();
    let header = far.windows(11).position(|w| w == b"end_header\n").unwrap() + 11;
    let first_face = header + 9 * 31;
    far[first_face + 1..first_face + 5].copy_from_slice(&77u32.to_le_bytes());
    let e = error(&far);
    assert!(
        e.starts_with(&format!(
            "m.ply: at byte {}: face 0 refers to vertex 77",
            first_face + 1
        )),
        "{e}"
    );
    // Data past the declared counts would be faces lost without a word.
    let e = error(&edit(Format::Ascii, "element face 6", "element face 5"));
    assert!(
        e.contains("after the last element the header declares"),
        "{e}"
    );
    let mut longer = whole.clone();
    longer.extend([0; 3]);
    assert!(error(&longer).contains("3 bytes after the last element"));
    // Not PLY at all, an unknown format or type, a point cloud.
    assert!(error(b"solid x\n").starts_with("m.ply:1:1: expected 'ply'"));
    let e = error(&edit(Format::Ascii, "format ascii", "format utf8"));
    assert!(
        e.starts_with("m.ply:2:8: expected ascii, binary_little_endian"),
        "{e}"
    );
    let e = error(&edit(Format::Ascii, "property float x", "property quad x"));
    assert!(e.starts_with("m.ply:5:10: expected a type"), "{e}");
    let e = error(b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\nend_header\n0 0 0\n");
    assert!(e.contains("no faces"), "{e}");
}

#[test]
fn degenerate_faces_are_dropped_with_a_warning_and_the_mesh_statement_places_ply() {
    let dir = temp_dir("ply-mesh");
    let bytes = String::from_utf8(write(&mesh(), Format::Ascii, false)).unwrap();
    let two = bytes.replace("\n3 0 4 3 2 0.25 0.75", "\n2 0 4 2 0.25 0.75");
    assert_ne!(two, bytes);
    std::fs::write(dir.join("m.ply"), &two).unwrap();
    let s = scene::load(&dir.join("m.ply")).expect("loads");
    assert!(
        s.warnings
            .iter()
            .any(|w| w.contains("m.ply:32:3: degenerate face 1 with 2 corners dropped")),
        "{:?}",
        s.warnings
    );
    std::fs::write(dir.join("m.ply"), &bytes).unwrap();
    let bare = scene::load(&dir.join("m.ply")).expect("loads");
    std::fs::write(
        dir.join("s.nff"),
        "v\nfrom 0 -5 3\nat 0 0 0\nup 0 0 1\nangle 40\nhither 0.01\nresolution 8 8\nl 1 1 5\n\
         f 1 0 0 1 0 0 0 0\nmesh m.ply translate 0 0 2\n",
    )
    .unwrap();
    let placed = scene::load(&dir.join("s.nff")).expect("the mesh statement reads PLY");
    assert_eq!(placed.triangles.len(), bare.triangles.len());
    for (a, b) in placed.triangles.iter().zip(&bare.triangles) {
        assert_eq!(a.v, b.v.map(|p| p + Vec3::new(0.0, 0.0, 2.0)));
    }
    // From the command line: a picture, or exit 2 and no picture.
    let out = gpurt(
        &[
            "m.ply",
            "-o",
            "m.png",
            "--width",
            "16",
            "--height",
            "16",
            "--backend",
            "cpu",
        ],
        &dir,
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(dir.join("m.png").is_file());
    std::fs::write(dir.join("bad.ply"), b"ply\nformat ascii 2.0\n").unwrap();
    let out = gpurt(&["bad.ply", "-o", "bad.png"], &dir);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("bad.ply:2:14: PLY version '2.0' is not read"),
        "{err}"
    );
    assert!(!dir.join("bad.png").exists());
}

/// Counts that would take long to go through are refused or take no time: an element of
/// no properties declared four billion times, a face of a million corners in a small file.
#[test]
fn hostile_counts_cost_nothing() {
    let started = std::time::Instant::now();
    let junk = edit(
        Format::Little,
        "element edge 2",
        "element junk 4000000000\nelement edge 2",
    );
    assert!(parse(&junk, None).is_ok());
    let mut long = edit(
        Format::Little,
        "list uchar int vertex_indices",
        "list uint int vertex_indices",
    );
    // The first face's length, now four bytes, says a million.
    let header = long.windows(11).position(|w| w == b"end_header\n").unwrap() + 11;
    let first_face = header + 9 * 31;
    long[first_face..first_face + 4].copy_from_slice(&1_000_000u32.to_le_bytes());
    let e = error(&long);
    assert!(e.contains("the file ends inside a 'face' element"), "{e}");
    assert!(started.elapsed().as_secs() < 5, "{:?}", started.elapsed());
}
