//! The interval test that culls a wide node's children for a whole packet at once: the
//! packet's origins and inverse directions as intervals, per axis, and from them a lower
//! bound on where any of its rays enters each child box and an upper bound on where it
//! leaves (interval arithmetic, Benthin's thesis ch. 4; Reshetov et al.'s "multi-level
//! ray tracing"). Eight children in two `Vec4`s, one test for all of them.
//!
//! The bounds are safe in floating point without any margin: every step (a subtraction, a
//! product, a minimum) is monotonic in its operands, even rounded, so the bound computed
//! from an interval's end is never on the wrong side of what a lane computes for its own
//! ray with the same operations (`walk::child_slab`). A child culled here is one that every
//! lane's own test would miss; the lanes' own tests still decide what each lane enters.

use glam::Vec4;

use super::lanes::Lanes;
use super::rays::Rays;
use crate::bvh::wide::{WIDTH, WideNode};
use crate::gpu_types::SLAB_WIDEN;

/// One axis of the packet, where all its directions have one sign on it, its values
/// spread over four lanes (a node's boxes are four to a `Vec4`).
#[derive(Clone, Copy, Debug)]
struct Axis {
    /// Which axis (0, 1, 2).
    a: usize,
    /// The directions are negative: the boxes' `hi` faces are the near ones.
    neg: bool,
    /// The origin coordinate that makes `face - origin` smallest for the near face and
    /// largest for the far face (`max` then `min` of the lanes' for a positive direction).
    o_near: Vec4,
    o_far: Vec4,
    /// The lanes' inverse directions on this axis, least and greatest.
    i_lo: Vec4,
    i_hi: Vec4,
}

/// A packet's rays as intervals, per axis; an axis on which the directions differ in sign
/// bounds nothing (its interval of inverses spans both infinities' neighbourhoods), and is
/// left out: `axes[..bounded]` are the others.
#[derive(Clone, Copy, Debug)]
pub struct Frustum {
    axes: [Axis; 3],
    bounded: usize,
}

impl Frustum {
    /// The intervals of the lanes `lanes` of the rays `r`.
    #[inline(always)]
    pub fn new<L: Lanes>(l: L, r: &Rays<L>, lanes: u32) -> Self {
        let none = Axis {
            a: 0,
            neg: false,
            o_near: Vec4::ZERO,
            o_far: Vec4::ZERO,
            i_lo: Vec4::ZERO,
            i_hi: Vec4::ZERO,
        };
        let mut f = Frustum {
            axes: [none; 3],
            bounded: 0,
        };
        for a in 0..3 {
            let (i_lo, i_hi) = (l.min_of(r.inv[a], lanes), l.max_of(r.inv[a], lanes));
            let (o_lo, o_hi) = (l.min_of(r.o[a], lanes), l.max_of(r.o[a], lanes));
            let neg = i_hi < 0.0;
            if neg || i_lo > 0.0 {
                f.axes[f.bounded] = Axis {
                    a,
                    neg,
                    o_near: Vec4::splat(if neg { o_lo } else { o_hi }),
                    o_far: Vec4::splat(if neg { o_hi } else { o_lo }),
                    i_lo: Vec4::splat(i_lo),
                    i_hi: Vec4::splat(i_hi),
                };
                f.bounded += 1;
            }
        }
        f
    }

    /// The children of `n` that a ray of the packet may reach within `[tmin, tmax]` (the
    /// least `tmin` and greatest `tmax` of its lanes), as a bit mask, and for each child a
    /// lower bound of where the packet's rays enter it: the order to visit them in.
    #[inline(always)]
    pub fn cull(&self, n: &WideNode, tmin: f32, tmax: f32) -> (u32, [Vec4; WIDTH / 4]) {
        let mut near = [Vec4::splat(tmin); WIDTH / 4];
        let mut far = [Vec4::splat(tmax); WIDTH / 4];
        for x in &self.axes[..self.bounded] {
            let (near_face, far_face) = if x.neg {
                (&n.hi[x.a], &n.lo[x.a])
            } else {
                (&n.lo[x.a], &n.hi[x.a])
            };
            for half in 0..WIDTH / 4 {
                let dn = near_face[half] - x.o_near;
                let df = far_face[half] - x.o_far;
                near[half] = near[half].max((dn * x.i_lo).min(dn * x.i_hi));
                far[half] = far[half].min((df * x.i_lo).max(df * x.i_hi));
            }
        }
        let mut mask = 0;
        for half in 0..WIDTH / 4 {
            mask |= near[half].cmple(far[half] * SLAB_WIDEN).bitmask() << (4 * half);
        }
        (mask, near)
    }
}

#[cfg(test)]
mod tests {
    use super::super::lanes::Portable;
    use super::super::rays::Rows;
    use super::super::walk::child_slab;
    use super::*;
    use crate::cpu::intersect::lanes_of;
    use glam::Vec3;

    /// A node of eight random boxes (some empty) around the origin.
    fn node(rand: &mut impl FnMut() -> f32) -> WideNode {
        let mut n = WideNode::empty();
        for l in 0..WIDTH - 1 {
            for a in 0..3 {
                let (c, r) = (rand() * 10.0, rand().abs() * 3.0);
                n.lo[a][l / 4][l % 4] = c - r;
                n.hi[a][l / 4][l % 4] = c + r;
            }
            n.set_leaf(l, 0, 1);
        }
        n
    }

    /// Whatever the packet, a child culled by the interval test is missed by every lane's
    /// own slab test (the packet walk's `child_slab`), and children are culled:
    /// packets of nearly parallel rays, of rays through one point, and of rays whose
    /// directions differ in sign on an axis.
    #[test]
    fn a_culled_child_is_missed_by_every_lane() {
        let mut rand = crate::cpu::xorshift(0x9e37_79b9_7f4a_7c15);
        let (mut culled, mut kept) = (0, 0);
        for case in 0..3000 {
            let n = node(&mut rand);
            let base = Vec3::new(rand(), rand(), rand()) * 30.0;
            let aim = Vec3::new(rand(), rand(), rand()) * 8.0 - base;
            let spread = [0.001, 0.05, 1.0][case % 3];
            let mut rows = Rows::default();
            for k in 0..4 {
                let o = base + Vec3::new(rand(), rand(), rand()) * spread * (case % 2) as f32;
                let d = (aim + Vec3::new(rand(), rand(), rand()) * spread * 10.0).normalize();
                for a in 0..3 {
                    (rows.origin[a][k], rows.dir[a][k]) = (o[a], d[a]);
                }
            }
            let r = Rays::new(Portable, &rows);
            let f = Frustum::new(Portable, &r, 0xf);
            let tmax = if case % 5 == 0 { 20.0 } else { f32::MAX };
            let (mask, near) = f.cull(&n, 0.0, tmax);
            for k in 0..4 {
                let inv = crate::cpu::intersect::safe_inverse(rows.ray(k).dir);
                assert_eq!(inv, r.inv_of(k));
            }
            for c in 0..WIDTH {
                let (lane_near, reached) = child_slab(Portable, &r, &n, c, [tmax; 4]);
                for k in lanes_of(reached) {
                    assert_eq!(mask >> c & 1, 1, "case {case} lane {k}: culled child {c}");
                    assert!(near[c / 4][c % 4] <= lane_near[k], "case {case}");
                }
            }
            culled += (0x7f & !mask).count_ones();
            kept += mask.count_ones();
        }
        assert!(culled > 1000 && kept > 1000, "culled {culled}, kept {kept}");
    }
}
