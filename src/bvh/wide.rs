//! The wide trees: the binary tree of `SceneBuffers::nodes` collapsed so that each node
//! holds several children, whose boxes one ray tests together. Eight wide for the CPU
//! renderer (`WideNode`, `build`; walked by `cpu::wide`), in SIMD lanes: two of glam's
//! `Vec4`s per coordinate (SSE on x86-64, NEON on AArch64; one AVX register where the
//! compiler may use it). Four wide for the GPU's `TRAVERSAL_WIDE` walk (`GpuWideNode`,
//! `gpu_nodes`): there a ray waits on node fetches, and a wide node halves the chain of
//! them. On the CPU eight lanes beat four on primary rays (2 to 10% more a second on the
//! five SPD scenes of `benches/embree.sh`), docs/bvh.md.
//!
//! The leaves are the binary tree's leaves, the same primitive ranges of the same `prims`
//! array. Building a tree belongs with the tree: `pack` caches both wide trees without
//! depending on either renderer.

use glam::Vec4;

use crate::gpu_types::{
    GpuNode, GpuWideNode, TRAVERSAL_STACK, WIDE_EMPTY, WIDE_FIRST_SHIFT, WIDE_LEAF,
};

/// Children of a wide node.
pub const WIDTH: usize = 8;

/// One coordinate of the boxes of a wide node's children: lane `l` is `[l / 4][l % 4]`.
pub(crate) type Lanes = [Vec4; WIDTH / 4];

/// Bits of a `Link` that hold a leaf's count, below its first primitive.
const COUNT_BITS: u32 = 3;

/// `Link::count` of a lane that holds no child (its box is empty, so no ray enters): the
/// count bits all set, above any leaf's count.
pub(crate) const EMPTY: u32 = (1 << COUNT_BITS) - 1;

const _: () = assert!(crate::bvh::MAX_LEAF_PRIMS < EMPTY);
// A leaf's first primitive is a record's index: spatial splits make at most a fifth more
// records than the scene's primitives.
const _: () = assert!(crate::util::limits::MAX_PRIMITIVES / 5 * 6 < 1 << (32 - COUNT_BITS));

/// Words of a `WideNode`: an inner child's `Link` is its index times this. A multiple of
/// `1 << COUNT_BITS`, so that the count bits of an inner child's link are clear.
const NODE_WORDS: u32 = (size_of::<WideNode>() / 4) as u32;

const _: () = assert!(NODE_WORDS.is_multiple_of(1 << COUNT_BITS));

/// Where a lane of a `WideNode` leads, in one word: a leaf's first primitive and count
/// (`first << COUNT_BITS | count`), an inner child's wide node as where it starts in the
/// tree's words (its index times `NODE_WORDS`, the count bits clear), or nothing
/// (`u32::MAX`, count `EMPTY`). The walks find an inner child at four times its link in
/// bytes (`Link::node`): no multiplication on the chain of dependent operations that a
/// ray's walk waits on, where an index's, by 224, cost gears-4's mirror rays 2 to 4%.
/// Only `build` makes links to nodes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(transparent)]
pub struct Link(u32);

impl Link {
    /// The root, where every walk of the whole tree starts.
    pub const ROOT: Link = Link(0);
    const NONE: Link = Link(u32::MAX);

    /// The link of the wide node at `index`. A tree can link 76 million nodes (`u32::MAX`
    /// words), where a 2M-triangle terrain's tree holds 17 primitives a node (docs/bvh.md):
    /// scenes of up to `MAX_PRIMITIVES` stay far below it.
    fn inner(index: u32) -> Link {
        let words = index.checked_mul(NODE_WORDS);
        Link(words.expect("a CPU tree of more than 76 million wide nodes"))
    }

    fn leaf(first: u32, count: u32) -> Link {
        debug_assert!((1..EMPTY).contains(&count) && first < 1 << (32 - COUNT_BITS));
        Link(first << COUNT_BITS | count)
    }

    /// Primitives of a leaf, 0 for an inner child, `EMPTY` for no child.
    #[inline(always)]
    pub fn count(self) -> u32 {
        self.0 & EMPTY
    }

    /// A leaf's first primitive.
    #[inline(always)]
    pub fn first(self) -> u32 {
        self.0 >> COUNT_BITS
    }

