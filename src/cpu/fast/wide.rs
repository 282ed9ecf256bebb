//! The CPU renderer's walk of its eight-wide tree (`bvh::wide::WideNode`): the boxes of a
//! node's children tested together in SIMD lanes, the children reached entered nearest
//! first.
//!
//! Each lane's box test is `intersect::overlaps` with its widening (`SLAB_WIDEN`) taken
//! into the far faces' distances, the inverse direction scaled before the product rather
//! than the nearest far face after it (`Slabs::inv_far`): one multiplication fewer on the
//! longest chain of dependent operations of a node's test. The two far ends differ by the
//! rounding of that product, a few ulps, where the widening is 2^-16: a box holding a hit
//! is overlapped under both, by far more than either's rounding, so a ray finds the same
//! nearest hit as the binary walk (the first of two primitives at exactly the same
//! distance may differ, as the order in which leaves are visited already lets), and the
//! colour a pixel gets does not depend on the walk. The packets' lanes keep `overlaps`'
//! arithmetic (`packet::walk`), and so meet the same nearest hits. The AVX2 copy
//! (`SlabsAvx`) takes its minima and maxima as integers, which give `Slabs`' entries and
//! boxes but where a ray leaves a box exactly at its origin (see there), where it overlaps
//! one box more. The `cost` AOV, which counts the nodes of the GPU's walk, still uses the
//! binary walk (`Bindings::new`).

use std::mem::MaybeUninit;

use glam::{Vec3, Vec4};

use crate::bvh::wide::{EMPTY, Lanes, Link, Tree, WIDTH, WideNode};
use crate::gpu_types::{SLAB_WIDEN, TRAVERSAL_STACK};

/// Lane `l` of `row`. Read from the row as eight floats: a `Vec4` indexed by a lane known
/// only at run time compiles to a jump table, an indirect branch at every read.
#[inline(always)]
pub(crate) fn lane(row: &Lanes, l: usize) -> f32 {
    bytemuck::cast_ref::<Lanes, [f32; WIDTH]>(row)[l]
}

/// A child waiting on the stack: where it leads and where the ray enters its box.
#[derive(Clone, Copy)]
struct Entry {
    link: Link,
    near: f32,
}

/// Entries a walk can hold: a wide tree is no deeper than the binary one, which is below
/// `TRAVERSAL_STACK`, and each level leaves at most `WIDTH - 1` children waiting.
const STACK: usize = TRAVERSAL_STACK * (WIDTH - 1) + 1;

/// The eight-lane slab test a walk uses: `Slabs`, in two halves of four lanes, or on
/// x86-64 with AVX2 `SlabsAvx`, in one register of eight (the same boxes but for one
/// case: see there).
pub trait Boxes {
    /// `intersect::slab_entry` for the eight boxes of `n` at once, widened as the module
    /// says: where the ray enters each, clamped to `tmin`, and a bit mask of those it
    /// overlaps within `[tmin, tmax]`.
    fn test(&self, n: &WideNode, tmin: f32, tmax: f32) -> (Lanes, u32);
}

/// The ray's constants for the eight-lane slab test.
pub struct Slabs {
    origin: [Vec4; 3],
    inv_dir: [Vec4; 3],
    /// `inv_dir * SLAB_WIDEN`, for the far faces: their distances come out widened.
    inv_far: [Vec4; 3],
    /// Per axis, the near face's index in `[lo, hi]`: 1 where the direction is negative.
    /// Choosing the near face by the sign of the inverse direction gives the same value
    /// as the scalar `min(t0, t1)`, since that sign orders `t0` and `t1`.
    near: [usize; 3],
}

impl Slabs {
    pub fn new(origin: Vec3, inv_dir: Vec3) -> Self {
        // Written out: `[0, 1, 2].map(..)` stayed a call on each ray.
        Slabs {
            origin: [
                Vec4::splat(origin.x),
                Vec4::splat(origin.y),
                Vec4::splat(origin.z),
            ],
            inv_dir: [
                Vec4::splat(inv_dir.x),
                Vec4::splat(inv_dir.y),
                Vec4::splat(inv_dir.z),
            ],
            inv_far: [
                Vec4::splat(inv_dir.x * SLAB_WIDEN),
                Vec4::splat(inv_dir.y * SLAB_WIDEN),
                Vec4::splat(inv_dir.z * SLAB_WIDEN),
            ],
            near: [
                usize::from(inv_dir.x < 0.0),
                usize::from(inv_dir.y < 0.0),
                usize::from(inv_dir.z < 0.0),
            ],
        }
    }
}

