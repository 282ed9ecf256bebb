//! The CPU renderer's triangle leaves as blocks of up to four, coordinates in SIMD lanes
//! (`v0`, the edges `e1` and `e2`, each a `Vec4` a coordinate: Embree's `Triangle4`), so
//! that a single ray tests a leaf's triangles without gathering and transposing its
//! `GpuPrim`s (`intersect::intersect_triangles4` does that for leaves without a block).
//! Built from the eight-wide tree's leaves on the first CPU render.
//!
//! Stored packed, 36 bytes a triangle: a leaf of `n` triangles is nine rows of `n` floats,
//! each row loaded as four lanes (those past the leaf hold the next row's floats, which
//! every test masks off by the leaf's length), found by its first primitive's rank among
//! the triangles in blocks, which a bit a primitive and a count a 64 of them give. Blocks
//! of four lanes found through a word a primitive took 144 bytes a leaf and 4 a
//! primitive: on a 2M-triangle terrain 46 bytes a primitive where this takes 36, and
//! the largest share of the CPU renderer's peak after the primitives themselves.

use glam::Vec4;

use super::wide::WideNode;
use crate::gpu_types::{GpuPrim, PRIM_TRIANGLE};

/// Rows of a block: `v0`, `e1` and `e2`, by coordinate.
const ROWS: usize = 9;

/// A leaf of two to four triangles, a triangle a lane; lanes past the leaf repeat its
/// first triangle (as `intersect_triangles4` has them).
#[derive(Clone, Copy, Debug)]
#[repr(C, align(16))]
pub struct TriangleBlock {
    /// Vertex 0, then the edges to vertices 1 and 2 (`GpuPrim::p0`, `p1`, `p2`), each by
    /// coordinate: `v0[1]` holds the four triangles' y.
    pub v0: [Vec4; 3],
    pub e1: [Vec4; 3],
    pub e2: [Vec4; 3],
}

impl TriangleBlock {
    /// Whether `leaf` makes a block: two to four primitives, all triangles.
    #[inline(always)]
    pub fn fits(leaf: &[GpuPrim]) -> bool {
        (2..=4).contains(&leaf.len()) && leaf.iter().all(|p| p.kind() == PRIM_TRIANGLE)
    }

    /// The block of a leaf of two to four primitives, `None` unless all are triangles.
    #[inline(always)]
    pub fn of_leaf(leaf: &[GpuPrim]) -> Option<Self> {
        if !Self::fits(leaf) {
            return None;
        }
        let p: [&GpuPrim; 4] = std::array::from_fn(|k| leaf.get(k).unwrap_or(&leaf[0]));
        let lanes = |f: &dyn Fn(&GpuPrim) -> f32| Vec4::new(f(p[0]), f(p[1]), f(p[2]), f(p[3]));
        Some(TriangleBlock {
            v0: [lanes(&|q| q.p0.x), lanes(&|q| q.p0.y), lanes(&|q| q.p0.z)],
            e1: [lanes(&|q| q.p1.x), lanes(&|q| q.p1.y), lanes(&|q| q.p1.z)],
            e2: [lanes(&|q| q.p2.x), lanes(&|q| q.p2.y), lanes(&|q| q.p2.z)],
        })
    }
}

/// 64 primitives of `Blocks::covered`.
#[derive(Clone, Copy, Debug, Default)]
struct Covered {
    bits: u64,
    before: u32,
}

/// The blocks of a tree's triangle leaves, found by the leaf's first primitive.
#[derive(Clone, Debug, Default)]
pub struct Blocks {
    /// For each 64 primitives, a bit each, set where it lies in a block, and the
    /// primitives in blocks before them: side by side, so a lookup reads one cache line.
    covered: Vec<Covered>,
    /// The blocks' rows in primitive order, `ROWS` floats a triangle, and three more at
    /// the end so that the last row's four lanes stay inside.
    rows: Vec<f32>,
}

impl Blocks {
    /// The blocks of the leaves of the eight-wide tree `wide` (the binary tree's leaves,
    /// which it keeps) over `prims`, each array of its exact size.
    pub fn build(wide: &[WideNode], prims: &[GpuPrim]) -> Self {
        let leaf = |&(first, count): &(u32, u32)| &prims[first as usize..(first + count) as usize];
        let blocks = || {
            wide.iter()
                .flat_map(WideNode::leaves)
                .filter(|l| TriangleBlock::fits(leaf(l)))
        };
        let mut covered = vec![Covered::default(); prims.len().div_ceil(64)];
        for (first, count) in blocks() {
            for i in first as usize..(first + count) as usize {
                covered[i / 64].bits |= 1 << (i % 64);
            }
        }
        let mut triangles = 0;
        for c in &mut covered {
            c.before = triangles;
            triangles += c.bits.count_ones();
        }
        let mut out = Blocks {
            covered,
            rows: vec![0.0; ROWS * triangles as usize + 3],
        };
        for l in blocks() {
            let (at, n) = (ROWS * out.rank(l.0 as usize), l.1 as usize);
            for (k, p) in leaf(&l).iter().enumerate() {
                let coords = [p.p0, p.p1, p.p2].map(|v| v.to_array());
                for (r, c) in coords.iter().flatten().enumerate() {
                    out.rows[at + r * n + k] = *c;
                }
            }
        }
        out
    }