    /// The wide node of an inner child (`count() == 0`) of the tree `wide`.
    ///
    /// # Safety
    /// The link is `ROOT` or an inner child's read from a node of `wide`: `build` checks
    /// that each of those starts a node of its tree. Unchecked here because a bounds check
    /// in the walks (a compare, and one more value to keep at hand in a loop short of
    /// registers) made the packets' walks 4 to 7% slower (teapot-6's primary packets,
    /// AVX-512).
    #[inline(always)]
    pub unsafe fn node(self, wide: &Tree) -> &WideNode {
        let word = self.0 as usize;
        debug_assert!(
            self.count() == 0 && word + NODE_WORDS as usize <= size_of_val(&wide.0[..]) / 4,
            "a link to no node"
        );
        // SAFETY: by the contract, the word starts a node of `wide`.
        unsafe { &*wide.0.as_ptr().cast::<u32>().add(word).cast::<WideNode>() }
    }

    /// Whether the link leads to a node of `wide` (the root, or any inner child's link read
    /// from the tree): where a walk may start.
    pub fn leads_into(self, wide: &Tree) -> bool {
        self.count() == 0 && self.0.is_multiple_of(NODE_WORDS) && self.index() < wide.len() as u32
    }

    /// The index in its tree of an inner child's wide node.
    pub fn index(self) -> u32 {
        debug_assert_eq!(self.count(), 0);
        self.0 / NODE_WORDS
    }
}

/// The CPU renderer's eight-wide tree as `build` made it, the root first (a root of empty
/// lanes where the scene has no primitives in a tree, so that `Link::ROOT` always leads
/// to a node and a walk from it needs no check): whole, so that every link to a node read
/// from it leads to one of its nodes (`Link::node`). Read as the slice of its nodes.
#[derive(Clone, Debug)]
pub struct Tree(Vec<WideNode>);

impl std::ops::Deref for Tree {
    type Target = [WideNode];

    fn deref(&self) -> &[WideNode] {
        &self.0
    }
}

/// Eight child boxes in structure-of-arrays form, and where each child leads: 224 bytes,
/// seven rows of eight lanes, so that no 32-byte row crosses a cache line.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(32))]
pub struct WideNode {
    /// Lower and upper corners: `lo[axis]` holds that coordinate of the eight boxes.
    pub(crate) lo: [Lanes; 3],
    pub(crate) hi: [Lanes; 3],
    /// Where each lane leads, a child and a count in one word: in two rows of their own
    /// they made the node 256 bytes, and every ray fetched the eighth more.
    links: [Link; WIDTH],
}

const _: () = assert!(size_of::<WideNode>() == 7 * 32);

impl WideNode {
    /// Where lane `l` leads.
    #[inline(always)]
    pub fn link(&self, l: usize) -> Link {
        self.links[l]
    }

    /// The node's leaf children as `(first primitive, count)`.
    pub fn leaves(&self) -> impl Iterator<Item = (u32, u32)> + '_ {
        self.links
            .iter()
            .filter(|k| k.count() != 0 && k.count() != EMPTY)
            .map(|k| (k.first(), k.count()))
    }

    pub(crate) fn empty() -> Self {
        WideNode {
            lo: [[Vec4::INFINITY; WIDTH / 4]; 3],
            hi: [[Vec4::NEG_INFINITY; WIDTH / 4]; 3],
            links: [Link::NONE; WIDTH],
        }
    }

    /// Lane `l` leads to a leaf of `count` primitives from `first` (a test's node).
    #[cfg(test)]
    pub(crate) fn set_leaf(&mut self, l: usize, first: u32, count: u32) {
        self.links[l] = Link::leaf(first, count);
    }
}

/// Surface area of a binary node's box: the node opened first when collapsing.
fn area(n: &GpuNode) -> f32 {
    let d = n.max - n.min;
    d.x * d.y + d.y * d.z + d.z * d.x
}

/// The binary nodes that stand as the children of binary node `i` in a wide node of up to
/// `width` children, into `kids` (emptied first; the collapse reuses one vector for every
/// node): its two children, then repeatedly the two children of the largest inner one in
/// its place while a lane is free. A tree that is one leaf gives itself.
fn children_into(nodes: &[GpuNode], i: u32, width: usize, kids: &mut Vec<u32>) {
    let n = &nodes[i as usize];
    kids.clear();
    if n.count() > 0 {
        kids.push(i); // a tree that is one leaf
    } else {
        kids.extend([i + 1, n.offset]);
    }
    while kids.len() < width {
        let open = kids
            .iter()
            .enumerate()
            .filter(|&(_, &k)| nodes[k as usize].count() == 0)
            .max_by(|a, b| area(&nodes[*a.1 as usize]).total_cmp(&area(&nodes[*b.1 as usize])));
        let Some((j, &k)) = open else { break };
        kids.swap_remove(j);
        kids.extend([k + 1, nodes[k as usize].offset]);
    }
}

