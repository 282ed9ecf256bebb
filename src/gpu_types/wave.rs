//! The records of the wavefront path (`shaders/wave.wgsl`): a path per pixel sample
//! (`GpuWavePath`), the rays of a round (`GpuWaveRay`), their hits (`GpuWaveHit`) and
//! their shadow rays (`GpuWaveShadow`), and the words of the wave's counts. The host only
//! sizes and allocates them; the CPU twin (`cpu::wavefront`) keeps the same records. Part
//! of `gpu_types`, which re-exports all of it.

use bytemuck::{Pod, Zeroable};
use glam::Vec3;

use super::GpuPixelCounts;

/// One pixel sample of a wave: its colour so far, its rays, its counts (`COUNTERS`), and
/// whether any of its work was cut short.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuWavePath {
    pub colour: Vec3,
    pub rays: u32,
    pub counts: GpuPixelCounts,
    pub cut: u32,
    pub _pad0: u32,
    pub _pad1: u32,
    pub _pad2: u32,
}

/// A ray of a round: what its light is worth to its path (`weight`), and the path. Its
/// depth is the round's.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuWaveRay {
    pub origin: Vec3,
    pub weight: f32,
    pub dir: Vec3,
    pub path: u32,
}

/// The closest hit of the ray of the same index (a WGSL `Hit`, 5 words), the nodes its
/// walk fetched, `flags` (`WAVE_CUT`, and from bit `WAVE_SENDS_SHIFT` the rays of the
/// next round it sends), where the first of those goes within its workgroup's, and the
/// hit's ambient term, from the shade kernel.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuWaveHit {
    pub hit: [u32; 5],
    pub nodes: u32,
    pub flags: u32,
    pub children: u32,
    pub ambient: Vec3,
    pub _pad: u32,
}

/// The shadow ray of one light at one hit, and the light's term, which the shadow kernel
/// replaces with what the light gives through the scene; `flags`: `WAVE_TRACED`,
/// `WAVE_CUT`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuWaveShadow {
    pub origin: Vec3,
    pub dist: f32,
    pub dir: Vec3,
    pub flags: u32,
    pub light: Vec3,
    pub nodes: u32,
}

/// Words of a wave's counts: the round under way (1 for the eye rays), its rays, the rays
/// written for the next round, and the shadow rays queued in this one.
pub const WAVE_ROUND: u32 = 0;
pub const WAVE_RAYS: u32 = 1;
pub const WAVE_NEXT: u32 = 2;
pub const WAVE_SHADOWS: u32 = 3;
pub const WAVE_COUNT_WORDS: u32 = 4;

/// `GpuWaveShadow::flags`: the light is above the surface and its shadow ray was traced.
pub const WAVE_TRACED: u32 = 1;
/// `GpuWaveHit::flags` and `GpuWaveShadow::flags`: the walk was cut short.
pub const WAVE_CUT: u32 = 2;
/// The bit of `GpuWaveHit::flags` from which it counts the rays of the next round the
/// hit sends (0 to 2).
pub const WAVE_SENDS_SHIFT: u32 = 2;

/// Rays a round of a wave holds per path: as many as the eye rays, the rays of the deepest
/// round for a quarter of the paths on mirror-and-glass scenes that send two rays a hit.
/// A path whose rays do not fit is cut short and traced again by `resume`.
pub const WAVE_RAYS_PER_PATH: u64 = 4;

/// Bytes of each of a wave's buffers for `paths` paths and `lights` lights, in binding
/// order: paths, rays (two halves), hits, shadow slots, the shadow queue, the workgroups'
/// first rays.
pub const fn wave_buffer_bytes(paths: u64, lights: u64) -> [u64; 6] {
    let rays = paths * WAVE_RAYS_PER_PATH;
    let slots = rays * if lights > 0 { lights } else { 1 };
    [
        paths * size_of::<GpuWavePath>() as u64,
        2 * rays * size_of::<GpuWaveRay>() as u64,
        rays * size_of::<GpuWaveHit>() as u64,
        slots * size_of::<GpuWaveShadow>() as u64,
        slots * 4,
        4 * rays.div_ceil(super::WORKGROUP_INVOCATIONS as u64),
    ]
}

const _: () = {
    assert!(size_of::<GpuWavePath>() == 64);
    assert!(size_of::<GpuWaveRay>() == 32);
    assert!(size_of::<GpuWaveHit>() == 48);
    assert!(size_of::<GpuWaveShadow>() == 48);
};
