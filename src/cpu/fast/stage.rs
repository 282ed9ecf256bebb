//! A stage of `coherent`'s tiles: one kind of a block's rays (camera, mirror or refracted)
//! traced as a packet, the surfaces they met, and what each point or directional light
//! gives those surfaces from its shadow packet, kept for the pixels' shading to take.

use glam::Vec3;

use super::lights::{Surfaces, light_rays};
use super::packet::{Kernels, MAX_LANES, Packet};
use crate::cpu::intersect::lanes_of;
use crate::cpu::shade::{Surface, offset_origin, reflect_dir, refracted_dir, surface, unlit};
use crate::cpu::texture::textured;
use crate::cpu::types::{Bindings, Hit, Ray, RayCounts};
use crate::gpu_types::*;

/// What a point or directional light gives a surface met by a packet's ray, worked out
/// from its shadow packet: `light_sample`'s answer, with the node fetches of its shadow
/// ray and whether the packet traced it (rather than a walk of its own).
#[derive(Clone, Copy)]
pub(super) struct Lit {
    sample: Option<Vec3>,
    nodes: u32,
    packed: bool,
}

impl Lit {
    /// Its sample, with its shadow ray's node fetches, and whether a packet traced it,
    /// added to `counts` as `light_sample` counts a shadow ray (which `direct` then
    /// counts as a ray).
    #[inline(always)]
    pub(super) fn counted(&self, counts: &mut RayCounts) -> Option<Vec3> {
        if self.sample.is_some() {
            counts.shadow_nodes += u64::from(self.nodes);
            counts.shadow_packed += u64::from(self.packed);
        }
        self.sample
    }
}

const UNLIT: Lit = Lit {
    sample: None,
    nodes: 0,
    packed: false,
};

/// What a lane without a surface holds in a stage's array of surfaces.
const NO_SURFACE: Surface = Surface {
    point: Vec3::ZERO,
    ng: Vec3::ZERO,
    ns: Vec3::ZERO,
    entering: false,
    material: 0,
};

const NO_RAY: Ray = Ray {
    origin: Vec3::ZERO,
    dir: Vec3::X,
};

/// What a lane holds in a stage's array of hits before a packet answers it.
const NO_HIT_YET: Hit = Hit {
    t: 0.0,
    prim: NO_PRIM,
    u: 0.0,
    v: 0.0,
    cost: 0,
    nodes: 0,
};

/// One kind of a block's rays (its camera rays, their mirror rays, their refracted rays
/// or those rays' refracted rays) traced as a packet and shaded ahead of the pixels' own
/// shading: each lane's ray and hit, the surface it met, and what each point or
/// directional light gives that surface, its shadow rays traced as one packet a light.
/// Kept from block to block and written in place: arrays built afresh for each block were
/// copied through temporaries a field at a time, and the wide loads after the narrow
/// stores stalled (a tenth of teapot-6's render, by `perf`).
pub(super) struct Stage {
    /// Which rays: the camera rays (`None`), or rays the shading sends on.
    pub(super) kind: Option<Secondary>,
    pub(super) rays: [Ray; MAX_LANES],
    tmin: f32,
    /// The lanes holding a ray.
    pub(super) traced: u32,
    pub(super) hits: [Hit; MAX_LANES],
    /// The lanes the packet answered (rather than walks of their own).
    pub(super) packed: u32,
    /// The surfaces of the lanes in `met` (those whose ray met one).
    pub(super) surfaces: [Surface; MAX_LANES],
    pub(super) met: u32,
    /// `lights.len() / MAX_LANES` a lane: one a point or directional light, in the
    /// lights' order.
    pub(super) lights: Vec<Lit>,
    /// The primitive that blocked a lane of the last shadow packet to each of the
    /// `shadowed` lights, tested first by the next (`Kernels::transmissions`' hint).
    blockers: Vec<Option<u32>>,
}

impl Stage {
    pub(super) fn new(shadowed: usize, kind: Option<Secondary>) -> Self {
        Stage {
            kind,
            rays: [NO_RAY; MAX_LANES],
            tmin: 0.0,
            traced: 0,
            hits: [NO_HIT_YET; MAX_LANES],
            packed: 0,
            surfaces: [NO_SURFACE; MAX_LANES],
            met: 0,
            lights: vec![UNLIT; MAX_LANES * shadowed],
            blockers: vec![None; shadowed],
        }
    }

    /// Traces the rays of `packet` (each from `tmin`), and keeps them with their hits.
    pub(super) fn trace(&mut self, b: &Bindings, kernels: &Kernels, packet: &Packet, tmin: f32) {
        self.traced = packet.lanes();
        self.tmin = tmin;
        self.met = 0;
        for k in lanes_of(self.traced) {
            // Field by field: a copy whole read the ray back in loads that straddled the
            // packet's stores.
            let ray = packet.ray(k);
            (self.rays[k].origin, self.rays[k].dir) = (ray.origin, ray.dir);
        }
        self.packed = if self.traced == 0 {
            0
        } else {
            kernels.closest_hits(b, packet, &mut self.hits)
        };
    }