/// The lanes that cost rays the fewest node visits, for every wide tree: the
/// SAH-optimal collapse of Ylitie, Karras and Laine (2017, "Efficient Incoherent Ray
/// Traversal on GPUs Through Compressed Wide BVHs"), without their merging of leaves (the
/// leaves stay the binary tree's, which the triangle blocks and every other walk share).
/// A wide node stands for the binary node it replaces, and a ray visits it as often as
/// that node's surface area says; the cost of a subtree given up to `i` lanes of the node
/// above it is the least total area of the wide nodes it then needs (0 for a leaf, which
/// takes one lane). Greedy opening of the largest child (`children_into`, which the GPU's
/// trees used before) leaves the lowest wide nodes of a balanced tree two to four lanes
/// full: eight wide on a 2M-triangle terrain this makes 40% fewer nodes, and fewer fetched
/// a ray (docs/bvh.md).
///
/// What is kept is each inner node's choices, a word a node: for each number of lanes
/// from 2 to the width, 0 for a wide node of its own or the lanes its first child takes,
/// and in the place of 1 lane, the first child's lanes in a node of its own. The costs
/// live only on a stack while the tree is walked children first, so the collapse never
/// holds more than the tree it makes and this word.
struct Optimal<'a> {
    nodes: &'a [GpuNode],
    /// Lanes of a wide node, at most `WIDTH`.
    width: usize,
    choices: Vec<u32>,
}

/// Bits of a choice in `Optimal::choices`: a number of lanes below `WIDTH`.
const CHOICE_BITS: usize = 3;

impl<'a> Optimal<'a> {
    fn new(nodes: &'a [GpuNode], width: usize) -> Self {
        assert!((2..=WIDTH).contains(&width), "a wide node of {width} lanes");
        let mut choices = vec![0u32; nodes.len()];
        // Nodes are in depth-first order, the first child right after its parent and the
        // second after the first's subtree: backwards, a node comes right after its first
        // child, whose cost row is then on top of the stack and its second child's below.
        let mut stack: Vec<[f64; WIDTH]> = Vec::new();
        for n in (0..nodes.len()).rev() {
            let node = &nodes[n];
            if node.count() > 0 {
                stack.push([0.0; WIDTH]);
                continue;
            }
            let (Some(first), Some(second)) = (stack.pop(), stack.pop()) else {
                unreachable!("an inner node's children come after it");
            };
            // The least cost of the two children sharing `lanes`, and the first child's
            // lanes (the fewest, among equal costs: `min_by` keeps the first).
            let split = |lanes: usize| {
                (1..lanes)
                    .map(|k| (first[k - 1] + second[lanes - k - 1], k))
                    .min_by(|a, b| a.0.total_cmp(&b.0))
                    .expect("two lanes or more")
            };
            let (spread, own) = split(width);
            // In f64: a scene's coordinates may reach 1e35 (the chain of the walks' tests),
            // whose areas overflow f32 and would leave every choice tied at infinity.
            let d = (node.max - node.min).as_dvec3();
            let open = d.x * d.y + d.y * d.z + d.z * d.x + spread;
            let mut row = [open; WIDTH];
            let mut word = own as u32;
            for lanes in 2..=width {
                let (cost, k) = split(lanes);
                if cost <= open {
                    row[lanes - 1] = cost;
                    word |= (k as u32) << (CHOICE_BITS * (lanes - 1));
                }
            }
            choices[n] = word;
            stack.push(row);
        }
        Optimal {
            nodes,
            width,
            choices,
        }
    }

    /// For inner node `n` in up to `lanes` lanes: 0 for a wide node of its own, else the
    /// lanes its first child takes (`lanes` 1: those of its own node's first child).
    fn choice(&self, n: u32, lanes: usize) -> usize {
        (self.choices[n as usize] >> (CHOICE_BITS * (lanes - 1))) as usize
            & ((1 << CHOICE_BITS) - 1)
    }

