//! A leaf's primitives against a packet's lanes: triangles, spheres and planes in SIMD
//! across the rays, with `intersect.rs`'s operations in `intersect.rs`'s order (so each lane
//! gets the bits its ray gets alone); cones and boxes lane by lane with `intersect_prim`
//! itself. The nearest hit so far is kept per lane (`Best`), as `closest_in_leaf` keeps it.

use super::lanes::{Lanes, MAX_LANES, Row};
use super::rays::{Found, Occluded, Rays, Rows};
use crate::cpu::intersect::{self, lanes_of};
use crate::cpu::types::Bindings;
use crate::gpu_types::{
    GpuPlane, GpuPrim, NO_HIT, NO_PRIM, PLANE_FLAG, PRIM_SPHERE, PRIM_TRIANGLE,
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
            _ => {
                // Cones and boxes, one lane at a time with the scalar test.
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
/// intervals are `(0, tmax)`: the lanes each primitive crosses end there, blocked by an
/// opaque one, or handed to `transmission` by one that transmits.
#[inline(always)]
pub fn occlusion<L: Lanes>(
    l: L,
    b: &Bindings,
    r: &Rays<L>,
    rows: &Rows,
    (first, count): (u32, u32),
    mut lanes: u32,
    tmax: L::F,
) -> Occluded {
    let zero = l.splat(0.0);
    let inside = |t: L::F| l.and(l.gt(t, zero), l.lt(t, tmax));
    let mut out = Occluded::default();
    for i in first..first + count {
        let p = &b.prims[i as usize];
        let crossed = match p.kind() {
            PRIM_TRIANGLE => l.bits(inside(triangle(l, p, r).0)),
            PRIM_SPHERE => {
                let (t0, t1) = sphere(l, p, r);
                l.bits(l.or(inside(t0), inside(t1)))
            }
            _ => lanes_of(lanes).fold(0, |m, k| {
                let t = intersect::intersect_prim(p, &rows.ray(k), r.inv_of(k));
                let (lo, hi) = (0.0, rows.tmax[k]);
                let crosses = (t.x > lo && t.x < hi) || (t.y > lo && t.y < hi);
                m | u32::from(crosses) << k
            }),
        } & lanes;
        if crossed != 0 {
            if b.materials[p.material() as usize].t <= 0.0 {
                out.blocked |= crossed;
            } else {
                out.transmits |= crossed;
            }
            lanes &= !crossed;
            if lanes == 0 {
                break;
            }
        }
    }
    out
}
