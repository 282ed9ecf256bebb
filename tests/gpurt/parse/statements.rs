//! NFF statements as read: degenerate polygons dropped with a warning, lights, materials
//! and their defaults, numbers, line endings, P3D's `pl` and `aabb`, our extension lights
//! and ambient; what every text reader does with a byte-order mark and with control
//! characters; and every example of docs/scene-format.md reads as documented.

use std::path::Path;

use glam::Vec3;
use gpurt::Error;
use gpurt::scene::{BoxPrim, Light, Material, MaterialId, Plane, nff, obj, stl};

use crate::common::inputs::{VIEW, ascii_stl, gzip, parse_error, parse_ok, tetra, write};
use crate::common::temp_dir;

#[test]
fn degenerate_polygons_are_dropped_with_a_warning_naming_their_line() {
    let s = parse_ok(&format!(
        "{VIEW}p 3\n0 0 0\n1 1 1\n2 2 2\np 3\n0 0 0\n1 0 0\n0 1 0\n\n  pp 2\n0 0 0 0 0 1\n1 0 0 0 0 1\ns 0 0 0 0\n"
    ));
    assert_eq!(s.triangles.len(), 1);
    assert!(s.spheres.is_empty());
    assert_eq!(s.warnings.len(), 3, "{:?}", s.warnings);
    assert!(s.warnings[0].starts_with("t.nff:6:1: "), "{:?}", s.warnings);
    assert!(s.warnings[0].contains("degenerate polygon"));
    assert!(
        s.warnings[1].starts_with("t.nff:15:3: "),
        "{:?}",
        s.warnings
    );
    assert!(s.warnings[1].contains("degenerate patch"));
    assert!(
        s.warnings[2].starts_with("t.nff:18:1: "),
        "{:?}",
        s.warnings
    );
}

#[test]
fn lights_with_and_without_colour() {
    let s = parse_ok(&format!("l 1 2 3\nl 4 5 6 0.5 0.25 1\n{VIEW}l 7 8 9\n"));
    assert_eq!(
        s.lights,
        [
            Light::Point {
                position: Vec3::new(1.0, 2.0, 3.0),
                color: None
            },
            Light::Point {
                position: Vec3::new(4.0, 5.0, 6.0),
                color: Some(Vec3::new(0.5, 0.25, 1.0))
            },
            Light::Point {
                position: Vec3::new(7.0, 8.0, 9.0),
                color: None
            },
        ]
    );
}

#[test]
fn materials_default_sharing_and_zero_ior() {
    let s = parse_ok(&format!(
        "{VIEW}s 0 0 0 1\nf 1 0 0 0.5 0.5 10 0 0\ns 1 0 0 1\nf 0 1 0 1 0 1 0.5 1.5\nc 0 0 0 1 0 0 1 0.5\nf 1 0 0 0.5 0.5 10 0 0\ns 2 0 0 -1\n"
    ));
    // Before the first `f`: the documented default (white, Kd 1, Ks 0, Shine 1, T 0, ior 1).
    let default = Material {
        color: Vec3::ONE,
        kd: 1.0,
        ks: 0.0,
        shine: 1.0,
        t: 0.0,
        ior: 1.0,
        emission: Vec3::ZERO,
        texture: None,
        ambient: None,
    };
    assert_eq!(Material::DEFAULT, default);
    let m = |i: usize| s.materials[s.spheres[i].material.0 as usize];
    assert_eq!(m(0), default);
    // T = 0 with ior 0 is accepted; ior is then meaningless and stored as 1.
    assert_eq!(
        m(1),
        Material {
            color: Vec3::X,
            kd: 0.5,
            ks: 0.5,
            shine: 10.0,
            t: 0.0,
            ior: 1.0,
            emission: Vec3::ZERO,
            texture: None,
            ambient: None,
        }
    );
    let cone_m = s.materials[s.cones[0].material.0 as usize];
    assert_eq!((cone_m.t, cone_m.ior), (0.5, 1.5));
    // A repeated `f` reuses its material; a negative radius is stored as its size.
    assert_eq!(s.spheres[2].material, s.spheres[1].material);
    assert_eq!(s.spheres[2].radius, 1.0);
    assert_eq!(s.materials.len(), 3);
}

#[test]
fn numbers_with_exponents_and_signs() {
    let s = parse_ok(&format!("{VIEW}s 1e0 -2.5E-1 +3e+2 1.11022e-16\n"));
    assert_eq!(s.spheres[0].center, Vec3::new(1.0, -0.25, 300.0));
    assert_eq!(s.spheres[0].radius, 1.11022e-16);
}