    /// The binary nodes that stand as the lanes of the wide node for binary node `i`,
    /// into `kids` (emptied first); a tree that is one leaf gives itself.
    fn children_into(&self, i: u32, kids: &mut Vec<u32>) {
        kids.clear();
        if self.nodes[i as usize].count() > 0 {
            kids.push(i);
        } else {
            self.spread(i, self.choice(i, 1), self.width, kids);
        }
    }

    /// Inner node `n`'s children over `lanes` lanes, `first` of them the first child's:
    /// each split again where its choice says, else one lane.
    fn spread(&self, n: u32, first: usize, lanes: usize, kids: &mut Vec<u32>) {
        let children = [
            (n + 1, first),
            (self.nodes[n as usize].offset, lanes - first),
        ];
        for (child, lanes) in children {
            let inner = self.nodes[child as usize].count() == 0;
            match lanes {
                2.. if inner && self.choice(child, lanes) > 0 => {
                    self.spread(child, self.choice(child, lanes), lanes, kids)
                }
                _ => kids.push(child),
            }
        }
    }
}

/// How the binary tree's nodes are gathered into the GPU's wide nodes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Collapse {
    /// The largest inner child opened while a lane is free (`children_into`).
    Greedy,
    /// The SAH-optimal gathering (`Optimal`).
    Optimal,
}

impl Collapse {
    /// The GPU's wide trees: `Greedy`, unless `GPURT_COLLAPSE=optimal`. On an H200 the
    /// optimal trees fetched 1 to 31% fewer node bytes a ray but traced gears-4 20 to 26%
    /// slower and teapot-6 5 to 18% faster (docs/bvh.md), so the walk's own speed, not
    /// the bytes, decides there; the setting measures both on one binary. The CPU's tree
    /// is always the optimal one.
    pub fn for_gpu() -> Result<Collapse, String> {
        match std::env::var("GPURT_COLLAPSE").as_deref() {
            Err(_) | Ok("") | Ok("greedy") => Ok(Collapse::Greedy),
            Ok("optimal") => Ok(Collapse::Optimal),
            Ok(v) => Err(format!("GPURT_COLLAPSE={v}: expected greedy or optimal")),
        }
    }
}

/// The lanes of each wide node of `width` over `nodes`, gathered as `collapse` says, for
/// `collapse`'s `children`.
pub(crate) struct Gather<'a> {
    nodes: &'a [GpuNode],
    width: usize,
    optimal: Option<Optimal<'a>>,
}

impl<'a> Gather<'a> {
    pub(crate) fn new(nodes: &'a [GpuNode], width: usize, collapse: Collapse) -> Self {
        let optimal = (collapse == Collapse::Optimal).then(|| Optimal::new(nodes, width));
        Gather {
            nodes,
            width,
            optimal,
        }
    }

    /// The binary nodes that stand as the lanes of the wide node for binary node `i`, into
    /// `kids` (emptied first); a tree that is one leaf gives itself.
    pub(crate) fn children_into(&self, i: u32, kids: &mut Vec<u32>) {
        match &self.optimal {
            Some(optimal) => optimal.children_into(i, kids),
            None => children_into(self.nodes, i, self.width, kids),
        }
    }
}

/// Collapses the flattened binary tree (children of inner node `i`: `i + 1` and
/// `offset`) into wide nodes, root first, each inner node's lanes the binary nodes that
/// `children(i, kids)` puts in `kids`. Each wide node starts as `empty` and gets its
/// lanes from `set(node, lane, binary child, wide node standing for it when it is
/// inner)`; `None` when `set` refuses one. The nodes are written in place as they are
/// found, into an array of the exact size (counted by a first pass that writes nothing),
/// so that the collapse holds nothing but the tree it makes.
fn collapse<N: Copy>(
    nodes: &[GpuNode],
    children: impl Fn(u32, &mut Vec<u32>),
    empty: N,
    set: impl FnMut(&mut N, usize, &GpuNode, u32) -> bool,
) -> Option<Vec<N>> {
    let count = collapse_into(nodes, &children, Vec::new(), (), |_, _, _, _| true)?.len();
    collapse_into(nodes, &children, Vec::with_capacity(count), empty, set)
}

