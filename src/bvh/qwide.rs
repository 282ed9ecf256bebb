//! The four-wide tree of the GPU's `TRAVERSAL_QWIDE` walk: `wide::gpu_nodes`' nodes, node
//! for node, with each node's four boxes quantised to a byte an axis on the node's own
//! grid, as `cwide` quantises its eight (`GpuQwideNode`). A node is then four texels
//! instead of seven, and the walk is the wide walk's, step for step, on boxes decoded as
//! they are fetched (`decode`), each holding its child's.

use glam::{Vec3, Vec4};

use super::cwide::{exponent, grid, quantise, scale};
use crate::gpu_types::{GpuQwideNode, GpuWideNode, WIDE_EMPTY};

/// `nodes` quantised, node for node; `None` where a node's boxes cannot be (a box beyond
/// the grid an f32 exponent can step).
pub fn build(nodes: &[GpuWideNode]) -> Option<Vec<GpuQwideNode>> {
    nodes.iter().map(node).collect()
}

/// One node quantised: on each axis the grid starts at the lowest of its children's
/// boxes and steps by the smallest power of two whose 255 steps reach the highest; each
/// box rounded outwards onto it. A lane without a child keeps zeros (the walk skips it
/// by its entry).
fn node(n: &GpuWideNode) -> Option<GpuQwideNode> {
    let lanes = || (0..4).filter(|&l| n.entry[l] != WIDE_EMPTY);
    let (mut origin, mut exps, mut q) = ([0.0f32; 3], 0, [0u32; 6]);
    for a in 0..3 {
        let (lo, hi) = match lanes().next() {
            None => (0.0, 0.0),
            Some(_) => (
                lanes().map(|l| n.lo[a][l]).fold(f32::INFINITY, f32::min),
                lanes()
                    .map(|l| n.hi[a][l])
                    .fold(f32::NEG_INFINITY, f32::max),
            ),
        };
        let e = exponent(lo, hi)?;
        origin[a] = lo;
        exps |= e << (8 * a);
        for l in lanes() {
            let (ql, qh) = quantise(lo, scale(e), n.lo[a][l], n.hi[a][l])?;
            q[a] |= ql << (8 * l);
            q[3 + a] |= qh << (8 * l);
        }
    }
    Some(GpuQwideNode {
        origin: Vec3::from(origin),
        exps,
        q,
        _pad: [0; 2],
        entry: n.entry,
    })
}

/// The four-wide node a quantised one stands for, its boxes decoded as the shader's
/// `qwide_node` decodes them (each grid line `origin + q * scale`, exact but for the
/// one rounding of the add).
pub fn decode(n: &GpuQwideNode) -> GpuWideNode {
    let axis = |a: usize, word: u32| {
        let step = scale((n.exps >> (8 * a)) & 0xff);
        Vec4::from_array([0, 1, 2, 3].map(|l| grid(n.origin[a], (word >> (8 * l)) & 0xff, step)))
    };
    GpuWideNode {
        lo: [0, 1, 2].map(|a| axis(a, n.q[a])),
        hi: [0, 1, 2].map(|a| axis(a, n.q[3 + a])),
        entry: n.entry,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bvh::{self, wide};
    use crate::gpu_types::GpuNode;

    /// Boxes of many sizes and places, a flat one among them: every decoded box holds its
    /// child's and is at most a grid step larger on each side, and the entries are kept.
    #[test]
    fn decoded_boxes_hold_their_childrens() {
        let mut aabbs = Vec::new();
        for i in 0..2000u32 {
            let f = i as f32;
            let c = Vec3::new(
                (f * 0.37).sin() * 50.0,
                (f * 0.11).cos() * 3.0,
                f * 0.01 - 7.0,
            );
            let r = Vec3::new(
                0.01 + (i % 7) as f32,
                0.5,
                if i % 13 == 0 { 0.0 } else { 0.2 },
            );
            aabbs.push(bvh::aabb(crate::scene::Bounds {
                min: c - r,
                max: c + r,
            }));
        }
        let tree = bvh::build(&aabbs, bvh::Quality::Medium);
        let nodes: Vec<GpuNode> = tree.nodes;
        let (wide, _) = wide::gpu_nodes(&nodes, wide::Collapse::Optimal).expect("fits the stack");
        let quantised = build(&wide).expect("quantises");
        assert_eq!(quantised.len(), wide.len());
        for (w, q) in wide.iter().zip(&quantised) {
            let d = decode(q);
            assert_eq!(d.entry, w.entry);
            for l in (0..4).filter(|&l| w.entry[l] != WIDE_EMPTY) {
                for a in 0..3 {
                    let step = scale((q.exps >> (8 * a)) & 0xff);
                    let (lo, hi) = (d.lo[a][l], d.hi[a][l]);
                    assert!(lo <= w.lo[a][l] && hi >= w.hi[a][l], "lane {l} axis {a}");
                    assert!(w.lo[a][l] - lo <= step * 1.01 && hi - w.hi[a][l] <= step * 1.01);
                }
            }
        }
    }
}
