//! A triangle cut by an axis-aligned plane, for spatial splits (`spatial`): the boxes of
//! its parts on either side. Two cuts on purpose: `chop` is the f32 estimate the binning
//! weighs at every plane of every node, `cut_triangle` the f64 cut, widened, that a split
//! keeps, whose boxes must hold their parts whatever the rounding.

use glam::{DVec3, Vec3A};
use obvhs::aabb::Aabb;

/// The boxes of triangle `v`'s parts inside `b` below and above `pos` on `axis`, in f32:
/// what the binning weighs (`cut_triangle` makes the cut itself).
#[inline]
pub(super) fn chop(v: &[Vec3A; 3], b: &Aabb, axis: usize, pos: f32) -> (Aabb, Aabb) {
    let (mut l, mut r) = (Aabb::empty(), Aabb::empty());
    for i in 0..3 {
        let (a, c) = (v[i], v[(i + 1) % 3]);
        if a[axis] <= pos {
            l.extend(a);
        }
        if a[axis] >= pos {
            r.extend(a);
        }
        if (a[axis] - pos) * (c[axis] - pos) < 0.0 {
            let x = a + (c - a) * ((pos - a[axis]) / (c[axis] - a[axis]));
            l.extend(x);
            r.extend(x);
        }
    }
    let (below, above) = sides(b, axis, pos);
    (l.intersection(&below), r.intersection(&above))
}

/// The boxes of triangle `v`'s parts inside `b` below and above `pos` on `axis`, each
/// sure to hold its part: the crossings of the plane are worked out in f64 and each box
/// widened by 16 ulps of the triangle's largest coordinate before it is cut to `b` and the
/// plane (an invalid box where no part lies on that side).
pub(super) fn cut_triangle(v: &[Vec3A; 3], b: &Aabb, axis: usize, pos: f32) -> (Aabb, Aabb) {
    let v = v.map(|p| p.as_dvec3());
    let p = f64::from(pos);
    let (mut lmin, mut lmax) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
    let (mut rmin, mut rmax) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
    let mut size = 0.0f64;
    for i in 0..3 {
        let (a, c) = (v[i], v[(i + 1) % 3]);
        size = size.max(a.abs().max_element());
        if a[axis] <= p {
            (lmin, lmax) = (lmin.min(a), lmax.max(a));
        }
        if a[axis] >= p {
            (rmin, rmax) = (rmin.min(a), rmax.max(a));
        }
        if (a[axis] < p && c[axis] > p) || (a[axis] > p && c[axis] < p) {
            let mut x = a + (c - a) * ((p - a[axis]) / (c[axis] - a[axis]));
            x[axis] = p;
            (lmin, lmax) = (lmin.min(x), lmax.max(x));
            (rmin, rmax) = (rmin.min(x), rmax.max(x));
        }
    }
    let w = DVec3::splat(size * f64::from(f32::EPSILON) * 16.0);
    let part = |min: DVec3, max: DVec3, side: Aabb| {
        if min.x > max.x {
            return Aabb::empty();
        }
        let widened = Aabb::new(
            Vec3A::from((min - w).as_vec3()),
            Vec3A::from((max + w).as_vec3()),
        );
        widened.intersection(&side)
    };
    let (below, above) = sides(b, axis, pos);
    (part(lmin, lmax, below), part(rmin, rmax, above))
}

/// `b`'s parts below and above `pos` on `axis` (invalid where `b` has none on that side),
/// cut in vector registers: writing one lane of a box in place and reading the box back
/// whole made a load wait for the store to retire, a fifth of the binning's time.
#[inline]
fn sides(b: &Aabb, axis: usize, pos: f32) -> (Aabb, Aabb) {
    let on_axis = Vec3A::AXES[axis].cmpeq(Vec3A::ONE);
    let plane = Vec3A::splat(pos);
    let below = Aabb::new(
        b.min,
        b.max.min(Vec3A::select(on_axis, plane, Vec3A::INFINITY)),
    );
    let above = Aabb::new(
        b.min
            .max(Vec3A::select(on_axis, plane, Vec3A::NEG_INFINITY)),
        b.max,
    );
    (below, above)
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// A small deterministic generator of floats in [0, 1).
    pub(crate) fn random(seed: u64) -> impl FnMut() -> f32 {
        let mut s = seed;
        move || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            (s >> 40) as f32 / (1u64 << 24) as f32
        }
    }

    /// Points over triangle `v`, worked out in f64: its corners, points along its edges and
    /// inside.
    pub(crate) fn samples(v: &[Vec3A; 3]) -> Vec<DVec3> {
        let [a, b, c] = v.map(|p| p.as_dvec3());
        let n = 8;
        let mut out = Vec::new();
        for i in 0..=n {
            for j in 0..=n - i {
                let (u, w) = (i as f64 / n as f64, j as f64 / n as f64);
                out.push(a + (b - a) * u + (c - a) * w);
            }
        }
        out
    }

    pub(crate) fn holds(b: &Aabb, q: DVec3) -> bool {
        (0..3).all(|k| f64::from(b.min[k]) <= q[k] && q[k] <= f64::from(b.max[k]))
    }

    /// Long, thin triangles at every angle across a few units, every seventh `far` from
    /// the origin: the slivers spatial splits are for.
    pub(crate) fn slivers(n: usize, seed: u64, far: f32) -> Vec<[Vec3A; 3]> {
        let mut r = random(seed);
        (0..n)
            .map(|i| {
                let offset = if i % 7 == 0 { far } else { 0.0 };
                let mut p = || Vec3A::new(r(), r(), r()) * 4.0 + Vec3A::splat(offset);
                let (a, b) = (p(), p());
                let thin = (b - a).cross(Vec3A::Z).normalize_or(Vec3A::X) * 0.01;
                [a, b, a + thin]
            })
            .collect()
    }

    /// Each part `cut_triangle` makes holds every point of the triangle inside the box it
    /// cuts and on its side of the plane, cut after cut.
    #[test]
    fn cut_parts_hold_their_points() {
        let mut r = random(7);
        for v in slivers(2000, 11, 1e4) {
            let mut b = Aabb::from_points(&v);
            for _ in 0..3 {
                let axis = (r() * 3.0) as usize % 3;
                let pos = b.min[axis] + (b.max[axis] - b.min[axis]) * r();
                let (l, rt) = cut_triangle(&v, &b, axis, pos);
                for q in samples(&v).into_iter().filter(|&q| holds(&b, q)) {
                    let x = q[axis];
                    assert!(
                        x > f64::from(pos) || holds(&l, q),
                        "{v:?} {axis} {pos}: {q}"
                    );
                    assert!(
                        x < f64::from(pos) || holds(&rt, q),
                        "{v:?} {axis} {pos}: {q}"
                    );
                }
                b = if r() < 0.5 && l.valid() { l } else { rt };
                if !b.valid() {
                    break;
                }
            }
        }
    }
}