/// `collapse` into `wide` (empty, with the capacity wanted).
fn collapse_into<N: Copy>(
    nodes: &[GpuNode],
    children: &impl Fn(u32, &mut Vec<u32>),
    mut wide: Vec<N>,
    empty: N,
    mut set: impl FnMut(&mut N, usize, &GpuNode, u32) -> bool,
) -> Option<Vec<N>> {
    if nodes.is_empty() {
        return Some(wide);
    }
    wide.push(empty);
    // (wide node to fill, binary node it stands for)
    let mut todo = vec![(0usize, 0u32)];
    let mut kids: Vec<u32> = Vec::with_capacity(WIDTH + 1);
    while let Some((w, i)) = todo.pop() {
        children(i, &mut kids);
        for (lane, &k) in kids.iter().enumerate() {
            let c = &nodes[k as usize];
            let mut inner = 0;
            if c.count() == 0 {
                inner = wide.len() as u32;
                todo.push((wide.len(), k));
                wide.push(empty);
            }
            if !set(&mut wide[w], lane, c, inner) {
                return None;
            }
        }
    }
    Some(wide)
}

/// The CPU renderer's eight-wide tree over the binary `nodes`.
pub fn build(nodes: &[GpuNode]) -> Tree {
    let optimal = Optimal::new(nodes, WIDTH);
    let children = |i, kids: &mut Vec<u32>| optimal.children_into(i, kids);
    let mut wide =
        collapse(nodes, children, WideNode::empty(), set_lane).expect("every lane is taken");
    if wide.is_empty() {
        wide.push(WideNode::empty()); // the root of no primitives
    }
    // What `Link::node` relies on: every inner child's link starts a node of the tree.
    let links = wide.iter().flat_map(|n| n.links);
    let inner = |l: &Link| l.count() == 0;
    assert!(
        links.filter(inner).all(|l| l.index() < wide.len() as u32),
        "a wide node links outside its tree"
    );
    Tree(wide)
}

/// Lane `lane` of a CPU wide node for binary child `c` (`collapse`'s `set`), the wide node
/// `wide` standing for it when it is inner; every lane is taken.
fn set_lane(node: &mut WideNode, lane: usize, c: &GpuNode, wide: u32) -> bool {
    for axis in 0..3 {
        node.lo[axis][lane / 4][lane % 4] = c.min[axis];
        node.hi[axis][lane / 4][lane % 4] = c.max[axis];
    }
    node.links[lane] = if c.count() > 0 {
        Link::leaf(c.offset, c.count())
    } else {
        Link::inner(wide)
    };
    true
}

