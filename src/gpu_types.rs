//! Every struct that crosses to WGSL, defined once here and mirrored in `shaders/types.wgsl`
//! (keep the two in sync: `tests/gpurt/layout.rs` checks sizes and field offsets against
//! naga's reflection of the shader). All are `#[repr(C)]` + `Pod`, so `pack` can hand the
//! vectors to wgpu as bytes, and the CPU reference renderer reads the very same values.
//!
//! And every constant the shader shares with Rust, defined only here: `WGSL_CONSTANTS`
//! lists them, and `gpu::shaders::source` declares each in the header of the generated
//! shader source, so no WGSL file writes one (the layout test checks both).
//!
//! The BVH's nodes are in `nodes`; the states a pixel keeps between dispatches, and its
//! counts, in `pixel`; the wavefront's records in `wave`.
//!
//! Every `Vec3` is followed by a 4-byte scalar, which gives the WGSL `vec3<f32>` its
//! 16-byte alignment without hidden padding.

use bytemuck::{Pod, Zeroable};
use glam::{Vec2, Vec3};

use crate::util::limits::MAX_DEPTH;

mod nodes;
mod pixel;
mod wave;
pub use nodes::*;
pub use pixel::*;
pub use wave::*;

/// Primitive kinds in the top bits of `GpuPrim::tag`.
pub const PRIM_SPHERE: u32 = 0;
pub const PRIM_TRIANGLE: u32 = 1;
pub const PRIM_CONE: u32 = 2;
pub const PRIM_BOX: u32 = 3;
/// `tag = kind << PRIM_KIND_SHIFT | material`.
pub const PRIM_KIND_SHIFT: u32 = 28;
pub const PRIM_MATERIAL_MASK: u32 = (1 << PRIM_KIND_SHIFT) - 1;

/// One bounded primitive, 48 bytes. What the fields hold depends on the kind:
///
/// | kind     | p0, f0                   | p1, f1                     | p2          |
/// |----------|--------------------------|----------------------------|-------------|
/// | sphere   | centre, radius           | -                          | -           |
/// | triangle | v0, uv slot              | edge v1-v0, normal slot    | edge v2-v0  |
/// | cone     | base centre, base radius | apex centre, apex radius   | -           |
/// | box      | min, -                   | max, -                     | -           |
///
/// A triangle's "normal slot" indexes `tri_normals` as an exactly representable float
/// (-1 when the triangle has no shading normals); `pack` refuses more than 2^24 slots. Its
/// "uv slot" likewise indexes the records after them in the same texels, `tri_uvs` (-1
/// without texture coordinates).
/// Triangles store the two edges because that is what Möller-Trumbore needs.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuPrim {
    pub p0: Vec3,
    pub f0: f32,
    pub p1: Vec3,
    pub f1: f32,
    pub p2: Vec3,
    pub tag: u32,
}

impl GpuPrim {
    pub fn kind(&self) -> u32 {
        self.tag >> PRIM_KIND_SHIFT
    }
    pub fn material(&self) -> u32 {
        self.tag & PRIM_MATERIAL_MASK
    }
}

/// Shading normals of one triangle (`pp` vertex normals, STL facet normals, OBJ normals).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuTriNormals {
    pub n0: Vec3,
    pub _pad0: u32,
    pub n1: Vec3,
    pub _pad1: u32,
    pub n2: Vec3,
    pub _pad2: u32,
}

/// Texture coordinates of one triangle's corners, a record of the normals' size so that
/// both share one array of texels (`SceneBuffers::surface_texels`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuTriUvs {
    pub uv0: Vec2,
    pub uv1: Vec2,
    pub uv2: Vec2,
    pub _pad: [u32; 6],
}

/// An infinite plane `dot(normal, p) = d`; tested outside the BVH.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuPlane {
    pub normal: Vec3,
    pub d: f32,
    pub material: u32,
    pub _pad: [u32; 3],
}