impl Boxes for Slabs {
    #[inline(always)]
    fn test(&self, n: &WideNode, tmin: f32, tmax: f32) -> (Lanes, u32) {
        let faces = [&n.lo, &n.hi];
        let mut near = [Vec4::ZERO; WIDTH / 4];
        let mut mask = 0;
        for (half, near) in near.iter_mut().enumerate() {
            let t = |axis: usize, face: usize, inv: &[Vec4; 3]| {
                (faces[face][axis][half] - self.origin[axis]) * inv[axis]
            };
            let ([nx, ny, nz], (inv, far)) = (self.near, (&self.inv_dir, &self.inv_far));
            *near = t(0, nx, inv)
                .max(t(1, ny, inv))
                .max(t(2, nz, inv))
                .max(Vec4::splat(tmin));
            let far = t(0, 1 - nx, far)
                .min(t(1, 1 - ny, far))
                .min(t(2, 1 - nz, far))
                .min(Vec4::splat(tmax * SLAB_WIDEN));
            mask |= near.cmple(far).bitmask() << (4 * half);
        }
        (near, mask)
    }
}

/// `Slabs::test` in one AVX register of eight lanes: the same subtractions and products
/// in the same order on each lane, so the same distances, and their minima and maxima as
/// integers (`test_avx` says why, and where that overlaps one box more); a node's test in
/// half the instructions. Made only where the processor has AVX2.
#[cfg(target_arch = "x86_64")]
pub struct SlabsAvx {
    slabs: Slabs,
    /// Per axis, the byte offsets in a `WideNode` of the near and the far faces' row
    /// (`lo` or `hi`): worked out once a ray. Chosen at each node, the rows' addresses
    /// took a compare and two conditional moves an axis, a quarter of a node's test.
    near: [usize; 3],
    far: [usize; 3],
}

/// The byte offset in a `WideNode` of the row of `face` (0: `lo`, 1: `hi`) on `axis`:
/// `hi` follows `lo` (`repr(C)`).
#[cfg(target_arch = "x86_64")]
const fn row_offset(face: usize, axis: usize) -> usize {
    std::mem::offset_of!(WideNode, lo) + (face * 3 + axis) * std::mem::size_of::<Lanes>()
}

#[cfg(target_arch = "x86_64")]
const _: () = assert!(std::mem::offset_of!(WideNode, hi) == row_offset(1, 0));

#[cfg(target_arch = "x86_64")]
impl SlabsAvx {
    /// # Safety
    /// The processor must have AVX2 (`isa::x86_64_v3`).
    pub unsafe fn new(slabs: Slabs) -> Self {
        let [nx, ny, nz] = slabs.near;
        SlabsAvx {
            near: [row_offset(nx, 0), row_offset(ny, 1), row_offset(nz, 2)],
            far: [
                row_offset(1 - nx, 0),
                row_offset(1 - ny, 1),
                row_offset(1 - nz, 2),
            ],
            slabs,
        }
    }

    #[target_feature(enable = "avx2")]
    #[inline]
    fn test_avx(&self, n: &WideNode, tmin: f32, tmax: f32) -> (Lanes, u32) {
        use std::arch::x86_64::*;
        let s = &self.slabs;
        let node = std::ptr::from_ref(n).cast::<u8>();
        // SAFETY: `offset` is a row's (`row_offset`): eight consecutive f32 in `n`.
        let load = |offset: usize| unsafe { _mm256_loadu_ps(node.add(offset).cast()) };
        let wide = |v: Vec4| _mm256_set_m128(v.into(), v.into());
        let t = |axis: usize, offset: usize, inv: &[Vec4; 3]| {
            let d = _mm256_sub_ps(load(offset), wide(s.origin[axis]));
            _mm256_mul_ps(d, wide(inv[axis]))
        };
        // Maxima and minima of the floats' bits as signed integers (Embree's `maxi` and
        // `mini`): a cycle each on the chain of dependent operations that a ray's walk
        // waits on, where the float ones take two to four; gears-4's mirror rays 2.7%
        // faster. Not NaN, floats whose sign bit is clear order as their bits do, and
        // every float with the sign bit set (a negative, or -0.0) lies below them all
        // as an integer. So where `tmin` is +0.0 or more, `near` is the float chain's to
        // the bit, and `far` is where that is not negative; where it is, `far` is a value
        // with the sign bit set too, which `near` exceeds, but for -0.0 where `near` is
        // 0: a ray that leaves a box exactly at its origin on one axis, and before it on
        // another, overlaps that box here and not under the float test. Otherwise (a
        // `tmin` below +0.0, NaN from an origin at infinity) `near` is no greater and
        // `far` no less than the float chain's: a box more, never one fewer.
        let (near, far, inv) = (self.near, self.far, &s.inv_dir);
        let bits = |v: __m256| _mm256_castps_si256(v);
        let maxi = |a, b| _mm256_castsi256_ps(_mm256_max_epi32(bits(a), bits(b)));
        let mini = |a, b| _mm256_castsi256_ps(_mm256_min_epi32(bits(a), bits(b)));
        let near = maxi(
            maxi(
                maxi(t(0, near[0], inv), t(1, near[1], inv)),
                t(2, near[2], inv),
            ),
            _mm256_set1_ps(tmin),
        );
        let inv = &s.inv_far;
        let far = mini(
            mini(
                mini(t(0, far[0], inv), t(1, far[1], inv)),
                t(2, far[2], inv),
            ),
            _mm256_set1_ps(tmax * SLAB_WIDEN),
        );
        let mask = _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_LE_OQ>(near, far)) as u32;
        let mut out = [Vec4::ZERO; WIDTH / 4];
        // SAFETY: `out` is eight consecutive f32.
        unsafe { _mm256_storeu_ps(out.as_mut_ptr().cast(), near) };
        (out, mask)
    }
}

