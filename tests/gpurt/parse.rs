//! Scene input: the NFF reader (with the P3D dialect and our extensions), STL, OBJ, gzip and
//! bare meshes, checked against the shared SPD/P3D scenes, hand-written inputs for every
//! error class, and random mutations that must never make a reader panic.

use std::io::Write;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::Path;

use glam::{DVec2, DVec3, Vec3};
use gpurt::Error;
use gpurt::limits;
use gpurt::scene::{
    self, BoxPrim, Light, Material, MaterialId, Plane, Scene, Triangle, nff, obj, stl,
    triangulate::triangulate,
};

use crate::common::{files_with, shared_scenes, temp_dir};

// ---------------------------------------------------------------------------------------
// Exact primitive counts for every shared scene
// ---------------------------------------------------------------------------------------

#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
struct Counts {
    spheres: usize,
    triangles: usize,
    cones: usize,
    planes: usize,
}

/// What SPD scene `name` at size factor `sf` holds after triangulation, from the size
/// formulas of shared/docs/nff.md. Floors and backdrops are one quad, so two triangles.
fn spd_counts(name: &str, sf: u32) -> Counts {
    const QUAD: usize = 2;
    let sf_ = sf as usize;
    match name {
        "balls" => Counts {
            spheres: (0..=sf).map(|k| 9usize.pow(k)).sum(),
            triangles: QUAD,
            ..Counts::default()
        },
        // Each gear: two concave 144-gon faces (ear clipping gives 142 triangles each) and
        // 144 tooth quads.
        "gears" => Counts {
            triangles: sf_.pow(3) * (2 * 142 + 144 * 2) + QUAD,
            ..Counts::default()
        },
        "mount" => Counts {
            spheres: 4,
            triangles: 2 * 4usize.pow(sf),
            ..Counts::default()
        },
        "rings" => {
            let n = 5 * sf_ * (sf_ + 1) * (2 * sf_ + 1);
            Counts {
                spheres: n,
                cones: n,
                triangles: QUAD,
                ..Counts::default()
            }
        }
        // Triangle patches plus SF^2 checker quads.
        "teapot" => Counts {
            triangles: 64 * sf_ * sf_ - 8 * sf_ + sf_ * sf_ * QUAD,
            ..Counts::default()
        },
        "tetra" => Counts {
            triangles: 4usize.pow(sf),
            ..Counts::default()
        },
        "tree" => {
            let n = 2usize.pow(sf + 1) - 1;
            Counts {
                spheres: n,
                cones: n,
                triangles: QUAD,
                ..Counts::default()
            }
        }
        _ => panic!("no size formula for SPD scene '{name}'"),
    }
}

/// Expected counts for a shared scene file, from its name; `None` for an unknown name.
fn expected_counts(file_name: &str) -> Option<Counts> {
    let stem = file_name.strip_suffix(".gz").unwrap_or(file_name);
    let stem = stem.strip_suffix(".nff")?;
    if let Some((name, sf)) = stem.split_once('-') {
        return Some(spd_counts(name, sf.parse().ok()?));
    }
    // P3D: the SPD scene at a given size, balls with a `pl` floor instead of the quad.
    let (name, sf) = match stem {
        "balls_low" => ("balls", 1),
        "balls_medium" => ("balls", 2),
        "balls_high" => ("balls", 4),
        "mount_low" => ("mount", 1),
        "mount_high" => ("mount", 5),
        "mount_very_high" => ("mount", 7),
        _ => return None,
    };
    let mut c = spd_counts(name, sf);
    if name == "balls" {
        c.triangles = 0;
        c.planes = 1;
    }
    Some(c)
}

fn counts_of(s: &Scene) -> Counts {
    Counts {
        spheres: s.spheres.len(),
        triangles: s.triangles.len(),
        cones: s.cones.len(),
        planes: s.planes.len(),
    }
}

/// The formulas give the numbers the issue names for the landmark scenes.
#[test]
fn size_formulas_give_the_landmark_counts() {
    let balls4 = spd_counts("balls", 4);
    assert_eq!((balls4.spheres, balls4.triangles), (7381, 2));
    // gears-2: 8 gears; each 144-gon face gives 142 triangles.
    assert_eq!(
        spd_counts("gears", 2).triangles,
        8 * (2 * 142 + 2 * 144) + 2
    );
    let mount7 = spd_counts("mount", 7);
    assert_eq!((mount7.triangles, mount7.spheres), (32768, 4));
    assert_eq!(spd_counts("balls", 6).spheres, 597871);
}

