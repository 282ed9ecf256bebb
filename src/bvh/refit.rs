//! Trees for scenes that move (`pack::frames`): a tree refitted to its primitives' new
//! places (the same leaves, every box worked out again), the cost that tells how far a
//! refit has worn it, and two trees joined under one root (a scene's still part, built
//! once, and its moving part, built or refitted each frame). All three keep the layout
//! `flatten` makes, so both renderers and every walk read the result unchanged.

use glam::Vec3A;
use obvhs::aabb::Aabb;

use super::{FlatBvh, split_axis};
use crate::gpu_types::{GpuNode, NODE_AXIS_SHIFT};

/// Works every box of `nodes` out again from the bounds of the primitives their leaves
/// hold, `leaf_bounds(k)` for the primitive at position `k`; the shape of the tree and
/// each node's near-first axis stay as they were.
pub fn refit(nodes: &mut [GpuNode], leaf_bounds: impl Fn(usize) -> Aabb) {
    // Children come after their parent, so walking backwards meets them first.
    for i in (0..nodes.len()).rev() {
        let n = nodes[i];
        let (min, max) = if n.count() > 0 {
            let range = n.offset as usize..(n.offset + n.count()) as usize;
            range.fold((Vec3A::INFINITY, Vec3A::NEG_INFINITY), |(lo, hi), k| {
                let b = leaf_bounds(k);
                (lo.min(b.min), hi.max(b.max))
            })
        } else {
            let (a, b) = (&nodes[i + 1], &nodes[n.offset as usize]);
            (
                Vec3A::from(a.min).min(b.min.into()),
                Vec3A::from(a.max).max(b.max.into()),
            )
        };
        nodes[i].min = min.into();
        nodes[i].max = max.into();
    }
}

/// A box test's cost against a primitive test's, for `cost`: obvhs' leaf collapse
/// weighs them alike too.
const NODE_COST: f64 = 1.0;
const PRIM_COST: f64 = 1.0;

/// The tree's expected cost of a ray that crosses its root, by the surface area
/// heuristic: each node's surface over the root's, times a box test for an inner node and
/// its primitives' tests for a leaf. A refit keeps the leaves however the primitives
/// move apart, so the boxes grow and overlap and this grows with them; a fresh build
/// brings it back down. 0 for an empty tree.
pub fn cost(nodes: &[GpuNode]) -> f64 {
    let area = |n: &GpuNode| {
        let d = (n.max - n.min).max(glam::Vec3::ZERO).as_dvec3();
        d.x * d.y + d.y * d.z + d.z * d.x
    };
    let Some(root) = nodes.first().map(area).filter(|&a| a > 0.0) else {
        return 0.0;
    };
    let sum: f64 = nodes
        .iter()
        .map(|n| {
            let work = match n.count() {
                0 => NODE_COST,
                c => PRIM_COST * f64::from(c),
            };
            area(n) * work
        })
        .sum();
    sum / root
}

