//! What the packet kernels read and write: a packet's rays as rows of lane values
//! (`Rows`), the same in SIMD lanes (`Rays`), and their answers (`Found`, `Occluded`).

use glam::Vec3;

use super::lanes::{Lanes, MAX_LANES, Row};
use crate::cpu::intersect::lanes_of;
use crate::cpu::types::{Bindings, Ray};

/// A packet as the kernels read it: one row a coordinate, lane `k` of each the `k`-th ray.
#[derive(Clone, Debug)]
pub struct Rows {
    pub origin: [Row; 3],
    pub dir: [Row; 3],
    /// Each ray's interval `(tmin, tmax)`.
    pub tmin: Row,
    pub tmax: Row,
    /// The lanes holding a ray.
    pub lanes: u32,
}

impl Default for Rows {
    fn default() -> Self {
        Rows {
            origin: [[0.0; MAX_LANES]; 3],
            dir: [[0.0; MAX_LANES]; 3],
            tmin: [0.0; MAX_LANES],
            tmax: [0.0; MAX_LANES],
            lanes: 0,
        }
    }
}

impl Rows {
    /// Lane `k`'s ray.
    #[inline]
    pub fn ray(&self, k: usize) -> Ray {
        Ray {
            origin: self.at(&self.origin, k),
            dir: self.at(&self.dir, k),
        }
    }

    fn at(&self, rows: &[Row; 3], k: usize) -> Vec3 {
        at(rows, k)
    }
}

fn at(rows: &[Row; 3], k: usize) -> Vec3 {
    Vec3::new(rows[0][k], rows[1][k], rows[2][k])
}

/// A packet's rays in lanes.
pub struct Rays<L: Lanes> {
    pub o: [L::F; 3],
    pub d: [L::F; 3],
    /// `intersect::safe_inverse` of the directions, as the single-ray walk has them; and
    /// the same in rows, for lanes tested one at a time and for the interval test.
    pub inv: [L::F; 3],
    pub inv_rows: [Row; 3],
    /// Per axis, the lanes whose direction is negative: their boxes' `hi` faces are near.
    pub neg: [L::M; 3],
    pub tmin: L::F,
    /// The lanes whose origin, direction and `tmin` are finite: the others have no place
    /// in a packet (their slab distances may be NaN, where the interval test's bounds
    /// fail), and go alone.
    pub finite: u32,
}

impl<L: Lanes> Rays<L> {
    #[inline(always)]
    pub fn new(l: L, rows: &Rows) -> Self {
        // Written out: `array::map` is not always inlined, and then neither are the
        // instructions it calls (`Lanes` in lanes.rs).
        let load3 = |r: &[Row; 3]| [l.load(&r[0]), l.load(&r[1]), l.load(&r[2])];
        let d = load3(&rows.dir);
        // `safe_inverse`: a component below 1e-30 in size becomes 1e-30, then 1 / it.
        let (tiny, one) = (l.splat(1e-30), l.splat(1.0));
        let safe = |d: L::F| {
            let small = l.and(l.lt(d, tiny), l.gt(d, l.neg(tiny)));
            l.div(one, l.select(small, tiny, d))
        };
        let inv = [safe(d[0]), safe(d[1]), safe(d[2])];
        let mut inv_rows = [[0.0; MAX_LANES]; 3];
        l.store(inv[0], &mut inv_rows[0]);
        l.store(inv[1], &mut inv_rows[1]);
        l.store(inv[2], &mut inv_rows[2]);
        let zero = l.splat(0.0);
        let o = load3(&rows.origin);
        let tmin = l.load(&rows.tmin);
        let mut finite = l.mask(u32::MAX);
        for v in [o[0], o[1], o[2], d[0], d[1], d[2], tmin] {
            // `v - v` is 0 but for infinities and NaN.
            finite = l.and(finite, l.eq(l.sub(v, v), zero));
        }
        Rays {
            o,
            d,
            neg: [l.lt(inv[0], zero), l.lt(inv[1], zero), l.lt(inv[2], zero)],
            inv,
            inv_rows,
            tmin,
            finite: l.bits(finite),
        }
    }

    /// Lane `k`'s inverse direction.
    #[inline(always)]
    pub fn inv_of(&self, k: usize) -> Vec3 {
        at(&self.inv_rows, k)
    }
}

/// A closest-hit kernel's answer, per lane: the single-ray walk's `Hit` (but `cost`), and
/// the lanes that met two surfaces at exactly one distance: which of the two the single
/// walk keeps depends on the order it visits them in, so those lanes take its answer.
#[derive(Clone, Debug)]
pub struct Found {
    pub t: Row,
    pub prim: [u32; MAX_LANES],
    pub u: Row,
    pub v: Row,
    pub tied: u32,
    /// The lanes the kernel traced (`Rays::finite`).
    pub traced: u32,
    /// Wide nodes the walk fetched: once a node for the whole packet, and those of the
    /// lanes' walks alone.
    pub nodes: u32,
}

impl Default for Found {
    fn default() -> Self {
        Found {
            t: [0.0; MAX_LANES],
            prim: [0; MAX_LANES],
            u: [0.0; MAX_LANES],
            v: [0.0; MAX_LANES],
            tied: 0,
            traced: 0,
            nodes: 0,
        }
    }
}

/// An occlusion kernel's answer: the lanes that cross an opaque surface (no light arrives),
/// and those that cross only surfaces that transmit light, whose factors multiply the
/// light in the order the single-ray `transmission` visits them. Where every crossing is
/// of one material the order cannot change a bit of the product (the same factor each
/// time), so the packet answers it (`transmits`, `material`, `crossings`); where a lane
/// crosses two materials it is left to `transmission` (`mixed`). The other lanes cross
/// nothing.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Occluded {
    pub blocked: u32,
    pub transmits: u32,
    pub mixed: u32,
    /// The material of a lane in `transmits`, and how many times it crosses its surfaces.
    pub material: [u32; MAX_LANES],
    pub crossings: [u32; MAX_LANES],
    /// The lanes the kernel traced (`Rays::finite`).
    pub traced: u32,
    /// Wide nodes the walk fetched, as `Found::nodes`.
    pub nodes: u32,
    /// The opaque primitive that blocked a lane last, if one did.
    pub blocker: Option<u32>,
}

impl Occluded {
    /// The lanes still walking: those that have met neither an opaque surface nor a
    /// second material.
    #[inline(always)]
    pub fn open(&self, lanes: u32) -> u32 {
        lanes & !(self.blocked | self.mixed)
    }

    /// The lanes `once` cross a surface of primitive `prim`, of material `material`, those
    /// of them in `twice` a second time (a sphere or cone passed through).
    #[inline(always)]
    pub fn cross(&mut self, b: &Bindings, (prim, material): (u32, u32), once: u32, twice: u32) {
        let once = self.open(once);
        if once == 0 {
            return;
        }
        if b.materials[material as usize].t <= 0.0 {
            self.blocked |= once;
            self.blocker = Some(prim);
            return;
        }
        for k in lanes_of(once) {
            let bit = 1 << k;
            if self.transmits & bit == 0 {
                self.transmits |= bit;
                self.material[k] = material;
                self.crossings[k] = 0;
            } else if self.material[k] != material {
                self.mixed |= bit;
                continue;
            }
            self.crossings[k] += 1 + (twice >> k & 1);
        }
    }
}
