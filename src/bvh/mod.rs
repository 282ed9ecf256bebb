//! BVH construction and flattening: the binary tree here, collapsed into the wide trees
//! the walks that test several boxes at once read in `wide`.
//!
//! `obvhs` builds a binary BVH (PLOC, then reinsertion and SAH leaf collapsing) over the
//! bounds of every bounded primitive; this module flattens it into the depth-first
//! `GpuNode` layout both renderers traverse (first child next to its parent, second child
//! at `offset`, a split axis for near-first ordering) and reports the primitive order, so
//! `pack` can lay primitives out leaf by leaf with no indirection.
//!
//! Scenes of more than `build_chunk` primitives are first cut by object median, and obvhs
//! builds each group, which bounds the builder's memory. The traversal stack has a fixed
//! size (`TRAVERSAL_STACK`); a tree deeper than that is rebuilt with a median split, whose
//! depth is at most log2(n) + 1 and so always fits.

mod binning;
pub mod blocks;
mod clip;
pub mod cwide;
pub mod qwide;
pub mod refit;
pub mod spatial;
pub mod wide;

use glam::{Vec3, Vec3A};
use obvhs::{BvhBuildParams, aabb::Aabb, bvh2::Bvh2, ploc::PlocBuilder};

use crate::gpu_types::{GpuNode, NODE_AXIS_SHIFT, TRAVERSAL_STACK};
use crate::scene::Bounds;
pub use spatial::Splittable;

/// Most primitives a leaf may hold.
pub const MAX_LEAF_PRIMS: u32 = 4;

/// A flattened BVH.
#[derive(Clone, Debug, Default)]
pub struct FlatBvh {
    pub nodes: Vec<GpuNode>,
    /// `order[i]` is the input index of the primitive stored at position `i`. A primitive
    /// cut by spatial splits (`spatial`) is stored once for each leaf that holds it.
    pub order: Vec<u32>,
    /// Longest root-to-leaf path, in nodes.
    pub depth: usize,
}

/// A primitive's bounds as the builder takes them.
pub fn aabb(b: Bounds) -> Aabb {
    Aabb {
        min: Vec3A::from(b.min),
        max: Vec3A::from(b.max),
    }
}

/// How much work obvhs puts into a tree: `High` is its slowest, best build, `Medium`
/// about 5 times faster to build for trees that trace 8 to 20% slower.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Quality {
    Medium,
    High,
}

impl Quality {
    pub fn name(self) -> &'static str {
        match self {
            Quality::Medium => "medium",
            Quality::High => "high",
        }
    }

    /// The build that makes a render of `samples` camera samples (pixels times samples
    /// per pixel, over all its frames) over `prims` primitives fastest from start to end:
    /// `High` for small scenes, where it costs at most about 50 ms, and for renders of at
    /// least `HIGH_QUALITY_SAMPLES_PER_PRIM` samples per primitive, where the faster
    /// tracing repays the slower build on machines without a GPU (docs/bvh.md has the
    /// figures).
    pub fn for_work(prims: usize, samples: u64) -> Quality {
        if prims <= THOROUGH_BUILD_MAX_PRIMS
            || samples >= HIGH_QUALITY_SAMPLES_PER_PRIM.saturating_mul(prims as u64)
        {
            Quality::High
        } else {
            Quality::Medium
        }
    }

    /// The build a render of `samples` camera samples over `prims` primitives gets:
    /// `GPURT_BVH`'s (`forced`) where set, else `for_work`.
    pub fn chosen(prims: usize, samples: u64) -> Result<Quality, String> {
        Ok(Quality::forced()?.unwrap_or_else(|| Quality::for_work(prims, samples)))
    }

    /// `GPURT_BVH` (`medium` or `high`): every tree at that quality, for measuring a
    /// tracer on either tree whatever the render's length; `None` where unset or empty.
    pub fn forced() -> Result<Option<Quality>, String> {
        match std::env::var("GPURT_BVH").as_deref() {
            Err(_) | Ok("") => Ok(None),
            Ok("medium") => Ok(Some(Quality::Medium)),
            Ok("high") => Ok(Some(Quality::High)),
            Ok(v) => Err(format!("GPURT_BVH={v}: expected medium or high")),
        }
    }
}

