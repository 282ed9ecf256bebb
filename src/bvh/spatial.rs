//! The high-quality build's binary tree: top-down binned SAH with spatial splits (the
//! SBVH of Stich, Friedrich and Dietrich 2009, "Spatial Splits in Bounding Volume
//! Hierarchies"; Embree's `RTC_BUILD_QUALITY_HIGH` does the same). Where a node's best
//! split by centroids leaves its two halves overlapping, a plane across space may cost
//! less: a triangle straddling it then stands in both halves, each with the box of its part
//! on that side, so the halves' boxes no longer overlap and a ray enters fewer of them.
//!
//! Only primitives that may stand in several leaves are cut (`Splittable::corners`): an
//! opaque triangle, which a closest-hit ray meets at the same point whichever leaf tests
//! it and a shadow ray stops at. A transparent one would have its transmission multiplied
//! once a leaf; it and every other primitive go whole to one side of any plane.
//!
//! The cuts are bounded: at most `BUDGET` times the primitives more references, shared out
//! between a node's halves by their sizes (so the tree is the same however the threads
//! run), and only where a centroid split's halves overlap by more than `MIN_OVERLAP` of the
//! root's area. The result is obvhs' `Bvh2` with leaves of up to `max_leaf` references, for
//! the same reinsertion and leaf collapse as PLOC's tree.

use glam::Vec3A;
use obvhs::aabb::Aabb;
use obvhs::bvh2::{Bvh2, DEFAULT_MAX_STACK_DEPTH, node::Bvh2Node};

use super::binning::{
    BINS, Bins, FEW_BINS, Ref, Split, bounds, half_area, median, object_split, partition_objects,
    sweep,
};
use super::clip::{chop, cut_triangle};

/// References spatial splits may add, as a fraction of the primitives: gears-4's mirror
/// rays gained as much from 20% as from 50% or 100% (docs/bvh.md), and the records of the
/// references are the scene's largest array.
const BUDGET: f32 = 0.2;

/// Overlap of a centroid split's halves (as a fraction of the root's surface area) from
/// which a spatial split is weighed. Stich et al. take 1e-5; on gears-4 1e-3 made a tree
/// that fetches as few nodes a ray (secondary rays 813 bytes against 821) in 30% less
/// build time. 1e-2 cut less (839).
const MIN_OVERLAP: f32 = 1e-3;

/// The SAH's cost of a node visit against one primitive's test: obvhs' leaf collapse's.
const TRAVERSAL_COST: f32 = 3.0;

/// Below this depth nodes split by the median centroid only: every level then halves the
/// references, so no input, however its centroids are spread, makes the recursion deep.
const MEDIAN_DEPTH: usize = 40;

/// Nodes of more references than this build their halves on two threads: from 256, a
/// scene of a few thousand triangles builds on both (teapot-6 and mount-5 a third
/// faster than from 4096, the same trees).
const PARALLEL_MIN: usize = 256;

/// Nodes of fewer references than this weigh spatial splits at `FEW_BINS` planes an axis
/// rather than `BINS`: in a small node a triangle crosses many planes and is cut at each,
/// and half as many planes there built tetra-6 30% and mount-5 15% faster with node bytes
/// a ray within 1% (all 16 everywhere cost gears-4's eye rays 3.5%).
const FEW_REFS: usize = 256;

/// Which primitives may be cut, and where their corners are.
pub trait Splittable: Sync {
    /// The corners of primitive `prim` where it may stand in several leaves, else `None`.
    fn corners(&self, prim: u32) -> Option<[Vec3A; 3]>;
}

/// A subtree as `Bvh2` nodes (its root first, an inner node's children at `first_index`
/// and the next) and the primitives its leaves index.
struct Subtree {
    nodes: Vec<Bvh2Node>,
    prims: Vec<u32>,
    depth: usize,
}

