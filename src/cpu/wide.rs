//! The CPU renderer's walk of its eight-wide tree (`bvh::wide::WideNode`): the boxes of a
//! node's children tested together in SIMD lanes, the children reached entered nearest
//! first.
//!
//! Each lane's box test is `intersect::overlaps` to the bit, so a ray finds the same
//! primitives tested by the same code as the binary walk: only the order in which leaves
//! are visited differs. The closest hit is therefore the binary walk's (the first of two
//! primitives at exactly the same distance may differ), which is why the colour a pixel
//! gets does not depend on the walk; the `cost` AOV, which counts the nodes of the GPU's
//! walk, still uses the binary walk (`Bindings::new`).

use std::mem::MaybeUninit;

use glam::{Vec3, Vec4};

use crate::bvh::wide::{EMPTY, Lanes, WIDTH, WideNode};
use crate::gpu_types::{SLAB_WIDEN, TRAVERSAL_STACK};

/// A child waiting on the stack: where it leads (`WideNode::child`, `count`) and where the
/// ray enters its box.
#[derive(Clone, Copy)]
struct Entry {
    child: u32,
    count: u32,
    near: f32,
}

/// Entries a walk can hold: a wide tree is no deeper than the binary one, which is below
/// `TRAVERSAL_STACK`, and each level leaves at most `WIDTH - 1` children waiting.
const STACK: usize = TRAVERSAL_STACK * (WIDTH - 1) + 1;

/// The ray's constants for the eight-lane slab test.
pub struct Slabs {
    origin: [Vec4; 3],
    inv_dir: [Vec4; 3],
    /// Per axis, whether the direction is negative: then `hi` is the near face.
    neg: [bool; 3],
}

impl Slabs {
    pub fn new(origin: Vec3, inv_dir: Vec3) -> Self {
        Slabs {
            origin: [0, 1, 2].map(|a| Vec4::splat(origin[a])),
            inv_dir: [0, 1, 2].map(|a| Vec4::splat(inv_dir[a])),
            neg: [0, 1, 2].map(|a| inv_dir[a] < 0.0),
        }
    }

    /// `intersect::slab_entry` for the eight boxes at once: where the ray enters each,
    /// clamped to `tmin`, and a bit mask of those it overlaps within `[tmin, tmax]`.
    /// Choosing the near face by the sign of the inverse direction gives the same value
    /// as the scalar `min(t0, t1)`, since that sign orders `t0` and `t1`.
    #[inline(always)]
    pub(crate) fn test(&self, n: &WideNode, tmin: f32, tmax: f32) -> (Lanes, u32) {
        let mut near = [Vec4::ZERO; WIDTH / 4];
        let mut mask = 0;
        for (half, near) in near.iter_mut().enumerate() {
            let t = |axis: usize, is_near: bool| {
                let face = if self.neg[axis] == is_near {
                    n.hi[axis][half]
                } else {
                    n.lo[axis][half]
                };
                (face - self.origin[axis]) * self.inv_dir[axis]
            };
            *near = t(0, true)
                .max(t(1, true))
                .max(t(2, true))
                .max(Vec4::splat(tmin));
            let far = t(0, false)
                .min(t(1, false))
                .min(t(2, false))
                .min(Vec4::splat(tmax));
            mask |= near.cmple(far * SLAB_WIDEN).bitmask() << (4 * half);
        }
        (near, mask)
    }
}

/// Depth-first walk of the wide tree, nearest child first: calls `leaf(first, count)`
/// for each leaf the ray reaches, which returns the interval end to cull with from then
/// on (the nearest hit so far), or `None` to stop. Adds the nodes it fetched to `nodes`.
/// Without `NEAREST_FIRST` (a shadow ray's walk, in any order) `leaf` must return `tmax`
/// itself: the interval never shrinks, so no child waiting is culled again and where the
/// ray enters each is not kept.
#[inline(always)]
pub fn walk<const NEAREST_FIRST: bool>(
    wide: &[WideNode],
    slabs: &Slabs,
    tmin: f32,
    tmax: f32,
    nodes: &mut u32,
    leaf: impl FnMut(u32, u32) -> Option<f32>,
) {
    walk_from::<NEAREST_FIRST>(wide, slabs, 0, tmin, tmax, nodes, leaf);
}

