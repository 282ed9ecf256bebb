//! Polygon triangulation by ear clipping.
//!
//! NFF polygons are planar but only the corner at their first three vertices is guaranteed
//! convex: the SPD gears have 144-vertex concave faces, which a fan would get wrong. Ear
//! clipping yields n - 2 triangles whose areas sum to the polygon's and that all lie inside
//! it, for any simple polygon. (A crate such as `earcut` drops collinear vertices and so
//! changes the triangle count; this one keeps every vertex and the polygon's winding.)

use glam::{DVec2, Vec3};

/// Triangulates a planar polygon into `out` as index triples that keep the polygon's
/// winding. Returns false when the polygon is degenerate (no area, non-finite points).
///
/// The ring is a linked list walked by a cursor, and only vertices that are not strictly
/// convex are tested against a candidate ear (no convex vertex can be the only one inside an
/// ear of a simple polygon). So a convex polygon costs O(n), and the cost grows with the
/// number of reflex vertices rather than with n squared: large hostile polygons stay cheap.
pub fn triangulate(points: &[Vec3], out: &mut Vec<[u32; 3]>) -> bool {
    let n = points.len();
    if n < 3 {
        return false;
    }
    let normal = newell_normal(points);
    // (A non-finite point makes the normal non-finite too.)
    if !normal.is_finite() || normal.length_squared() <= 0.0 {
        return false;
    }
    if n == 3 {
        out.push([0, 1, 2]);
        return true;
    }
    let pts = project(points, normal);
    // Orientation of the projected polygon: a corner is convex when its turn has this sign.
    let sign = signed_area(&pts).signum();
    if sign == 0.0 || sign.is_nan() {
        return false;
    }
    let convexity =
        |a: u32, b: u32, c: u32| sign * turn(pts[a as usize], pts[b as usize], pts[c as usize]);
    let mut prev: Vec<u32> = (0..n).map(|i| ((i + n - 1) % n) as u32).collect();
    let mut next: Vec<u32> = (0..n).map(|i| ((i + 1) % n) as u32).collect();
    // Vertices that are not strictly convex: the only ones that can block an ear.
    let mut reflex_flag: Vec<bool> = (0..n)
        .map(|i| convexity(prev[i], i as u32, next[i]) <= 0.0)
        .collect();
    let mut reflex: Vec<u32> = (0..n as u32).filter(|&i| reflex_flag[i as usize]).collect();

    let mut remaining = n;
    let mut i = 0u32;
    let mut misses = 0;
    while remaining > 3 {
        let (a, c) = (prev[i as usize], next[i as usize]);
        let is_ear = convexity(a, i, c) > 0.0
            && !reflex
                .iter()
                .any(|&p| reflex_flag[p as usize] && blocks_ear(&pts, p, a, i, c));
        let clip = if is_ear {
            i
        } else if misses + 1 < remaining {
            misses += 1;
            i = c;
            continue;
        } else {
            // A full turn without a clean ear: only a polygon with collinear runs or
            // self-intersections gets here. Clip its most convex corner so the count stays
            // n - 2 and the loop always ends.
            let mut best = i;
            let mut j = next[i as usize];
            while j != i {
                let (jp, jn) = (prev[j as usize], next[j as usize]);
                let (bp, bn) = (prev[best as usize], next[best as usize]);
                if convexity(jp, j, jn) > convexity(bp, best, bn) {
                    best = j;
                }
                j = jn;
            }
            best
        };
        let (a, c) = (prev[clip as usize], next[clip as usize]);
        out.push([a, clip, c]);
        next[a as usize] = c;
        prev[c as usize] = a;
        remaining -= 1;
        misses = 0;
        // The clipped vertex is gone and its neighbours have new corners: refresh their
        // flags (a reflex vertex usually becomes convex; degenerate input can do the reverse).
        let mut dropped = reflex_flag[clip as usize];
        reflex_flag[clip as usize] = false;
        for v in [a, c] {
            let is_reflex = convexity(prev[v as usize], v, next[v as usize]) <= 0.0;
            if is_reflex && !reflex_flag[v as usize] {
                reflex.push(v);
            }
            dropped |= reflex_flag[v as usize] && !is_reflex;
            reflex_flag[v as usize] = is_reflex;
        }
        if dropped {
            reflex.retain(|&p| reflex_flag[p as usize]);
        }
        // Go on one vertex past the new corner, as earcut does: clipping the corner
        // just made would take every ear from the same vertex, a fan of slivers across a
        // convex run (the SPD gears' 144-gons), while skipping one strips the run into
        // triangles of sound shape, which a BVH bounds far more tightly. The last triangle
        // starts at `c` as before, so quads are split exactly as they always were.
        i = if remaining > 3 { next[c as usize] } else { c };
    }
    out.push([prev[i as usize], i, next[i as usize]]);
    true
}

/// Newell's method: robust polygon normal, its length twice the area.
fn newell_normal(points: &[Vec3]) -> Vec3 {
    let mut n = Vec3::ZERO;
    for (i, &p) in points.iter().enumerate() {
        let q = points[(i + 1) % points.len()];
        n += Vec3::new(
            (p.y - q.y) * (p.z + q.z),
            (p.z - q.z) * (p.x + q.x),
            (p.x - q.x) * (p.y + q.y),
        );
    }
    n
}

