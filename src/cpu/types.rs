//! CPU twin of `shaders/types.wgsl`: rays, hits, the bindings as one borrowed struct, and
//! the counter-based hash both renderers draw samples from.

use glam::Vec3;

use crate::bvh::blocks::Blocks;
use crate::bvh::wide::Tree;
use crate::counters::Counters;
use crate::gpu_types::*;
use crate::pack::SceneBuffers;

/// The read-only bindings, as the shader sees them.
#[derive(Clone, Copy)]
pub struct Bindings<'a> {
    pub globals: &'a GpuGlobals,
    pub nodes: &'a [GpuNode],
    pub prims: &'a [GpuPrim],
    pub tri_normals: &'a [GpuTriNormals],
    /// Texture coordinates, whose slots count on from the normals' (`GpuPrim`).
    pub tri_uvs: &'a [GpuTriUvs],
    /// The textures' headers and texels, which the shader reads after `tri_uvs`.
    pub textures: &'a [GpuTexture],
    pub texels: &'a [glam::Vec4],
    pub planes: &'a [GpuPlane],
    pub materials: &'a [GpuMaterial],
    pub lights: &'a [GpuLight],
    /// The emitters' triangles, which the shader reads after `lights`
    /// (`SceneBuffers::gpu_lights`).
    pub emitter_triangles: &'a [GpuLight],
    /// The eight-wide tree (`bvh::wide`) the CPU walks (`wide.rs`) instead of `nodes` when
    /// given; `None` walks `nodes` as the shader does (`GpuGlobals::traversal`).
    pub wide: Option<&'a Tree>,
    /// The triangle leaves in blocks of four (`bvh::blocks`) for the single-ray walk of
    /// `wide`, when given.
    pub blocks: Option<&'a Blocks>,
    /// The GPU's four-wide tree, walked as the shader walks it, when `globals.traversal`
    /// is `TRAVERSAL_WIDE` or `TRAVERSAL_QWIDE` and `wide` is `None`.
    pub gpu_wide: Option<GpuWide<'a>>,
    /// The GPU's compressed eight-wide tree, walked as the shader walks it, when
    /// `globals.traversal` is `TRAVERSAL_CWIDE` and `wide` is `None`; `prims` are then in
    /// its order (`pack::GpuCwide`).
    pub gpu_cwide: Option<&'a [GpuCwideNode]>,
}

impl<'a> Bindings<'a> {
    /// What the CPU renderer reads: the buffers, walked through the eight-wide tree, but
    /// for the `cost` AOV, which counts the nodes of the GPU's walk.
    pub fn new(buffers: &'a SceneBuffers, globals: &'a GpuGlobals) -> Self {
        if globals.aov == AOV_COST {
            return Self::gpu_walk(buffers, globals);
        }
        Bindings {
            globals,
            nodes: &buffers.nodes,
            prims: &buffers.prims,
            tri_normals: &buffers.tri_normals,
            tri_uvs: &buffers.tri_uvs,
            textures: &buffers.textures,
            texels: &buffers.texels,
            planes: &buffers.planes,
            materials: &buffers.materials,
            lights: &buffers.lights,
            emitter_triangles: &buffers.emitter_triangles,
            wide: Some(buffers.wide_nodes()),
            blocks: Some(buffers.triangle_blocks()),
            gpu_wide: None,
            gpu_cwide: None,
        }
    }

    /// The bindings as the shader has them, walking the tree its way: for tests of the
    /// GPU's traversal on the CPU.
    pub fn gpu_walk(buffers: &'a SceneBuffers, globals: &'a GpuGlobals) -> Self {
        let cwide = (globals.traversal == TRAVERSAL_CWIDE)
            .then(|| buffers.gpu_cwide())
            .flatten();
        Bindings {
            globals,
            nodes: &buffers.nodes,
            prims: cwide.map_or(&buffers.prims, |c| &c.prims),
            tri_normals: &buffers.tri_normals,
            tri_uvs: &buffers.tri_uvs,
            textures: &buffers.textures,
            texels: &buffers.texels,
            planes: &buffers.planes,
            materials: &buffers.materials,
            lights: &buffers.lights,
            emitter_triangles: &buffers.emitter_triangles,
            wide: None,
            // Blocks are found by a leaf's first primitive in `buffers.prims`' order,
            // which the compressed tree's `prims` do not keep.
            blocks: None,
            gpu_wide: match globals.traversal {
                TRAVERSAL_WIDE => buffers.gpu_wide_nodes().map(GpuWide::Plain),
                TRAVERSAL_QWIDE => buffers.gpu_qwide_nodes().map(GpuWide::Quantised),
                _ => None,
            },
            gpu_cwide: cwide.map(|c| &c.nodes[..]),
        }
    }
}