#[test]
fn every_shared_scene_parses_with_exact_counts() {
    let Some(dir) = shared_scenes() else { return };
    let files = files_with(&dir, &[""]);
    let mut seen = Vec::new();
    for path in &files {
        let name = path.file_name().unwrap().to_string_lossy().into_owned();
        let want = expected_counts(&name)
            .unwrap_or_else(|| panic!("{name}: no expected counts for this scene name"));
        let s = scene::load(path).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(counts_of(&s), want, "{name}");
        assert!(s.boxes.is_empty(), "{name}: no SPD/P3D scene has boxes");
        assert!(s.warnings.is_empty(), "{name}: {:?}", s.warnings);
        assert!(!s.lights.is_empty(), "{name}: has lights");
        // SPD lights are uncoloured; the P3D course files give every light a colour.
        let p3d = path.parent().unwrap().ends_with("p3d");
        for l in &s.lights {
            match l {
                Light::Point { color, .. } => assert_eq!(color.is_some(), p3d, "{name}: {l:?}"),
                other => panic!("{name}: only point lights expected, found {other:?}"),
            }
        }
        seen.push(name);
    }
    for landmark in [
        "balls-4.nff",
        "gears-2.nff",
        "mount-7.nff",
        "balls-6.nff.gz",
    ] {
        assert!(seen.iter().any(|n| n == landmark), "{landmark} was checked");
    }
    assert!(seen.len() >= 30, "all shared scenes were found: {seen:?}");
}

// ---------------------------------------------------------------------------------------
// Concave triangulation: the 144-gon gear faces
// ---------------------------------------------------------------------------------------

/// The raw `p 144` polygons of an SPD file, read straight from the text (SPD writes no
/// comments, and `p` never appears as a number).
fn gear_faces(text: &str) -> Vec<Vec<Vec3>> {
    let toks: Vec<&str> = text.split_ascii_whitespace().collect();
    let mut faces = Vec::new();
    let mut i = 0;
    while i + 1 < toks.len() {
        if toks[i] == "p" && toks[i + 1] == "144" {
            let nums: Vec<f32> = toks[i + 2..i + 2 + 3 * 144]
                .iter()
                .map(|t| t.parse().expect("vertex coordinate"))
                .collect();
            faces.push(
                nums.chunks(3)
                    .map(|c| Vec3::new(c[0], c[1], c[2]))
                    .collect(),
            );
            i += 2 + 3 * 144;
        } else {
            i += 1;
        }
    }
    faces
}

