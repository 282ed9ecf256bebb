//! Polygon triangulation by ear clipping.
//!
//! NFF polygons are planar but only the corner at their first three vertices is guaranteed
//! convex: the SPD gears have 144-vertex concave faces, which a fan would get wrong. Ear
//! clipping yields n - 2 triangles whose areas sum to the polygon's and that all lie inside
//! it, for any simple polygon. (A crate such as `earcut` drops collinear vertices and so
//! changes the triangle count; this one keeps every vertex and the polygon's winding.)

use glam::{Vec2, Vec3};

/// Triangulates a planar polygon into `out` as index triples that keep the polygon's
/// winding. Returns false when the polygon is degenerate (no area, non-finite points).
pub fn triangulate(points: &[Vec3], out: &mut Vec<[u32; 3]>) -> bool {
    let n = points.len();
    if n < 3 {
        return false;
    }
    let normal = newell_normal(points);
    if !(normal.length_squared() > 0.0) || !normal.is_finite() {
        return false;
    }
    if n == 3 {
        out.push([0, 1, 2]);
        return true;
    }
    let pts = project(points, normal);
    // Orientation of the projected polygon: a corner is convex when its turn has this sign.
    let sign = signed_area(&pts).signum();
    if sign == 0.0 {
        return false;
    }
    let mut ring: Vec<u32> = (0..n as u32).collect();
    while ring.len() > 3 {
        let m = ring.len();
        let corner = |i: usize| {
            let (a, b, c) = (ring[(i + m - 1) % m], ring[i], ring[(i + 1) % m]);
            (
                a,
                b,
                c,
                sign * turn(pts[a as usize], pts[b as usize], pts[c as usize]),
            )
        };
        let ear = (0..m).find(|&i| {
            let (a, b, c, t) = corner(i);
            t > 0.0 && !ring.iter().any(|&p| blocks_ear(&pts, p, a, b, c))
        });
        // Only a polygon with collinear runs or self-intersections has no clean ear: clip
        // its most convex corner so the count stays n - 2 and the loop always ends.
        let i = ear.unwrap_or_else(|| {
            (0..m)
                .max_by(|&x, &y| corner(x).3.total_cmp(&corner(y).3))
                .expect("ring is not empty")
        });
        let (a, b, c, _) = corner(i);
        out.push([a, b, c]);
        ring.remove(i);
    }
    out.push([ring[0], ring[1], ring[2]]);
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

/// Drops the normal's dominant axis, keeping the other two.
fn project(points: &[Vec3], normal: Vec3) -> Vec<Vec2> {
    let a = normal.abs();
    let (u, v) = if a.x >= a.y && a.x >= a.z {
        (1, 2)
    } else if a.y >= a.z {
        (2, 0)
    } else {
        (0, 1)
    };
    // Centre the points first so that far-from-origin polygons keep their precision.
    let c = points.iter().copied().sum::<Vec3>() / points.len() as f32;
    points
        .iter()
        .map(|p| {
            let d = *p - c;
            Vec2::new(d[u], d[v])
        })
        .collect()
}

fn signed_area(p: &[Vec2]) -> f32 {
    let mut s = 0.0;
    for i in 0..p.len() {
        s += p[i].perp_dot(p[(i + 1) % p.len()]);
    }
    0.5 * s
}

/// Twice the signed area of triangle abc (positive when counter-clockwise).
fn turn(a: Vec2, b: Vec2, c: Vec2) -> f32 {
    (b - a).perp_dot(c - a)
}

/// Whether vertex `p` lies inside or on the candidate ear abc (vertices at the same position
/// as a corner do not count).
fn blocks_ear(pts: &[Vec2], p: u32, a: u32, b: u32, c: u32) -> bool {
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
}
