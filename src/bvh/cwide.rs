//! The compressed eight-wide tree of the GPU's `TRAVERSAL_CWIDE` walk (`GpuCwideNode`,
//! after Ylitie, Karras and Laine, "Efficient Incoherent Ray Traversal on GPUs Through
//! Compressed Wide BVHs", HPG 2017): the binary tree collapsed eight wide as the CPU's
//! tree is (`wide::Gather`), each child's box quantised to a byte an axis on its
//! node's grid (80 bytes a node instead of 112 for four children uncompressed), each child
//! placed in the lane of the octant of ray directions that should visit it first, and the
//! leaves' primitives laid out node by node so that a node finds them all from one base.
//!
//! Built here rather than with obvhs' `cwbvh`, which converts obvhs' own binary tree of
//! leaves of at most three primitives: this tree must keep the binary tree's leaves (up
//! to `MAX_LEAF_PRIMS`, the primitives every other walk and the CPU read), and the binary
//! tree of a large scene is joined from several obvhs builds (`BUILD_CHUNK`), so no obvhs
//! tree of the whole scene exists to convert.

use std::collections::VecDeque;

use super::wide::{Collapse, Gather};
use crate::gpu_types::{CWIDE_COUNT_SHIFT, CWIDE_INNER, GpuCwideNode, GpuNode, TRAVERSAL_STACK};

/// Children of a node.
pub const WIDTH: usize = 8;

/// The tree, the order of primitives its leaves index, and the stack its walk needs.
#[derive(Clone, Debug)]
pub struct Cwide {
    pub nodes: Vec<GpuCwideNode>,
    /// The walk's primitive `i` is the binary tree's primitive `order[i]`: each node's
    /// leaf children have their primitives together from its `prim_base`.
    pub order: Vec<u32>,
    /// Words of the traversal stack the walk writes: an entry (two words, a group of
    /// children) a level of the tree, and one more written and not kept.
    pub stack_words: u32,
}

/// The grid step an exponent byte stands for: the f32 whose exponent bits are `e`.
pub fn scale(e: u32) -> f32 {
    f32::from_bits(e << 23)
}

/// Where grid line `q` lies, computed as both walks compute it. `q * scale` is exact (an
/// integer below 256 times a power of two), so a fused multiply-add rounds the same.
pub(super) fn grid(origin: f32, q: u32, scale: f32) -> f32 {
    origin + q as f32 * scale
}

/// The exponent byte of the smallest power-of-two step whose 255 steps from `lo` reach
/// `hi` (as `grid` computes them); 0 for a flat axis; `None` beyond an f32's exponents.
pub(super) fn exponent(lo: f32, hi: f32) -> Option<u32> {
    if hi <= lo {
        return (hi == lo).then_some(0);
    }
    let guess = ((hi - lo) / 255.0).log2().ceil();
    let mut e = (guess as i32 + 127).clamp(1, 254) as u32;
    while e > 1 && grid(lo, 255, scale(e - 1)) >= hi {
        e -= 1;
    }
    while grid(lo, 255, scale(e)) < hi {
        e += 1;
        if e > 254 {
            return None;
        }
    }
    Some(e)
}

/// The highest grid line at or below `c`, and the lowest at or above it: a box rounded
/// outwards. `None` when the grid does not reach.
pub(super) fn quantise(origin: f32, step: f32, lo: f32, hi: f32) -> Option<(u32, u32)> {
    if step == 0.0 {
        return (lo == origin && hi == origin).then_some((0, 0));
    }
    let mut qlo = ((lo - origin) / step).floor().clamp(0.0, 255.0) as u32;
    while qlo > 0 && grid(origin, qlo, step) > lo {
        qlo -= 1;
    }
    let mut qhi = ((hi - origin) / step).ceil().clamp(0.0, 255.0) as u32;
    while qhi < 255 && grid(origin, qhi, step) < hi {
        qhi += 1;
    }
    (grid(origin, qlo, step) <= lo && grid(origin, qhi, step) >= hi).then_some((qlo, qhi))
}

/// The lane of each child: the child that lies farthest back along the directions of
/// octant `s` (bit 2: x negative, bit 1: y, bit 0: z) goes to lane `s`, greedily, the
/// best fits first, so that a ray of octant `o` taking lanes in the order `lane ^ o`
/// meets the children roughly near to far.
fn lanes(nodes: &[GpuNode], kids: &[u32]) -> [Option<u32>; WIDTH] {
    let centre = |k: u32| {
        let n = &nodes[k as usize];
        (n.min + n.max) * 0.5
    };
    let mid = kids.iter().map(|&k| centre(k)).sum::<glam::Vec3>() / kids.len() as f32;
    let mut fits = Vec::with_capacity(kids.len() * WIDTH);
    for (c, &k) in kids.iter().enumerate() {
        let d = centre(k) - mid;
        for s in 0..WIDTH {
            let sign = |bit: usize| if s & bit != 0 { -1.0 } else { 1.0 };
            let along = d.x * sign(4) + d.y * sign(2) + d.z * sign(1);
            fits.push((along, c, s));
        }
    }
    fits.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)).then(a.2.cmp(&b.2)));
    let mut out = [None; WIDTH];
    let mut placed = vec![false; kids.len()];
    for (_, c, s) in fits {
        if !placed[c] && out[s].is_none() {
            placed[c] = true;
            out[s] = Some(kids[c]);
        }
    }
    out
}