/// Checks that `tris` triangulates the planar polygon `poly`: n - 2 triangles with the
/// polygon's winding, total area equal to the polygon's (relative 1e-4), every triangle's
/// centroid inside the polygon, and no triangle edge properly crossing a polygon edge.
fn check_triangulation(poly: &[Vec3], tris: &[[u32; 3]]) -> Result<(), String> {
    let n = poly.len();
    if tris.len() != n - 2 {
        return Err(format!("{} triangles for {n} vertices", tris.len()));
    }
    let p3: Vec<DVec3> = poly.iter().map(|p| p.as_dvec3()).collect();
    // Newell normal: direction of the polygon's front, length twice its area.
    let mut normal = DVec3::ZERO;
    for i in 0..n {
        normal += p3[i].cross(p3[(i + 1) % n]);
    }
    let poly_area = 0.5 * normal.length();
    let nz = normal.normalize();
    // 2D coordinates in the polygon's plane.
    let u = nz.any_orthonormal_vector();
    let v = nz.cross(u);
    let p2: Vec<DVec2> = p3.iter().map(|p| DVec2::new(p.dot(u), p.dot(v))).collect();
    let scale = p2.iter().fold(0.0f64, |m, p| m.max(p.length()));
    let eps = 1e-9 * scale * scale;
    let orient = |a: DVec2, b: DVec2, c: DVec2| (b - a).perp_dot(c - a);

    let mut area = 0.0;
    for (k, t) in tris.iter().enumerate() {
        if t.iter().any(|&i| i as usize >= n) || t[0] == t[1] || t[1] == t[2] || t[0] == t[2] {
            return Err(format!("triangle {k} has bad indices {t:?}"));
        }
        let [a, b, c] = t.map(|i| p3[i as usize]);
        let cross = (b - a).cross(c - a);
        if cross.dot(nz) <= 0.0 {
            return Err(format!("triangle {k} {t:?} is flipped or flat"));
        }
        area += 0.5 * cross.length();
        // Centroid inside the polygon (even-odd crossing number).
        let g = t.map(|i| p2[i as usize]).iter().sum::<DVec2>() / 3.0;
        let mut inside = false;
        for i in 0..n {
            let (a, b) = (p2[i], p2[(i + 1) % n]);
            if (a.y > g.y) != (b.y > g.y) && g.x < a.x + (g.y - a.y) / (b.y - a.y) * (b.x - a.x) {
                inside = !inside;
            }
        }
        if !inside {
            return Err(format!(
                "triangle {k} {t:?} has its centroid outside the polygon"
            ));
        }
        // No edge crosses a polygon edge in the interior of both.
        for e in 0..3 {
            let (i, j) = (t[e] as usize, t[(e + 1) % 3] as usize);
            for s in 0..n {
                let (r, q) = (s, (s + 1) % n);
                if [r, q].contains(&i) || [r, q].contains(&j) {
                    continue;
                }
                let (d1, d2) = (orient(p2[i], p2[j], p2[r]), orient(p2[i], p2[j], p2[q]));
                let (d3, d4) = (orient(p2[r], p2[q], p2[i]), orient(p2[r], p2[q], p2[j]));
                let opposite = |x: f64, y: f64| (x > eps && y < -eps) || (x < -eps && y > eps);
                if opposite(d1, d2) && opposite(d3, d4) {
                    return Err(format!(
                        "edge {i}-{j} of triangle {k} crosses polygon edge {r}-{q}"
                    ));
                }
            }
        }
    }
    if ((area - poly_area) / poly_area).abs() > 1e-4 {
        return Err(format!("triangle area {area} != polygon area {poly_area}"));
    }
    Ok(())
}

#[test]
fn gear_faces_triangulate_inside_with_their_area() {
    let Some(dir) = shared_scenes() else { return };
    let mut checked = 0;
    for (file, sf) in [("gears-1.nff", 1), ("gears-2.nff", 2), ("gears-4.nff", 4)] {
        let text = std::fs::read_to_string(dir.join("spd").join(file)).expect("gears file reads");
        let faces = gear_faces(&text);
        assert_eq!(faces.len(), 2 * sf * sf * sf, "{file}: two faces per gear");
        for (f, poly) in faces.iter().enumerate() {
            let mut tris = Vec::new();
            assert!(triangulate(poly, &mut tris), "{file} face {f}");
            if let Err(e) = check_triangulation(poly, &tris) {
                panic!("{file} face {f}: {e}");
            }
            checked += 1;
        }
    }
    assert_eq!(checked, 2 * (1 + 8 + 64));
}

/// The checker above rejects what it must: a fan is wrong on a concave gear face.
#[test]
fn triangulation_checker_rejects_a_fan_on_a_gear_face() {
    let Some(dir) = shared_scenes() else { return };
    let text = std::fs::read_to_string(dir.join("spd/gears-1.nff")).expect("gears file reads");
    let poly = &gear_faces(&text)[0];
    let fan: Vec<[u32; 3]> = (1..poly.len() as u32 - 1).map(|i| [0, i, i + 1]).collect();
    assert!(check_triangulation(poly, &fan).is_err());
}

// ---------------------------------------------------------------------------------------
// NFF: errors with exact positions
// ---------------------------------------------------------------------------------------

/// A valid view on lines 1-5; entities after it start on line 6.
const VIEW: &str = "v\nfrom 0 -5 0\nat 0 0 0\nup 0 0 1\nangle 45\n";

fn parse_nff(src: &str) -> Result<Scene, Error> {
    nff::parse(src.as_bytes(), "t.nff", Path::new("."))
}