/// The binary `nodes` collapsed four wide, as the GPU's `TRAVERSAL_WIDE` walk reads them
/// (`GpuWideNode`), and the traversal-stack entries that walk can need on them; `None`
/// where that walk cannot take the tree: a path whose waiting children could overflow
/// `TRAVERSAL_STACK` (see `next_leaf_wide` in traverse.wgsl: a node leaves at most three
/// children waiting, and its pushes write up to two slots past those it keeps), a leaf of
/// more than four primitives, a first primitive beyond the entry's 29 bits, or no tree.
pub fn gpu_nodes(nodes: &[GpuNode], how: Collapse) -> Option<(Vec<GpuWideNode>, u32)> {
    let empty = GpuWideNode {
        lo: [Vec4::INFINITY; 3],
        hi: [Vec4::NEG_INFINITY; 3],
        entry: [WIDE_EMPTY; 4],
    };
    let set = |node: &mut GpuWideNode, lane: usize, c: &GpuNode, wide: u32| {
        for axis in 0..3 {
            node.lo[axis][lane] = c.min[axis];
            node.hi[axis][lane] = c.max[axis];
        }
        node.entry[lane] = match c.count() {
            0 => wide,
            count @ 1..=4 if c.offset < (1 << 29) - 1 => {
                WIDE_LEAF | c.offset << WIDE_FIRST_SHIFT | (count - 1)
            }
            _ => return false,
        };
        true
    };
    let gather = Gather::new(nodes, 4, how);
    let children = |i, kids: &mut Vec<u32>| gather.children_into(i, kids);
    let out = collapse(nodes, children, empty, set)?;
    if out.is_empty() {
        return None;
    }
    // Entries waiting when the walk reaches each node: the sum over its ancestors of the
    // children each left waiting (at most its children less the one entered).
    let mut todo = vec![(0usize, 0usize)];
    let mut need = 0;
    while let Some((w, waiting)) = todo.pop() {
        need = need.max(waiting + 3);
        if need > TRAVERSAL_STACK {
            return None;
        }
        let entries = &out[w].entry;
        let lanes = entries.iter().filter(|&&e| e != WIDE_EMPTY).count();
        for &e in entries {
            if e != WIDE_EMPTY && e & WIDE_LEAF == 0 {
                todo.push((e as usize, waiting + lanes - 1));
            }
        }
    }
    Some((out, need as u32))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bvh::{self, Quality};
    use crate::gpu_types::WIDE_COUNT_MASK;
    use glam::Vec3;
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

    /// A lane of either wide tree, as `check` reads it: its box, and a leaf's (first,
    /// count), an inner child's node, or nothing.
    enum Child {
        Leaf(u32, u32),
        Inner(usize),
        Empty,
    }

    fn cpu_lanes(wide: &[WideNode]) -> Vec<Vec<(Vec3, Vec3, Child)>> {
        let at = |v: &[Lanes; 3], l: usize| Vec3::from_array([0, 1, 2].map(|a| v[a][l / 4][l % 4]));
        wide.iter()
            .map(|n| {
                (0..WIDTH)
                    .map(|l| {
                        let link = n.link(l);
                        let child = match link.count() {
                            EMPTY => Child::Empty,
                            0 => Child::Inner(link.index() as usize),
                            c => Child::Leaf(link.first(), c),
                        };
                        (at(&n.lo, l), at(&n.hi, l), child)
                    })
                    .collect()
            })
            .collect()
    }

    fn gpu_lanes(wide: &[GpuWideNode]) -> Vec<Vec<(Vec3, Vec3, Child)>> {
        let at = |v: &[Vec4; 3], l: usize| Vec3::from_array([0, 1, 2].map(|a| v[a][l]));
        wide.iter()
            .map(|n| {
                (0..4)
                    .map(|l| {
                        let e = n.entry[l];
                        let child = if e == WIDE_EMPTY {
                            Child::Empty
                        } else if e & WIDE_LEAF != 0 {
                            Child::Leaf(
                                (e & !WIDE_LEAF) >> WIDE_FIRST_SHIFT,
                                (e & WIDE_COUNT_MASK) + 1,
                            )
                        } else {
                            Child::Inner(e as usize)
                        };
                        (at(&n.lo, l), at(&n.hi, l), child)
                    })
                    .collect()
            })
            .collect()
    }

    /// Walks a wide tree: every binary leaf appears once, as a lane with the leaf's own
    /// box; every inner lane's box is that of a binary node; empty lanes come last and
    /// hold empty boxes; no path is deeper than the binary tree's (the stack bound); and
    /// for a greedy collapse, a lane stays free only when no inner child was left to open
    /// into it (the optimal one may leave lanes free where a child is cheaper as a node of
    /// its own).
    fn check(binary: &bvh::FlatBvh, wide: &[Vec<(Vec3, Vec3, Child)>], greedy: bool) {
        let leaves: Vec<&GpuNode> = binary.nodes.iter().filter(|n| n.count() > 0).collect();
        let mut seen = vec![0u32; binary.order.len()];
        let mut reached = vec![false; wide.len()];
        let mut todo = vec![(0usize, 1usize)];
        let mut depth = 0;
        while let Some((w, d)) = todo.pop() {
            assert!(!std::mem::replace(&mut reached[w], true), "node {w} twice");
            depth = depth.max(d);
            let n = &wide[w];
            let lanes = n
                .iter()
                .take_while(|l| !matches!(l.2, Child::Empty))
                .count();
            assert!(lanes >= 1 && n[lanes..].iter().all(|l| matches!(l.2, Child::Empty)));
            // A lane stays free only when no inner child was left to open into it.
            assert!(
                !greedy
                    || lanes == n.len()
                    || n[..lanes].iter().all(|l| matches!(l.2, Child::Leaf(..))),
                "node {w}"
            );
            for (lo, hi, child) in n {
                let box_of = |b: &GpuNode| b.min == *lo && b.max == *hi;
                match *child {
                    Child::Empty => assert!(lo.cmpgt(*hi).all(), "empty lane of {w} has a box"),
                    Child::Leaf(first, count) => {
                        assert!(
                            leaves
                                .iter()
                                .any(|l| l.offset == first && l.count() == count && box_of(l))
                        );
                        for k in first..first + count {
                            seen[k as usize] += 1;
                        }
                    }
                    Child::Inner(node) => {
                        assert!(binary.nodes.iter().any(|b| b.count() == 0 && box_of(b)));
                        todo.push((node, d + 1));
                    }
                }
            }
        }
        assert!(reached.iter().all(|&r| r), "unreachable wide nodes");
        assert!(
            seen.iter().all(|&s| s == 1),
            "a primitive is not in exactly one leaf"
        );
        assert!(
            depth <= binary.depth,
            "wide depth {depth} > {}",
            binary.depth
        );
    }

    /// A link is one word: a leaf's first primitive and count come back as set, and the
    /// node an inner child's link leads to (four times the link in bytes into the tree)
    /// is the node at its index, the root at `Link::ROOT`.
    #[test]
    fn a_link_leads_to_its_leaf_or_node() {
        for (first, count) in [(0, 1), (7, 4), ((1 << 29) - 1, 3)] {
            let leaf = Link::leaf(first, count);
            assert_eq!((leaf.first(), leaf.count()), (first, count));
        }
        assert_eq!(Link::NONE.count(), EMPTY);
        let tree = build(&bvh::build(&boxes(1000), Quality::High).nodes);
        assert!(tree.len() > 1);
        // SAFETY: the root of a tree `build` made.
        assert!(std::ptr::eq(unsafe { Link::ROOT.node(&tree) }, &tree[0]));
        let mut inner = 0;
        for n in tree.iter() {
            for l in (0..WIDTH).map(|l| n.link(l)).filter(|l| l.count() == 0) {
                // SAFETY: an inner child's link read from a node of the tree.
                let node = unsafe { l.node(&tree) };
                assert!(std::ptr::eq(node, &tree[l.index() as usize]));
                inner += 1;
            }
        }
        assert_eq!(
            inner,
            tree.len() - 1,
            "every node but the root is one lane's child"
        );
    }

    #[test]
    fn the_wide_tree_holds_the_binary_leaves_once_and_is_no_deeper() {
        for n in [1, 2, 3, 5, 17, 1000] {
            for quality in [Quality::Medium, Quality::High] {
                let binary = bvh::build(&boxes(n), quality);
                check(&binary, &cpu_lanes(&build(&binary.nodes)), false);
                for how in [Collapse::Greedy, Collapse::Optimal] {
                    let (gpu, _) = gpu_nodes(&binary.nodes, how).expect("a shallow tree fits");
                    check(&binary, &gpu_lanes(&gpu), how == Collapse::Greedy);
                }
            }
        }
        // A chain deeper than obvhs keeps, rebuilt by median splits (bvh.rs): the deepest
        // tree the stack must hold.
        let chain: Vec<Aabb> = (0..120)
            .map(|k| {
                let x = 2f32.powi(k);
                Aabb {
                    min: glam::Vec3A::new(x, 0.0, 0.0),
                    max: glam::Vec3A::new(x * 1.25, 1.0, 1.0),
                }
            })
            .collect();
        let binary = bvh::build(&chain, Quality::Medium);
        check(&binary, &cpu_lanes(&build(&binary.nodes)), false);
        // Boxes wide in two axes as far out as 1e35, whose areas overflow f32: the costs
        // must still choose (an all-infinite tie once gave a node nine lanes).
        let wide: Vec<Aabb> = (0..200)
            .map(|k| {
                let x = 1.5f32.powi(k);
                Aabb {
                    min: glam::Vec3A::new(0.7 * x, -0.3 * x, -0.3 * x),
                    max: glam::Vec3A::new(1.3 * x, 0.3 * x, 0.3 * x),
                }
            })
            .collect();
        let binary = bvh::build(&wide, Quality::Medium);
        check(&binary, &cpu_lanes(&build(&binary.nodes)), false);
        let none = build(&[]);
        assert!(none.len() == 1 && none[0].leaves().next().is_none());
        assert!(gpu_nodes(&[], Collapse::Optimal).is_none());
    }

    /// A binary tree whose path to its deepest leaf passes `depth` inner nodes, each with
    /// a larger two-leaf subtree beside it: collapsed, every wide node on that path leaves
    /// three children waiting.
    fn comb(depth: usize) -> Vec<GpuNode> {
        fn node(nodes: &mut Vec<GpuNode>, size: f32, count: u32) -> usize {
            nodes.push(GpuNode {
                min: Vec3::ZERO,
                max: Vec3::splat(size),
                offset: 0,
                count_axis: count,
            });
            nodes.len() - 1
        }
        fn path(nodes: &mut Vec<GpuNode>, depth: usize) -> usize {
            if depth == 0 {
                return node(nodes, 1.0, 1);
            }
            let i = node(nodes, 1.0, 0);
            let side = node(nodes, 10.0, 0);
            node(nodes, 10.0, 1);
            let second = node(nodes, 10.0, 1);
            nodes[side].offset = second as u32;
            nodes[i].offset = path(nodes, depth - 1) as u32;
            i
        }
        let mut nodes = Vec::new();
        path(&mut nodes, depth);
        nodes
    }

    /// The GPU's wide walk takes trees whose waiting children fit the traversal stack,
    /// and refuses the others, which then walk the binary tree in pairs.
    /// The SAH cost of a wide tree: the surface area of each node's box (the union of its
    /// lanes'), which a ray visits as often as that area says.
    fn sah(lanes: &[Vec<(Vec3, Vec3, Child)>]) -> f64 {
        lanes
            .iter()
            .map(|node| {
                let (lo, hi) = node
                    .iter()
                    .filter(|(_, _, c)| !matches!(c, Child::Empty))
                    .fold(
                        (Vec3::INFINITY, Vec3::NEG_INFINITY),
                        |(lo, hi), (l, h, _)| (lo.min(*l), hi.max(*h)),
                    );
                let d = hi - lo;
                f64::from(d.x * d.y + d.y * d.z + d.z * d.x)
            })
            .sum()
    }

    /// The CPU's collapse is the SAH-optimal one (`Optimal`): never costlier than opening
    /// the largest child greedily, and fewer nodes on trees large enough for the greedy
    /// collapse to leave its lowest nodes part full.
    #[test]
    fn the_optimal_collapse_costs_no_more_than_the_greedy_one() {
        for n in [2, 5, 17, 100, 1000, 5000] {
            for quality in [Quality::Medium, Quality::High] {
                let binary = bvh::build(&boxes(n), quality);
                let nodes = &binary.nodes;
                let optimal = build(nodes);
                let children = |i, kids: &mut Vec<u32>| children_into(nodes, i, WIDTH, kids);
                let greedy = collapse(nodes, children, WideNode::empty(), set_lane).unwrap();
                check(&binary, &cpu_lanes(&greedy), true);
                let (o, g) = (sah(&cpu_lanes(&optimal)), sah(&cpu_lanes(&greedy)));
                assert!(
                    o <= g * (1.0 + 1e-6),
                    "{n} boxes: SAH {o} against greedy {g}"
                );
                // The GPU's four-wide tree too.
                let gpu = |how| gpu_lanes(&gpu_nodes(nodes, how).expect("fits").0);
                let (o4, g4) = (gpu(Collapse::Optimal), gpu(Collapse::Greedy));
                assert!(sah(&o4) <= sah(&g4) * (1.0 + 1e-6), "{n} boxes, four wide");
                assert!(o4.len() <= g4.len(), "{n} boxes, four wide");
                if n >= 1000 {
                    assert!(
                        optimal.len() < greedy.len(),
                        "{n} boxes: {} nodes against greedy {}",
                        optimal.len(),
                        greedy.len()
                    );
                }
            }
        }
    }

    #[test]
    fn the_gpu_wide_tree_is_refused_where_it_could_overflow_the_stack() {
        for n in [1, 17, 1000] {
            let binary = bvh::build(&boxes(n), Quality::High);
            for how in [Collapse::Greedy, Collapse::Optimal] {
                let (gpu, need) = gpu_nodes(&binary.nodes, how).expect("a shallow tree fits");
                check(&binary, &gpu_lanes(&gpu), how == Collapse::Greedy);
                assert!((3..=TRAVERSAL_STACK as u32).contains(&need));
            }
        }
        // Two binary levels a wide node, three waiting each: 20 levels need 3 * 10 + 3
        // entries, 42 need 66, more than the stack.
        // The optimal collapse gathers the comb otherwise (the large two-leaf subtrees
        // beside the path cost more as nodes of their own), with more children waiting.
        for (how, need) in [(Collapse::Greedy, 33), (Collapse::Optimal, 41)] {
            assert_eq!(gpu_nodes(&comb(20), how).map(|(_, need)| need), Some(need));
            let deep = comb(42);
            assert!(deep.len() < 4 * 42 + 2);
            assert!(gpu_nodes(&deep, how).is_none());
        }
    }
}
