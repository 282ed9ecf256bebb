//! The CPU renderer's triangle leaves as blocks of four, coordinates in SIMD lanes (`v0`,
//! the edges `e1` and `e2`, each a `Vec4` a coordinate: Embree's `Triangle4`), so that a
//! single ray tests a leaf's triangles without gathering and transposing four `GpuPrim`s
//! (`intersect::intersect_triangles4` does that for leaves without a block). Built beside
//! the eight-wide tree on the first CPU render: 144 bytes a leaf of two to four triangles
//! and a word a primitive, about as much again as the triangles' own records.

use glam::Vec4;

use crate::gpu_types::{GpuNode, GpuPrim, PRIM_TRIANGLE};

/// `Blocks::of_first` of a primitive that starts no block.
const NONE: u32 = u32::MAX;

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
    /// The block of a leaf of two to four primitives, `None` unless all are triangles.
    #[inline(always)]
    pub fn of_leaf(leaf: &[GpuPrim]) -> Option<Self> {
        if !(2..=4).contains(&leaf.len()) || leaf.iter().any(|p| p.kind() != PRIM_TRIANGLE) {
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

/// The blocks of a tree's triangle leaves, found by the leaf's first primitive.
#[derive(Clone, Debug, Default)]
pub struct Blocks {
    /// Per primitive, the block of the leaf it starts, or `NONE`.
    of_first: Vec<u32>,
    blocks: Vec<TriangleBlock>,
}

impl Blocks {
    /// The blocks of the leaves of `nodes` (the binary tree, whose leaves the wide tree
    /// keeps) over `prims`.
    pub fn build(nodes: &[GpuNode], prims: &[GpuPrim]) -> Self {
        let mut out = Blocks {
            of_first: vec![NONE; prims.len()],
            blocks: Vec::new(),
        };
        for n in nodes.iter().filter(|n| n.count() > 0) {
            let range = n.offset as usize..(n.offset + n.count()) as usize;
            if let Some(block) = TriangleBlock::of_leaf(&prims[range]) {
                out.of_first[n.offset as usize] = out.blocks.len() as u32;
                out.blocks.push(block);
            }
        }
        out
    }

    /// The block of the leaf whose first primitive is `first`, if it has one.
    #[inline(always)]
    pub fn get(&self, first: u32) -> Option<&TriangleBlock> {
        let i = *self.of_first.get(first as usize)?;
        self.blocks.get(i as usize)
    }

    /// Bytes held.
    pub fn bytes(&self) -> usize {
        self.of_first.len() * 4 + self.blocks.len() * std::mem::size_of::<TriangleBlock>()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every leaf of two to four triangles has its block, lane `k` its `k`-th triangle (the
    /// first again past the leaf), and no other leaf has one.
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
        let blocks = Blocks::build(&b.nodes, &b.prims);
        let (mut with, mut without) = (0, 0);
        for n in b.nodes.iter().filter(|n| n.count() > 0) {
            let leaf = &b.prims[n.offset as usize..(n.offset + n.count()) as usize];
            let triangles = leaf.iter().all(|p| p.kind() == PRIM_TRIANGLE);
            match blocks.get(n.offset) {
                Some(block) => {
                    assert!(triangles && leaf.len() >= 2, "a block for {leaf:?}");
                    for k in 0..4 {
                        let p = leaf.get(k).unwrap_or(&leaf[0]);
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