/// NFF `f r g b Kd Ks Shine T ior`, the radiance the surface emits from its front
/// (OBJ's `Ke`, glTF's emissive; zero for NFF's materials), and the colour the scene's
/// ambient light is multiplied by (`Kd` times the colour, or AFF's `fm` ambient colour).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuMaterial {
    pub color: Vec3,
    pub kd: f32,
    pub ks: f32,
    pub shine: f32,
    pub t: f32,
    pub ior: f32,
    pub emission: Vec3,
    /// Its texture's index (`GpuTexture`), or `NO_TEXTURE`.
    pub texture: u32,
    pub ambient: Vec3,
    pub _pad: u32,
}

/// `GpuMaterial::texture` of a material without one.
pub const NO_TEXTURE: u32 = u32::MAX;

/// A texture's header, one texel in the triangle surfaces' texels
/// (`SceneBuffers::surface_texels`, from `GpuGlobals::textures_at`): where its texels
/// start, counted from that first header (each a texel of linear RGB floats, row by row
/// from the top), its size, and how u (bits 0-1) and v (bits 2-3) wrap (`WRAP_*`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuTexture {
    pub first: u32,
    pub width: u32,
    pub height: u32,
    pub wrap: u32,
}

pub const WRAP_REPEAT: u32 = 0;
pub const WRAP_CLAMP: u32 = 1;
pub const WRAP_MIRROR: u32 = 2;

pub const LIGHT_POINT: u32 = 0;
pub const LIGHT_DIRECTIONAL: u32 = 1;
pub const LIGHT_AREA: u32 = 2;
pub const LIGHT_EMITTER: u32 = 3;

/// A light with its final intensity. Point: `pos`. Directional: `pos` is the unit direction
/// towards the light. Area: the rectangle `pos + a*u + b*v`, sampled `nu x nv` times, each
/// sample carrying `color / (nu*nv)`. Emitter (the triangles of one emissive material):
/// `color` is their radiance, `nu` the samples it takes, `nv` its triangles, the emitter
/// triangles `first..first + nv` (`SceneBuffers::emitter_triangles`) hold them.
///
/// An emitter triangle is a `GpuLight` too, so that it travels in the lights' buffer
/// after the lights (the shader's bindings stay as they are): `pos` its first corner, `u`
/// and `v` its edges, `color` the emitter's area up to and including it and its own area
/// (x and y), which the emitter's samples are chosen by.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuLight {
    pub pos: Vec3,
    pub kind: u32,
    pub u: Vec3,
    pub nu: u32,
    pub v: Vec3,
    pub nv: u32,
    pub color: Vec3,
    pub first: u32,
}

/// AOV modes (`--aov`): what a pixel holds instead of shaded colour.
pub const AOV_COLOR: u32 = 0;
/// Shading normal facing the eye, mapped to colour `0.5 * (n + 1)`.
pub const AOV_NORMAL: u32 = 1;
/// Hit distance of the eye ray (0 on a miss).
pub const AOV_DEPTH: u32 = 2;
/// BVH nodes visited by the eye ray's closest-hit traversal.
pub const AOV_COST: u32 = 3;
/// Texture coordinates at the eye ray's hit, interpolated, in red and green (0 where the
/// surface has none).
pub const AOV_UV: u32 = 4;

