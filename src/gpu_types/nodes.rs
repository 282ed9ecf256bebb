//! The BVH's nodes as the walks read them (`GpuNode` for the single and pairs walks,
//! `GpuWideNode`, `GpuQwideNode` and `GpuCwideNode` for the wider ones), and the
//! constants that pack their entries: one definition each, mirrored in
//! `shaders/types.wgsl` as the rest of `gpu_types` is. Part of `gpu_types`, which
//! re-exports all of it.

use bytemuck::{Pod, Zeroable};
use glam::{Vec3, Vec4};

/// A flattened BVH node, 32 bytes (pbrt's `LinearBVHNode`). Nodes are in depth-first
/// order: an inner node's first child is the next node, its second child is at `offset`.
/// A leaf (`count > 0`) holds `count` primitives starting at `prims[offset]`.
/// `axis` is the axis along which the first child lies before the second: rays with a
/// negative direction on that axis visit the second child first.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuNode {
    pub min: Vec3,
    pub offset: u32,
    pub max: Vec3,
    /// `count | axis << NODE_AXIS_SHIFT`.
    pub count_axis: u32,
}

/// Where `GpuNode::count_axis` holds the split axis; the count is the bits below.
pub const NODE_AXIS_SHIFT: u32 = 16;
pub const NODE_COUNT_MASK: u32 = (1 << NODE_AXIS_SHIFT) - 1;

impl GpuNode {
    pub fn count(&self) -> u32 {
        self.count_axis & NODE_COUNT_MASK
    }
    pub fn axis(&self) -> u32 {
        self.count_axis >> NODE_AXIS_SHIFT
    }
}

/// A node of the four-wide BVH the `TRAVERSAL_WIDE` walk reads (`bvh::wide` collapses the
/// binary tree into it), 112 bytes, seven texels: the four children's boxes by axis
/// (`lo[axis]` holds that coordinate of the four boxes), and where each child leads,
/// as a traversal-stack entry: a wide node's index,
/// `WIDE_LEAF | first << WIDE_FIRST_SHIFT | (count - 1)` for a leaf of `count` (at most
/// `MAX_LEAF_PRIMS`) primitives from `prims[first]`, or `WIDE_EMPTY` for a lane without a
/// child (whose box is empty: lo above hi).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct GpuWideNode {
    pub lo: [Vec4; 3],
    pub hi: [Vec4; 3],
    pub entry: [u32; 4],
}

/// A node of the four-wide tree as the `TRAVERSAL_QWIDE` walk reads it (`bvh::qwide`
/// quantises a `GpuWideNode` into it), 64 bytes, four texels: on axis `a`, child `l`'s box
/// spans `origin[a] + q * scale[a]` for its low and high `q` (bytes `l` of `q[a]` and
/// `q[3 + a]`), with `scale[a] = 2^(e[a] - 127)` for the exponent `e[a]`, byte `a` of
/// `exps` (an f32 with those exponent bits). `q * scale` is exact, so both renderers
/// decode the same floats whether or not a compiler fuses the multiply-add; the boxes are
/// rounded outwards when quantised, so that each holds its child. `entry` as the wide
/// node's.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct GpuQwideNode {
    pub origin: Vec3,
    pub exps: u32,
    pub q: [u32; 6],
    pub _pad: [u32; 2],
    pub entry: [u32; 4],
}

/// Bit of a `GpuWideNode::entry` that marks a leaf.
pub const WIDE_LEAF: u32 = 1 << 31;
/// `GpuWideNode::entry` of a lane without a child.
pub const WIDE_EMPTY: u32 = u32::MAX;
/// Where a leaf's `GpuWideNode::entry` holds its first primitive; `count - 1` is the bits
/// below.
pub const WIDE_FIRST_SHIFT: u32 = 2;
pub const WIDE_COUNT_MASK: u32 = (1 << WIDE_FIRST_SHIFT) - 1;

/// A node of the compressed eight-wide BVH the `TRAVERSAL_CWIDE` walk reads
/// (`bvh::cwide` builds it from the binary tree), 80 bytes, five texels: the layout of
/// Ylitie, Karras and Laine's compressed wide BVH (HPG 2017), with leaves of up to
/// `MAX_LEAF_PRIMS` primitives. Each child's box is quantised to 8 bits an axis on a grid
/// over the node's own box: on axis `a`, lane `l` spans `origin[a] + q * scale[a]` for
/// its low and high `q`, with `scale[a] = 2^(e[a] - 127)` (an f32 whose exponent bits are
/// `e[a]`; 0 for a flat axis), computed as both renderers do, rounded outwards when built
/// so that a decoded box holds the child's. A child sits in the lane of the octant of ray
/// directions that should visit it first (`bvh::cwide`), so that a walk taking the lanes
/// in the order `lane ^ octant` goes roughly near to far without sorting.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuCwideNode {
    /// The low corner of the node's grid.
    pub origin: Vec3,
    /// Bytes 0 to 2: the scale exponents `e` of x, y and z; byte 3: a bit per lane that
    /// holds an inner child.
    pub exp_inner: u32,
    /// The node's inner children are nodes `child_base ..`, in lane order.
    pub child_base: u32,
    /// The primitives of its leaf children are `prim_base ..` (in the walk's own order of
    /// primitives, `bvh::cwide::Cwide::order`).
    pub prim_base: u32,
    /// A byte per lane (lanes 0 to 3, then 4 to 7): 0 for no child, `CWIDE_INNER` for an
    /// inner child, `count << CWIDE_COUNT_SHIFT | offset` for a leaf of `count`
    /// primitives from `prim_base + offset`.
    pub tags: [u32; 2],
    /// Per axis, a byte per lane: the low `q` of lanes 0 to 3 and of 4 to 7, then the high.
    pub quant: [[u32; 4]; 3],
}

/// `GpuCwideNode::tags` byte of an inner child.
pub const CWIDE_INNER: u32 = 1;
/// Where a leaf's `GpuCwideNode::tags` byte holds its primitive count; its offset is the
/// bits below.
pub const CWIDE_COUNT_SHIFT: u32 = 5;
pub const CWIDE_OFFSET_MASK: u32 = (1 << CWIDE_COUNT_SHIFT) - 1;