/// Samples per primitive from which `Quality::High` pays for itself. Measured on two cores
/// (mount-9, 512x512): the high build takes 1.2 s longer and saves 0.024 s of tracing
/// for every 262 144 samples on the CPU backend (break-even at 25 samples a primitive)
/// and 0.073 s on lavapipe (8). A fast GPU traces so quickly that it would need about
/// 1 600, but its host builds quickly too, and every frame of a view gains.
pub const HIGH_QUALITY_SAMPLES_PER_PRIM: u64 = 32;

/// Builds a BVH over primitive bounds, cutting none. An empty input gives an empty tree.
pub fn build(aabbs: &[Aabb], quality: Quality) -> FlatBvh {
    build_with(aabbs.len(), |i| aabbs[i as usize], quality, None)
}

/// Builds a BVH over `count` primitives whose bounds `aabb` gives by index: the bounds
/// are worked out as they are needed, a group at a time, so that a large scene's are never
/// held all at once (`pack` computes them from its primitives). The high-quality build
/// cuts the primitives `split` allows with spatial splits, in groups that are mostly
/// such primitives (`build_group`).
pub fn build_with(
    count: usize,
    aabb: impl Fn(u32) -> Aabb,
    quality: Quality,
    split: Option<&dyn Splittable>,
) -> FlatBvh {
    if count == 0 {
        return FlatBvh::default();
    }
    let chunk = build_chunk(count);
    let split = split.filter(|_| quality == Quality::High);
    let flat = if count <= chunk {
        let aabbs: Vec<Aabb> = (0..count as u32).map(&aabb).collect();
        build_group(
            &aabbs,
            quality,
            split.map(|split| Local { split, ids: None }),
        )
    } else {
        median_split(count, &aabb, chunk, quality, split)
    };
    if flat.depth < TRAVERSAL_STACK {
        flat
    } else {
        median_leaves(count, &aabb)
    }
}

/// The primitives of a group that may be cut, by their index in the group (`ids`: the
/// scene's index of each; `None`: the group is the scene).
#[derive(Clone, Copy)]
struct Local<'a> {
    split: &'a dyn Splittable,
    ids: Option<&'a [u32]>,
}

impl Splittable for Local<'_> {
    fn corners(&self, prim: u32) -> Option<[Vec3A; 3]> {
        let prim = self.ids.map_or(prim, |ids| ids[prim as usize]);
        self.split.corners(prim)
    }
}

/// One group's tree: with spatial splits where `split` allows cutting at least half of its
/// primitives (a mesh), else obvhs' build; median splits where the boxes are mostly
/// coincident. Spheres and cones are not cut, and on trees of them the top-down build
/// traced worse than PLOC's (tree-11's mirror rays 44% slower, its floor the only
/// triangles; docs/bvh.md).
fn build_group(aabbs: &[Aabb], quality: Quality, split: Option<Local>) -> FlatBvh {
    if mostly_coincident(aabbs) {
        return median_leaves(aabbs.len(), &|i| aabbs[i as usize]);
    }
    let split = split.filter(|s| {
        let cut = (0..aabbs.len() as u32).filter(|&i| s.corners(i).is_some());
        2 * cut.count() >= aabbs.len()
    });
    let mut bvh = match split {
        Some(split) => spatial::build(aabbs, &split, MAX_LEAF_PRIMS as usize),
        None => build_obvhs(aabbs, quality),
    };
    optimise(&mut bvh, quality);
    flatten(&bvh, aabbs)
}

/// A balanced tree by object median splits all the way down to leaves.
fn median_leaves(count: usize, aabb: &impl Fn(u32) -> Aabb) -> FlatBvh {
    // Groups of MAX_LEAF_PRIMS are leaves, so obvhs (and its quality) is never called.
    median_split(count, aabb, MAX_LEAF_PRIMS as usize, Quality::Medium, None)
}