/// BVH walk: one node fetched and tested per step, the nearer child along the split axis
/// first. What the CPU backend's own frames name (its renderer walks a wide tree of its
/// own, `cpu::wide`, but for the cost AOV).
pub const TRAVERSAL_SINGLE: u32 = 0;
/// BVH walk: both children of a node fetched and tested together, the nearer by entry
/// distance first. The fallback of `TRAVERSAL_WIDE` (see docs/gpu.md).
pub const TRAVERSAL_PAIRS: u32 = 1;
/// BVH walk: the four-wide tree (`GpuWideNode`), a node's four boxes tested together and
/// the children reached entered nearest first. Every GPU's choice; falls back to `TRAVERSAL_PAIRS` for a
/// scene whose wide tree does not fit the traversal stack (`SceneBuffers::gpu_wide_nodes`).
pub const TRAVERSAL_WIDE: u32 = 2;
/// BVH walk: the compressed eight-wide tree (`GpuCwideNode`), a node's eight boxes
/// tested together, the inner children reached taken in the order of the ray's octant
/// and held as one group (base node and bit mask) a level on the stack, the leaves
/// reached tested at once. Falls back like `TRAVERSAL_WIDE` where the tree does not fit
/// (`SceneBuffers::gpu_cwide`).
pub const TRAVERSAL_CWIDE: u32 = 3;
/// BVH walk: `TRAVERSAL_WIDE`'s, step for step, over the same four-wide tree with each
/// node's boxes quantised (`GpuQwideNode`: 64 bytes, four texels, against 112 and seven),
/// decoded as it is fetched. Falls back like `TRAVERSAL_WIDE`, and where a node cannot be
/// quantised (`SceneBuffers::gpu_qwide_nodes`).
pub const TRAVERSAL_QWIDE: u32 = 4;
/// The walks' names, indexed by `TRAVERSAL_*` (`GPURT_TRAVERSAL`, reports).
pub const TRAVERSAL_NAMES: [&str; 5] = ["single", "pairs", "wide", "cwide", "qwide"];

/// Shading model of the specular highlight (`--shading`, `frame::Shading`): Phong,
/// `Ks * max(0, R.L)^Shine` with R the incoming ray mirrored about N (NFF's model, the
/// default).
pub const SHADING_PHONG: u32 = 0;
/// Blinn-Phong, `Ks * max(0, N.H)^Shine` with `H = normalize(L + V)`, V towards the viewer
/// (the IST P3D course tracer's model).
pub const SHADING_BLINN_PHONG: u32 = 1;

/// Per-render constants (a read-only storage buffer).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuGlobals {
    pub cam_pos: Vec3,
    pub hither: f32,
    pub cam_forward: Vec3,
    /// Pixel pitch at unit distance: `2 tan(angle/2) / (H - 1)`.
    pub pixel_pitch: f32,
    pub cam_right: Vec3,
    /// Thin-lens aperture diameter (0 = pinhole).
    pub aperture: f32,
    pub cam_up: Vec3,
    pub focal: f32,
    pub background: Vec3,
    /// Secondary-ray offset along the geometric normal (see `pack::epsilon`).
    pub epsilon: f32,
    pub ambient: Vec3,
    pub max_depth: u32,
    pub width: u32,
    pub height: u32,
    pub spp: u32,
    pub seed: u32,
    pub n_nodes: u32,
    pub n_planes: u32,
    pub n_lights: u32,
    pub aov: u32,
    /// How the BVH is walked: `TRAVERSAL_SINGLE`, `TRAVERSAL_PAIRS` or `TRAVERSAL_WIDE`
    /// (see traverse.wgsl).
    pub traversal: u32,
    /// 1: count each pixel's rays and node fetches by kind of ray (`GpuPixelCounts`, the
    /// `COUNTERS` specialisation), for `--stats` and `gpurt bench`; 0: count nothing.
    pub counters: u32,
    /// 1: trace through the wavefront kernels (`shaders/wavefront.wgsl`) instead of the
    /// one `main` kernel; colour frames only.
    pub wavefront: u32,
    /// The highlight's model: `SHADING_PHONG` or `SHADING_BLINN_PHONG` (see shade.wgsl's
    /// `highlight`).
    pub shading: u32,
    /// Where the textures' headers start in the triangle surfaces' texels (after the
    /// normals' and texture coordinates' records).
    pub textures_at: u32,
    pub _pad: [u32; 3],
}

/// The image region one dispatch traces, which of its samples, and where its pixels go in
/// the output buffer: pixel (x + i, y + j) of the image is `output[out_base + j *
/// out_stride + i]`. One per dispatch, at a dynamic offset into a uniform buffer. A pass
/// whose samples do not start at 0 adds to what the earlier passes left there.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuTile {
    pub x: u32,
    pub y: u32,
    pub width: u32,
    pub height: u32,
    pub out_base: u32,
    pub out_stride: u32,
    pub sample_start: u32,
    pub sample_count: u32,
    /// Which 8x8 block of the tile each workgroup traces: workgroup `i` of the dispatch
    /// (row-major) traces block `i * scatter mod n` of the `n` (row-major), `scatter`
    /// coprime with `n`; 0 or 1 keeps workgroup `i` on block `i`. See `cut::scatter`.
    pub scatter: u32,
    /// Pixels a side of the square one workgroup traces: `WORKGROUP_SIDE` (or 0) for
    /// `main`, a multiple of it for `pooled` (`POOL_SIDE`), whose lanes share out the
    /// square's pixels.
    pub group_side: u32,
}