#[test]
fn crlf_and_lone_cr_files_read_the_same_and_report_true_lines() {
    let src = format!(
        "# comment\nb 0.1 0.2 0.3\n{VIEW}hither 0.5\nresolution 320 240\nl 1 2 3 # trailing comment\nf 1 1 1 1 0 1 0 1\np 3\n0 0 0\n1 0 0\n0 1 0\n"
    );
    let lf = parse_ok(&src);
    assert_eq!(lf.triangles.len(), 1);
    assert_eq!(lf.lights.len(), 1, "a comment ends at its line's end");
    for eol in ["\r\n", "\r"] {
        let s = parse_ok(&src.replace('\n', eol));
        assert_eq!(s, lf, "line ending {eol:?}");
        // An error on line 16 is reported on line 16 whatever ends the lines.
        let bad = format!("{src}s 0 0 x 1\n").replace('\n', eol);
        let (line, col, _) = parse_error(&bad);
        assert_eq!((line, col), (16, 7), "line ending {eol:?}");
    }
}

#[test]
fn p3d_plane_and_box() {
    let s = parse_ok(&format!(
        "{VIEW}f 1 0 0 1 0 1 0 1\npl 0 0 -1 1 0 -1 0 1 -1\naabb 1 -1 2 3 -5 5\n"
    ));
    let m = MaterialId(0);
    assert_eq!(
        s.planes,
        [Plane {
            point: Vec3::new(0.0, 0.0, -1.0),
            normal: Vec3::Z,
            material: m
        }]
    );
    assert_eq!(
        s.boxes,
        [BoxPrim {
            min: Vec3::new(-1.0, 2.0, -5.0),
            max: Vec3::new(1.0, 3.0, 5.0),
            material: m
        }]
    );
}

#[test]
fn extension_lights_and_ambient() {
    let s = parse_ok(&format!(
        "{VIEW}dl 0 0 -2\ndl 1 0 0 1 0.5 0\nal 0 0 5 1 0 0 0 1 0 1 1 1 4 2\nam 0.1 0.2 0.3\n"
    ));
    assert_eq!(
        s.lights,
        [
            Light::Directional {
                direction: Vec3::NEG_Z,
                color: None
            },
            Light::Directional {
                direction: Vec3::X,
                color: Some(Vec3::new(1.0, 0.5, 0.0))
            },
            Light::Area {
                corner: Vec3::new(0.0, 0.0, 5.0),
                u: Vec3::X,
                v: Vec3::Y,
                color: Vec3::ONE,
                samples: [4, 2]
            },
        ]
    );
    assert_eq!(s.ambient, Some(Vec3::new(0.1, 0.2, 0.3)));
    assert_eq!(parse_ok(VIEW).ambient, None);
}

/// A leading UTF-8 byte-order mark is skipped by every text reader: the result is the one
/// without it, and columns on the first line count from the first visible character.
#[test]
fn byte_order_mark_is_accepted() {
    let bom = |s: &str| [b"\xEF\xBB\xBF".as_slice(), s.as_bytes()].concat();

    let nff_src = "v\nfrom 0 -4 1\nat 0 0 0\nup 0 0 1\nangle 40\nresolution 8 8\nl 1 2 3\n\
                   f 1 0 0 1 0 1 0 1\ns 0 0 0 1\n";
    let plain = nff::parse(nff_src.as_bytes(), "a.nff", Path::new(".")).expect("parses");
    let marked = nff::parse(&bom(nff_src), "a.nff", Path::new(".")).expect("parses with a BOM");
    assert_eq!(plain.spheres, marked.spheres);
    assert_eq!(plain.camera, marked.camera);
    let err = nff::parse(&bom("q 1 2\n"), "a.nff", Path::new(".")).unwrap_err();
    assert!(err.to_string().starts_with("a.nff:1:1:"), "{err}");

    let obj_src = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\nf 1 2 4\n";
    let plain = obj::parse(obj_src.as_bytes(), "a.obj").expect("parses");
    let marked = obj::parse(&bom(obj_src), "a.obj").expect("parses with a BOM");
    assert_eq!(plain, marked);
    assert_eq!(marked.len(), 2);

    let stl_src = ascii_stl(&tetra());
    let plain = stl::parse(stl_src.as_bytes(), "a.stl").expect("parses");
    let marked = stl::parse(&bom(&stl_src), "a.stl").expect("parses with a BOM as ASCII");
    assert_eq!(plain, marked);
}

