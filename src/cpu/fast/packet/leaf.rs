//! A leaf's primitives against a packet's lanes: triangles, spheres and planes in SIMD
//! across the rays, with `intersect.rs`'s operations in `intersect.rs`'s order (so each lane
//! gets the bits its ray gets alone), cones too; boxes lane by lane with `intersect_prim`
//! itself. The nearest hit so far is kept per lane (`Best`), as `closest_in_leaf` keeps it.

use super::lanes::{Lanes, MAX_LANES, Row};
use super::rays::{Found, Occluded, Rays, Rows};
use crate::cpu::intersect::{self, lanes_of};
use crate::cpu::types::Bindings;
use crate::gpu_types::{
    GpuPlane, GpuPrim, NO_HIT, NO_PRIM, PLANE_FLAG, PRIM_CONE, PRIM_SPHERE, PRIM_TRIANGLE,
};

/// `intersect_triangle` (as `intersect_triangles4` has it) of one triangle with every lane:
/// `(t, u, v)`, `t = NO_HIT` where the lane's ray misses.
#[inline(always)]
pub fn triangle<L: Lanes>(l: L, p: &GpuPrim, r: &Rays<L>) -> (L::F, L::F, L::F) {
    let s = |x: f32| l.splat(x);
    let (v0, e1, e2) = (p.p0, p.p1, p.p2);
    let [dx, dy, dz] = r.d;
    let dot = |a: [L::F; 3], b: [L::F; 3]| {
        l.add(
            l.add(l.mul(a[0], b[0]), l.mul(a[1], b[1])),
            l.mul(a[2], b[2]),
        )
    };
    // pvec = dir x e2
    let p = [
        l.sub(l.mul(dy, s(e2.z)), l.mul(s(e2.y), dz)),
        l.sub(l.mul(dz, s(e2.x)), l.mul(s(e2.z), dx)),
        l.sub(l.mul(dx, s(e2.y)), l.mul(s(e2.x), dy)),
    ];
    let det = dot([s(e1.x), s(e1.y), s(e1.z)], p);
    let inv = l.div(s(1.0), det);
    let (tx, ty, tz) = (
        l.sub(r.o[0], s(v0.x)),
        l.sub(r.o[1], s(v0.y)),
        l.sub(r.o[2], s(v0.z)),
    );
    let u = l.mul(dot([tx, ty, tz], p), inv);
    // qvec = tvec x e1
    let q = [
        l.sub(l.mul(ty, s(e1.z)), l.mul(s(e1.y), tz)),
        l.sub(l.mul(tz, s(e1.x)), l.mul(s(e1.z), tx)),
        l.sub(l.mul(tx, s(e1.y)), l.mul(s(e1.x), ty)),
    ];
    let v = l.mul(dot(r.d, q), inv);
    let t = l.mul(dot([s(e2.x), s(e2.y), s(e2.z)], q), inv);
    let (zero, one) = (s(0.0), s(1.0));
    let hit = l.and(l.and(l.ne(det, zero), l.le(zero, u)), l.le(u, one));
    let hit = l.and_not(l.and_not(hit, l.lt(v, zero)), l.gt(l.add(u, v), one));
    (l.select(hit, t, s(NO_HIT)), u, v)
}

/// `intersect_sphere` of one sphere with every lane: both crossings, `NO_HIT` on a miss.
#[inline(always)]
pub fn sphere<L: Lanes>(l: L, p: &GpuPrim, r: &Rays<L>) -> (L::F, L::F) {
    let c = p.p0;
    let oc = [
        l.sub(r.o[0], l.splat(c.x)),
        l.sub(r.o[1], l.splat(c.y)),
        l.sub(r.o[2], l.splat(c.z)),
    ];
    let dot = |a: &[L::F; 3], b: &[L::F; 3]| {
        l.add(
            l.add(l.mul(a[0], b[0]), l.mul(a[1], b[1])),
            l.mul(a[2], b[2]),
        )
    };
    let b = dot(&oc, &r.d);
    let qc = [
        l.sub(oc[0], l.mul(b, r.d[0])),
        l.sub(oc[1], l.mul(b, r.d[1])),
        l.sub(oc[2], l.mul(b, r.d[2])),
    ];
    let h = l.sub(l.splat(p.f0 * p.f0), dot(&qc, &qc));
    let miss = l.lt(h, l.splat(0.0));
    let h = l.sqrt(h);
    let nb = l.neg(b);
    let no = l.splat(NO_HIT);
    (
        l.select(miss, no, l.sub(nb, h)),
        l.select(miss, no, l.add(nb, h)),
    )
}