impl GpuTile {
    /// The workgroups a dispatch of this tile runs, across and down.
    pub fn workgroups(&self) -> [u32; 2] {
        let side = self.group_side.max(WORKGROUP_SIDE);
        [self.width, self.height].map(|n| n.div_ceil(side).max(1))
    }
}

/// Pixels a workgroup of `pixel.wgsl` covers along each axis, and its invocations (8 x 8,
/// in 4 x 2 blocks of neighbouring pixels).
pub const WORKGROUP_SIDE: u32 = 8;
pub const WORKGROUP_INVOCATIONS: u32 = WORKGROUP_SIDE * WORKGROUP_SIDE;

/// Pixels a side of the square a workgroup of the `pooled` entry point traces: 4 pixels a
/// lane, taken one at a time from the square's pool (`GPURT_POOL_SIDE` overrides it).
pub const POOL_SIDE: u32 = 2 * WORKGROUP_SIDE;

/// The largest square a workgroup of `pooled` traces, 64 pixels a lane: it sizes the
/// workgroup's record of which pixels are done.
pub const POOL_MAX_SIDE: u32 = 8 * WORKGROUP_SIDE;

/// Fixed sizes of the per-pixel stacks in both renderers.
/// The BVH builder guarantees a depth below `TRAVERSAL_STACK` (it falls back to a
/// median split otherwise); the CLI refuses a `--depth` above `MAX_DEPTH`, and a Whitted
/// path with depth limit D never holds more than D pending rays (each pop pushes at most
/// two rays one level deeper), so `RAY_STACK = MAX_DEPTH` cannot overflow.
pub const TRAVERSAL_STACK: usize = 64;

/// Texels (16 bytes) a row of the textures that carry `GpuNode`s and `GpuPrim`s to the
/// shader; below WebGPU's guaranteed 8192, and 64 KiB a row, a multiple of the 256-byte
/// row alignment of texture uploads.
pub const TEXTURE_WIDTH: u32 = 4096;

/// The pending-ray stack, as long as the deepest ray (`limits::MAX_DEPTH`, the eye ray
/// counting as 1) needs (see the stack sizes above).
pub const RAY_STACK: usize = MAX_DEPTH as usize;

/// "No hit" distance: the largest f32, since WGSL has no infinity literal.
pub const NO_HIT: f32 = f32::MAX;
/// The largest finite f32, which WGSL has no name for (`unit_or_zero` in intersect.wgsl
/// tells a finite squared length from one that overflowed with it).
pub const F32_MAX: f32 = f32::MAX;
/// Set in `Hit::prim` when the hit is a plane (index into `planes`).
pub const PLANE_FLAG: u32 = 0x8000_0000;
/// `Hit::prim` when nothing was hit.
pub const NO_PRIM: u32 = 0xffff_ffff;

/// Relative widening of the far end in `overlaps` (intersect.wgsl, `cpu::intersect`):
/// 2^-16, far more than the rounding of the slab distances on either renderer (Vulkan lets
/// a GPU divide 2.5 ulp off; depths agree to about 1e-6). Rays grazing a box face, and
/// boxes whose near face lies exactly at a hit, are common with flat axis-aligned faces
/// (the gears); they now count as overlapping on both renderers instead of depending on
/// the last bits of arithmetic.
pub const SLAB_WIDEN: f32 = 1.0 + 1.0 / 65536.0;

/// An emitter's radiance becomes a light's intensity over `PI` (docs/model.md).
pub const PI: f32 = std::f32::consts::PI;

