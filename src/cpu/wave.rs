//! CPU twin of `shaders/wave.wgsl`: a wave's records (the shader's group 2 and 3), and
//! the small steps every wavefront kernel of `wavefront.rs` takes on them.

use glam::Vec3;

use super::types::{Bindings, Hit, RayCounts};
use crate::gpu_types::*;

/// A path of the wave: one pixel sample's colour so far, its rays, counts, and whether any
/// of its work was cut short (the shader's `WavePath`; `GpuWavePath` on the host).
#[derive(Clone, Copy, Default)]
pub(super) struct WavePath {
    pub(super) colour: Vec3,
    pub(super) rays: u32,
    pub(super) counts: RayCounts,
    pub(super) cut: u32,
}

/// A ray of a round (`WaveRay`).
#[derive(Clone, Copy, Default)]
pub(super) struct WaveRay {
    pub(super) origin: Vec3,
    pub(super) weight: f32,
    pub(super) dir: Vec3,
    pub(super) path: u32,
}

/// What `wf_extend` found for the ray of the same index, and the ambient term `wf_shade`
/// found (`WaveHit`; the walk's node fetches are the CPU hit's `nodes`).
#[derive(Clone, Copy, Default)]
pub(super) struct WaveHit {
    pub(super) hit: Hit,
    pub(super) flags: u32,
    pub(super) children: u32,
    pub(super) ambient: Vec3,
}

/// The shadow ray of one light at one hit (`WaveShadow`).
#[derive(Clone, Copy, Default)]
pub(super) struct WaveShadow {
    pub(super) origin: Vec3,
    pub(super) dist: f32,
    pub(super) dir: Vec3,
    pub(super) flags: u32,
    pub(super) light: Vec3,
    pub(super) nodes: u32,
}

/// A tile's wave, as the shader's group 2 and 3 hold it, and the output it adds to.
pub(super) struct Wave<'w, 'a> {
    pub(super) b: &'w Bindings<'a>,
    pub(super) tile: GpuTile,
    pub(super) paths: Vec<WavePath>,
    pub(super) rays: Vec<WaveRay>,
    pub(super) hits: Vec<WaveHit>,
    pub(super) shadows: Vec<WaveShadow>,
    pub(super) queue: Vec<u32>,
    pub(super) scan: Vec<u32>,
    pub(super) counts: [u32; WAVE_COUNT_WORDS as usize],
    pub(super) args: [u32; 6],
    pub(super) out: Vec<(Vec3, u32, RayCounts)>,
}

pub(super) const W: u32 = WORKGROUP_INVOCATIONS;

impl Wave<'_, '_> {
    pub(super) fn wave_capacity(&self) -> u32 {
        self.rays.len() as u32 / 2
    }

    pub(super) fn wave_ray_index(&self, d: u32, k: u32) -> usize {
        ((d % 2) * self.wave_capacity() + k) as usize
    }

    pub(super) fn wave_material(&self, hit: &Hit) -> &GpuMaterial {
        let b = self.b;
        let material = if hit.prim & PLANE_FLAG != 0 {
            b.planes[(hit.prim & !PLANE_FLAG) as usize].material
        } else {
            b.prims[hit.prim as usize].material()
        };
        &b.materials[material as usize]
    }

    pub(super) fn wave_children(&self, d: u32, hit: &Hit) -> u32 {
        if hit.prim == NO_PRIM || d >= self.b.globals.max_depth {
            return 0;
        }
        let m = self.wave_material(hit);
        u32::from(m.ks > 0.0) + u32::from(m.t > 0.0)
    }

    pub(super) fn wave_child_index(&self, k: u32) -> u32 {
        self.scan[(k / W) as usize] + self.hits[k as usize].children
    }

    /// Pixel i of the tile: strips of `WORKGROUP_SIDE` rows, each column by column.
    pub(super) fn wave_xy(&self, i: u32) -> (u32, u32, usize) {
        let t = &self.tile;
        let strip = WORKGROUP_SIDE * t.width;
        let full = t.height / WORKGROUP_SIDE;
        let (rows, s, j) = if i / strip >= full {
            (t.height - full * WORKGROUP_SIDE, full, i - full * strip)
        } else {
            (WORKGROUP_SIDE, i / strip, i % strip)
        };
        let (x, y) = (j / rows, s * WORKGROUP_SIDE + j % rows);
        (
            t.x + x,
            t.y + y,
            (t.out_base + y * t.out_stride + x) as usize,
        )
    }

    /// The dispatch size for `n` invocations, at word `at` of the args; the twin's host
    /// loop runs that many workgroups, as the GPU does.
    pub(super) fn wave_dispatch(&mut self, at: usize, n: u32) {
        self.args[at] = n.div_ceil(W);
        self.args[at + 1] = 1;
        self.args[at + 2] = 1;
    }
}