/// `intersect_cone` of one cone with every lane: both crossings, `NO_HIT` where there is
/// none. The scalar test's operations in its order; its branches become selects (a lane
/// parallel to a generating line takes the linear root, the others the quadratic's), and
/// `f32::min`/`max` of the two roots is written as x86-64 lowers them (the first operand
/// NaN gives the second, else `minps(r1, r0)`), which a unit test holds against `f32::min`
/// itself on zeros and NaN.
#[inline(always)]
pub fn cone<L: Lanes>(l: L, p: &GpuPrim, r: &Rays<L>) -> (L::F, L::F) {
    let s = |x: f32| l.splat(x);
    // The cone's own constants, once for all lanes (`inv`, `delta`: `intersect_cone`'s).
    let axis = p.p1 - p.p0;
    let inv = s(1.0 / axis.dot(axis));
    let delta = p.f1 - p.f0;
    let mid = 0.5 * (p.p0 + p.p1);
    let a = [s(axis.x), s(axis.y), s(axis.z)];
    let dot = |u: &[L::F; 3], v: &[L::F; 3]| dot(l, u, v);
    let [o, d] = [&r.o, &r.d];
    let to_mid = [
        l.sub(s(mid.x), o[0]),
        l.sub(s(mid.y), o[1]),
        l.sub(s(mid.z), o[2]),
    ];
    let tc = dot(&to_mid, d);
    let co = [
        l.sub(l.add(o[0], l.mul(tc, d[0])), s(p.p0.x)),
        l.sub(l.add(o[1], l.mul(tc, d[1])), s(p.p0.y)),
        l.sub(l.add(o[2], l.mul(tc, d[2])), s(p.p0.z)),
    ];
    let dv = l.mul(dot(d, &a), inv);
    let cv = l.mul(dot(&co, &a), inv);
    let dp = [
        l.sub(d[0], l.mul(dv, a[0])),
        l.sub(d[1], l.mul(dv, a[1])),
        l.sub(d[2], l.mul(dv, a[2])),
    ];
    let cp = [
        l.sub(co[0], l.mul(cv, a[0])),
        l.sub(co[1], l.mul(cv, a[1])),
        l.sub(co[2], l.mul(cv, a[2])),
    ];
    let rr = l.add(s(p.f0), l.mul(s(delta), cv));
    let kd = l.mul(s(delta), dv);
    let qa = l.sub(dot(&dp, &dp), l.mul(kd, kd));
    let qb = l.sub(dot(&cp, &dp), l.mul(rr, kd));
    let qc = l.sub(dot(&cp, &cp), l.mul(rr, rr));
    let (zero, no) = (s(0.0), s(NO_HIT));
    // |qa| < 1e-12 (a NaN `qa` fails it, as the scalar's `abs` does).
    let parallel = l.lt(l.max(qa, l.neg(qa)), s(1e-12));
    let linear = l.select(l.ne(qb, zero), l.div(l.neg(qc), l.mul(s(2.0), qb)), no);
    let disc = l.sub(l.mul(qb, qb), l.mul(qa, qc));
    let sq = l.sqrt(disc);
    let r0 = l.div(l.sub(l.neg(qb), sq), qa);
    let r1 = l.div(l.add(l.neg(qb), sq), qa);
    let r0_nan = l.ne(r0, r0);
    let t0 = l.select(parallel, linear, l.select(r0_nan, r1, l.min(r1, r0)));
    let t1 = l.select(parallel, no, l.select(r0_nan, r1, l.max(r1, r0)));
    // Between the caps, where the radius is not negative; none where the quadratic has
    // no root (the scalar returns before this test there).
    let no_roots = l.and_not(l.lt(disc, zero), parallel);
    let (ok0, ok1) = (
        l.and_not(cone_valid(l, t0, (cv, dv), (p.f0, delta)), no_roots),
        l.and_not(cone_valid(l, t1, (cv, dv), (p.f0, delta)), no_roots),
    );
    let (t0, t1) = (l.add(t0, tc), l.add(t1, tc));
    (
        l.select(ok0, t0, l.select(ok1, t1, no)),
        l.select(l.and(ok0, ok1), t1, no),
    )
}