/// Whether one box repeats a thousand times or more, judged on up to 1024 boxes spread
/// over the input (the repeats seen, scaled by the sampling step). obvhs' PLOC pairs only
/// mutual nearest neighbours, and among identical boxes it finds few per pass: 10 000
/// coincident triangles took 2.6 s to build and 100 000 more than 100 s. Such input is
/// built by median splits instead, in O(n log n). (A few copies, such as the two halves
/// of an axis-aligned quad, are ordinary and stay with obvhs.)
fn mostly_coincident(aabbs: &[Aabb]) -> bool {
    const SAMPLES: usize = 1024;
    const MANY: usize = 1000;
    if aabbs.len() < MANY {
        return false;
    }
    let step = aabbs.len().div_ceil(SAMPLES);
    let mut counts = std::collections::HashMap::new();
    for b in aabbs.iter().step_by(step) {
        let key = [b.min, b.max].map(|v| v.to_array().map(f32::to_bits));
        *counts.entry(key).or_insert(0usize) += 1;
    }
    let most = counts.values().copied().max().unwrap_or(0);
    most >= 16 && most * step >= MANY
}

/// Most primitives one obvhs build takes in a scene of `count`. Its builder holds about
/// 230 bytes a primitive while it runs (two node arrays and the sort keys, then the
/// tree's own nodes), more than the finished scene (about 90 with the CPU's wide tree);
/// larger scenes are cut by object median into groups of at most this many, each built
/// by obvhs in turn. A sixteenth of the scene keeps the builder's share near 15 bytes a
/// primitive at the peak of the load, which the records, the tree and the builder's
/// group make (docs/bvh.md); a scene of up to `BUILD_CHUNK_MIN` is built whole (the
/// builder's 15 MB do not count), and no group is larger than `BUILD_CHUNK_MAX`, where
/// the top levels' median splits have long stopped mattering.
pub fn build_chunk(count: usize) -> usize {
    (count / 16).clamp(BUILD_CHUNK_MIN, BUILD_CHUNK_MAX)
}

/// The smallest and largest groups of `build_chunk`.
pub const BUILD_CHUNK_MIN: usize = 1 << 16;
pub const BUILD_CHUNK_MAX: usize = 1 << 19;

/// Scenes up to this many primitives always get the high-quality build: at about 2.5 us
/// a primitive it costs at most about 50 ms, and it traced balls-4 13% faster on lavapipe
/// (0.80 s against 0.92 s). Larger scenes get it when the render is long enough to repay
/// it (`Quality::for_work`); the medium build is 2 to 5 times faster to build (mount-9:
/// 0.46 s against 1.13 s on two cores, docs/bvh.md).
pub const THOROUGH_BUILD_MAX_PRIMS: usize = 20_000;

/// obvhs' settings for `quality`, leaves of at most `MAX_LEAF_PRIMS`.
fn params(quality: Quality) -> BvhBuildParams {
    let preset = match quality {
        Quality::High => BvhBuildParams::very_slow_build(),
        Quality::Medium => BvhBuildParams::medium_build(),
    };
    BvhBuildParams {
        max_prims_per_leaf: MAX_LEAF_PRIMS,
        // obvhs' own splitting (early split clipping, before PLOC) cuts every large box
        // whether or not it helps, transparent primitives too: measured worse
        // (docs/bvh.md). `spatial` cuts where the SAH says so.
        pre_split: false,
        ..preset
    }
}

/// obvhs' PLOC tree over `aabbs`.
fn build_obvhs(aabbs: &[Aabb], quality: Quality) -> Bvh2 {
    let params = params(quality);
    PlocBuilder::with_capacity(aabbs.len()).build(
        params.ploc_search_distance,
        aabbs,
        (0..aabbs.len() as u32).collect(),
        params.sort_precision,
        params.search_depth_threshold,
    )
}

/// obvhs' reinsertion (moving badly placed subtrees where the SAH says), then its
/// collapse of subtrees into leaves, and a second reinsertion pass.
fn optimise(bvh: &mut Bvh2, quality: Quality) {
    let params = params(quality);
    let mut reinsertion = obvhs::bvh2::reinsertion::ReinsertionOptimizer::default();
    reinsertion.run(bvh, params.reinsertion_batch_ratio, None);
    obvhs::bvh2::leaf_collapser::collapse(
        bvh,
        params.max_prims_per_leaf,
        params.collapse_traversal_cost,
    );
    reinsertion.run(
        bvh,
        params.reinsertion_batch_ratio * params.post_collapse_reinsertion_batch_ratio_multiplier,
        None,
    );
}

/// The axis along which `b` lies most clearly after `a`, and whether it lies before.
fn split_axis(a: &Aabb, b: &Aabb) -> (u32, bool) {
    let d = (b.min + b.max) - (a.min + a.max);
    let axis = d.abs().max_position() as u32;
    (axis, d[axis as usize] < 0.0)
}