/// The tree over `aabbs`, the primitives `split` allows cut with spatial splits, leaves of
/// at most `max_leaf` references.
pub fn build(aabbs: &[Aabb], split: &dyn Splittable, max_leaf: usize) -> Bvh2 {
    let refs: Vec<Ref> = (0..aabbs.len() as u32)
        .map(|prim| Ref {
            b: aabbs[prim as usize],
            prim,
        })
        .collect();
    let b = Builder {
        split,
        min_overlap: MIN_OVERLAP * half_area(&bounds(&refs)),
        max_leaf,
    };
    let budget = (aabbs.len() as f32 * BUDGET) as usize;
    let tree = if refs.is_empty() {
        Subtree {
            nodes: Vec::new(),
            prims: Vec::new(),
            depth: 0,
        }
    } else {
        b.subtree(refs, budget, 1)
    };
    Bvh2 {
        nodes: tree.nodes,
        primitive_indices: tree.prims,
        max_depth: tree.depth.max(DEFAULT_MAX_STACK_DEPTH),
        uses_spatial_splits: true,
        ..Bvh2::default()
    }
}

struct Builder<'a> {
    split: &'a dyn Splittable,
    /// `MIN_OVERLAP` of the root's half area.
    min_overlap: f32,
    max_leaf: usize,
}

