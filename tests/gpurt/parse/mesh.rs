//! Meshes: binary and ASCII STL, OBJ, the NFF `mesh` statement that places them, and bare
//! meshes that become scenes of their own.

use glam::Vec3;
use gpurt::Error;
use gpurt::scene::{self, Triangle, nff, obj, stl};

use crate::common::inputs::{VIEW, ascii_stl, gzip, header, tetra, tri, write};
use crate::common::temp_dir;

#[test]
fn stl_binary_ascii_and_solid_headed_binary_give_the_same_triangles() {
    let tris = tetra();
    let plain = stl::write_binary(&tris, &header(b"binary part"));
    let solid = stl::write_binary(&tris, &header(b"solid but binary"));
    let ascii = ascii_stl(&tris);
    for (what, bytes) in [
        ("binary", &plain[..]),
        ("binary with a 'solid' header", &solid[..]),
        ("ascii", ascii.as_bytes()),
        ("ascii with CRLF", ascii.replace('\n', "\r\n").as_bytes()),
    ] {
        let got = stl::parse(bytes, "t.stl").unwrap_or_else(|e| panic!("{what}: {e}"));
        // Facet normals are kept; the zero normal written for the fourth facet is `None`.
        assert_eq!(got, tris, "{what}");
    }
    // Normals are normalised, zero and non-finite ones dropped.
    let odd = [
        tri(
            [[0., 0., 0.], [1., 0., 0.], [0., 1., 0.]],
            Some([0., 0., 2.]),
        ),
        tri(
            [[0., 0., 0.], [1., 0., 0.], [0., 1., 0.]],
            Some([f32::NAN, 0., 1.]),
        ),
    ];
    let got = stl::parse(&stl::write_binary(&odd, &[0; 80]), "t.stl").unwrap();
    assert_eq!(got[0].n.as_deref(), Some(&[Vec3::Z; 3]));
    assert_eq!(got[1].n, None);
}

#[test]
fn broken_binary_stl_reports_byte_offsets() {
    let tris = tetra();
    for h in [header(b"part"), header(b"solid part")] {
        let full = stl::write_binary(&tris, &h);
        // Truncated inside the third triangle: reported where the data stops.
        let cut = &full[..84 + 50 * 2 + 20];
        match stl::parse(cut, "t.stl") {
            Err(Error::Binary { offset, msg, .. }) => {
                assert_eq!(offset, cut.len() as u64);
                assert!(msg.contains("triangle 3 of 5"), "{msg}");
            }
            other => panic!("expected a binary error, got {other:?}"),
        }
        // A count that claims more triangles than the file holds.
        let mut more = full.clone();
        more[80..84].copy_from_slice(&9u32.to_le_bytes());
        match stl::parse(&more, "t.stl") {
            Err(Error::Binary { offset, msg, .. }) => {
                assert_eq!(offset, more.len() as u64);
                assert!(msg.contains("triangle 6 of 9"), "{msg}");
            }
            other => panic!("expected a binary error, got {other:?}"),
        }
        // A count that claims fewer: reported at the count.
        let mut fewer = full.clone();
        fewer[80..84].copy_from_slice(&2u32.to_le_bytes());
        match stl::parse(&fewer, "t.stl") {
            Err(Error::Binary { offset, msg, .. }) => {
                assert_eq!(offset, 80);
                assert!(msg.contains("2 triangles"), "{msg}");
            }
            other => panic!("expected a binary error, got {other:?}"),
        }
    }
    match stl::parse(b"not an stl", "t.stl") {
        Err(Error::Binary { offset, .. }) => assert_eq!(offset, 10),
        other => panic!("expected a binary error, got {other:?}"),
    }
    // A non-finite vertex is reported at that vertex.
    let mut nan = stl::write_binary(&tris, &[0; 80]);
    let at = 84 + 50 + 12 + 4;
    nan[at..at + 4].copy_from_slice(&f32::NAN.to_le_bytes());
    match stl::parse(&nan, "t.stl") {
        Err(Error::Binary { offset, .. }) => assert_eq!(offset, 84 + 50 + 12),
        other => panic!("expected a binary error, got {other:?}"),
    }
}