#[cfg(target_arch = "x86_64")]
impl Boxes for SlabsAvx {
    #[inline(always)]
    fn test(&self, n: &WideNode, tmin: f32, tmax: f32) -> (Lanes, u32) {
        // SAFETY: a `SlabsAvx` exists only where the processor has AVX2.
        unsafe { self.test_avx(n, tmin, tmax) }
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
    wide: &Tree,
    slabs: &impl Boxes,
    tmin: f32,
    tmax: f32,
    nodes: &mut u32,
    leaf: impl FnMut(u32, u32) -> Option<f32>,
) {
    // SAFETY: every tree has a root (`Tree`).
    unsafe { walk_tree::<NEAREST_FIRST>(wide, slabs, Link::ROOT, tmin, tmax, nodes, leaf) };
}

/// `walk` of the subtree under the wide node `node` (its children, not its own box): where
/// a packet's walk hands a lane over to a walk of its own (`packet::walk`).
#[inline(always)]
pub fn walk_from<const NEAREST_FIRST: bool>(
    wide: &Tree,
    slabs: &impl Boxes,
    node: Link,
    tmin: f32,
    tmax: f32,
    nodes: &mut u32,
    leaf: impl FnMut(u32, u32) -> Option<f32>,
) {
    // Checked once a walk: every link the walk reads after it comes from the tree's own
    // nodes, which `build` checked.
    assert!(node.leads_into(wide), "a walk from outside the tree");
    // SAFETY: checked above.
    unsafe { walk_tree::<NEAREST_FIRST>(wide, slabs, node, tmin, tmax, nodes, leaf) };
}

/// `walk_from`, unchecked.
///
/// # Safety
/// `node` leads into the tree (`Link::leads_into`): the root, or an inner child's link read
/// from one of its nodes.
#[inline(always)]
unsafe fn walk_tree<const NEAREST_FIRST: bool>(
    wide: &Tree,
    slabs: &impl Boxes,
    node: Link,
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
        link: node,
        near: tmin,
    };
    loop {
        let count = next.link.count();
        if count > 0 {
            // An empty lane is reached only by a ray whose slab distances are NaN (an
            // origin at infinity), which the min/max chain lets through as the scalar
            // test does: it leads nowhere.
            if count != EMPTY {
                match leaf(next.link.first(), count) {
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
            // SAFETY: `next` is `node`, which leads into the tree (`walk_tree`'s contract),
            // or came from one of the tree's nodes and leads to an inner child.
            let n = unsafe { next.link.node(wide) };
            *nodes += 1;
            let (near, mut mask) = slabs.test(n, tmin, tmax);
            let entry = |l: usize| Entry {
                link: n.link(l),
                near: if NEAREST_FIRST { lane(&near, l) } else { tmin },
            };
            if mask != 0 && mask & (mask - 1) == 0 {
                // One child reached (the common case): straight on, nothing pushed.
                next = entry(mask.trailing_zeros() as usize);
                continue;
            }
            if NEAREST_FIRST && mask.count_ones() == 2 {
                // Two (the next most common): on to the nearer, the other pushed, as the
                // insertion below would order them (on a tie, the second lane first).
                let a = entry(mask.trailing_zeros() as usize);
                let b = entry((mask & (mask - 1)).trailing_zeros() as usize);
                // A branch, where a select of the 8-byte entries would make the next
                // node's fetch wait on the comparison (gears-4's mirror rays 4% slower).
                if a.near < b.near {
                    stack[sp] = MaybeUninit::new(b);
                    next = a;
                } else {
                    stack[sp] = MaybeUninit::new(a);
                    next = b;
                }
                sp += 1;
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
    use crate::cpu::intersect::lanes_of;
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
        assert!((0..WIDTH).any(|l| wide[0].link(l).count() == EMPTY));
        let origin = Vec3::new(f32::INFINITY, f32::NEG_INFINITY, f32::INFINITY);
        let slabs = Slabs::new(origin, Vec3::new(1.25, 1.75, -11.25));
        let mut leaves = Vec::new();
        walk::<true>(&wide, &slabs, 0.0, f32::MAX, &mut 0, |first, count| {
            leaves.push((first, count));
            Some(f32::MAX)
        });
        assert_eq!(leaves, []);
    }

    /// The far faces widened through the inverse direction keep the test conservative:
    /// every box the ray meets within `[tmin, tmax]`, worked out exactly (in f64, where the
    /// differences and products of these f32 are exact) from the same origin and inverse
    /// direction, is overlapped. The rays are aimed at the boxes' corners and edges, and
    /// some end there, so that entry and exit meet; without the widening the same
    /// arithmetic misses some of those boxes, which shows the cases reach the boundary.
    #[test]
    fn the_widened_test_overlaps_every_box_the_ray_meets() {
        let mut rand = crate::cpu::xorshift(0x2545_f491_4f6c_dd1d);
        let wide = build(&bvh::build(&boxes(40), Quality::High).nodes);
        let (mut met, mut missed_unwidened) = (0, 0);
        for case in 0..30_000 {
            let (n, l) = (&wide[case % wide.len()], case % WIDTH);
            if n.link(l).count() == EMPTY {
                continue;
            }
            let face = |row: &[Lanes; 3]| Vec3::from_array([0, 1, 2].map(|a| lane(&row[a], l)));
            let (lo, hi) = (face(&n.lo), face(&n.hi));
            // A corner, or a point on an edge: two or three coordinates on the faces.
            let along = (case / WIDTH) % 4;
            let target = Vec3::from_array([0, 1, 2].map(|a| match (case / (4 * WIDTH) + a) % 2 {
                _ if a == along => lo[a] + (hi[a] - lo[a]) * (0.5 + 0.5 * rand()),
                0 => lo[a],
                _ => hi[a],
            }));
            let origin = target + Vec3::new(rand(), rand(), rand()) * 20.0;
            let inv = crate::cpu::intersect::safe_inverse(target - origin);
            // The target lies near t = 1: a third of the rays end there.
            let (tmin, tmax) = (0.0, [f32::MAX, 1.0, 2.0][case % 3]);
            let (_, mask) = Slabs::new(origin, inv).test(n, tmin, tmax);
            let exact =
                |a: usize, f: f32| (f64::from(f) - f64::from(origin[a])) * f64::from(inv[a]);
            let (mut near, mut far) = (f64::from(tmin), f64::from(tmax));
            let unwidened = |a: usize, f: f32| (f - origin[a]) * inv[a];
            let (mut near32, mut far32) = (tmin, tmax);
            for a in 0..3 {
                let (t0, t1) = (exact(a, lo[a]), exact(a, hi[a]));
                (near, far) = (near.max(t0.min(t1)), far.min(t0.max(t1)));
                let (t0, t1) = (unwidened(a, lo[a]), unwidened(a, hi[a]));
                (near32, far32) = (near32.max(t0.min(t1)), far32.min(t0.max(t1)));
            }
            if near <= far {
                met += 1;
                assert_eq!(
                    mask >> l & 1,
                    1,
                    "case {case}: a box the ray meets is missed"
                );
                missed_unwidened += usize::from(near32 > far32);
            }
        }
        assert!(
            met > 5_000 && missed_unwidened > 5,
            "met {met}, missed unwidened {missed_unwidened}"
        );
    }

    /// `SlabsAvx` for a ray's origin and inverse direction; `None`, saying the test is
    /// skipped, where the processor has no AVX2.
    #[cfg(target_arch = "x86_64")]
    fn avx_slabs() -> Option<impl Fn(Vec3, Vec3) -> SlabsAvx> {
        if !crate::cpu::fast::isa::x86_64_v3() {
            eprintln!("skipped: this processor has no AVX2");
            return None;
        }
        // SAFETY: the processor has AVX2, checked above.
        Some(|origin, inv| unsafe { SlabsAvx::new(Slabs::new(origin, inv)) })
    }

    /// The AVX slab test gives `Slabs::test`'s bits, lane by lane, on random boxes and
    /// rays: axis-parallel ones, origins inside boxes, empty lanes; and where its integer
    /// minima and maxima need not (a `tmin` below zero, NaN from an origin at infinity),
    /// it overlaps every box `Slabs::test` does, entering none later.
    #[cfg(target_arch = "x86_64")]
    #[test]
    fn eight_lanes_in_avx_match_two_halves_of_four() {
        let Some(avx) = avx_slabs() else {
            return;
        };
        let mut rand = crate::cpu::xorshift(0x9e37_79b9_7f4a_7c15);
        let wide = build(&bvh::build(&boxes(40), Quality::High).nodes);
        let (mut reached, mut loose) = (0, 0);
        for case in 0..20_000 {
            let n = &wide[case % wide.len()];
            let mut origin = Vec3::new(rand() * 20.0, rand() * 20.0, rand() * 5.0);
            // Aimed near one lane's box (an empty lane's centre is NaN: a random direction).
            let l = case % WIDTH;
            let centre = (0..3).map(|a| 0.5 * (n.lo[a][l / 4][l % 4] + n.hi[a][l / 4][l % 4]));
            let centre = Vec3::from_slice(&centre.collect::<Vec<f32>>());
            let wobble = Vec3::new(rand(), rand(), rand());
            let mut dir = if centre.is_finite() {
                centre + wobble - origin
            } else {
                wobble
            };
            if case % 5 == 0 {
                dir[case % 3] = 0.0;
            }
            if case % 7 == 0 {
                origin.x = f32::INFINITY;
            }
            let inv = crate::cpu::intersect::safe_inverse(dir);
            let tmin = match case % 13 {
                0 => -rand().abs() * 5.0,
                1 => -0.0,
                _ => rand().abs(),
            };
            let tmax = [f32::MAX, 3.0, 30.0][case % 3];
            let (near, mask) = Slabs::new(origin, inv).test(n, tmin, tmax);
            let (near_avx, mask_avx) = avx(origin, inv).test(n, tmin, tmax);
            let lanes = |near: &Lanes| [0, 1, 2, 3, 4, 5, 6, 7].map(|l| lane(near, l));
            let (near, near_avx) = (lanes(&near), lanes(&near_avx));
            if origin.is_finite() && tmin.is_sign_positive() {
                assert_eq!(mask, mask_avx, "case {case}");
                assert_eq!(
                    near.map(f32::to_bits),
                    near_avx.map(f32::to_bits),
                    "case {case}"
                );
            } else {
                assert_eq!(mask & !mask_avx, 0, "case {case}: a box missed");
                for l in lanes_of(mask) {
                    assert!(
                        near_avx[l].partial_cmp(&near[l]) != Some(std::cmp::Ordering::Greater),
                        "case {case} lane {l}: entered later"
                    );
                }
                loose += 1;
            }
            reached += mask.count_ones();
        }
        assert!(
            reached > 5_000 && loose > 2_000,
            "{reached} boxes reached, {loose} cases of NaN or tmin below zero"
        );
    }

    /// The one place where the AVX test overlaps a box that `Slabs::test` does not, with
    /// `tmin` zero: a ray leaving the box exactly at its origin on one axis (a far
    /// distance of -0.0, the direction negative) and before it on another.
    #[cfg(target_arch = "x86_64")]
    #[test]
    fn avx_overlaps_a_box_left_at_the_origin_on_one_axis_and_before_on_another() {
        let Some(avx) = avx_slabs() else {
            return;
        };
        let wide = build(&bvh::build(&boxes(1), Quality::High).nodes);
        let (n, l) = (&wide[0], 0);
        let (lo, hi) = (n.lo.map(|r| lane(&r, l)), n.hi.map(|r| lane(&r, l)));
        // On the box's `lo` face in x, heading down x; beyond its `hi` face in y,
        // heading up y.
        let origin = Vec3::new(lo[0], hi[1] + 1.0, 0.5 * (lo[2] + hi[2]));
        let inv = crate::cpu::intersect::safe_inverse(Vec3::new(-1.0, 1.0, 0.0));
        let (_, mask) = Slabs::new(origin, inv).test(n, 0.0, f32::MAX);
        let (_, mask_avx) = avx(origin, inv).test(n, 0.0, f32::MAX);
        assert_eq!((mask >> l & 1, mask_avx >> l & 1), (0, 1));
    }
}