fn flatten(bvh: &Bvh2, aabbs: &[Aabb]) -> FlatBvh {
    let mut out = FlatBvh {
        nodes: Vec::with_capacity(bvh.nodes.len()),
        order: Vec::with_capacity(aabbs.len()),
        depth: 0,
    };
    // (obvhs node, output node whose `offset` must point here, depth)
    let mut stack = vec![(0usize, None::<usize>, 1usize)];
    while let Some((i, patch, depth)) = stack.pop() {
        let n = &bvh.nodes[i];
        let here = out.nodes.len();
        if let Some(p) = patch {
            out.nodes[p].offset = here as u32;
        }
        out.depth = out.depth.max(depth);
        let mut node = GpuNode {
            min: Vec3::from(n.aabb.min),
            max: Vec3::from(n.aabb.max),
            ..GpuNode::default()
        };
        if n.prim_count > 0 {
            node.offset = out.order.len() as u32;
            let first = n.first_index as usize;
            // The parts of a primitive cut by spatial splits may come together again in
            // one leaf, which holds it once.
            for &p in &bvh.primitive_indices[first..first + n.prim_count as usize] {
                if !out.order[node.offset as usize..].contains(&p) {
                    out.order.push(p);
                }
            }
            node.count_axis = out.order.len() as u32 - node.offset;
            out.nodes.push(node);
        } else {
            let (mut c0, mut c1) = (n.first_index as usize, n.first_index as usize + 1);
            let (axis, swap) = split_axis(&bvh.nodes[c0].aabb, &bvh.nodes[c1].aabb);
            if swap {
                std::mem::swap(&mut c0, &mut c1);
            }
            node.count_axis = axis << NODE_AXIS_SHIFT;
            out.nodes.push(node);
            stack.push((c1, Some(here), depth + 1));
            stack.push((c0, None, depth + 1));
        }
    }
    out
}

/// A tree by object median on the widest centroid axis down to ranges of at most `chunk`
/// primitives: leaves where `chunk` is `MAX_LEAF_PRIMS` (a balanced tree, depth at most
/// log2(n) + 1), else subtrees built by `build_group`, each over its own range. The ranges
/// are reordered in place, unless a group's spatial splits (`split`) may store a primitive
/// more than once: then the leaves' primitives are gathered in a second array, leaf by
/// leaf.
fn median_split(
    count: usize,
    aabb: &impl Fn(u32) -> Aabb,
    chunk: usize,
    quality: Quality,
    split: Option<&dyn Splittable>,
) -> FlatBvh {
    let mut out = FlatBvh {
        order: (0..count as u32).collect(),
        ..FlatBvh::default()
    };
    let mut gathered: Vec<u32> = Vec::new();
    // Each split's sort keys (twice the centre on the split axis, and the primitive),
    // worked out once a level rather than at every comparison: `aabb` computes bounds from
    // a primitive record, and the selection compares each several times. The buffer is
    // reused down a path and freed before a group's build, whose own peak it would add to.
    let mut keys: Vec<(f32, u32)> = Vec::new();
    // (range start, range end, output node to patch, depth)
    let mut stack = vec![(0usize, count, None::<usize>, 1usize)];
    while let Some((lo, hi, patch, depth)) = stack.pop() {
        let here = out.nodes.len();
        if let Some(p) = patch {
            out.nodes[p].offset = here as u32;
        }
        if hi - lo > MAX_LEAF_PRIMS as usize && hi - lo <= chunk {
            keys = Vec::new();
            let first = if split.is_some() { gathered.len() } else { lo };
            let ids = out.order[lo..hi].to_vec();
            let local = split.map(|split| Local {
                split,
                ids: Some(&ids),
            });
            let order = append_subtree(&mut out, aabb, &ids, first as u32, depth, quality, local);
            if split.is_some() {
                gathered.extend(order);
            } else {
                out.order[lo..hi].copy_from_slice(&order);
            }
            continue;
        }
        out.depth = out.depth.max(depth);
        let (mut min, mut max) = (Vec3A::INFINITY, Vec3A::NEG_INFINITY);
        let (mut cmin, mut cmax) = (Vec3A::INFINITY, Vec3A::NEG_INFINITY);
        for &i in &out.order[lo..hi] {
            let b = aabb(i);
            (min, max) = (min.min(b.min), max.max(b.max));
            let c = b.min + b.max;
            (cmin, cmax) = (cmin.min(c), cmax.max(c));
        }
        let mut node = GpuNode {
            min: min.into(),
            max: max.into(),
            ..GpuNode::default()
        };
        if hi - lo <= MAX_LEAF_PRIMS as usize {
            node.offset = lo as u32;
            if split.is_some() {
                node.offset = gathered.len() as u32;
                gathered.extend_from_slice(&out.order[lo..hi]);
            }
            node.count_axis = (hi - lo) as u32;
            out.nodes.push(node);
            continue;
        }
        let axis = (cmax - cmin).max_position();
        let mid = (lo + hi) / 2;
        keys.clear();
        keys.extend(out.order[lo..hi].iter().map(|&i| {
            let b = aabb(i);
            (b.min[axis] + b.max[axis], i)
        }));
        keys.select_nth_unstable_by(mid - lo, |a, b| a.0.total_cmp(&b.0));
        for (slot, &(_, i)) in out.order[lo..hi].iter_mut().zip(&keys) {
            *slot = i;
        }
        node.count_axis = (axis as u32) << NODE_AXIS_SHIFT;
        out.nodes.push(node);
        stack.push((mid, hi, Some(here), depth + 1));
        stack.push((lo, mid, None, depth + 1));
    }
    if split.is_some() {
        out.order = gathered;
    }
    out
}