#[test]
fn ascii_stl_errors_have_positions() {
    let src = "solid x\nfacet normal 0 0 1\n outer loop\n  vertex 0 0 0\n  vertex 1 0 0\n  vertex 0 1 zz\n";
    match stl::parse(src.as_bytes(), "t.stl") {
        Err(Error::Parse { line, col, msg, .. }) => {
            assert_eq!((line, col), (6, 14), "{msg}");
            assert!(msg.contains("'zz'"));
        }
        other => panic!("expected a parse error, got {other:?}"),
    }
    let src = "solid x\nfacet normal 0 0 1\n outer loop\n  vertex 0 0 0\n";
    match stl::parse(src.as_bytes(), "t.stl") {
        Err(Error::Parse { line, col, msg, .. }) => {
            assert_eq!((line, col), (5, 1), "{msg}");
            assert!(
                msg.contains("'vertex'") && msg.contains("end of file"),
                "{msg}"
            );
        }
        other => panic!("expected a parse error, got {other:?}"),
    }
}

fn area(tris: &[Triangle]) -> f32 {
    tris.iter().map(Triangle::area).sum()
}

#[test]
fn obj_normals_quads_and_concave_faces() {
    let src = "\
# a triangle with normals, a quad and a concave L-shaped hexagon
v 0 0 0
v 1 0 0
v 0 1 0
vn 0 0 2
vn 0 0 1
vn 0 1 1
f 1//1 2//2 3//3
v 0 0 1
v 2 0 1
v 2 1 1
v 0 1 1
f 4 5 6 7
v 0 0 2
v 2 0 2
v 2 1 2
v 1 1 2
v 1 2 2
v 0 2 2
f 8 9 10 11 12 13
";
    let tris = obj::parse(src.as_bytes(), "t.obj").unwrap();
    assert_eq!(tris.len(), 1 + 2 + 4);
    let d = 1.0 / 2f32.sqrt();
    assert_eq!(
        tris[0].n.as_deref(),
        Some(&[Vec3::Z, Vec3::Z, Vec3::new(0.0, d, d)]),
        "per-vertex normals kept, normalised"
    );
    assert_eq!(
        tris[0].v,
        [Vec3::ZERO, Vec3::X, Vec3::Y],
        "vertex order kept"
    );
    let quad: Vec<Triangle> = tris.iter().filter(|&t| t.v[0].z == 1.0).cloned().collect();
    let ell: Vec<Triangle> = tris.iter().filter(|&t| t.v[0].z == 2.0).cloned().collect();
    assert_eq!((quad.len(), ell.len()), (2, 4));
    assert!((area(&quad) - 2.0).abs() < 1e-6);
    assert!((area(&ell) - 3.0).abs() < 1e-6, "concave face: no fan");
    for t in quad.iter().chain(&ell) {
        assert!(t.n.is_none());
        assert!(t.cross().z > 0.0, "winding kept: {t:?}");
    }
    // Negative indices count back from the latest vertex; forward references work.
    let rel = obj::parse(b"f 1 2 3\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf -3 -2 -1\n", "t.obj").unwrap();
    assert_eq!(rel.len(), 2);
    assert_eq!(rel[0], rel[1]);
    // Errors point at the offending corner or the end of a short line.
    for (src, line, col, words) in [
        (
            "v 0 0 0\nv 1 0 0\nf 1 2 9\n",
            3,
            7,
            "vertex that does not exist",
        ),
        (
            "v 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 2 -4\n",
            4,
            7,
            "vertex that does not exist",
        ),
        (
            "v 0 0 0\nvn 0 0 1\nf 1//1 1//2 1//1\n",
            3,
            8,
            "normal that does not exist",
        ),
        (
            "v 0 0 0\nvt 0 0\nf 1/1 1/2 1/1\n",
            3,
            7,
            "texture coordinate that does not exist (the file has 1)",
        ),
        ("v 0 0 0\nvt 0 x\n", 2, 6, "number"),
        ("v 0 0 0\nf 1 0 1\n", 2, 5, "face corner"),
        ("v 0 0 0\nf 1 a/b 1\n", 2, 5, "'a/b'"),
        ("v 0 0\nv 1 1 1\n", 1, 6, "end of line"),
        ("v 0 0 0\nvn 0 nan 1\n", 2, 6, "finite"),
    ] {
        match obj::parse(src.as_bytes(), "t.obj") {
            Err(e @ Error::Parse { .. }) => {
                let msg = e.to_string();
                assert!(
                    msg.starts_with(&format!("t.obj:{line}:{col}: ")),
                    "{src:?}: {msg}"
                );
                assert!(msg.contains(words), "{src:?}: {msg}");
            }
            other => panic!("expected a parse error for {src:?}, got {other:?}"),
        }
    }
}