/// The position and message of the parse error `src` must give.
fn parse_error(src: &str) -> (u32, u32, String) {
    match parse_nff(src) {
        Err(e @ Error::Parse { .. }) => {
            let shown = e.to_string();
            let Error::Parse {
                file,
                line,
                col,
                msg,
            } = e
            else {
                unreachable!()
            };
            assert_eq!(file, "t.nff");
            assert_eq!(shown, format!("t.nff:{line}:{col}: {msg}"), "error display");
            (line, col, msg)
        }
        other => panic!("expected a parse error for {src:?}, got {other:?}"),
    }
}

/// Asserts the error's line and column and that its message mentions every `words`.
#[track_caller]
fn assert_error(src: &str, line: u32, col: u32, words: &[&str]) {
    let (l, c, msg) = parse_error(src);
    assert_eq!((l, c), (line, col), "position of error {msg:?} in {src:?}");
    for w in words {
        assert!(msg.contains(w), "{msg:?} mentions {w:?}");
    }
}

#[test]
fn truncated_entity_points_at_the_end_of_the_file() {
    assert_error(
        &format!("{VIEW}s 0 0 0"),
        6,
        8,
        &["sphere radius", "end of file"],
    );
    assert_error(
        &format!("{VIEW}p 3\n0.5 0.5 0.5\n1.5 0.5"),
        8,
        8,
        &["polygon vertex 2 of 3", "end of file"],
    );
    assert_error(
        &format!("{VIEW}pp 3\n0.0 0.0 0.0 0.0 0.0 1.0\n1.0 0.0 0.0 0.0 0.0"),
        8,
        20,
        &["normal of patch vertex 2 of 3", "end of file"],
    );
    // A file cut short by far more than a number is caught at the polygon's count.
    assert_error(
        &format!("{VIEW}p 3\n0 0 0\n1 0\n"),
        6,
        3,
        &["vertex count 3", "rest of the file"],
    );
}

#[test]
fn polygon_with_fewer_vertices_than_its_count() {
    // The fourth vertex's first number is the next entity's keyword.
    assert_error(
        &format!("{VIEW}p 5\n0 0 0\n1 0 0\n1 1 0\ns 0 0 0 1\n"),
        10,
        1,
        &["polygon vertex 4 of 5", "'s'"],
    );
}

#[test]
fn absurd_counts_are_rejected_at_the_count() {
    assert_error(
        &format!("{VIEW}p 4000000000\n0 0 0\n1 0 0\n1 1 0\n"),
        6,
        3,
        &["4000000000", "rest of the file"],
    );
    assert_error(
        &format!("{VIEW}pp 99999999999\n"),
        6,
        4,
        &["patch vertex count", "below 2^32", "'99999999999'"],
    );
    assert_error(
        &format!("{VIEW}p -3\n0 0 0\n1 0 0\n1 1 0\n"),
        6,
        3,
        &["non-negative", "'-3'"],
    );
    assert_error(&format!("{VIEW}p 3.5\n"), 6, 3, &["non-negative integer"]);
}

#[test]
fn non_numbers_and_non_finite_numbers() {
    assert_error(
        &format!("{VIEW}s 0 0 zero 1\n"),
        6,
        7,
        &["sphere centre", "(a number)", "'zero'"],
    );
    assert_error(&format!("{VIEW}s 0 nan 0 1\n"), 6, 5, &["finite", "'nan'"]);
    assert_error(&format!("{VIEW}s 0 0 0 inf\n"), 6, 9, &["radius", "finite"]);
    assert_error(&format!("{VIEW}s -inf 0 0 1\n"), 6, 3, &["finite"]);
    // Overflows f32 to infinity.
    assert_error(
        &format!("{VIEW}s 0 0 0 1e39\n"),
        6,
        9,
        &["finite", "'1e39'"],
    );
    assert_error(
        &format!("{VIEW}f 1 1 1 0.5 0.5 3 0 1.5.1\n"),
        6,
        21,
        &["index of refraction"],
    );
}

#[test]
fn unknown_keywords_and_stray_numbers_are_named() {
    assert_error(&format!("{VIEW}sphere 0 0 0 1\n"), 6, 1, &["'sphere'"]);
    assert_error(&format!("{VIEW}\n\n   cyl 1\n"), 8, 4, &["'cyl'"]);
    // The `l x y z intensity r g b` variant leaves a number where a keyword belongs.
    assert_error(
        &format!("{VIEW}l 1 2 3 0.5 1 1 1\n"),
        6,
        17,
        &["number '1'", "keyword"],
    );
    // Whole keywords only: `ppp` is not `pp`.
    assert_error(&format!("{VIEW}ppp 3\n"), 6, 1, &["'ppp'"]);
}