/// The binary `nodes` as the compressed eight-wide tree, nodes breadth first (each
/// node's inner children together, in lane order); `None` where the walk cannot take
/// the tree: no tree, a leaf of more primitives than a lane's count holds, a grid beyond
/// an f32's exponents, or a tree too deep for the traversal stack.
pub fn build(nodes: &[GpuNode], how: Collapse) -> Option<Cwide> {
    if nodes.is_empty() {
        return None;
    }
    let gather = Gather::new(nodes, WIDTH, how);
    let mut kids = Vec::with_capacity(WIDTH + 1);
    let mut out = vec![GpuCwideNode::default()];
    let mut order = Vec::new();
    let mut todo = VecDeque::from([(0u32, 0usize, 0u32)]);
    let mut deepest = 0;
    while let Some((binary, at, depth)) = todo.pop_front() {
        deepest = deepest.max(depth);
        gather.children_into(binary, &mut kids);
        let slots = lanes(nodes, &kids);
        let kids = slots.iter().flatten().map(|&k| &nodes[k as usize]);
        let lo = kids.clone().fold(glam::Vec3::INFINITY, |m, n| m.min(n.min));
        let hi = kids.fold(glam::Vec3::NEG_INFINITY, |m, n| m.max(n.max));
        let mut node = GpuCwideNode {
            origin: lo,
            child_base: out.len() as u32,
            prim_base: order.len() as u32,
            ..Default::default()
        };
        let mut steps = [0.0; 3];
        for a in 0..3 {
            let e = exponent(lo[a], hi[a])?;
            node.exp_inner |= e << (8 * a);
            steps[a] = scale(e);
        }
        for (lane, slot) in slots.iter().enumerate() {
            let Some(k) = *slot else { continue };
            let child = &nodes[k as usize];
            let byte = |v: u32, word: &mut u32, lane: usize| *word |= v << (8 * (lane % 4));
            for a in 0..3 {
                let (qlo, qhi) = quantise(lo[a], steps[a], child.min[a], child.max[a])?;
                byte(qlo, &mut node.quant[a][lane / 4], lane);
                byte(qhi, &mut node.quant[a][2 + lane / 4], lane);
            }
            let tag = if child.count() == 0 {
                node.exp_inner |= 1 << (24 + lane);
                todo.push_back((k, out.len(), depth + 1));
                out.push(GpuCwideNode::default());
                CWIDE_INNER
            } else {
                let offset = order.len() as u32 - node.prim_base;
                // The count must fit its bits of the tag, and the node's primitives the
                // 32 bits of the walk's mask of leaves reached.
                if child.count() >= 1 << (8 - CWIDE_COUNT_SHIFT) || offset + child.count() > 32 {
                    return None;
                }
                order.extend(child.offset..child.offset + child.count());
                child.count() << CWIDE_COUNT_SHIFT | offset
            };
            byte(tag, &mut node.tags[lane / 4], lane);
        }
        out[at] = node;
    }
    // A node at depth d leaves at most d groups waiting, and the walk writes the slot
    // above them before it knows whether to keep it.
    let stack_words = 2 * (deepest + 1);
    (stack_words as usize <= TRAVERSAL_STACK).then_some(Cwide {
        nodes: out,
        order,
        stack_words,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bvh::{self, Quality};
    use crate::gpu_types::CWIDE_OFFSET_MASK;
    use glam::Vec3;
    use obvhs::aabb::Aabb;

    fn boxes(n: usize) -> Vec<Aabb> {
        (0..n)
            .map(|i| {
                let p = glam::Vec3A::new((i * 7 % 13) as f32, (i * 5 % 11) as f32, i as f32 * 0.1);
                Aabb {
                    min: p,
                    max: p + 0.5 + (i % 3) as f32 * 0.25,
                }
            })
            .collect()
    }

    /// A lane's decoded box on the node's grid.
    fn decoded(n: &GpuCwideNode, lane: usize) -> (Vec3, Vec3) {
        let q = |a: usize, hi: usize| n.quant[a][2 * hi + lane / 4] >> (8 * (lane % 4)) & 0xff;
        let at = |hi: usize| {
            Vec3::from_array([0, 1, 2].map(|a| {
                let step = scale(n.exp_inner >> (8 * a) & 0xff);
                grid(n.origin[a], q(a, hi), step)
            }))
        };
        (at(0), at(1))
    }

    /// Every binary leaf appears once, as a lane whose decoded box holds the leaf's box,
    /// as do the decoded boxes of every inner lane above it, with its primitives together
    /// in `order`; every inner lane leads to a later node; no node is reached twice; the
    /// stack bound holds.
    fn check(binary: &bvh::FlatBvh, tree: &Cwide) {
        let mut seen = vec![0u32; binary.order.len()];
        let mut reached = vec![false; tree.nodes.len()];
        let mut todo = vec![(0usize, Vec::<(Vec3, Vec3)>::new(), 0u32)];
        while let Some((i, above, depth)) = todo.pop() {
            assert!(!std::mem::replace(&mut reached[i], true), "node {i} twice");
            assert!(2 * (depth + 1) <= tree.stack_words);
            let n = &tree.nodes[i];
            let mut inner = 0;
            for lane in 0..WIDTH {
                let tag = n.tags[lane / 4] >> (8 * (lane % 4)) & 0xff;
                if tag == 0 {
                    continue;
                }
                let (lo, hi) = decoded(n, lane);
                let is_inner = n.exp_inner >> (24 + lane) & 1 == 1;
                assert_eq!(is_inner, tag == CWIDE_INNER, "node {i} lane {lane}");
                if is_inner {
                    let child = n.child_base as usize + inner;
                    inner += 1;
                    assert!(child > i && child < tree.nodes.len());
                    let mut boxes = above.clone();
                    boxes.push((lo, hi));
                    todo.push((child, boxes, depth + 1));
                } else {
                    let (count, offset) = (tag >> CWIDE_COUNT_SHIFT, tag & CWIDE_OFFSET_MASK);
                    let first = (n.prim_base + offset) as usize;
                    let prims = &tree.order[first..first + count as usize];
                    let leaf = binary
                        .nodes
                        .iter()
                        .find(|b| b.count() == count && b.offset == prims[0])
                        .expect("a lane's primitives are a binary leaf's");
                    assert!(prims.iter().copied().eq(leaf.offset..leaf.offset + count));
                    for (lo, hi) in above.iter().chain([&(lo, hi)]) {
                        assert!(lo.cmple(leaf.min).all() && hi.cmpge(leaf.max).all());
                    }
                    for &p in prims {
                        seen[p as usize] += 1;
                    }
                }
            }
        }
        assert!(reached.iter().all(|&r| r), "unreachable nodes");
        assert!(
            seen.iter().all(|&s| s == 1),
            "a primitive not in exactly one leaf"
        );
        assert_eq!(tree.order.len(), binary.order.len());
    }

    #[test]
    fn the_compressed_tree_holds_every_leaf_once_in_boxes_rounded_outwards() {
        for n in [1, 2, 3, 5, 17, 1000, 5000] {
            for quality in [Quality::Medium, Quality::High] {
                let binary = bvh::build(&boxes(n), quality);
                for how in [Collapse::Greedy, Collapse::Optimal] {
                    let tree = build(&binary.nodes, how).expect("a shallow tree fits");
                    check(&binary, &tree);
                    assert!(tree.nodes.len() * 4 <= binary.nodes.len().max(4));
                }
            }
        }
        assert!(build(&[], Collapse::Optimal).is_none());
    }

    /// Flat boxes (a grid of quads in z = 1) get a zero step on their flat axis and
    /// decode to exactly their plane; boxes far from the origin round outwards.
    #[test]
    fn flat_and_distant_boxes_decode_around_their_own() {
        let quads: Vec<Aabb> = (0..64)
            .map(|i| {
                let p = glam::Vec3A::new((i % 8) as f32, (i / 8) as f32, 1.0);
                Aabb {
                    min: p,
                    max: p + glam::Vec3A::new(1.0, 1.0, 0.0),
                }
            })
            .collect();
        let binary = bvh::build(&quads, Quality::High);
        let tree = build(&binary.nodes, Collapse::Optimal).expect("fits");
        check(&binary, &tree);
        assert_eq!(tree.nodes[0].exp_inner >> 16 & 0xff, 0, "z is flat");
        let far: Vec<Aabb> = boxes(300)
            .into_iter()
            .map(|b| Aabb {
                min: b.min * 1e-3 + 1e6,
                max: b.max * 1e-3 + 1e6,
            })
            .collect();
        let binary = bvh::build(&far, Quality::Medium);
        check(
            &binary,
            &build(&binary.nodes, Collapse::Optimal).expect("fits"),
        );
    }

    /// Each child goes to the lane of the octant that meets it first: of two boxes apart
    /// along x, the one at low x is in a lane whose x bit is clear (rays going +x).
    #[test]
    fn children_sit_in_the_lanes_of_the_octants_that_meet_them_first() {
        let two = [
            Aabb {
                min: glam::Vec3A::ZERO,
                max: glam::Vec3A::ONE,
            },
            Aabb {
                min: glam::Vec3A::new(10.0, 0.0, 0.0),
                max: glam::Vec3A::new(11.0, 1.0, 1.0),
            },
        ];
        let binary = bvh::build(&two, Quality::High);
        let tree = build(&binary.nodes, Collapse::Optimal).expect("fits");
        let root = &tree.nodes[0];
        let low_x = binary.order.iter().position(|&i| i == 0).unwrap() as u32;
        for lane in 0..WIDTH {
            let tag = root.tags[lane / 4] >> (8 * (lane % 4)) & 0xff;
            if tag != 0 {
                let first = tree.order[(root.prim_base + (tag & CWIDE_OFFSET_MASK)) as usize];
                assert_eq!(lane & 4 == 0, first == low_x, "lane {lane}");
            }
        }
    }
}
