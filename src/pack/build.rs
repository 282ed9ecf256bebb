//! The binary tree over a scene's records, and the records put in its leaf order: in
//! place where each is stored once, copied where spatial splits store an opaque triangle
//! in several leaves.

use crate::bvh::{self, FlatBvh};
use crate::gpu_types::*;
use crate::scene::{Material, flat};

/// The tree over `records` at `quality`, the records put in its leaf order, and how many
/// of them are copies: spatial splits may store an opaque triangle in several leaves
/// (`OpaqueTriangles`), each leaf then with its own copy.
pub(super) fn build_in_leaf_order(
    records: &mut Vec<GpuPrim>,
    materials: &[Material],
    quality: bvh::Quality,
) -> (FlatBvh, usize) {
    let opaque: Vec<bool> = materials.iter().map(|m| m.t <= 0.0).collect();
    let split = OpaqueTriangles {
        records,
        opaque: &opaque,
    };
    let mut tree = build_tree(records, quality, Some(&split));
    let order = std::mem::take(&mut tree.order);
    let copies = order.len() - records.len();
    if copies == 0 {
        permute(records, order);
    } else {
        *records = order.iter().map(|&i| records[i as usize]).collect();
    }
    (tree, copies)
}

/// A tree over `records` (triangles by their corners), their bounds worked out a group at
/// a time as the build needs them; the high-quality build cuts those `split` allows.
pub(super) fn build_tree(
    records: &[GpuPrim],
    quality: bvh::Quality,
    split: Option<&dyn bvh::Splittable>,
) -> FlatBvh {
    let mut tree = bvh::build_with(
        records.len(),
        |i| bvh::aabb(flat::record_bounds(&records[i as usize])),
        quality,
        split,
    );
    tree.nodes.shrink_to_fit();
    tree
}

/// The records' opaque triangles, which the high-quality build's spatial splits may store
/// in several leaves (`bvh::spatial`): a ray meets such a triangle at the same point
/// whichever leaf it tests it in, and a shadow ray stops at it, where a transparent one's
/// transmission would be counted once a leaf.
struct OpaqueTriangles<'a> {
    records: &'a [GpuPrim],
    /// Whether each material lets no light through (`t` of 0).
    opaque: &'a [bool],
}

impl bvh::Splittable for OpaqueTriangles<'_> {
    fn corners(&self, prim: u32) -> Option<[glam::Vec3A; 3]> {
        let p = &self.records[prim as usize];
        (p.kind() == PRIM_TRIANGLE && self.opaque[p.material() as usize])
            .then(|| [p.p0, p.p1, p.p2].map(glam::Vec3A::from))
    }
}

/// Puts `v` in the order `order` gives (`v[i]` becomes the old `v[order[i]]`) in place,
/// cycle by cycle, using `order` itself to mark the positions done: a second copy of the
/// primitives would double the peak of the largest scenes.
pub(super) fn permute<T: Copy>(v: &mut [T], mut order: Vec<u32>) {
    const DONE: u32 = u32::MAX;
    debug_assert_eq!(v.len(), order.len());
    for start in 0..v.len() {
        if order[start] == DONE {
            continue;
        }
        let first = v[start];
        let mut i = start;
        loop {
            let from = order[i] as usize;
            order[i] = DONE;
            if from == start {
                v[i] = first;
                break;
            }
            v[i] = v[from];
            i = from;
        }
    }
}