/// `walk` of the subtree under the wide node `node` (its children, not its own box): where
/// a packet's walk hands a lane over to a walk of its own (`packet::walk`).
#[inline(always)]
pub fn walk_from<const NEAREST_FIRST: bool>(
    wide: &[WideNode],
    slabs: &Slabs,
    node: u32,
    tmin: f32,
    mut tmax: f32,
    nodes: &mut u32,
    mut leaf: impl FnMut(u32, u32) -> Option<f32>,
) {
    // Not zeroed: a ray's walk touches a few of these 193 entries, and clearing all
    // 2.3 KB for every ray made the walk 20 to 30% slower (teapot-6, tree-11). Only
    // entries below `sp` are ever read.
    let mut stack = [const { MaybeUninit::<Entry>::uninit() }; STACK];
    let mut sp = 0;
    let mut next = Entry {
        child: node,
        count: 0,
        near: tmin,
    };
    loop {
        if next.count > 0 {
            // An empty lane is reached only by a ray whose slab distances are NaN (an
            // origin at infinity), which the min/max chain lets through as the scalar
            // test does: it leads nowhere.
            if next.count != EMPTY {
                match leaf(next.child, next.count) {
                    Some(t) => {
                        debug_assert!(
                            NEAREST_FIRST || t == tmax,
                            "an any-order walk's interval shrank"
                        );
                        tmax = t
                    }
                    None => return,
                }
            }
        } else {
            let n = &wide[next.child as usize];
            *nodes += 1;
            let (near, mut mask) = slabs.test(n, tmin, tmax);
            let entry = |lane: usize| Entry {
                child: n.child[lane],
                count: n.count[lane],
                near: if NEAREST_FIRST {
                    near[lane / 4][lane % 4]
                } else {
                    tmin
                },
            };
            if mask != 0 && mask & (mask - 1) == 0 {
                // One child reached (the common case): straight on, nothing pushed.
                next = entry(mask.trailing_zeros() as usize);
                continue;
            }
            // Push the children reached farthest first, so that the nearest is taken
            // next: insertion into the run pushed for this node.
            let base = sp;
            while mask != 0 {
                let e = entry(mask.trailing_zeros() as usize);
                mask &= mask - 1;
                let mut j = sp;
                // SAFETY: entries below `sp` have been written.
                while NEAREST_FIRST
                    && j > base
                    && unsafe { stack[j - 1].assume_init() }.near < e.near
                {
                    stack[j] = stack[j - 1];
                    j -= 1;
                }
                stack[j] = MaybeUninit::new(e);
                sp += 1;
            }
        }
        // The next waiting child the ray can still reach before `tmax`.
        loop {
            if sp == 0 {
                return;
            }
            sp -= 1;
            // SAFETY: entries below the old `sp` have been written.
            next = unsafe { stack[sp].assume_init() };
            if !NEAREST_FIRST || next.near <= tmax * SLAB_WIDEN {
                break;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bvh::{self, Quality, wide::build};
    use obvhs::aabb::Aabb;

    fn boxes(n: usize) -> Vec<Aabb> {
        (0..n)
            .map(|i| {
                let p = glam::Vec3A::new((i * 7 % 13) as f32, (i * 5 % 11) as f32, i as f32 * 0.1);
                Aabb {
                    min: p,
                    max: p + 0.5,
                }
            })
            .collect()
    }

    /// A ray from infinity gets NaN slab distances from the empty lanes' infinite
    /// boxes, which the min/max chain lets through, and infinite ones from real boxes,
    /// which it misses: the walk hands no leaf over (an empty lane would be a leaf of
    /// `EMPTY` primitives).
    #[test]
    fn a_ray_from_infinity_reaches_only_real_leaves() {
        let binary = bvh::build(&boxes(3), Quality::High);
        let wide = build(&binary.nodes);
        assert!(wide[0].count.contains(&EMPTY));
        let origin = Vec3::new(f32::INFINITY, f32::NEG_INFINITY, f32::INFINITY);
        let slabs = Slabs::new(origin, Vec3::new(1.25, 1.75, -11.25));
        let mut leaves = Vec::new();
        walk::<true>(&wide, &slabs, 0.0, f32::MAX, &mut 0, |first, count| {
            leaves.push((first, count));
            Some(f32::MAX)
        });
        assert_eq!(leaves, []);
    }
}