/// `a . b` in lanes, in `Vec3::dot`'s order. A function, not a closure: a closure that
/// is not inlined is compiled without the kernel's instruction set, and every `Lanes`
/// operation in it becomes a call.
#[inline(always)]
fn dot<L: Lanes>(l: L, a: &[L::F; 3], b: &[L::F; 3]) -> L::F {
    l.add(
        l.add(l.mul(a[0], b[0]), l.mul(a[1], b[1])),
        l.mul(a[2], b[2]),
    )
}

/// `intersect_cone`'s test of a crossing `t`: between the caps (the axis coordinate `cv +
/// t dv` in `[0, 1]`) where the radius `f0 + delta s` is not negative.
#[inline(always)]
fn cone_valid<L: Lanes>(l: L, t: L::F, (cv, dv): (L::F, L::F), (f0, delta): (f32, f32)) -> L::M {
    let zero = l.splat(0.0);
    let sv = l.add(cv, l.mul(t, dv));
    let ok = l.and(l.ne(t, l.splat(NO_HIT)), l.le(zero, sv));
    let ok = l.and(ok, l.le(sv, l.splat(1.0)));
    l.and(
        ok,
        l.le(zero, l.add(l.splat(f0), l.mul(l.splat(delta), sv))),
    )
}

/// `intersect_plane` with every lane.
#[inline(always)]
pub fn plane<L: Lanes>(l: L, pl: &GpuPlane, r: &Rays<L>) -> L::F {
    let n = [
        l.splat(pl.normal.x),
        l.splat(pl.normal.y),
        l.splat(pl.normal.z),
    ];
    let dot = |v: &[L::F; 3]| {
        l.add(
            l.add(l.mul(n[0], v[0]), l.mul(n[1], v[1])),
            l.mul(n[2], v[2]),
        )
    };
    let denom = dot(&r.d);
    let t = l.div(l.sub(l.splat(pl.d), dot(&r.o)), denom);
    l.select(l.eq(denom, l.splat(0.0)), l.splat(NO_HIT), t)
}

/// Per lane, the nearest hit so far: its distance (the interval's end from then on), what
/// was hit, a triangle's barycentrics; and the lanes that met a surface at exactly the
/// distance of the one they hold.
#[derive(Clone, Copy)]
pub struct Best<L: Lanes> {
    pub t: L::F,
    u: L::F,
    v: L::F,
    /// Primitive indices as bits.
    prim: L::F,
    tied: L::M,
    /// The interval's end the walk started with: a distance below it is a hit.
    t0: L::F,
}

impl<L: Lanes> Best<L> {
    #[inline(always)]
    pub fn new(l: L, rows: &Rows) -> Self {
        let t = l.load(&rows.tmax);
        Best {
            t,
            u: l.splat(0.0),
            v: l.splat(0.0),
            prim: l.splat_bits(NO_PRIM),
            tied: l.mask(0),
            t0: t,
        }
    }

    /// A crossing `t` (the first past `tmin`) of primitive `prim` in the lanes `active`:
    /// kept where it is nearer than the lane's hit, as `closest_in_leaf` keeps it.
    #[inline(always)]
    fn offer(&mut self, l: L, r: &Rays<L>, active: L::M, t: L::F, uv: (L::F, L::F), prim: u32) {
        let live = l.and(active, l.gt(t, r.tmin));
        let same = l.and(l.eq(t, self.t), l.lt(self.t, self.t0));
        self.tied = l.or(self.tied, l.and(live, same));
        let take = l.and(live, l.lt(t, self.t));
        self.t = l.select(take, t, self.t);
        self.u = l.select(take, uv.0, self.u);
        self.v = l.select(take, uv.1, self.v);
        self.prim = l.select(take, l.splat_bits(prim), self.prim);
    }

    /// The planes, before the tree and in their order, as `closest_hit` tests them.
    #[inline(always)]
    pub fn planes(&mut self, l: L, b: &Bindings, r: &Rays<L>, lanes: u32) {
        let active = l.mask(lanes);
        for (i, pl) in b.planes.iter().enumerate() {
            let t = plane(l, pl, r);
            let take = l.and(active, l.and(l.gt(t, r.tmin), l.lt(t, self.t)));
            self.t = l.select(take, t, self.t);
            self.prim = l.select(take, l.splat_bits(PLANE_FLAG | i as u32), self.prim);
        }
    }

