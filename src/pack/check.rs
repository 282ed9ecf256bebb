//! The invariants the GPU shader relies on, proved on the host before an upload: it runs
//! without runtime bounds checks.

use super::SceneBuffers;
use crate::gpu_types::*;
use crate::util::error::{Error, Result};
use crate::util::limits::MAX_DEPTH;

impl SceneBuffers {
    /// `check`, for a GPU's frame: which also needs the binary tree (`for_cpu_alone`).
    pub fn check_for_gpu(&self, globals: &GpuGlobals) -> Result<()> {
        if self.is_cpu_only() {
            return Err(Error::Gpu(
                "internal error: the binary tree was dropped for the CPU's walk alone".into(),
            ));
        }
        self.check(globals)
    }

    /// Proves the invariants the GPU shader relies on, since it runs without runtime
    /// bounds checks: every index in range, every inner node's children after it (so a
    /// traversal visits each node at most once and ends), the tree shallow enough for the
    /// fixed traversal stack, and the ray depth within the ray stack.
    pub fn check(&self, globals: &GpuGlobals) -> Result<()> {
        let fail = |msg: String| Err(Error::Gpu(format!("internal error: {msg}")));
        let n = self.nodes.len();
        for (i, node) in self.nodes.iter().enumerate() {
            let (count, offset) = (node.count() as usize, node.offset as usize);
            if count > 0 {
                if offset + count > self.prims.len() {
                    return fail(format!("leaf {i} refers past the primitives"));
                }
            } else if !(i + 1 < n && offset > i + 1 && offset < n) || node.axis() > 2 {
                return fail(format!("inner node {i} has bad children or axis"));
            }
        }
        if self.bvh_depth >= TRAVERSAL_STACK {
            return fail(format!("BVH depth {} exceeds the stack", self.bvh_depth));
        }
        if globals.traversal == TRAVERSAL_QWIDE
            && self.gpu_qwide_nodes().map(<[_]>::len) != self.gpu_wide_nodes().map(<[_]>::len)
        {
            return fail("the quantised walk was chosen for a tree it cannot take".into());
        }
        if globals.traversal == TRAVERSAL_WIDE || globals.traversal == TRAVERSAL_QWIDE {
            // The wide tree's leaves are the binary tree's (checked above); its inner
            // entries must lead to later nodes, and `wide::gpu_nodes` bounded the stack.
            // The quantised tree's entries are the wide tree's (`qwide::build`).
            let Some(wide) = self.gpu_wide_nodes() else {
                return fail("the wide walk was chosen for a tree it cannot take".into());
            };
            for (i, node) in wide.iter().enumerate() {
                for &e in &node.entry {
                    if e & WIDE_LEAF == 0 && !(e as usize > i && (e as usize) < wide.len()) {
                        return fail(format!("wide node {i} has a bad child"));
                    }
                }
            }
        }
        if globals.traversal == TRAVERSAL_CWIDE {
            let Some(c) = self.gpu_cwide() else {
                return fail("the compressed walk was chosen for a tree it cannot take".into());
            };
            if let Some(i) = c.nodes.iter().enumerate().position(|(i, n)| {
                let inner = (n.exp_inner >> 24).count_ones() as usize;
                let leaves = n.tags.iter().flat_map(|w| w.to_le_bytes()).map(u32::from);
                let past = leaves
                    .filter(|&m| m > CWIDE_INNER)
                    .map(|m| n.prim_base + (m & CWIDE_OFFSET_MASK) + (m >> CWIDE_COUNT_SHIFT))
                    .any(|end| end as usize > c.prims.len());
                past || inner > 0
                    && !(n.child_base as usize > i
                        && n.child_base as usize + inner <= c.nodes.len())
            }) {
                return fail(format!("compressed node {i} has a bad child"));
            }
        }
        for (i, p) in self.prims.iter().enumerate() {
            let slot_ok =
                p.kind() != PRIM_TRIANGLE || p.f1 < 0.0 || (p.f1 as usize) < self.tri_normals.len();
            let uv_ok = p.kind() != PRIM_TRIANGLE
                || p.f0 < 0.0
                || (self.tri_normals.len()..self.tri_normals.len() + self.tri_uvs.len())
                    .contains(&(p.f0 as usize));
            if p.material() as usize >= self.materials.len()
                || p.kind() > PRIM_BOX
                || !slot_ok
                || !uv_ok
            {
                return fail(format!(
                    "primitive {i} has a bad material, kind, normal slot or uv slot"
                ));
            }
        }
        if self
            .planes
            .iter()
            .any(|p| p.material as usize >= self.materials.len())
        {
            return fail("a plane has a bad material".into());
        }
        let emitter_triangles = self.emitter_triangles.len() as u64;
        if self.lights.iter().any(|l| match l.kind {
            LIGHT_POINT | LIGHT_DIRECTIONAL => false,
            LIGHT_AREA => l.nu == 0 || l.nv == 0,
            LIGHT_EMITTER => {
                l.nu == 0 || l.nv == 0 || u64::from(l.first) + u64::from(l.nv) > emitter_triangles
            }
            _ => true,
        }) {
            return fail("a light has a bad kind, sample count or triangle range".into());
        }
        let counts_ok = globals.n_nodes as usize == self.node_count
            && globals.n_planes as usize == self.planes.len()
            && globals.n_lights as usize == self.lights.len();
        if !counts_ok || globals.max_depth > MAX_DEPTH || globals.spp == 0 {
            return fail("render constants disagree with the scene buffers".into());
        }
        Ok(())
    }
}