impl Builder<'_> {
    /// The subtree over `refs` at `depth`, adding at most `budget` references.
    fn subtree(&self, refs: Vec<Ref>, budget: usize, depth: usize) -> Subtree {
        if refs.len() < PARALLEL_MIN {
            let mut out = Subtree {
                nodes: vec![Bvh2Node::default()],
                prims: Vec::with_capacity(refs.len()),
                depth,
            };
            self.node(&mut out, 0, refs, budget, depth);
            return out;
        }
        let bounds = bounds(&refs);
        let Ok(((left, lb), (right, rb))) = self.split_node(refs, &bounds, budget, depth) else {
            unreachable!("more than `max_leaf` references always split");
        };
        let (l, r) = join(
            || self.subtree(left, lb, depth + 1),
            || self.subtree(right, rb, depth + 1),
        );
        // [root, left's root, right's root, the rest of left's, the rest of right's]: a
        // pair of children stays side by side.
        let mut nodes = Vec::with_capacity(1 + l.nodes.len() + r.nodes.len());
        nodes.push(Bvh2Node::new(bounds, 0, 1));
        let moved = |n: &Bvh2Node, to: u32, first: u32| {
            let mut n = *n;
            n.first_index += if n.prim_count > 0 { first } else { to };
            n
        };
        let (lshift, rshift) = (2, l.nodes.len() as u32 + 1);
        let lprims = l.prims.len() as u32;
        nodes.push(moved(&l.nodes[0], lshift, 0));
        nodes.push(moved(&r.nodes[0], rshift, lprims));
        nodes.extend(l.nodes[1..].iter().map(|n| moved(n, lshift, 0)));
        nodes.extend(r.nodes[1..].iter().map(|n| moved(n, rshift, lprims)));
        let mut prims = l.prims;
        prims.extend(r.prims);
        Subtree {
            nodes,
            prims,
            depth: l.depth.max(r.depth),
        }
    }

    /// Node `slot` of `out` over `refs`, its descendants appended.
    fn node(&self, out: &mut Subtree, slot: usize, refs: Vec<Ref>, budget: usize, depth: usize) {
        out.depth = out.depth.max(depth);
        let bounds = bounds(&refs);
        match self.split_node(refs, &bounds, budget, depth) {
            Err(refs) => {
                out.nodes[slot] = Bvh2Node::new(bounds, refs.len() as u32, out.prims.len() as u32);
                out.prims.extend(refs.iter().map(|r| r.prim));
            }
            Ok(((left, lb), (right, rb))) => {
                let first = out.nodes.len();
                out.nodes.extend([Bvh2Node::default(); 2]);
                out.nodes[slot] = Bvh2Node::new(bounds, 0, first as u32);
                self.node(out, first, left, lb, depth + 1);
                self.node(out, first + 1, right, rb, depth + 1);
            }
        }
    }

    /// `refs` (of box `bounds`) cut in two by the split the SAH prefers, with each half's
    /// share of `budget`; `Err(refs)` where a leaf costs less.
    #[allow(clippy::type_complexity)]
    fn split_node(
        &self,
        refs: Vec<Ref>,
        bounds: &Aabb,
        budget: usize,
        depth: usize,
    ) -> Result<((Vec<Ref>, usize), (Vec<Ref>, usize)), Vec<Ref>> {
        if refs.len() <= 1 {
            return Err(refs);
        }
        if depth >= MEDIAN_DEPTH {
            if refs.len() <= self.max_leaf {
                return Err(refs);
            }
            let mut left = median(refs);
            let right = left.split_off(left.len() / 2);
            return Ok(((left, 0), (right, 0)));
        }
        let object = object_split(&refs);
        let overlap = object.map_or(f32::INFINITY, |s| half_area(&s.left.intersection(&s.right)));
        let spatial = (budget > 0 && overlap > self.min_overlap)
            .then(|| self.spatial_split(&refs, bounds))
            .flatten();
        let spatial = spatial.filter(|s| object.is_none_or(|o| s.cost < o.cost));
        let cost = spatial.or(object).map_or(f32::INFINITY, |s| s.cost);
        let area = half_area(bounds);
        if refs.len() <= self.max_leaf && refs.len() as f32 * area <= TRAVERSAL_COST * area + cost {
            return Err(refs);
        }
        let (left, right, used) = match (spatial, object) {
            (Some(s), _) => self.cut(refs, &s, budget),
            (None, Some(o)) => {
                let (l, r) = partition_objects(refs, &o);
                (l, r, 0)
            }
            (None, None) => {
                // Every centroid in one place and no plane between them: halves.
                let mut l = refs;
                let r = l.split_off(l.len() / 2);
                (l, r, 0)
            }
        };
        let rest = budget - used;
        let lb = rest * left.len() / (left.len() + right.len());
        Ok(((left, lb), (right, rest - lb)))
    }

    /// The cheapest plane between the bins of `bounds` on any axis, each reference's part
    /// in each bin it crosses bounded on its own (Stich et al.'s chopped binning).
    fn spatial_split(&self, refs: &[Ref], bounds: &Aabb) -> Option<Split> {
        let corners: Vec<Option<[Vec3A; 3]>> =
            refs.iter().map(|r| self.split.corners(r.prim)).collect();
        let mut best: Option<Split> = None;
        let count = if refs.len() < FEW_REFS {
            FEW_BINS
        } else {
            BINS
        };
        for bins in Bins::over(bounds, count) {
            let axis = bins.axis;
            let mut boxes = [Aabb::empty(); BINS];
            let (mut entry, mut exit) = ([0u32; BINS], [0u32; BINS]);
            for (r, v) in refs.iter().zip(&corners) {
                let Some(v) = v else {
                    // Whole, on its centroid's side (as `cut` puts it).
                    let k = bins.index(r.b.center_axis(axis));
                    boxes[k] = boxes[k].union(&r.b);
                    entry[k] += 1;
                    exit[k] += 1;
                    continue;
                };
                let (b0, b1) = (bins.index(r.b.min[axis]), bins.index(r.b.max[axis]));
                entry[b0] += 1;
                exit[b1] += 1;
                let mut rest = r.b;
                for (k, bx) in boxes.iter_mut().enumerate().take(b1).skip(b0) {
                    let (part, right) = chop(v, &rest, axis, bins.plane(k + 1));
                    *bx = bx.union(&part);
                    rest = right;
                }
                boxes[b1] = boxes[b1].union(&rest);
            }
            sweep(&mut best, bins, &boxes, &entry, &exit);
        }
        best
    }

    /// The references on each side of spatial split `s`, and how many it added: those
    /// across the plane cut in two, or kept whole on one side where that costs less
    /// (Stich et al.'s reference unsplitting), or where `budget` is spent.
    fn cut(&self, refs: Vec<Ref>, s: &Split, budget: usize) -> (Vec<Ref>, Vec<Ref>, usize) {
        let (axis, pos) = (s.bins.axis, s.plane());
        let (mut lb, mut rb) = (s.left, s.right);
        let (mut nl, mut nr) = (s.counts.0 as f32, s.counts.1 as f32);
        let (mut left, mut right) = (Vec::new(), Vec::new());
        let mut added = 0;
        for r in refs {
            if r.b.max[axis] <= pos {
                left.push(r);
                continue;
            }
            if r.b.min[axis] >= pos {
                right.push(r);
                continue;
            }
            let Some(v) = self.split.corners(r.prim) else {
                if r.b.center_axis(axis) < pos {
                    left.push(r);
                } else {
                    right.push(r);
                }
                continue;
            };
            let both = half_area(&lb) * nl + half_area(&rb) * nr;
            let (lw, rw) = (lb.union(&r.b), rb.union(&r.b));
            let only_left = half_area(&lw) * nl + half_area(&rb) * (nr - 1.0);
            let only_right = half_area(&lb) * (nl - 1.0) + half_area(&rw) * nr;
            let (l, rt) = cut_triangle(&v, &r.b, axis, pos);
            if !rt.valid() || !l.valid() {
                // Its part of `r.b` lies on one side only (the box was loose).
                let part = Ref {
                    b: if l.valid() { l } else { rt },
                    prim: r.prim,
                };
                if l.valid() {
                    left.push(part);
                } else {
                    right.push(part);
                }
            } else if only_left < both && only_left <= only_right {
                left.push(r);
                (lb, nr) = (lw, nr - 1.0);
            } else if only_right < both || added == budget {
                right.push(r);
                (rb, nl) = (rw, nl - 1.0);
            } else {
                added += 1;
                left.push(Ref { b: l, prim: r.prim });
                right.push(Ref {
                    b: rt,
                    prim: r.prim,
                });
            }
        }
        if left.is_empty() || right.is_empty() {
            // Every reference ended on one side (all kept whole): halves by centroid.
            let mut all = median(if left.is_empty() { right } else { left });
            let r = all.split_off(all.len() / 2);
            return (all, r, added);
        }
        (left, right, added)
    }
}