    /// Writes the lanes' hits out.
    #[inline(always)]
    pub fn store(&self, l: L, found: &mut Found) {
        let mut prim = [0.0; MAX_LANES];
        l.store(self.t, &mut found.t);
        l.store(self.u, &mut found.u);
        l.store(self.v, &mut found.v);
        l.store(self.prim, &mut prim);
        for (p, f) in found.prim.iter_mut().zip(prim) {
            *p = f.to_bits();
        }
        found.tied = l.bits(self.tied);
    }

    /// Takes the lanes' hits back from `found` (after lanes walked on alone).
    #[inline(always)]
    pub fn reload(&mut self, l: L, found: &Found) {
        self.t = l.load(&found.t);
        self.u = l.load(&found.u);
        self.v = l.load(&found.v);
        let mut prim = [0.0; MAX_LANES];
        for (f, p) in prim.iter_mut().zip(found.prim) {
            *f = f32::from_bits(p);
        }
        self.prim = l.load(&prim);
        self.tied = l.mask(found.tied);
    }
}

/// The primitives `first..first + count` against the lanes `lanes`, nearest hits into `best`.
#[inline(always)]
pub fn closest<L: Lanes>(
    l: L,
    b: &Bindings,
    r: &Rays<L>,
    rows: &Rows,
    (first, count): (u32, u32),
    lanes: u32,
    best: &mut Best<L>,
) {
    let active = l.mask(lanes);
    for i in first..first + count {
        let p = &b.prims[i as usize];
        match p.kind() {
            PRIM_TRIANGLE => {
                let (t, u, v) = triangle(l, p, r);
                best.offer(l, r, active, t, (u, v), i);
            }
            PRIM_SPHERE => {
                let (t0, t1) = sphere(l, p, r);
                // `first_in`: the first crossing past tmin; the second one is farther.
                let t = l.select(l.gt(t0, r.tmin), t0, t1);
                let zero = l.splat(0.0);
                best.offer(l, r, active, t, (zero, zero), i);
            }
            PRIM_CONE => {
                let (t0, t1) = cone(l, p, r);
                // As for spheres: the first crossing past tmin.
                let t = l.select(l.gt(t0, r.tmin), t0, t1);
                let zero = l.splat(0.0);
                best.offer(l, r, active, t, (zero, zero), i);
            }
            _ => {
                // Boxes, one lane at a time with the scalar test.
                let (mut t, mut u, mut v): (Row, Row, Row) =
                    ([NO_HIT; MAX_LANES], [0.0; MAX_LANES], [0.0; MAX_LANES]);
                for k in lanes_of(lanes) {
                    let h = intersect::intersect_prim(p, &rows.ray(k), r.inv_of(k));
                    t[k] = if h.x > rows.tmin[k] { h.x } else { h.y };
                    (u[k], v[k]) = (h.z, h.w);
                }
                let uv = (l.load(&u), l.load(&v));
                best.offer(l, r, active, l.load(&t), uv, i);
            }
        }
    }
}

