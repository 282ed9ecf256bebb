//! The shared SPD and P3D scenes: every file parses to the primitive counts its generator's
//! size formulas give, and the concave 144-gon gear faces triangulate inside the polygon
//! with its area.

use glam::{DVec2, DVec3, Vec3};
use gpurt::scene::{self, Light, Scene, triangulate::triangulate};

use crate::common::{files_with, shared_scenes};

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