/// The GPU's four-wide tree as a walk reads it: its nodes as they are
/// (`TRAVERSAL_WIDE`), or quantised (`TRAVERSAL_QWIDE`, each decoded as it is fetched).
#[derive(Clone, Copy, Debug)]
pub enum GpuWide<'a> {
    Plain(&'a [GpuWideNode]),
    Quantised(&'a [GpuQwideNode]),
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    pub origin: Vec3,
    pub dir: Vec3,
}

/// Closest hit: distance, what was hit, triangle barycentrics, the boxes the walk tested
/// (the `cost` AOV) and the nodes it fetched (the counters; the shader keeps those in a
/// private variable).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Hit {
    pub t: f32,
    pub prim: u32,
    pub u: f32,
    pub v: f32,
    pub cost: u32,
    pub nodes: u32,
}

/// PCG hash (Jarzynski & Olano, "Hash Functions for GPU Rendering", 2020): wrapping u32
/// arithmetic, so CPU and GPU produce identical bits.
pub fn pcg_hash(v: u32) -> u32 {
    let state = v.wrapping_mul(747796405).wrapping_add(2891336453);
    let word = ((state >> ((state >> 28) + 4)) ^ state).wrapping_mul(277803737);
    (word >> 22) ^ word
}

/// The random stream of one pixel sample.
pub fn rng_seed(pixel: u32, sample: u32, seed: u32) -> u32 {
    pcg_hash(pixel ^ pcg_hash(sample ^ pcg_hash(seed)))
}

/// Next uniform number in [0, 1) with 24 bits, advancing the stream.
pub fn rand(state: &mut u32) -> f32 {
    *state = pcg_hash(*state);
    (*state >> 8) as f32 * (1.0 / 16777216.0)
}

/// Count of the rays traced, by kind (the shader sums them into one), of those the CPU
/// traced in packets (`cpu::packet`), which are counted in their kind too, and of the BVH
/// nodes their walks fetched (the shader's `PixelCounts`; a packet's fetch of a node is
/// shared by the rays it answered, `packet::Kernels::closest_hits`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RayCounts {
    pub eye: u64,
    pub shadow: u64,
    pub reflected: u64,
    pub refracted: u64,
    pub eye_packed: u64,
    pub shadow_packed: u64,
    pub reflected_packed: u64,
    pub refracted_packed: u64,
    pub eye_nodes: u64,
    pub shadow_nodes: u64,
    /// Of reflected and refracted rays.
    pub secondary_nodes: u64,
}

impl RayCounts {
    pub fn total(&self) -> u64 {
        self.eye + self.shadow + self.reflected + self.refracted
    }
    pub fn add(&mut self, o: &RayCounts) {
        self.eye += o.eye;
        self.shadow += o.shadow;
        self.reflected += o.reflected;
        self.refracted += o.refracted;
        self.eye_packed += o.eye_packed;
        self.shadow_packed += o.shadow_packed;
        self.reflected_packed += o.reflected_packed;
        self.refracted_packed += o.refracted_packed;
        self.eye_nodes += o.eye_nodes;
        self.shadow_nodes += o.shadow_nodes;
        self.secondary_nodes += o.secondary_nodes;
    }
    /// The counts by the kinds the GPU counts, for a walk of `node_bytes` nodes.
    pub fn counters(&self, node_bytes: u64) -> Counters {
        Counters {
            rays: [self.eye, self.shadow, self.reflected + self.refracted],
            nodes: [self.eye_nodes, self.shadow_nodes, self.secondary_nodes],
            node_bytes,
            ..Counters::default()
        }
    }
}