/// Input quoted in a message, and the line excerpt shown under it, escape control
/// characters and bytes that are not UTF-8 one way, `\xNN`: an ESC sequence in a scene
/// file must not reach the terminal, and random bytes read the same wherever they stand.
#[test]
fn messages_escape_control_characters_and_bad_bytes_one_way() {
    let err = nff::parse(b"\x1b[31mred 1 2 3\n", "esc.nff", Path::new(".")).unwrap_err();
    let msg = err.to_string();
    assert!(!msg.contains('\x1b'), "{msg:?}");
    assert!(msg.contains("\\x1b[31mred"), "{msg:?}");
    let err = nff::parse(b"mesh \"a\x07b.ply\"\n", "esc.nff", Path::new(".")).unwrap_err();
    assert!(!err.to_string().contains('\x07'), "{err}");
    assert!(err.to_string().contains("a\\x07b.ply"), "{err}");
    let err = nff::parse(
        b"s 0 0 0 1\n\xff\xfe\x01zz\xc3\xa9 2\n",
        "rnd.nff",
        Path::new("."),
    )
    .unwrap_err();
    let msg = err.to_string();
    assert!(msg.ends_with("found '\\xff\\xfe\\x01zz\u{e9}'"), "{msg}");
    assert!(!msg.contains('\u{fffd}') && !msg.contains("\\u{"), "{msg}");
    let Error::Parse {
        excerpt: Some(x), ..
    } = err
    else {
        panic!("{err:?}")
    };
    assert_eq!(x.text, "\\xff\\xfe\\x01zz\u{e9} 2");
    assert_eq!(&x.text[x.span.clone()], "\\xff\\xfe\\x01zz\u{e9}");
}

// ---------------------------------------------------------------------------------------
// docs/scene-format.md: every example reads as documented
// ---------------------------------------------------------------------------------------

/// The fenced blocks of a Markdown text as (info string, body).
fn fenced_blocks(md: &str) -> Vec<(String, String)> {
    let mut blocks = Vec::new();
    let mut open: Option<(String, String)> = None;
    for line in md.lines() {
        match (&mut open, line.strip_prefix("```")) {
            (None, Some(info)) => open = Some((info.trim().to_string(), String::new())),
            (Some(_), Some(_)) => blocks.push(open.take().unwrap()),
            (Some((_, body)), None) => {
                body.push_str(line);
                body.push('\n');
            }
            (None, None) => {}
        }
    }
    assert!(open.is_none(), "unclosed code block");
    blocks
}

#[test]
fn docs_examples_read_as_documented() {
    let md =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/scene-format.md"))
            .expect("docs/scene-format.md reads");
    let dir = temp_dir("docs");
    let blocks = fenced_blocks(&md);
    let (mut parsed, mut errors) = (0, 0);
    for (i, (info, body)) in blocks.iter().enumerate() {
        match info.as_str() {
            "nff" => {
                // Mesh files the example names are made up: a tetrahedron in each format.
                for line in body.lines() {
                    let toks: Vec<&str> = line.split_whitespace().collect();
                    if toks.first() == Some(&"mesh") {
                        let path = dir.join(toks[1].trim_matches('"'));
                        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
                        let name = path.to_string_lossy().into_owned();
                        let bytes = if name.trim_end_matches(".gz").ends_with(".obj") {
                            b"v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n"
                                .to_vec()
                        } else {
                            stl::write_binary(&tetra(), &[0; 80])
                        };
                        let bytes = if name.ends_with(".gz") {
                            gzip(&bytes)
                        } else {
                            bytes
                        };
                        write(&path, &bytes);
                    }
                }
                let has_view = body
                    .lines()
                    .any(|l| l.split_whitespace().next() == Some("v"));
                let src = if has_view {
                    body.clone()
                } else {
                    format!("{VIEW}{body}")
                };
                let s = nff::parse(src.as_bytes(), "example.nff", &dir)
                    .unwrap_or_else(|e| panic!("docs example {i} should parse: {e}\n{body}"));
                assert!(s.warnings.is_empty(), "docs example {i}: {:?}", s.warnings);
                parsed += 1;
            }
            "nff-error" => {
                let (next_info, want) = blocks.get(i + 1).expect("a text block after nff-error");
                assert_eq!(next_info, "text", "docs example {i}: message block follows");
                let e = nff::parse(body.as_bytes(), "example.nff", &dir)
                    .expect_err("docs error example must fail");
                assert_eq!(e.to_string(), want.trim_end(), "docs example {i}");
                errors += 1;
            }
            _ => {}
        }
    }
    assert!(
        parsed >= 15 && errors >= 5,
        "{parsed} parsed, {errors} errors"
    );
}