/// The value of a constant shared with WGSL, of the WGSL type it is declared with.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum WgslValue {
    U32(u32),
    F32(f32),
}

/// `(name, value)` of each constant listed by its identifier, which is also its name in
/// WGSL: a name cannot be paired with another constant's value.
macro_rules! wgsl_constants {
    ($($kind:ident $name:ident),* $(,)?) => {
        &[$((stringify!($name), WgslValue::$kind($name as _))),*]
    };
}

/// Every constant shared with WGSL, by its name there (the same as here): the header of
/// the generated shader source declares each (`gpu::shaders::source`), and no WGSL file
/// writes one itself (`tests/gpurt/layout.rs`, which reads each back from naga's module).
pub const WGSL_CONSTANTS: &[(&str, WgslValue)] = wgsl_constants![
    U32 PRIM_SPHERE,
    U32 PRIM_TRIANGLE,
    U32 PRIM_CONE,
    U32 PRIM_BOX,
    U32 PRIM_KIND_SHIFT,
    U32 PRIM_MATERIAL_MASK,
    U32 NODE_AXIS_SHIFT,
    U32 NODE_COUNT_MASK,
    U32 WIDE_LEAF,
    U32 WIDE_EMPTY,
    U32 WIDE_FIRST_SHIFT,
    U32 WIDE_COUNT_MASK,
    U32 CWIDE_INNER,
    U32 CWIDE_COUNT_SHIFT,
    U32 CWIDE_OFFSET_MASK,
    U32 LIGHT_POINT,
    U32 LIGHT_DIRECTIONAL,
    U32 LIGHT_AREA,
    U32 LIGHT_EMITTER,
    U32 NO_TEXTURE,
    U32 WRAP_REPEAT,
    U32 WRAP_CLAMP,
    U32 WRAP_MIRROR,
    U32 AOV_COLOR,
    U32 AOV_NORMAL,
    U32 AOV_DEPTH,
    U32 AOV_COST,
    U32 AOV_UV,
    U32 SHADING_PHONG,
    U32 SHADING_BLINN_PHONG,
    U32 PHASE_SAMPLE,
    U32 PHASE_RAY,
    U32 PHASE_LIGHT,
    U32 PHASE_DONE,
    U32 RESUME_BUDGET,
    U32 RESUME_Y_SHIFT,
    U32 RESUME_X_MASK,
    U32 PIXEL_CUT_SHORT,
    U32 WAVE_ROUND,
    U32 WAVE_RAYS,
    U32 WAVE_NEXT,
    U32 WAVE_SHADOWS,
    U32 WAVE_COUNT_WORDS,
    U32 WAVE_TRACED,
    U32 WAVE_CUT,
    U32 WAVE_SENDS_SHIFT,
    U32 WORKGROUP_SIDE,
    U32 WORKGROUP_INVOCATIONS,
    U32 POOL_MAX_SIDE,
    U32 TRAVERSAL_STACK,
    U32 TEXTURE_WIDTH,
    U32 RAY_STACK,
    F32 NO_HIT,
    F32 F32_MAX,
    U32 PLANE_FLAG,
    U32 NO_PRIM,
    F32 SLAB_WIDEN,
    F32 PI,
];

const _: () = {
    assert!(size_of::<GpuPrim>() == 48);
    assert!(size_of::<GpuTriNormals>() == 48);
    assert!(size_of::<GpuTriUvs>() == size_of::<GpuTriNormals>());
    assert!(size_of::<GpuNode>() == 32);
    assert!(size_of::<GpuCwideNode>() == 80);
    assert!(size_of::<GpuQwideNode>() == 64);
    assert!(size_of::<GpuPlane>() == 32);
    assert!(size_of::<GpuMaterial>() == 64);
    assert!(size_of::<GpuLight>() == 64);
    assert!(size_of::<GpuGlobals>() == 160);
    assert!(size_of::<GpuTexture>() == 16);
    assert!(size_of::<GpuTile>() == 40);
    assert!(std::mem::offset_of!(GpuGlobals, width) == 96);
};