/// `a` and `b` on two threads where the crate has them (`native`), else one after the
/// other (the browser's build).
fn join<A: Send, B: Send>(a: impl FnOnce() -> A + Send, b: impl FnOnce() -> B + Send) -> (A, B) {
    #[cfg(feature = "native")]
    return rayon::join(a, b);
    #[cfg(not(feature = "native"))]
    (a(), b())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bvh::clip::tests::{holds, random, samples, slivers};
    use crate::bvh::{FlatBvh, Quality, build_with};
    use crate::gpu_types::TRAVERSAL_STACK;

    /// Triangles, and whether each may be cut.
    struct Triangles(Vec<[Vec3A; 3]>, Vec<bool>);

    impl Splittable for Triangles {
        fn corners(&self, prim: u32) -> Option<[Vec3A; 3]> {
            self.1[prim as usize].then(|| self.0[prim as usize])
        }
    }

    impl Triangles {
        fn aabbs(&self) -> Vec<Aabb> {
            self.0.iter().map(|v| Aabb::from_points(v)).collect()
        }
    }

    /// The tree with spatial splits over `tris`, checked: every point of every triangle
    /// lies in the box of a leaf that holds it and of every node above that leaf, a
    /// triangle that may not be cut is in one leaf only, the tree fits the walks' stack and
    /// the references added stay within the budget. How many triangles were cut.
    fn build_and_check(tris: &Triangles) -> usize {
        let aabbs = tris.aabbs();
        let tree: FlatBvh = build_with(
            aabbs.len(),
            |i| aabbs[i as usize],
            Quality::High,
            Some(tris),
        );
        assert!(tree.depth < TRAVERSAL_STACK, "depth {}", tree.depth);
        // Each leaf's box with the boxes of the nodes above it, by primitive.
        let mut leaves: Vec<Vec<Vec<Aabb>>> = vec![Vec::new(); aabbs.len()];
        let mut stack = vec![(0usize, Vec::<Aabb>::new())];
        while let Some((i, mut path)) = stack.pop() {
            let n = &tree.nodes[i];
            path.push(Aabb::new(n.min.into(), n.max.into()));
            if n.count() > 0 {
                for k in n.offset..n.offset + n.count() {
                    leaves[tree.order[k as usize] as usize].push(path.clone());
                }
            } else {
                stack.push((i + 1, path.clone()));
                stack.push((n.offset as usize, path));
            }
        }
        let mut cut = 0;
        for (p, paths) in leaves.iter().enumerate() {
            assert!(!paths.is_empty(), "primitive {p} in no leaf");
            if !tris.1[p] {
                assert_eq!(paths.len(), 1, "primitive {p} may not be cut");
            }
            cut += (paths.len() > 1) as usize;
            for q in samples(&tris.0[p]) {
                assert!(
                    paths.iter().any(|path| path.iter().all(|b| holds(b, q))),
                    "primitive {p}: {q} outside every leaf that holds it"
                );
            }
        }
        let added = tree.order.len() - aabbs.len();
        assert!(added as f32 <= BUDGET * aabbs.len() as f32, "{added} added");
        cut
    }

    /// Long, thin triangles, four in five of which may be cut: the tree holds them all,
    /// and spatial splits do cut some.
    #[test]
    fn split_trees_cover_every_triangle_and_cut_only_what_may_be() {
        let corners = slivers(3000, 5, 0.0);
        let cut: Vec<bool> = (0..corners.len()).map(|i| i % 5 != 0).collect();
        let cut = build_and_check(&Triangles(corners, cut));
        assert!(cut > 20, "{cut} primitives cut");
    }

    /// Inputs that leave the binning nothing to divide: one triangle many times over (900
    /// times: from 1 000, `build_group` takes such input to median splits instead),
    /// triangles flat in one plane, slivers of no area, a fan of triangles sharing a
    /// corner, and scenes a millionth and a million units across.
    #[test]
    fn degenerate_triangles_build_trees_that_hold_them() {
        let one = [Vec3A::ZERO, Vec3A::X, Vec3A::Y];
        let mut r = random(3);
        let flat: Vec<[Vec3A; 3]> = (0..2000)
            .map(|_| {
                let mut p = || Vec3A::new(r() * 10.0, r() * 10.0, 0.0);
                [p(), p(), p()]
            })
            .collect();
        let lines: Vec<[Vec3A; 3]> = (0..2000)
            .map(|i| {
                let a = Vec3A::splat(i as f32 * 1e-3);
                [
                    a,
                    a + Vec3A::new(5.0, 1.0, 0.5),
                    a + Vec3A::new(10.0, 2.0, 1.0),
                ]
            })
            .collect();
        let fan: Vec<[Vec3A; 3]> = (0..2000)
            .map(|i| {
                let (s, c) = (i as f32 * 0.003).sin_cos();
                [
                    Vec3A::ZERO,
                    Vec3A::new(c, s, 0.1) * 50.0,
                    Vec3A::new(c, s, -0.1) * 50.0,
                ]
            })
            .collect();
        let scaled = |k: f32| {
            slivers(2000, 9, 0.0)
                .into_iter()
                .map(move |v| v.map(|p| p * k))
        };
        let sets: [Vec<[Vec3A; 3]>; 6] = [
            vec![one; 900],
            flat,
            lines,
            fan,
            scaled(1e-6).collect(),
            scaled(1e6).collect(),
        ];
        for corners in sets {
            let cut = vec![true; corners.len()];
            build_and_check(&Triangles(corners, cut));
        }
    }
}
