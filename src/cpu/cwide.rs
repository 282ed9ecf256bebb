//! CPU twin of `shaders/cwide.wgsl`: the walk of the compressed eight-wide tree
//! (`TRAVERSAL_CWIDE`; `bvh::cwide` builds it).

use glam::{Vec3, Vec4};

use super::intersect;
use super::types::Ray;
use super::walk::Walk;
use crate::gpu_types::{CWIDE_COUNT_SHIFT, CWIDE_INNER, CWIDE_OFFSET_MASK, GpuCwideNode};

/// Lanes `4 * half` to `4 * half + 3` of compressed node `n`: the inner children the
/// ray reaches within `[tmin, tmax]`, as bits at `lane ^ octant`, and the primitives
/// of the leaves it reaches, as bits at their offsets from `n.prim_base`. Each box is
/// decoded from its grid and tested as `next_leaf_wide` tests its four.
#[allow(clippy::too_many_arguments)]
pub(super) fn cwide_reached(
    n: &GpuCwideNode,
    half: usize,
    ray: &Ray,
    inv_dir: Vec3,
    tmin: f32,
    tmax: f32,
    octant: u32,
) -> (u32, u32) {
    let lanes = |w: u32| Vec4::from_array([0, 8, 16, 24].map(|s| (w >> s & 0xff) as f32));
    let step = |a: u32| f32::from_bits((n.exp_inner >> (8 * a) & 0xff) << 23);
    let bound =
        |a: usize, hi: usize| n.origin[a] + lanes(n.quant[a][2 * hi + half]) * step(a as u32);
    let (lo, hi) = (
        [0, 1, 2].map(|a| bound(a, 0)),
        [0, 1, 2].map(|a| bound(a, 1)),
    );
    let (_, reached) = intersect::slab4(lo, hi, ray.origin, inv_dir, tmin, tmax);
    let (mut inner, mut leaves) = (0, 0);
    for l in 0..4 {
        let tag = n.tags[half] >> (8 * l) & 0xff;
        if reached & (1 << l) == 0 || tag == 0 {
            continue;
        }
        let count = tag >> CWIDE_COUNT_SHIFT;
        if tag == CWIDE_INNER {
            inner |= 1 << ((4 * half as u32 + l) ^ octant);
        } else if count != 0 {
            leaves |= ((1 << count) - 1) << (tag & CWIDE_OFFSET_MASK);
        }
    }
    (inner, leaves)
}

/// `next_leaf` for `TRAVERSAL_CWIDE`, over the compressed eight-wide tree: hands over
/// the primitives of the leaves reached at the node entered last, a run of consecutive
/// ones at a time; then enters the next inner child of its group in the order of the
/// ray's octant, the rest of the group waiting on the stack (written whatever is left,
/// kept when some is, as the shader does); then a waiting group. `cost` counts the
/// boxes tested. (Why: traverse.wgsl.)
#[allow(clippy::too_many_arguments)]
pub(super) fn next_leaf_cwide(
    walk: &mut Walk,
    cwide: &[GpuCwideNode],
    ray: &Ray,
    inv_dir: Vec3,
    tmin: f32,
    tmax: f32,
    cost: &mut u32,
) -> (u32, u32) {
    loop {
        let m = walk.leaves.1;
        if m != 0 {
            let first = m.trailing_zeros();
            let run = (m >> first).trailing_ones();
            let bits = if run == 32 { u32::MAX } else { (1 << run) - 1 };
            walk.leaves.1 = m & !(bits << first);
            return (walk.leaves.0 + first, run);
        }
        let hits = walk.group.1 & 0xff;
        if hits == 0 {
            if !walk.pop_group() {
                return (0, 0);
            }
            continue;
        }
        let bit = hits.trailing_zeros();
        let group = (walk.group.0, walk.group.1 & !(1 << bit));
        let lane = bit ^ walk.octant;
        let node = group.0 + ((group.1 >> 8) & ((1 << lane) - 1)).count_ones();
        let k = 2 * walk.sp;
        walk.stack_store(k, group.0);
        walk.stack_store(k + 1, group.1);
        walk.sp += usize::from(group.1 & 0xff != 0);
        let n = &cwide[node as usize];
        *cost += 8;
        walk.fetched += 1;
        let a = cwide_reached(n, 0, ray, inv_dir, tmin, tmax, walk.octant);
        let c = cwide_reached(n, 1, ray, inv_dir, tmin, tmax, walk.octant);
        walk.group = (n.child_base, (n.exp_inner >> 24) << 8 | a.0 | c.0);
        walk.leaves = (n.prim_base, a.1 | c.1);
    }
}