    /// Primitives in blocks before primitive `i`.
    #[inline(always)]
    fn rank(&self, i: usize) -> usize {
        let c = &self.covered[i / 64];
        c.before as usize + (c.bits & ((1u64 << (i % 64)) - 1)).count_ones() as usize
    }

    /// The block of the leaf of `count` primitives from `first`, if it has one: lanes
    /// from `count` on hold other floats (see the module's comment).
    #[inline(always)]
    pub fn get(&self, first: u32, count: u32) -> Option<TriangleBlock> {
        let i = first as usize;
        if self.covered.get(i / 64)?.bits >> (i % 64) & 1 == 0 {
            return None;
        }
        let (at, n) = (ROWS * self.rank(i), count as usize);
        // Every row's four lanes inside `rows`, checked once for all nine loads.
        if n > 4 || at + ROWS * n + 3 > self.rows.len() {
            return None;
        }
        // SAFETY: `at + r * n + 4 <= at + 8 * n + 4 <= at + ROWS * n + 3` for `n >= 1`,
        // within `rows` by the check above; a read of four floats needs no alignment.
        let row = |r: usize| unsafe { load4(self.rows.as_ptr().add(at + r * n)) };
        Some(TriangleBlock {
            v0: [row(0), row(1), row(2)],
            e1: [row(3), row(4), row(5)],
            e2: [row(6), row(7), row(8)],
        })
    }

    /// Bytes held.
    pub fn bytes(&self) -> usize {
        self.covered.len() * std::mem::size_of::<Covered>() + self.rows.len() * 4
    }
}

/// Four floats from `p`, one unaligned load (`read_unaligned` of an array became four).
///
/// # Safety
/// `p` must be valid for reading four floats.
#[inline(always)]
unsafe fn load4(p: *const f32) -> Vec4 {
    #[cfg(target_arch = "x86_64")]
    // SAFETY: as the caller promises; SSE is in every x86-64.
    return Vec4::from(unsafe { std::arch::x86_64::_mm_loadu_ps(p) });
    #[cfg(not(target_arch = "x86_64"))]
    // SAFETY: as the caller promises.
    Vec4::from_array(unsafe { p.cast::<[f32; 4]>().read_unaligned() })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every leaf of two to four triangles has its block, lane `k` its `k`-th triangle,
    /// and no other leaf has one.
    #[test]
    fn each_triangle_leaf_has_its_block_and_no_other() {
        let mut src = String::from("v from 0 -30 5 at 0 0 0 up 0 0 1 angle 40 resolution 8 8\n");
        src += "f 1 1 1 1 0 1 0 0\n";
        for i in 0..300 {
            let (x, y) = ((i % 20) as f32, (i / 20) as f32);
            src += &format!("p 3 {x} {y} 0 {} {y} 0.5 {x} {} 0.25\n", x + 0.9, y + 0.9);
            if i % 7 == 0 {
                src += &format!("s {x} {y} 1 0.3\n");
            }
        }
        let scene = crate::scene::nff::parse(src.as_bytes(), "t", std::path::Path::new("."))
            .expect("scene");
        let b = crate::pack::pack(scene).expect("packed");
        let blocks = Blocks::build(&crate::bvh::wide::build(&b.nodes), &b.prims);
        let (mut with, mut without) = (0, 0);
        for n in b.nodes.iter().filter(|n| n.count() > 0) {
            let leaf = &b.prims[n.offset as usize..(n.offset + n.count()) as usize];
            let triangles = leaf.iter().all(|p| p.kind() == PRIM_TRIANGLE);
            match blocks.get(n.offset, n.count()) {
                Some(block) => {
                    assert!(triangles && leaf.len() >= 2, "a block for {leaf:?}");
                    for (k, p) in leaf.iter().enumerate() {
                        for a in 0..3 {
                            assert_eq!(block.v0[a][k], p.p0[a]);
                            assert_eq!(block.e1[a][k], p.p1[a]);
                            assert_eq!(block.e2[a][k], p.p2[a]);
                        }
                    }
                    with += 1;
                }
                None => {
                    assert!(!triangles || leaf.len() < 2, "no block for {leaf:?}");
                    without += 1;
                }
            }
        }
        assert!(
            with > 20 && without > 0,
            "{with} leaves with blocks, {without} without"
        );
    }
}