/// OBJ faces with two corners, or with collinear corners, are dropped with a warning
/// naming where they are, as NFF's degenerate polygons are.
#[test]
fn degenerate_obj_faces_are_dropped_with_a_warning() {
    let src = "v 0 0 0\nv 1 0 0\nv 2 0 0\nv 0 1 0\nf 1 2\nf 1 2 3\nf 1 2 4\n";
    let mesh = obj::parse_with_warnings(src.as_bytes(), "d.obj").expect("parses");
    assert_eq!(mesh.triangles.len(), 1);
    assert_eq!(
        mesh.warnings,
        [
            "d.obj:5:3: degenerate face with 2 corners dropped",
            "d.obj:6:3: degenerate face with 3 corners dropped"
        ]
    );
    let dir = temp_dir("degenerate-obj");
    std::fs::write(dir.join("d.obj"), src).unwrap();
    let scene = scene::load(&dir.join("d.obj")).expect("loads");
    assert_eq!(scene.warnings.len(), 2, "{:?}", scene.warnings);
}

#[test]
fn missing_mesh_file_points_at_the_path() {
    let dir = temp_dir("missing-mesh");
    let src = format!("{VIEW}f 1 1 1 1 0 1 0 1\nmesh nope.stl scale 2\n");
    match nff::parse(src.as_bytes(), "t.nff", &dir) {
        Err(Error::Parse { line, col, msg, .. }) => {
            assert_eq!((line, col), (7, 6), "{msg}");
            assert!(msg.contains("nope.stl"), "{msg}");
        }
        other => panic!("expected a parse error, got {other:?}"),
    }
    // A path that is not a mesh format is refused before anything is read.
    let src = format!("{VIEW}mesh other.nff\n");
    match nff::parse(src.as_bytes(), "t.nff", &dir) {
        Err(Error::Parse { line, col, msg, .. }) => {
            assert_eq!((line, col), (6, 6));
            assert!(msg.contains(".stl, .obj or .ply"), "{msg}");
        }
        other => panic!("expected a parse error, got {other:?}"),
    }
}

#[test]
fn mesh_statement_places_meshes_with_the_current_material() {
    let dir = temp_dir("mesh-statement");
    std::fs::create_dir_all(dir.join("parts")).unwrap();
    let one = [tri(
        [[1., 0., 0.], [0., 1., 0.], [0., 0., 1.]],
        Some([0., 0., 1.]),
    )];
    write(
        &dir.join("parts/one.stl"),
        &stl::write_binary(&one, &[0; 80]),
    );
    write(
        &dir.join("parts/one.stl.gz"),
        &gzip(&stl::write_binary(&one, &[0; 80])),
    );
    write(
        &dir.join("parts/one.obj"),
        b"v 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\n",
    );
    let src = format!(
        "{VIEW}f 1 0 0 1 0 1 0 1\nmesh parts/one.stl translate 1 2 3 rotate 0 0 90 scale 2\nf 0 1 0 1 0 1 0 1\nmesh \"parts/one.stl.gz\"\nmesh parts/one.obj scale 1 2 3 rotate 90 0 0\n"
    );
    write(&dir.join("scene.nff"), src.as_bytes());
    let s = scene::load(&dir.join("scene.nff")).unwrap();
    assert_eq!(s.triangles.len(), 3);
    let close = |a: Vec3, b: Vec3| (a - b).length() < 1e-5;
    // Scale 2, then 90 degrees about Z ((x, y, z) -> (-y, x, z)), then translate (1, 2, 3).
    let want = [
        Vec3::new(1.0, 4.0, 3.0),
        Vec3::new(-1.0, 2.0, 3.0),
        Vec3::new(1.0, 2.0, 5.0),
    ];
    let t = &s.triangles;
    assert!(
        t[0].v.iter().zip(want).all(|(&a, b)| close(a, b)),
        "{:?}",
        t[0].v
    );
    assert!(
        close(t[0].n.as_ref().unwrap()[0], Vec3::Z),
        "normal turned with the mesh"
    );
    assert_eq!(t[1].v, one[0].v, "gzip mesh, no transform");
    // Scale (1, 2, 3), then 90 degrees about X ((x, y, z) -> (x, -z, y)).
    let want = [
        Vec3::new(1.0, 0.0, 0.0),
        Vec3::new(0.0, 0.0, 2.0),
        Vec3::new(0.0, -3.0, 0.0),
    ];
    assert!(
        t[2].v.iter().zip(want).all(|(&a, b)| close(a, b)),
        "{:?}",
        t[2].v
    );
    let color = |i: usize| s.materials[t[i].material.0 as usize].color;
    assert_eq!((color(0), color(1), color(2)), (Vec3::X, Vec3::Y, Vec3::Y));
}