    /// Finds the surfaces the rays met and lights them with each of the `shadowed` lights
    /// (`packet` is the scratch for the shadow rays).
    pub(super) fn light(
        &mut self,
        b: &Bindings,
        kernels: &Kernels,
        shadowed: &[usize],
        packet: &mut Packet,
    ) {
        match kernels.lanes() {
            4 => self.light_lanes::<4>(b, kernels, shadowed, packet),
            8 => self.light_lanes::<8>(b, kernels, shadowed, packet),
            _ => self.light_lanes::<MAX_LANES>(b, kernels, shadowed, packet),
        }
    }

    /// `light` for packets of `N` lanes: the lights' arithmetic worked out for those lanes
    /// only (`Surfaces`).
    fn light_lanes<const N: usize>(
        &mut self,
        b: &Bindings,
        kernels: &Kernels,
        shadowed: &[usize],
        packet: &mut Packet,
    ) {
        self.met = 0;
        for k in lanes_of(self.traced).filter(|&k| self.hits[k].prim != NO_PRIM) {
            self.surfaces[k] = surface(b, &self.rays[k], &self.hits[k]);
            self.met |= 1 << k;
        }
        if self.met == 0 {
            return;
        }
        let dirs = self.rays.map(|ray| ray.dir);
        let lit = Surfaces::new::<N>(b, (&self.surfaces, self.met), &self.hits, &dirs);
        let mut light = [Vec3::ZERO; MAX_LANES];
        let mut nodes = [0; MAX_LANES];
        for (j, &li) in shadowed.iter().enumerate() {
            let rays = light_rays::<N>(b, &lit, &b.lights[li], packet);
            let packed = if packet.lanes() == 0 {
                0
            } else {
                kernels.transmissions(b, packet, &mut light, &mut nodes, &mut self.blockers[j])
            };
            for k in lanes_of(self.met) {
                self.lights[k * shadowed.len() + j] = if rays.live & 1 << k != 0 {
                    // `light_sample`'s product, in its order.
                    Lit {
                        sample: Some(light[k] * rays.intensity * rays.term(k)),
                        nodes: nodes[k],
                        packed: packed & 1 << k != 0,
                    }
                } else {
                    UNLIT
                };
            }
        }
    }

    /// `direct` at lane `k`'s surface (of material `m`, `textured`), summed from the
    /// stage's light samples in the lights' order and counted as `light_sample` and
    /// `direct` count them: every light is packed.
    #[inline(always)]
    pub(super) fn direct(
        &self,
        b: &Bindings,
        k: usize,
        m: &GpuMaterial,
        counts: &mut RayCounts,
    ) -> Vec3 {
        let shadowed = self.lights.len() / MAX_LANES;
        let mut colour = unlit(b.globals, &self.surfaces[k], m);
        for lit in &self.lights[k * shadowed..(k + 1) * shadowed] {
            if let Some(c) = lit.counted(counts) {
                counts.shadow += 1;
                colour += c;
            }
        }
        colour
    }

    /// Lane `k`'s surface material (`textured`).
    #[inline(always)]
    pub(super) fn material(&self, b: &Bindings, k: usize) -> GpuMaterial {
        let m = &b.materials[self.surfaces[k].material as usize];
        textured(b, m, &self.hits[k])
    }

    /// Sets `packet` to the `kind` rays that the shading sends on from the surfaces the
    /// stage's rays met, as `trace` makes them (`shade::secondary`), in the lanes of those
    /// rays. A ray made otherwise would be walked alone, not answered wrongly: the
    /// shading's rays are matched to the packets' bit for bit (`holds`).
    pub(super) fn secondary(&self, b: &Bindings, kind: Secondary, packet: &mut Packet) {
        packet.clear();
        for k in lanes_of(self.met) {
            let s = &self.surfaces[k];
            let m = &b.materials[s.material as usize];
            let dir = match kind {
                Secondary::Mirror if m.ks > 0.0 => reflect_dir(self.rays[k].dir, s.ns),
                // `trace`'s material, textured: the same index of refraction to the bit.
                Secondary::Refracted if m.t > 0.0 => {
                    refracted_dir(s, &self.material(b, k), self.rays[k].dir)
                }
                _ => continue,
            };
            let ray = Ray {
                origin: offset_origin(s, dir, b.globals.epsilon),
                dir,
            };
            packet.set(k, &ray, 0.0, NO_HIT);
        }
    }

    /// Whether `(ray, tmin, tmax)` is lane `k`'s ray, bit for bit (its answer, then, is
    /// lane `k`'s hit).
    pub(super) fn holds(&self, k: usize, ray: &Ray, tmin: f32, tmax: f32) -> bool {
        let same =
            |a: Vec3, b: Vec3| a.to_array().map(f32::to_bits) == b.to_array().map(f32::to_bits);
        same(self.rays[k].origin, ray.origin)
            && same(self.rays[k].dir, ray.dir)
            && self.tmin.to_bits() == tmin.to_bits()
            && NO_HIT.to_bits() == tmax.to_bits()
    }
}

/// The rays a stage after the camera rays' holds.
#[derive(Clone, Copy)]
pub(super) enum Secondary {
    Mirror,
    Refracted,
}
