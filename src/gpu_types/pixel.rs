//! What a pixel keeps on the device between dispatches: the state of a pixel continued
//! by `resume` (`GpuPixelState`) and what its rays cost (`GpuPixelCounts`), with the
//! constants that go with them. Part of `gpu_types`, which re-exports all of it.

use bytemuck::{Pod, Zeroable};
use glam::Vec3;

use super::RAY_STACK;

/// A pixel whose work continues across dispatches (`resume` in `shaders/pixel.wgsl`). The
/// host reads `sum` (of the samples traced, once `phase` is `PHASE_DONE`), `rays` and `cut`;
/// the rest is the shader's own bookkeeping, kept as words here (`ray_in` and `stack` hold
/// WGSL `Pending` structs of 12 words).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct GpuPixelState {
    pub sum: Vec3,
    pub sample: u32,
    pub colour: Vec3,
    pub rng: u32,
    pub lit: Vec3,
    pub rays: u32,
    pub point: Vec3,
    pub sp: u32,
    pub ng: Vec3,
    pub light: u32,
    pub ns: Vec3,
    pub light_sample: u32,
    /// The colour of the surface being lit, its texture's applied (`textured`).
    pub albedo: Vec3,
    pub _pad: u32,
    pub ray_in: [u32; 12],
    pub material: u32,
    pub entering: u32,
    pub phase: u32,
    pub cut: u32,
    /// The pixel's counts so far (`COUNTERS`).
    pub counts: GpuPixelCounts,
    pub stack: [[u32; 12]; RAY_STACK],
}

/// What one pixel's rays cost, by kind of ray, when counting (`GpuGlobals::counters`):
/// the rays traced and the BVH nodes their walks fetched (a fetch of a binary node, a
/// four-wide node or a compressed eight-wide node, whatever the walk reads; the bytes
/// are the fetches times the size of the walk's node, `node_bytes`). Summed over a
/// band's passes like `PixelOut`, and read back beside it.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Pod, Zeroable)]
pub struct GpuPixelCounts {
    pub eye_rays: u32,
    pub eye_nodes: u32,
    pub shadow_rays: u32,
    pub shadow_nodes: u32,
    /// Reflected and refracted rays.
    pub secondary_rays: u32,
    pub secondary_nodes: u32,
    pub _pad: [u32; 2],
}

/// `GpuPixelState::phase` of a pixel about to start its next sample.
pub const PHASE_SAMPLE: u32 = 0;
/// `GpuPixelState::phase` of a pixel tracing the pending rays of its sample.
pub const PHASE_RAY: u32 = 1;
/// `GpuPixelState::phase` of a pixel sampling the lights of a hit.
pub const PHASE_LIGHT: u32 = 2;
/// `GpuPixelState::phase` of a finished pixel.
pub const PHASE_DONE: u32 = 3;

/// Loop iterations after which `resume` (pixel.wgsl) suspends a pixel until the next
/// dispatch. Lavapipe ends every loop once an invocation has run 65535 loop iterations,
/// and counts the iterations of all eight invocations of a SIMD batch together, so eight
/// budgets plus one traversal must stay under 65535.
pub const RESUME_BUDGET: u32 = 2048;

/// A pixel to resume, as `resume_pixels` (pixel.wgsl) holds it: `x | y << RESUME_Y_SHIFT`.
pub const RESUME_Y_SHIFT: u32 = 16;
pub const RESUME_X_MASK: u32 = (1 << RESUME_Y_SHIFT) - 1;

/// Bit of `PixelOut::rays` set when a pixel's work was cut short: the driver ended one of
/// the shader's loops before it finished (lavapipe ends every loop once one invocation
/// has run 65535 loop iterations). The other bits count the rays traced.
pub const PIXEL_CUT_SHORT: u32 = 1 << 31;

const _: () = {
    assert!(size_of::<GpuPixelState>() == 208 + 48 * RAY_STACK);
    assert!(size_of::<GpuPixelCounts>() == 32);
};