#[test]
fn sense8_nff_header_is_rejected() {
    assert_error("nff\nversion 2.0\n", 1, 1, &["Sense8"]);
    assert_error("# a comment first\n  nff\n", 2, 3, &["Sense8"]);
    // Only as the very first token: later it is just an unknown keyword.
    let (_, _, msg) = parse_error(&format!("{VIEW}nff\n"));
    assert!(!msg.contains("Sense8"), "{msg}");
}

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
            assert!(msg.contains(".stl or .obj"), "{msg}");
        }
        other => panic!("expected a parse error, got {other:?}"),
    }
}

#[test]
fn other_entity_errors() {
    assert_error(
        &format!("{VIEW}\nf 1 1 1 0.5 0.5 3 0.5 0\n"),
        7,
        1,
        &["index of refraction"],
    );
    assert_error(
        &format!("{VIEW}pl 0 0 0 1 1 1 2 2 2\n"),
        6,
        1,
        &["collinear"],
    );
    assert_error(&format!("{VIEW}dl 0 0 0\n"), 6, 1, &["zero direction"]);
    assert_error(
        &format!("{VIEW}al 0 0 5 1 0 0 0 1 0 1 1 1 0 4\n"),
        6,
        28,
        &["samples"],
    );
    assert_error(
        &format!("{VIEW}al 0 0 5 1 0 0 2 0 0 1 1 1 4 4\n"),
        6,
        1,
        &["parallel"],
    );
}

// ---------------------------------------------------------------------------------------
// NFF: what is accepted
// ---------------------------------------------------------------------------------------

fn parse_ok(src: &str) -> Scene {
    parse_nff(src).unwrap_or_else(|e| panic!("{src:?} should parse: {e}"))
}

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
            ior: 1.0
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

// ---------------------------------------------------------------------------------------
// Meshes: STL, OBJ, the `mesh` statement, gzip, bare meshes
// ---------------------------------------------------------------------------------------

fn tri(v: [[f32; 3]; 3], n: Option<[f32; 3]>) -> Triangle {
    Triangle {
        v: v.map(Vec3::from),
        n: n.map(|n| Box::new([Vec3::from(n); 3])),
        material: MaterialId(0),
    }
}