/// Drops the normal's dominant axis, keeping the other two, in f64 so that the orientation
/// tests below are (nearly) exact for f32 input.
fn project(points: &[Vec3], normal: Vec3) -> Vec<DVec2> {
    let a = normal.abs();
    let (u, v) = if a.x >= a.y && a.x >= a.z {
        (1, 2)
    } else if a.y >= a.z {
        (2, 0)
    } else {
        (0, 1)
    };
    // Centre the points first so that far-from-origin polygons keep their precision.
    let c = points.iter().map(|p| p.as_dvec3()).sum::<glam::DVec3>() / points.len() as f64;
    points
        .iter()
        .map(|p| {
            let d = p.as_dvec3() - c;
            DVec2::new(d[u], d[v])
        })
        .collect()
}

fn signed_area(p: &[DVec2]) -> f64 {
    let mut s = 0.0;
    for i in 0..p.len() {
        s += p[i].perp_dot(p[(i + 1) % p.len()]);
    }
    0.5 * s
}

/// Twice the signed area of triangle abc (positive when counter-clockwise).
fn turn(a: DVec2, b: DVec2, c: DVec2) -> f64 {
    (b - a).perp_dot(c - a)
}

/// Whether vertex `p` lies inside or on the candidate ear abc (vertices at the same position
/// as a corner do not count).
fn blocks_ear(pts: &[DVec2], p: u32, a: u32, b: u32, c: u32) -> bool {
    if p == a || p == b || p == c {
        return false;
    }
    let (q, a, b, c) = (
        pts[p as usize],
        pts[a as usize],
        pts[b as usize],
        pts[c as usize],
    );
    if q == a || q == b || q == c {
        return false;
    }
    let (d1, d2, d3) = (turn(a, b, q), turn(b, c, q), turn(c, a, q));
    let has_neg = d1 < 0.0 || d2 < 0.0 || d3 < 0.0;
    let has_pos = d1 > 0.0 || d2 > 0.0 || d3 > 0.0;
    !(has_neg && has_pos)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn area(points: &[Vec3], tris: &[[u32; 3]]) -> f32 {
        tris.iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| points[i as usize]);
                0.5 * (b - a).cross(c - a).length()
            })
            .sum()
    }

    #[test]
    fn concave_l_shape_keeps_area_and_count() {
        // An L made of three unit squares, counter-clockwise in the z = 0 plane.
        let pts: Vec<Vec3> = [(0., 0.), (2., 0.), (2., 1.), (1., 1.), (1., 2.), (0., 2.)]
            .iter()
            .map(|&(x, y)| Vec3::new(x, y, 0.0))
            .collect();
        let mut tris = Vec::new();
        assert!(triangulate(&pts, &mut tris));
        assert_eq!(tris.len(), 4);
        assert!((area(&pts, &tris) - 3.0).abs() < 1e-5);
        for t in &tris {
            let [a, b, c] = t.map(|i| pts[i as usize]);
            assert!((b - a).cross(c - a).z > 0.0, "winding kept");
        }
    }

    #[test]
    fn collinear_and_degenerate_polygons() {
        let line: Vec<Vec3> = (0..4).map(|i| Vec3::new(i as f32, 0.0, 0.0)).collect();
        assert!(!triangulate(&line, &mut Vec::new()));
        // A square with a collinear midpoint still gives n - 2 triangles of the full area.
        let sq: Vec<Vec3> = [(0., 0.), (1., 0.), (2., 0.), (2., 2.), (0., 2.)]
            .iter()
            .map(|&(x, y)| Vec3::new(x, 0.0, y))
            .collect();
        let mut tris = Vec::new();
        assert!(triangulate(&sq, &mut tris));
        assert_eq!(tris.len(), 3);
        assert!((area(&sq, &tris) - 4.0).abs() < 1e-5);
    }
    /// A 144-gon, convex or with gear teeth (as the SPD gears), is cut into triangles of
    /// sound shape: their boxes cover at most four times the polygon's area, where a fan
    /// from one vertex covers 30 times on the circle, and no vertex is in more than 16
    /// triangles (the fan's first is in all 142).
    #[test]
    fn large_polygons_are_cut_into_strips_not_fans() {
        for inner in [1.0f32, 0.8] {
            let n = 144;
            let pts: Vec<Vec3> = (0..n)
                .map(|k| {
                    let a = k as f32 / n as f32 * std::f32::consts::TAU;
                    let r = if k % 4 < 2 { 1.0 } else { inner };
                    Vec3::new(r * a.cos(), r * a.sin(), 0.0)
                })
                .collect();
            let mut tris = Vec::new();
            assert!(triangulate(&pts, &mut tris));
            assert_eq!(tris.len(), n - 2);
            let boxes: f32 = tris
                .iter()
                .map(|t| {
                    let [a, b, c] = t.map(|i| pts[i as usize]);
                    let d = a.max(b).max(c) - a.min(b).min(c);
                    d.x * d.y
                })
                .sum();
            let polygon = area(&pts, &tris);
            assert!(boxes < 4.0 * polygon, "{boxes} for area {polygon}");
            let mut degree = vec![0; n];
            for &i in tris.iter().flatten() {
                degree[i as usize] += 1;
            }
            assert!(degree.iter().all(|&d| d <= 16), "{degree:?}");
        }
    }

    /// A quad keeps the split it always had: (3, 0, 1) and (3, 1, 2).
    #[test]
    fn quads_are_split_from_the_first_corner() {
        let sq: Vec<Vec3> = [(0., 0.), (1., 0.), (1., 1.), (0., 1.)]
            .iter()
            .map(|&(x, y)| Vec3::new(x, y, 0.0))
            .collect();
        let mut tris = Vec::new();
        assert!(triangulate(&sq, &mut tris));
        assert_eq!(tris, [[3, 0, 1], [3, 1, 2]]);
    }
}
