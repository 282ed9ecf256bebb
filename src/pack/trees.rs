//! The trees each walk reads, derived from the binary tree `pack` builds (`build`) and
//! kept with the scene: the CPU renderer's eight-wide tree and its triangle blocks, and
//! the GPU's four-wide, quantised and compressed trees, each built the first time its walk
//! asks.

use super::SceneBuffers;
use crate::bvh::blocks::Blocks;
use crate::bvh::wide::{self, Tree};
use crate::bvh::{cwide, qwide};
use crate::gpu_types::*;

/// The compressed eight-wide tree (`bvh::cwide`) with `prims` in the order its leaves
/// index, as the `TRAVERSAL_CWIDE` walk reads them instead of `nodes` and `prims`.
#[derive(Clone, Debug)]
pub struct GpuCwide {
    pub nodes: Vec<GpuCwideNode>,
    pub prims: Vec<GpuPrim>,
    /// Traversal-stack words the walk needs.
    pub stack_words: u32,
}

impl SceneBuffers {
    /// `nodes` collapsed eight wide for the CPU renderer (`bvh::wide`), built the first
    /// time it is asked for: `nodes` must not change after that.
    pub fn wide_nodes(&self) -> &Tree {
        self.wide.get_or_init(|| wide::build(&self.nodes))
    }

    /// The leaves of two to four triangles as blocks for the CPU renderer's single-ray
    /// walk (`bvh::blocks`), from the eight-wide tree's leaves, built the first time they
    /// are asked for: `nodes` and `prims` must not change after that.
    pub fn triangle_blocks(&self) -> &Blocks {
        self.blocks
            .get_or_init(|| Blocks::build(self.wide_nodes(), &self.prims))
    }

    /// Readies the scene for frames of the AOV `aov` that only the CPU traces, and frees
    /// what they never read: builds the eight-wide tree, drops the binary tree it was
    /// built from (the CPU walks the wide tree; only the GPU, its wireframe and the
    /// `cost` AOV, which walks the GPU's tree, read `nodes`), then builds the triangle
    /// blocks from the wide tree's leaves, so that the binary tree and the blocks are
    /// never held at once. Nothing for the `cost` AOV. A 2M-triangle terrain peaks 19
    /// bytes a primitive lower (`benches/scene-memory.sh`). The scene cannot go to the
    /// GPU after this: `check_for_gpu` refuses it.
    pub fn for_cpu_alone(&mut self, aov: u32) {
        if aov == AOV_COST {
            return;
        }
        self.wide_nodes();
        self.nodes = Vec::new();
        self.triangle_blocks();
    }

    /// Whether `for_cpu_alone` has dropped the binary tree.
    pub fn is_cpu_only(&self) -> bool {
        self.nodes.len() != self.node_count
    }

    /// Nodes of the binary tree as built (`GpuGlobals::n_nodes`; its count stays when
    /// `for_cpu_alone` drops it).
    pub fn node_count(&self) -> usize {
        self.node_count
    }

    /// `nodes` collapsed four wide, as the GPU's `TRAVERSAL_WIDE` walk reads them, built
    /// the first time they are asked for (the CPU's tree is not needed); `None` when that
    /// walk cannot take this scene (`wide::gpu_nodes`), which then walks the binary tree
    /// in pairs.
    pub fn gpu_wide_nodes(&self) -> Option<&[GpuWideNode]> {
        self.gpu_wide().map(|(nodes, _)| &nodes[..])
    }

    fn gpu_wide(&self) -> Option<&(Vec<GpuWideNode>, u32)> {
        self.gpu_wide
            .get_or_init(|| wide::gpu_nodes(&self.nodes, self.gpu_collapse))
            .as_ref()
    }

    /// The four-wide tree's nodes quantised, as the `TRAVERSAL_QWIDE` walk reads them,
    /// built the first time they are asked for; `None` where that walk cannot take this
    /// scene (no wide tree, or a node that does not quantise: `qwide::build`).
    pub fn gpu_qwide_nodes(&self) -> Option<&[GpuQwideNode]> {
        self.gpu_qwide
            .get_or_init(|| qwide::build(self.gpu_wide_nodes()?))
            .as_deref()
    }

    /// The compressed eight-wide tree and its primitives, built the first time they are
    /// asked for; `None` when the `TRAVERSAL_CWIDE` walk cannot take this scene
    /// (`cwide::build`).
    pub fn gpu_cwide(&self) -> Option<&GpuCwide> {
        self.gpu_cwide
            .get_or_init(|| {
                let tree = cwide::build(&self.nodes, self.gpu_collapse)?;
                Some(GpuCwide {
                    nodes: tree.nodes,
                    prims: tree.order.iter().map(|&i| self.prims[i as usize]).collect(),
                    stack_words: tree.stack_words,
                })
            })
            .as_ref()
    }

    /// Whether the four-wide and the compressed trees have been built (tests: each walk
    /// asks for its own tree only).
    #[cfg(test)]
    pub(crate) fn trees_built(&self) -> (bool, bool, bool) {
        (
            self.gpu_wide.get().is_some(),
            self.gpu_cwide.get().is_some(),
            self.gpu_qwide.get().is_some(),
        )
    }

    /// Traversal-stack entries (words) the GPU's walk `traversal` (as `traversal_for`
    /// gives it) can need on this scene, at most `TRAVERSAL_STACK`: for the binary walks,
    /// one per inner node on the longest path (the tree's depth bounds it); for the wide
    /// walks, what `wide::gpu_nodes` and `cwide::build` found.
    pub fn stack_entries(&self, traversal: u32) -> u32 {
        // Only the walk's own tree is asked for: each is built on first use.
        match traversal {
            // The quantised tree is the wide tree's shape.
            TRAVERSAL_WIDE | TRAVERSAL_QWIDE => self.gpu_wide().map(|&(_, need)| need),
            TRAVERSAL_CWIDE => self.gpu_cwide().map(|c| c.stack_words),
            _ => None,
        }
        .unwrap_or(self.bvh_depth.max(1) as u32)
    }

    /// The walk a GPU that prefers `traversal` uses for this scene: `TRAVERSAL_CWIDE`
    /// only where the compressed tree fits it, `TRAVERSAL_QWIDE` only where the wide tree
    /// quantises, else the wide walk where the scene's wide tree fits it, else pairs.
    pub fn traversal_for(&self, traversal: u32) -> u32 {
        match traversal {
            TRAVERSAL_CWIDE if self.gpu_cwide().is_some() => TRAVERSAL_CWIDE,
            TRAVERSAL_QWIDE if self.gpu_qwide_nodes().is_some() => TRAVERSAL_QWIDE,
            TRAVERSAL_WIDE | TRAVERSAL_CWIDE | TRAVERSAL_QWIDE
                if self.gpu_wide_nodes().is_some() =>
            {
                TRAVERSAL_WIDE
            }
            TRAVERSAL_WIDE | TRAVERSAL_CWIDE | TRAVERSAL_QWIDE => TRAVERSAL_PAIRS,
            _ => traversal,
        }
    }
}