/// The primitives `first..first + count` against the shadow rays in `lanes`, whose
/// intervals are `(0, tmax)`: each crossing goes into `out` (`Occluded::cross`), and the
/// lanes it closes test no further primitive.
#[inline(always)]
pub fn occlusion<L: Lanes>(
    l: L,
    b: &Bindings,
    r: &Rays<L>,
    rows: &Rows,
    (first, count): (u32, u32),
    mut lanes: u32,
    out: &mut Occluded,
) {
    let (zero, tmax) = (l.splat(0.0), l.load(&rows.tmax));
    // Functions, not closures: one the compiler leaves out of line loses the kernel's
    // instruction set, and every operation becomes a call.
    // The lanes whose `t` lies in `(0, tmax)`.
    #[inline(always)]
    fn inside<L: Lanes>(l: L, t: L::F, zero: L::F, tmax: L::F) -> L::M {
        l.and(l.gt(t, zero), l.lt(t, tmax))
    }
    // The lanes crossing a surface of two roots once, and those crossing it twice.
    #[inline(always)]
    fn roots<L: Lanes>(l: L, (t0, t1): (L::F, L::F), zero: L::F, tmax: L::F) -> (u32, u32) {
        let (in0, in1) = (inside(l, t0, zero, tmax), inside(l, t1, zero, tmax));
        (l.bits(l.or(in0, in1)), l.bits(l.and(in0, in1)))
    }
    for i in first..first + count {
        let p = &b.prims[i as usize];
        let (once, twice) = match p.kind() {
            PRIM_TRIANGLE => (l.bits(inside(l, triangle(l, p, r).0, zero, tmax)), 0),
            PRIM_SPHERE => roots(l, sphere(l, p, r), zero, tmax),
            PRIM_CONE => roots(l, cone(l, p, r), zero, tmax),
            _ => lanes_of(lanes).fold((0, 0), |(once, twice), k| {
                let t = intersect::intersect_prim(p, &rows.ray(k), r.inv_of(k));
                let (lo, hi) = (0.0, rows.tmax[k]);
                let (in0, in1) = (t.x > lo && t.x < hi, t.y > lo && t.y < hi);
                (
                    once | u32::from(in0 || in1) << k,
                    twice | u32::from(in0 && in1) << k,
                )
            }),
        };
        let once = once & lanes;
        if once != 0 {
            out.cross(b, (i, p.material()), once, twice);
            lanes = out.open(lanes);
            if lanes == 0 {
                break;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cpu::fast::packet::lanes::Portable;
    use crate::cpu::intersect::intersect_cone;
    use crate::cpu::xorshift;
    use crate::gpu_types::PRIM_KIND_SHIFT;
    use glam::Vec3;

    /// `cone` gives each lane `intersect_cone`'s bits on random cones (cylinders, cones
    /// narrowing to a point and past it) and rays aimed near them, some along the axis,
    /// some along a generating line (the linear root), some from infinity (NaN).
    fn cones_match_the_scalar_test<L: Lanes>(l: L) {
        let mut rand = xorshift(0x5851_f42d_4c95_7f2d);
        let mut hits = 0;
        for case in 0..4_000 {
            let p0 = Vec3::new(rand(), rand(), rand()) * 10.0;
            let p1 = p0 + Vec3::new(rand(), rand(), rand()) * 4.0;
            let f0 = rand().abs() * 2.0;
            let f1 = match case % 4 {
                0 => f0,
                1 => 0.0,
                2 => -rand().abs(),
                _ => rand().abs() * 2.0,
            };
            // Every 10th: an upright cone whose generating lines have exact directions, so
            // that rays along them take the linear root (qa = 0 exactly).
            let exact = case % 10 == 7;
            let (p0, p1, f0, f1) = if exact {
                let base = Vec3::new(rand(), rand(), rand()).round() * 4.0;
                (base, base + Vec3::Z * 2.0, 1.0, 0.0)
            } else {
                (p0, p1, f0, f1)
            };
            let prim = GpuPrim {
                p0,
                p1,
                f0,
                f1,
                tag: PRIM_CONE << PRIM_KIND_SHIFT,
                ..Default::default()
            };
            let mut rows = Rows::default();
            for k in 0..L::N {
                let origin = Vec3::new(rand(), rand(), rand()) * 30.0;
                let aim = p0 + (p1 - p0) * (rand() + 0.5) + Vec3::new(rand(), rand(), rand());
                let mut dir = (aim - origin).normalize();
                let mut origin = origin;
                match (case + k) % 23 {
                    // Along the axis, and along a generating line (qa = 0).
                    0 => dir = (p1 - p0).normalize(),
                    1 => {
                        let w = (p1 - p0).normalize().any_orthonormal_vector();
                        let (base, top) = (p0 + w * f0, p1 + w * f1);
                        dir = (top - base).normalize();
                        origin = base - (top - base) * 3.0;
                    }
                    2 => origin.x = f32::INFINITY,
                    _ => {}
                }
                if exact && k % 4 != 3 {
                    // Parallel to the generating line from a point on the base rim to the
                    // apex, a quarter of the radius inside or outside it.
                    let rim = [Vec3::X, Vec3::Y, -Vec3::X, -Vec3::Y][(case / 10 + k) % 4];
                    dir = (Vec3::Z - 0.5 * rim) * [1.0, -1.0][k % 2];
                    let inside = rim * [0.75, 1.25][k % 3 / 2];
                    origin = p0 + inside - dir * (k % 3 + 1) as f32;
                }
                for a in 0..3 {
                    (rows.origin[a][k], rows.dir[a][k]) = (origin[a], dir[a]);
                }
            }
            let r = Rays::new(l, &rows);
            let (t0, t1) = cone(l, &prim, &r);
            let (mut t0s, mut t1s) = ([0.0; MAX_LANES], [0.0; MAX_LANES]);
            l.store(t0, &mut t0s);
            l.store(t1, &mut t1s);
            for k in 0..L::N {
                let want = intersect_cone(&prim, &rows.ray(k));
                assert_eq!(
                    t0s[k].to_bits(),
                    want.x.to_bits(),
                    "t0, case {case} lane {k}"
                );
                assert_eq!(
                    t1s[k].to_bits(),
                    want.y.to_bits(),
                    "t1, case {case} lane {k}"
                );
                hits += usize::from(want.x != NO_HIT);
            }
        }
        assert!(hits > 1_000, "only {hits} hits");
    }

    #[test]
    fn cones_in_every_instruction_set_match_the_scalar_test() {
        cones_match_the_scalar_test(Portable);
        #[cfg(target_arch = "x86_64")]
        {
            use crate::cpu::fast::packet::x86::{Avx2, Avx512, Sse};
            cones_match_the_scalar_test(Sse::new());
            match Avx2::detect() {
                Some(l) => cones_match_the_scalar_test(l),
                None => eprintln!("SKIPPED the AVX2 lanes: this processor lacks AVX2"),
            }
            match Avx512::detect() {
                Some(l) => cones_match_the_scalar_test(l),
                None => eprintln!("SKIPPED the AVX-512 lanes: this processor lacks AVX-512F"),
            }
        }
    }

    /// Random rays for the lanes of `L`, aimed at `aim` give or take `spread`, from
    /// `reach` away at most: some from inside what they aim at, some parallel to an axis
    /// (zero direction components), one in 23 from infinity (NaN).
    fn rays_at<L: Lanes>(
        rand: &mut impl FnMut() -> f32,
        aim: Vec3,
        spread: f32,
        reach: f32,
    ) -> Rows {
        let mut rows = Rows::default();
        for k in 0..L::N {
            let mut origin = aim + Vec3::new(rand(), rand(), rand()) * reach;
            let target = aim + Vec3::new(rand(), rand(), rand()) * spread;
            let mut dir = (target - origin).normalize();
            match k % 23 {
                0 => dir = Vec3::new(dir.x, 0.0, 0.0).normalize_or(Vec3::X),
                1 => origin.y = f32::INFINITY,
                2 => origin = aim,
                _ => {}
            }
            for a in 0..3 {
                (rows.origin[a][k], rows.dir[a][k]) = (origin[a], dir[a]);
            }
        }
        rows
    }

    /// `sphere`, `triangle` and `plane` give each lane the bits its ray gets alone
    /// (`intersect_sphere`, `intersect_triangles4` of a leaf of the triangle twice,
    /// `intersect_plane`):
    /// random spheres, triangles (thin ones, and edges the rays graze) and planes, rays
    /// aimed near them, some missing, some parallel, some from infinity.
    fn surfaces_match_the_scalar_tests<L: Lanes>(l: L) {
        use crate::cpu::intersect::{intersect_plane, intersect_sphere, intersect_triangles4};
        let mut rand = xorshift(0x2545_f491_4f6c_dd1d);
        let bits = |v: L::F| {
            let mut out = [0.0; MAX_LANES];
            l.store(v, &mut out);
            out.map(f32::to_bits)
        };
        let (mut sphere_hits, mut triangle_hits, mut plane_hits) = (0, 0, 0);
        for case in 0..3_000 {
            let centre = Vec3::new(rand(), rand(), rand()) * 20.0;
            let radius = rand().abs() * 3.0 + 1e-3;
            let ball = GpuPrim {
                p0: centre,
                f0: radius,
                tag: PRIM_SPHERE << PRIM_KIND_SHIFT,
                ..Default::default()
            };
            let rows = rays_at::<L>(&mut rand, centre, radius * 1.5, 15.0);
            let (t0, t1) = sphere(l, &ball, &Rays::new(l, &rows));
            let (t0, t1) = (bits(t0), bits(t1));
            for k in 0..L::N {
                let want = intersect_sphere(centre, radius, &rows.ray(k));
                assert_eq!(t0[k], want.x.to_bits(), "sphere t0, case {case} lane {k}");
                assert_eq!(t1[k], want.y.to_bits(), "sphere t1, case {case} lane {k}");
                sphere_hits += usize::from(want.x != NO_HIT);
            }

            // Edges from the first corner, as the packed records hold a triangle; every
            // 5th a sliver.
            let v0 = Vec3::new(rand(), rand(), rand()) * 20.0;
            let e1 = Vec3::new(rand(), rand(), rand()) * 4.0;
            let e2 = match case % 5 {
                0 => e1 * 0.5 + Vec3::new(rand(), rand(), rand()) * 1e-3,
                _ => Vec3::new(rand(), rand(), rand()) * 4.0,
            };
            let tri = GpuPrim {
                p0: v0,
                p1: e1,
                p2: e2,
                tag: PRIM_TRIANGLE << PRIM_KIND_SHIFT,
                ..Default::default()
            };
            let rows = rays_at::<L>(&mut rand, v0 + (e1 + e2) * 0.3, 3.0, 15.0);
            let (t, u, v) = triangle(l, &tri, &Rays::new(l, &rows));
            let (t, u, v) = (bits(t), bits(u), bits(v));
            for k in 0..L::N {
                let (wt, wu, wv) =
                    intersect_triangles4(&[tri, tri], &rows.ray(k)).expect("a block");
                assert_eq!(t[k], wt.x.to_bits(), "triangle t, case {case} lane {k}");
                if wt.x != NO_HIT {
                    assert_eq!(
                        (u[k], v[k]),
                        (wu.x.to_bits(), wv.x.to_bits()),
                        "case {case}"
                    );
                    triangle_hits += 1;
                }
            }

            let normal = Vec3::new(rand(), rand(), rand()).normalize_or(Vec3::Z);
            let normal = if case % 7 == 0 { Vec3::Y } else { normal };
            let pl = GpuPlane {
                normal,
                d: rand() * 10.0,
                ..Default::default()
            };
            let rows = rays_at::<L>(&mut rand, normal * pl.d, 5.0, 15.0);
            let t = bits(plane(l, &pl, &Rays::new(l, &rows)));
            for (k, &got) in t.iter().enumerate().take(L::N) {
                let want = intersect_plane(&pl, &rows.ray(k));
                assert_eq!(got, want.to_bits(), "plane, case {case} lane {k}");
                plane_hits += usize::from(want != NO_HIT && want > 0.0);
            }
        }
        let n = 3_000 * L::N;
        assert!(sphere_hits > n / 4, "only {sphere_hits} sphere hits of {n}");
        assert!(
            triangle_hits > n / 20,
            "only {triangle_hits} triangle hits of {n}"
        );
        assert!(plane_hits > n / 4, "only {plane_hits} plane hits of {n}");
    }

    #[test]
    fn spheres_triangles_and_planes_in_every_instruction_set_match_the_scalar_tests() {
        surfaces_match_the_scalar_tests(Portable);
        #[cfg(target_arch = "x86_64")]
        {
            use crate::cpu::fast::packet::x86::{Avx2, Avx512, Sse};
            surfaces_match_the_scalar_tests(Sse::new());
            match Avx2::detect() {
                Some(l) => surfaces_match_the_scalar_tests(l),
                None => eprintln!("SKIPPED the AVX2 lanes: this processor lacks AVX2"),
            }
            match Avx512::detect() {
                Some(l) => surfaces_match_the_scalar_tests(l),
                None => eprintln!("SKIPPED the AVX-512 lanes: this processor lacks AVX-512F"),
            }
        }
    }

    /// The way `cone` orders its two roots is `f32::min` and `max` on this machine, on
    /// zeros of both signs, infinities and NaN.
    #[test]
    fn the_roots_order_as_f32_min_and_max() {
        let l = Portable;
        let values = [0.0, -0.0, 1.0, -1.0, f32::INFINITY, f32::NAN];
        for r0 in values {
            for r1 in values {
                let (a, b) = (l.splat(r0), l.splat(r1));
                let nan = l.ne(a, a);
                let lo = l.select(nan, b, l.min(b, a))[0];
                let hi = l.select(nan, b, l.max(b, a))[0];
                let (min, max) = (std::hint::black_box(r0).min(r1), r0.max(r1));
                assert_eq!(lo.to_bits(), min.to_bits(), "min({r0}, {r1})");
                assert_eq!(hi.to_bits(), max.to_bits(), "max({r0}, {r1})");
            }
        }
    }
}