/// A tetrahedron with unit facet normals, one facet without a normal.
fn tetra() -> Vec<Triangle> {
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

fn ascii_stl(tris: &[Triangle]) -> String {
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

fn header(text: &[u8]) -> [u8; 80] {
    let mut h = [b' '; 80];
    h[..text.len()].copy_from_slice(text);
    h
}

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

fn gzip(bytes: &[u8]) -> Vec<u8> {
    let mut e = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
    e.write_all(bytes).unwrap();
    e.finish().unwrap()
}

fn write(path: &Path, bytes: &[u8]) {
    std::fs::write(path, bytes).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
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

#[test]
fn gzip_inputs_load_like_plain_ones() {
    let dir = temp_dir("gzip");
    let tris = tetra();
    let bin = stl::write_binary(&tris, &[0; 80]);
    let nff_src = format!("{VIEW}f 1 1 1 1 0 1 0 1\ns 0 0 0 1\np 4\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n");
    let files: [(&str, Vec<u8>); 4] = [
        ("part.stl", bin.clone()),
        ("part.stl.gz", gzip(&bin)),
        ("scene.nff", nff_src.clone().into_bytes()),
        ("scene.nff.gz", gzip(nff_src.as_bytes())),
    ];
    for (name, bytes) in &files {
        write(&dir.join(name), bytes);
    }
    let load = |name: &str| scene::load(&dir.join(name)).unwrap_or_else(|e| panic!("{e}"));
    let (stl_plain, stl_gz) = (load("part.stl"), load("part.stl.gz"));
    assert_eq!(stl_gz.triangles, tris);
    assert_eq!(stl_gz.triangles, stl_plain.triangles);
    assert_eq!(stl_gz.camera, stl_plain.camera);
    let (nff_plain, nff_gz) = (load("scene.nff"), load("scene.nff.gz"));
    assert_eq!((nff_gz.spheres.len(), nff_gz.triangles.len()), (1, 2));
    assert_eq!(nff_gz.triangles, nff_plain.triangles);
    assert_eq!(nff_gz.spheres, nff_plain.spheres);
    // A corrupt gzip stream is an error naming the file.
    let mut bad = gzip(&bin);
    let mid = bad.len() / 2;
    bad.truncate(mid);
    write(&dir.join("bad.stl.gz"), &bad);
    let e = scene::load(&dir.join("bad.stl.gz")).unwrap_err();
    assert!(e.to_string().contains("bad.stl.gz"), "{e}");
}

/// A bare mesh becomes a scene: a camera aimed at the mesh's centre that sees all of it, a
/// light, and a ground plane just under the lowest point along the format's up axis.
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
        assert!(
            (c.at - b.center()).length() < 1e-5,
            "{name}: aims at the centre"
        );
        assert_eq!(c.up, up, "{name}");
        assert!(!s.lights.is_empty(), "{name}: has a light");
        // Every corner of the bounds is inside the field of view.
        let view = (c.at - c.from).normalize();
        for i in 0..8 {
            let corner = Vec3::new(
                if i & 1 == 0 { b.min.x } else { b.max.x },
                if i & 2 == 0 { b.min.y } else { b.max.y },
                if i & 4 == 0 { b.min.z } else { b.max.z },
            );
            let off = (corner - c.from).normalize().dot(view).acos().to_degrees();
            assert!(off < c.angle / 2.0, "{name}: corner {corner} is in view");
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

// ---------------------------------------------------------------------------------------
// Mutation: random damage must give Ok or Err, never a panic
// ---------------------------------------------------------------------------------------

/// xorshift64: deterministic, no dependency.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
}

/// Tokens worth inserting: digits and number parts, every keyword of every reader, counts
/// that lie, and line structure.
const INSERTS: &[&str] = &[
    "0",
    "1",
    "7",
    "9",
    "-",
    "e",
    "E",
    ".",
    "+",
    " ",
    "\n",
    "\r",
    "\r\n",
    "#",
    "nan",
    "inf",
    "1e39",
    "-3",
    "4000000000",
    "99999999999",
    "v",
    "b",
    "l",
    "f",
    "c",
    "s",
    "p",
    "pp",
    "pl",
    "aabb",
    "mesh",
    "dl",
    "al",
    "am",
    "from",
    "at",
    "up",
    "angle",
    "hither",
    "resolution",
    "aperture",
    "focal",
    "translate",
    "rotate",
    "scale",
    "nff",
    "p 3",
    "pp 3",
    "p 200",
    "mesh part.stl",
    "mesh part.obj",
    "mesh nope.stl",
    "solid",
    "endsolid",
    "facet",
    "normal",
    "outer",
    "loop",
    "vertex",
    "endloop",
    "endfacet",
    "vn",
    "vt",
    "f 1 2 3",
    "f 1//1 2//2 3//3",
    "f -1 -2 -3",
    "f 1/1/1 2/2/2 3/3/3",
    "/",
    "//",
    "o",
    "g",
    "usemtl",
    "mtllib x.mtl",
    "\0",
    "\u{ff}",
];

fn mutate(rng: &mut Rng, input: &[u8]) -> Vec<u8> {
    let mut b = input.to_vec();
    for _ in 0..1 + rng.below(4) {
        let at = rng.below(b.len() + 1);
        match rng.below(7) {
            // Replace a byte, or flip one bit of it.
            0 if !b.is_empty() => {
                let i = rng.below(b.len());
                b[i] = rng.next() as u8;
            }
            1 if !b.is_empty() => {
                let i = rng.below(b.len());
                b[i] ^= 1 << rng.below(8);
            }
            // Delete a short run.
            2 => {
                let end = (at + 1 + rng.below(16)).min(b.len());
                b.drain(at.min(end)..end);
            }
            // Insert a token.
            3 | 4 => {
                let t = INSERTS[rng.below(INSERTS.len())];
                b.splice(at..at, t.bytes());
            }
            // Duplicate the line around `at`.
            5 => {
                let start = b[..at]
                    .iter()
                    .rposition(|&c| c == b'\n')
                    .map_or(0, |i| i + 1);
                let end = b[at..]
                    .iter()
                    .position(|&c| c == b'\n')
                    .map_or(b.len(), |i| at + i + 1);
                let line = b[start..end].to_vec();
                b.splice(start..start, line);
            }
            // Truncate.
            _ => b.truncate(at),
        }
    }
    b
}

#[test]
fn random_mutations_never_panic_a_reader() {
    let dir = temp_dir("mutation");
    // Mesh files for `mesh` statements in the mutated NFF text.
    let tris = tetra();
    let bin = stl::write_binary(&tris, &header(b"solid part"));
    write(&dir.join("part.stl"), &bin);
    let obj_src = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0.5 0.5 1\nvn 0 0 1\nvt 0 0\nf 1//1 2//1 3//1 4//1\nf 1/1 2/1 5/1\nf -1 -2 -3\n";
    write(&dir.join("part.obj"), obj_src.as_bytes());

    enum Reader {
        Nff,
        Stl,
        Obj,
    }
    let ext = format!(
        "{VIEW}hither 0.1\nresolution 64 48\naperture 0.1\nfocal 4\nam 0.1 0.1 0.1\ndl 0 0 -1\nal 0 0 5 1 0 0 0 1 0 1 1 1 2 2\nf 1 1 1 1 0 1 0 1\nmesh part.stl translate 1 2 3 rotate 0 0 90 scale 2\nmesh part.obj scale 1 2 3\npl 0 0 -1 1 0 -1 0 1 -1\naabb 0 1 0 1 0 1\nc 0 0 0 1 0 0 1 0.5\npp 3\n0 0 0 0 0 1\n1 0 0 0 0 1\n0 1 0 0 0 1\n"
    );
    let mut inputs: Vec<(String, Reader, Vec<u8>)> = vec![
        ("extensions.nff".into(), Reader::Nff, ext.into_bytes()),
        ("part.stl".into(), Reader::Stl, bin.clone()),
        (
            "part-ascii.stl".into(),
            Reader::Stl,
            ascii_stl(&tris).into_bytes(),
        ),
        ("part.obj".into(), Reader::Obj, obj_src.as_bytes().to_vec()),
    ];
    if let Some(shared) = shared_scenes() {
        for f in [
            "spd/balls-1.nff",
            "spd/gears-1.nff",
            "spd/rings-1.nff",
            "spd/teapot-2.nff",
            "spd/tetra-3.nff",
            "spd/tree-1.nff",
            "p3d/mount_low.nff",
            "p3d/balls_low.nff",
        ] {
            let bytes = std::fs::read(shared.join(f)).expect("shared scene reads");
            inputs.push((f.into(), Reader::Nff, bytes));
        }
    }

    let mut rng = Rng(0x2545_F491_4F6C_DD1D);
    let started = std::time::Instant::now();
    let (mut ok, mut err) = (0, 0);
    // A few hundred milliseconds by default; `GPURT_MUTATIONS=N` runs a longer soak.
    let mutations: usize = std::env::var("GPURT_MUTATIONS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(20_000);
    for k in 0..mutations {
        let (name, reader, input) = &inputs[k % inputs.len()];
        let bytes = mutate(&mut rng, input);
        let result = catch_unwind(AssertUnwindSafe(|| match reader {
            Reader::Nff => nff::parse(&bytes, name, &dir).map(|s| s.triangles.len()),
            Reader::Stl => stl::parse(&bytes, name).map(|t| t.len()),
            Reader::Obj => obj::parse(&bytes, name).map(|t| t.len()),
        }));
        match result {
            Ok(Ok(_)) => ok += 1,
            Ok(Err(_)) => err += 1,
            Err(_) => {
                let keep = dir.join(format!("panic-{k}-{}", name.replace('/', "_")));
                write(&keep, &bytes);
                panic!(
                    "mutation {k} of {name} made the reader panic; input kept at {}",
                    keep.display()
                );
            }
        }
    }
    // The mutations must exercise both outcomes, or they test nothing.
    assert!(
        ok > mutations / 20 && err > mutations / 20,
        "ok {ok}, err {err}"
    );
    eprintln!(
        "{mutations} mutations: {ok} parsed, {err} rejected, in {:?}",
        started.elapsed()
    );
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

/// Input quoted in a message has its control characters escaped: an ESC sequence in a
/// scene file must not reach the terminal.
#[test]
fn messages_escape_control_characters_from_the_input() {
    let err = nff::parse(b"\x1b[31mred 1 2 3\n", "esc.nff", Path::new(".")).unwrap_err();
    let msg = err.to_string();
    assert!(!msg.contains('\x1b'), "{msg:?}");
    assert!(msg.contains("\\u{1b}[31mred"), "{msg:?}");
    let err = nff::parse(b"mesh \"a\x07b.ply\"\n", "esc.nff", Path::new(".")).unwrap_err();
    assert!(!err.to_string().contains('\x07'), "{err}");
}

/// Zero bytes after the last gzip member are padding (`gzip -t` accepts them); other
/// bytes after it are still an error, and a second member is read like the first.
#[test]
fn gzip_padding_with_zeros_is_accepted() {
    let dir = temp_dir("gzip-padding");
    let src = format!("{VIEW}f 1 1 1 1 0 1 0 1\ns 0 0 0 1\n");
    let one = gzip(src.as_bytes());
    let cases: [(&str, Vec<u8>, Option<usize>); 3] = [
        (
            "padded.nff.gz",
            [one.clone(), vec![0; 1024]].concat(),
            Some(1),
        ),
        ("two.nff.gz", [one.clone(), one.clone()].concat(), Some(2)),
        (
            "junk.nff.gz",
            [one.clone(), b"junk".to_vec()].concat(),
            None,
        ),
    ];
    for (name, bytes, spheres) in cases {
        write(&dir.join(name), &bytes);
        match (scene::load(&dir.join(name)), spheres) {
            (Ok(s), Some(n)) => assert_eq!(s.spheres.len(), n, "{name}"),
            (Err(e), None) => assert!(e.to_string().contains(name), "{e}"),
            (r, _) => panic!("{name}: {:?}", r.map(|s| s.spheres.len())),
        }
    }
}

/// `decompress` is the one home of the gzip handling `read_file` does: the same bytes for
/// a file and for its contents, plain bytes passed through, and output past the limit an
/// error naming the file (the fuzz target runs it with a small limit).
#[test]
fn decompress_is_what_read_file_does_and_honours_its_limit() {
    let dir = temp_dir("decompress");
    let src = format!("{VIEW}f 1 1 1 1 0 1 0 1\ns 0 0 0 1\n");
    let gz = [gzip(src.as_bytes()), gzip(b"# second member\n")].concat();
    let path = dir.join("scene.nff.gz");
    write(&path, &gz);
    let read = scene::io::read_file(&path).unwrap();
    assert_eq!(read, [src.as_bytes(), b"# second member\n"].concat());
    assert_eq!(
        scene::io::decompress(gz.clone(), &path, limits::MAX_FILE_BYTES).unwrap(),
        read
    );
    let plain = src.clone().into_bytes();
    assert_eq!(
        scene::io::decompress(plain.clone(), &path, 4).unwrap(),
        plain
    );
    // Exactly the limit is fine; one byte more is not.
    let n = read.len() as u64;
    assert_eq!(scene::io::decompress(gz.clone(), &path, n).unwrap(), read);
    let e = scene::io::decompress(gz.clone(), &path, n - 1).unwrap_err();
    let shown = e.to_string();
    assert!(
        shown.contains("scene.nff.gz") && shown.contains(&format!("more than {} bytes", n - 1)),
        "{shown}"
    );
    // A bomb: a megabyte of zeros in about a kilobyte, refused at 64 KiB.
    let bomb = gzip(&vec![0; 1 << 20]);
    assert!(bomb.len() < 8192, "{}", bomb.len());
    assert!(scene::io::decompress(bomb, &path, 64 << 10).is_err());
    // Past HELD_BYTES the size is counted first, then the whole decompressed again:
    // the same bytes, to the last one, and still refused one byte past the limit.
    let held = limits::HELD_BYTES as usize;
    let big = [gzip(&vec![0; held]), gzip(b"# tail\n")].concat();
    let out = scene::io::decompress(big.clone(), &path, limits::MAX_FILE_BYTES).unwrap();
    assert_eq!(out.len(), held + 7);
    assert!(out.ends_with(b"\0# tail\n") && out[..held].iter().all(|&b| b == 0));
    let e = scene::io::decompress(big, &path, held as u64 + 6).unwrap_err();
    assert!(
        e.to_string()
            .contains(&format!("more than {} bytes", held + 6)),
        "{e}"
    );
}