/// A bare mesh becomes a scene: a camera aimed near the mesh's centre that sees all of it
/// (how closely it fits: `bare.rs`), a light, and a ground plane just under the lowest
/// point along the format's up axis.
#[test]
fn bare_meshes_get_a_camera_light_and_ground() {
    let dir = temp_dir("bare-mesh");
    let tris = tetra();
    write(&dir.join("x.stl"), &stl::write_binary(&tris, &[0; 80]));
    let mut obj_src = String::new();
    for t in &tris {
        for v in t.v {
            obj_src += &format!("v {} {} {}\n", v.x, v.y, v.z);
        }
    }
    for i in 0..tris.len() {
        obj_src += &format!("f {} {} {}\n", 3 * i + 1, 3 * i + 2, 3 * i + 3);
    }
    write(&dir.join("x.obj"), obj_src.as_bytes());
    for (name, up) in [("x.stl", Vec3::Z), ("x.obj", Vec3::Y)] {
        let s = scene::load(&dir.join(name)).unwrap();
        assert_eq!(s.triangles.len(), tris.len(), "{name}");
        let b = s.bounds();
        let c = &s.camera;
        let view = (c.at - c.from).normalize();
        let miss = (b.center() - c.from).reject_from(view).length();
        assert!(
            miss < 0.1 * b.extent().length(),
            "{name}: aims near the centre ({miss})"
        );
        assert_eq!(c.up, up, "{name}");
        assert!(!s.lights.is_empty(), "{name}: has a light");
        // Every corner of the bounds is inside the frame.
        let right = view.cross(c.up).normalize();
        let cam_up = right.cross(view);
        let half = (c.angle.to_radians() / 2.0).tan() * c.height as f32 / (c.height - 1) as f32;
        for i in 0..8 {
            let corner = Vec3::new(
                if i & 1 == 0 { b.min.x } else { b.max.x },
                if i & 2 == 0 { b.min.y } else { b.max.y },
                if i & 4 == 0 { b.min.z } else { b.max.z },
            );
            let d = corner - c.from;
            let (x, y) = (d.dot(right) / d.dot(view), d.dot(cam_up) / d.dot(view));
            assert!(
                d.dot(view) > 0.0 && x.abs() < half && y.abs() < half,
                "{name}: corner {corner} is in view"
            );
        }
        assert_eq!(s.planes.len(), 1, "{name}");
        let ground = s.planes[0];
        assert_eq!(ground.normal, up, "{name}");
        let lowest = b.min.dot(up);
        // Just below the lowest point: a thousandth of the mesh's half-diagonal, so a flat
        // mesh lying there does not z-fight with it.
        let gap = lowest - ground.point.dot(up);
        let half_diagonal = 0.5 * b.extent().length();
        assert!(
            gap > 0.0 && gap <= 1.01e-3 * half_diagonal,
            "{name}: ground just under the mesh (gap {gap})"
        );
        for m in s
            .triangles
            .iter()
            .map(|t| t.material)
            .chain([ground.material])
        {
            assert!(
                (m.0 as usize) < s.materials.len(),
                "{name}: material exists"
            );
        }
    }
    // An empty mesh is an error, not an empty picture.
    write(&dir.join("empty.stl"), &stl::write_binary(&[], &[0; 80]));
    assert!(scene::load(&dir.join("empty.stl")).is_err());
}