/// `a` and `b` under one new root, `b`'s primitives stored after `a`'s `a_prims`: the
/// nodes of each are copied with their offsets moved, and the root's near-first axis is
/// the one along which the two lie most clearly apart. `order` is left empty (each part
/// holds its primitives in its own leaf order already). Either may be empty.
pub fn join(a: &FlatBvh, a_prims: u32, b: &FlatBvh) -> FlatBvh {
    fn shifted(t: &FlatBvh, base: u32, prims: u32) -> impl Iterator<Item = GpuNode> + '_ {
        t.nodes.iter().map(move |n| GpuNode {
            offset: n.offset + if n.count() > 0 { prims } else { base },
            ..*n
        })
    }
    if a.nodes.is_empty() || b.nodes.is_empty() {
        let (t, prims) = if a.nodes.is_empty() {
            (b, a_prims)
        } else {
            (a, 0)
        };
        return FlatBvh {
            nodes: shifted(t, 0, prims).collect(),
            order: Vec::new(),
            depth: t.depth,
        };
    }
    let bounds = |t: &FlatBvh| Aabb {
        min: t.nodes[0].min.into(),
        max: t.nodes[0].max.into(),
    };
    let (ba, bb) = (bounds(a), bounds(b));
    let (axis, swap) = split_axis(&ba, &bb);
    // The child that lies first along the axis goes first, as `flatten` orders them.
    let ((first, first_prims), (second, second_prims)) = if swap {
        ((b, a_prims), (a, 0))
    } else {
        ((a, 0), (b, a_prims))
    };
    let mut nodes = Vec::with_capacity(1 + a.nodes.len() + b.nodes.len());
    nodes.push(GpuNode {
        min: ba.min.min(bb.min).into(),
        max: ba.max.max(bb.max).into(),
        offset: 1 + first.nodes.len() as u32,
        count_axis: axis << NODE_AXIS_SHIFT,
    });
    nodes.extend(shifted(first, 1, first_prims));
    let base = nodes.len() as u32;
    nodes.extend(shifted(second, base, second_prims));
    FlatBvh {
        nodes,
        order: Vec::new(),
        depth: 1 + a.depth.max(b.depth),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bvh::{Quality, build};
    use glam::Vec3;

    fn boxes(n: usize, shift: Vec3) -> Vec<Aabb> {
        (0..n)
            .map(|i| {
                let p = Vec3::new((i * 7 % 13) as f32, (i * 5 % 11) as f32, i as f32 * 0.1);
                let p = Vec3A::from(p + shift);
                Aabb {
                    min: p,
                    max: p + Vec3A::splat(0.5),
                }
            })
            .collect()
    }

    /// Every primitive of `prims` (by stored position) inside its leaf, every child
    /// inside its parent, and every position held by one leaf.
    fn contains(nodes: &[GpuNode], prims: &[Aabb]) {
        let inside = |n: &GpuNode, b: &Aabb| {
            Vec3A::from(n.min).cmple(b.min).all() && Vec3A::from(n.max).cmpge(b.max).all()
        };
        let mut held = vec![0; prims.len()];
        for (i, n) in nodes.iter().enumerate() {
            if n.count() > 0 {
                for k in n.offset..n.offset + n.count() {
                    held[k as usize] += 1;
                    assert!(inside(n, &prims[k as usize]), "leaf {i}, primitive {k}");
                }
            } else {
                for c in [&nodes[i + 1], &nodes[n.offset as usize]] {
                    let b = Aabb {
                        min: c.min.into(),
                        max: c.max.into(),
                    };
                    assert!(inside(n, &b), "node {i}");
                }
            }
        }
        assert!(held.iter().all(|&h| h == 1), "{held:?}");
    }

    /// The boxes in the order the tree's leaves store them.
    fn stored(tree: &FlatBvh, input: &[Aabb]) -> Vec<Aabb> {
        tree.order.iter().map(|&i| input[i as usize]).collect()
    }

    #[test]
    fn a_refitted_tree_holds_its_moved_primitives_and_its_cost_says_how_worn_it_is() {
        let before = boxes(500, Vec3::ZERO);
        let mut tree = build(&before, Quality::High);
        let fresh = cost(&tree.nodes);
        // Every box moved alike: the same tree, moved, costs the same.
        let moved = boxes(500, Vec3::new(3.0, -2.0, 1.0));
        refit(&mut tree.nodes, |k| moved[tree.order[k] as usize]);
        contains(&tree.nodes, &stored(&tree, &moved));
        assert!((cost(&tree.nodes) / fresh - 1.0).abs() < 1e-3);
        // Shuffled: the old leaves now gather boxes far apart, and the cost shows it.
        let shuffled: Vec<Aabb> = (0..500).map(|i| moved[(i * 211) % 500]).collect();
        refit(&mut tree.nodes, |k| shuffled[tree.order[k] as usize]);
        contains(&tree.nodes, &stored(&tree, &shuffled));
        assert!(cost(&tree.nodes) > 2.0 * fresh, "{}", cost(&tree.nodes));
        assert_eq!(cost(&[]), 0.0);
    }

    #[test]
    fn two_joined_trees_hold_both_parts_in_order() {
        let (a, b) = (
            boxes(300, Vec3::ZERO),
            boxes(40, Vec3::new(-20.0, 0.0, 0.0)),
        );
        let (ta, tb) = (build(&a, Quality::Medium), build(&b, Quality::Medium));
        let joined = join(&ta, a.len() as u32, &tb);
        let mut prims = stored(&ta, &a);
        prims.extend(stored(&tb, &b));
        contains(&joined.nodes, &prims);
        assert_eq!(joined.depth, 1 + ta.depth.max(tb.depth));
        // b lies before a along x: it is the root's first child, along x.
        assert_eq!(joined.nodes[0].count_axis >> NODE_AXIS_SHIFT, 0);
        let root = |n: &GpuNode| (n.min, n.max);
        assert_eq!(root(&joined.nodes[1]), root(&tb.nodes[0]));
        // An empty part leaves the other as it was.
        assert_eq!(join(&FlatBvh::default(), 0, &tb).nodes, tb.nodes);
        assert_eq!(join(&ta, 300, &FlatBvh::default()).nodes, ta.nodes);
    }
}