/// Builds the group of primitives `ids` (`build_group`) and appends its flattened subtree
/// at the end of `out.nodes` (its root at depth `depth`, its leaves' primitives counted
/// from `first`); the primitives in the order its leaves hold them.
fn append_subtree(
    out: &mut FlatBvh,
    aabb: &impl Fn(u32) -> Aabb,
    ids: &[u32],
    first: u32,
    depth: usize,
    quality: Quality,
    split: Option<Local>,
) -> Vec<u32> {
    let sub_aabbs: Vec<Aabb> = ids.iter().map(|&i| aabb(i)).collect();
    let sub = build_group(&sub_aabbs, quality, split);
    drop(sub_aabbs);
    let base = out.nodes.len() as u32;
    out.nodes.extend(sub.nodes.iter().map(|n| GpuNode {
        offset: n.offset + if n.count() > 0 { first } else { base },
        ..*n
    }));
    out.depth = out.depth.max(depth - 1 + sub.depth);
    sub.order.iter().map(|&j| ids[j as usize]).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn unit_boxes(n: usize) -> Vec<Aabb> {
        (0..n)
            .map(|i| {
                let p = Vec3::new((i * 7 % 13) as f32, (i * 5 % 11) as f32, i as f32 * 0.1);
                aabb(Bounds {
                    min: p,
                    max: p + Vec3::splat(0.5),
                })
            })
            .collect()
    }

    /// Every primitive appears once, every leaf's bounds contain its primitives and every
    /// inner node's bounds contain its children.
    fn check(bvh: &FlatBvh, aabbs: &[Aabb]) {
        let bounds: Vec<Bounds> = aabbs
            .iter()
            .map(|b| Bounds {
                min: b.min.into(),
                max: b.max.into(),
            })
            .collect();
        let mut seen = vec![false; bounds.len()];
        for &i in &bvh.order {
            assert!(!std::mem::replace(&mut seen[i as usize], true));
        }
        assert!(seen.iter().all(|&s| s));
        let inside = |n: &GpuNode, b: &Bounds| n.min.cmple(b.min).all() && n.max.cmpge(b.max).all();
        for (i, n) in bvh.nodes.iter().enumerate() {
            if n.count() > 0 {
                for k in n.offset..n.offset + n.count() {
                    assert!(inside(n, &bounds[bvh.order[k as usize] as usize]));
                }
            } else {
                for c in [i + 1, n.offset as usize] {
                    let c = &bvh.nodes[c];
                    assert!(inside(
                        n,
                        &Bounds {
                            min: c.min,
                            max: c.max
                        }
                    ));
                }
            }
        }
    }

    #[test]
    fn obvhs_and_median_trees_are_well_formed() {
        for n in [1, 2, 3, 5, 100, 1000] {
            let b = unit_boxes(n);
            for quality in [Quality::Medium, Quality::High] {
                check(&build(&b, quality), &b);
            }
            let m = median_leaves(b.len(), &|i| b[i as usize]);
            check(&m, &b);
            assert!(m.depth <= (n as f64).log2().ceil() as usize + 1);
        }
    }

    /// Longest root-to-leaf path, walked.
    fn walked_depth(bvh: &FlatBvh) -> usize {
        let mut deepest = 0;
        let mut stack = vec![(0usize, 1usize)];
        while let Some((i, d)) = stack.pop() {
            deepest = deepest.max(d);
            let n = &bvh.nodes[i];
            if n.count() == 0 {
                assert!(n.offset as usize > i + 1, "children after their parent");
                stack.push((i + 1, d + 1));
                stack.push((n.offset as usize, d + 1));
            }
        }
        deepest
    }

    /// Cut into groups built by obvhs (small groups here, as `build_chunk` does for
    /// millions of primitives): still every primitive once, bounds that contain, and the
    /// depth it reports.
    #[test]
    fn trees_built_in_groups_are_well_formed() {
        for (n, chunk) in [(5, 4), (1000, 64), (5000, 300), (4097, 4096)] {
            let b = unit_boxes(n);
            let t = median_split(b.len(), &|i| b[i as usize], chunk, Quality::Medium, None);
            check(&t, &b);
            assert_eq!(t.depth, walked_depth(&t), "{n} boxes in groups of {chunk}");
            assert!(t.nodes.len() < 2 * n, "{} nodes", t.nodes.len());
        }
    }

    /// Coincident boxes (a hundred thousand copies of one triangle's) build in well under a
    /// second, by median splits, into a well-formed tree; ordinary boxes do not count as
    /// coincident.
    #[test]
    fn coincident_boxes_build_fast_by_median_splits() {
        let one = Aabb {
            min: Vec3A::new(-1.0, 0.0, -1.0),
            max: Vec3A::new(1.0, 0.0, 1.0),
        };
        let b = vec![one; 100_000];
        assert!(mostly_coincident(&b));
        assert!(!mostly_coincident(&unit_boxes(100_000)));
        let start = std::time::Instant::now();
        let t = build(&b, Quality::Medium);
        assert!(start.elapsed().as_secs_f64() < 5.0, "{:?}", start.elapsed());
        check(&t, &b);
    }

    /// Boxes spaced ever wider apart (each twice as far from the origin as the last)
    /// make obvhs' clustering chain them one by one, a tree deeper than the traversal
    /// stack: `build` must fall back to median splits, which fit.
    #[test]
    fn a_tree_deeper_than_the_stack_is_rebuilt_by_median_splits() {
        let b: Vec<Aabb> = (0..120)
            .map(|k| {
                let x = 2f32.powi(k);
                Aabb {
                    min: Vec3A::new(x, 0.0, 0.0),
                    max: Vec3A::new(x * 1.25, 1.0, 1.0),
                }
            })
            .collect();
        for quality in [Quality::Medium, Quality::High] {
            let chained = flatten(&build_obvhs(&b, quality), &b);
            assert!(
                chained.depth >= TRAVERSAL_STACK,
                "obvhs depth {}",
                chained.depth
            );
            let t = build(&b, quality);
            check(&t, &b);
            assert!(t.depth < TRAVERSAL_STACK, "depth {}", t.depth);
            assert_eq!(t.depth, walked_depth(&t));
        }
    }

    #[test]
    fn long_renders_and_small_scenes_get_the_high_quality_build() {
        let (small, large) = (THOROUGH_BUILD_MAX_PRIMS, 500_000);
        assert_eq!(Quality::for_work(small, 1), Quality::High);
        assert_eq!(Quality::for_work(large, 512 * 512), Quality::Medium);
        let enough = HIGH_QUALITY_SAMPLES_PER_PRIM * large as u64;
        assert_eq!(Quality::for_work(large, enough - 1), Quality::Medium);
        assert_eq!(Quality::for_work(large, enough), Quality::High);
        assert_eq!(Quality::for_work(usize::MAX, u64::MAX - 1), Quality::Medium);
    }

    #[test]
    fn empty_input_gives_empty_tree() {
        assert!(build(&[], Quality::High).nodes.is_empty());
    }
}
