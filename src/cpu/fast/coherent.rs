//! The CPU renderer's tiles traced with packets where rays are coherent: for each sample,
//! the camera rays of a block of pixels (4x4, 4x2 or 2x2, as many as the kernels' lanes)
//! go as one packet, then their shadow rays to each point or directional light as an
//! occlusion packet, then their reflections off flat mirrors (planes and triangles
//! without vertex normals) as another; every other ray (refraction, curved mirrors, area
//! light samples, deeper bounces) is walked alone when the shading asks for it.
//!
//! Each pixel is then shaded by `shade::trace`, the code every pixel runs, with a `Tracer`
//! (`Known`) that answers the rays traced beforehand from the packets' answers, which are
//! the single-ray walk's to the bit (`packet`), and walks the others alone: the image is the
//! per-pixel renderer's to the bit, and so are the rays counted. A camera or mirror ray is
//! answered from a packet only when it is that very ray (origin, direction and interval,
//! bit for bit); the camera ray's surface and light samples, which the shadow packets
//! needed, are handed over as `shade::surface` and `shade::light_sample` made them there
//! (the shading asks for them first, in the lights' order), not made a second time.

use std::ops::Range;

use glam::Vec3;

use super::lights::{Surfaces, light_rays, packed};
use super::packet::{Kernels, MAX_LANES, Packet};
use super::tracer::Alone;
use crate::cpu::intersect::lanes_of;
use crate::cpu::pixel::{aov, sample_ray};
use crate::cpu::shade::{
    Shaded, Surface, Tracer, count_nodes, light_sample, offset_origin, reflect_dir, surface, trace,
};
use crate::cpu::types::{Bindings, Hit, Ray, RayCounts};
use crate::gpu_types::*;

/// A ray traced in a packet, and its answer.
#[derive(Clone, Copy)]
struct Answer<T> {
    ray: Ray,
    tmin: f32,
    tmax: f32,
    value: T,
    /// Whether the packet answered it (rather than a walk of its own).
    packed: bool,
}

impl<T: Copy> Answer<T> {
    fn of(&self, ray: &Ray, tmin: f32, tmax: f32) -> Option<(T, bool)> {
        let same =
            |a: Vec3, b: Vec3| a.to_array().map(f32::to_bits) == b.to_array().map(f32::to_bits);
        (same(self.ray.origin, ray.origin)
            && same(self.ray.dir, ray.dir)
            && self.tmin.to_bits() == tmin.to_bits()
            && self.tmax.to_bits() == tmax.to_bits())
        .then_some((self.value, self.packed))
    }
}

/// What a point or directional light gives a camera ray's surface, worked out from its
/// shadow packet: `light_sample`'s answer, with the node fetches of its shadow ray and
/// whether the packet traced it (rather than a walk of its own).
#[derive(Clone, Copy)]
struct Lit {
    sample: Option<Vec3>,
    nodes: u32,
    packed: bool,
}

/// One pixel's rays traced beforehand: its camera ray and its mirror ray, and the camera
/// ray's surface and what each point or directional light gives it. Any other ray is
/// walked alone.
struct Known<'a> {
    eye: Option<Answer<Hit>>,
    mirror: Option<Answer<Hit>>,
    /// The camera ray's surface, for the first surface asked for (the camera ray's hit:
    /// the shading asks for that ray first).
    eye_surface: Option<&'a Surface>,
    /// Its light samples, one a point or directional light in the lights' order, handed
    /// out while the shading lights that surface (until it asks for the next surface).
    eye_lights: &'a [Lit],
    /// Rays answered from packets, by kind.
    counts: RayCounts,
}

impl Tracer for Known<'_> {
    fn closest_hit(&mut self, b: &Bindings, ray: &Ray, tmin: f32, tmax: f32) -> Hit {
        if let Some((hit, packed)) = self.eye.as_ref().and_then(|a| a.of(ray, tmin, tmax)) {
            self.eye = None;
            self.counts.eye_packed += u64::from(packed);
            return hit;
        }
        if let Some((hit, packed)) = self.mirror.as_ref().and_then(|a| a.of(ray, tmin, tmax)) {
            self.mirror = None;
            self.counts.reflected_packed += u64::from(packed);
            return hit;
        }
        Alone.closest_hit(b, ray, tmin, tmax)
    }

    fn transmission(&mut self, b: &Bindings, ray: &Ray, tmax: f32, nodes: &mut u32) -> Vec3 {
        Alone.transmission(b, ray, tmax, nodes)
    }

    fn surface(&mut self, b: &Bindings, ray: &Ray, hit: &Hit) -> Surface {
        match self.eye_surface.take() {
            Some(s) => *s,
            None => {
                self.eye_lights = &[];
                surface(b, ray, hit)
            }
        }
    }

    fn light_sample(
        &mut self,
        b: &Bindings,
        at: &Shaded,
        (light, k): (&GpuLight, u32),
        rng: &mut u32,
        counts: &mut RayCounts,
    ) -> Option<Vec3> {
        if packed(light)
            && let Some((lit, rest)) = self.eye_lights.split_first()
        {
            // `light_sample` on the same surface, its shadow ray answered by the packet
            // (the images are the per-pixel renderer's to the bit: tests/gpurt/packet.rs).
            self.eye_lights = rest;
            if lit.sample.is_some() {
                counts.shadow_nodes += u64::from(lit.nodes);
                self.counts.shadow_packed += u64::from(lit.packed);
            }
            return lit.sample;
        }
        light_sample(b, self, at, (light, k), rng, counts)
    }
}

/// What a lane without a surface holds in the packet loop's array of surfaces.
const NO_SURFACE: Surface = Surface {
    point: Vec3::ZERO,
    ng: Vec3::ZERO,
    ns: Vec3::ZERO,
    entering: false,
    material: 0,
};

/// Pixels of a packet, `(columns, rows)`, for `lanes` lanes.
fn block(lanes: usize) -> (u32, u32) {
    match lanes {
        16 => (4, 4),
        8 => (4, 2),
        _ => (2, 2),
    }
}

/// Whether reflections off the surface `hit` stay as coherent as the rays that met it:
/// a plane, or a triangle whose shading normal is its face's.
fn flat(b: &Bindings, hit: &Hit) -> bool {
    hit.prim & PLANE_FLAG != 0 || {
        let p = &b.prims[hit.prim as usize];
        p.kind() == PRIM_TRIANGLE && p.f1 < 0.0
    }
}

/// Samples `samples` of the pixels `x0..x1` by `rows` added to `sums` (row by row, `x1 -
/// x0` a row), as `main::sample_sum` adds them one pixel at a time, and the rays counted.
pub fn render_tile(
    b: &Bindings,
    kernels: &Kernels,
    (x0, x1): (u32, u32),
    rows: Range<u32>,
    samples: Range<u32>,
    sums: &mut [Vec3],
    counts: &mut RayCounts,
) {
    let g = b.globals;
    let (bw, bh) = block(kernels.lanes());
    let shadowed: Vec<usize> = (0..b.lights.len())
        .filter(|&i| packed(&b.lights[i]))
        .collect();
    let unlit = Lit {
        sample: None,
        nodes: 0,
        packed: false,
    };
    let mut eye_lights = vec![unlit; MAX_LANES * shadowed.len()];
    let mut packet = Packet::default();
    let mut hits = [Hit {
        t: 0.0,
        prim: NO_PRIM,
        u: 0.0,
        v: 0.0,
        cost: 0,
        nodes: 0,
    }; MAX_LANES];
    let mut light = [Vec3::ZERO; MAX_LANES];
    let mut shadow_nodes = [0; MAX_LANES];
    // The camera rays' surfaces, lane by lane, those of the lanes in a block's `met` mask
    // (the others: no surface, or no pixel). Kept from block to block and written in
    // place: an array of `Option`s built afresh for each block (`array::from_fn`) copied
    // every lane through temporaries a field at a time, and the wide loads after the
    // narrow stores stalled (a tenth of teapot-6's render, by `perf`).
    let mut surfaces = [NO_SURFACE; MAX_LANES];
    for s in samples {
        for by in rows.clone().step_by(bh as usize) {
            for bx in (x0..x1).step_by(bw as usize) {
                // The block's pixels: (sums index, camera ray, random stream), lane by lane.
                let mut lanes = [(
                    0usize,
                    Ray {
                        origin: Vec3::ZERO,
                        dir: Vec3::X,
                    },
                    0u32,
                ); MAX_LANES];
                let mut n = 0;
                packet.clear();
                for y in by..(by + bh).min(rows.end) {
                    for x in bx..(bx + bw).min(x1) {
                        let mut rng = 0;
                        let ray = sample_ray(g, x, y, s, &mut rng);
                        let i = ((y - rows.start) * (x1 - x0) + x - x0) as usize;
                        // Field by field: the ray comes back through memory, and a copy
                        // whole read it back in loads that straddled the call's stores.
                        let lane = &mut lanes[n];
                        (lane.0, lane.2) = (i, rng);
                        (lane.1.origin, lane.1.dir) = (ray.origin, ray.dir);
                        packet.set(n, &ray, g.hither, NO_HIT);
                        n += 1;
                    }
                }
                counts.eye += n as u64;
                let eye_packed = kernels.closest_hits(b, &packet, &mut hits);
                let answer = |k: usize, ray: Ray, tmin: f32, value: Hit, packed: u32| Answer {
                    ray,
                    tmin,
                    tmax: NO_HIT,
                    value,
                    packed: packed & 1 << k != 0,
                };
                if g.aov != AOV_COLOR {
                    for (k, &(i, ray, _)) in lanes[..n].iter().enumerate() {
                        let mut known = Known {
                            eye: Some(answer(k, ray, g.hither, hits[k], eye_packed)),
                            mirror: None,
                            eye_surface: None,
                            eye_lights: &[],
                            counts: RayCounts::default(),
                        };
                        sums[i] += aov(b, &mut known, &ray, counts);
                        counts.add(&known.counts);
                    }
                    continue;
                }
                let mut met = 0u32;
                for k in (0..n).filter(|&k| hits[k].prim != NO_PRIM) {
                    surfaces[k] = surface(b, &lanes[k].1, &hits[k]);
                    met |= 1 << k;
                }
                // Shadow rays to each point and directional light, one packet a light, and
                // what the light gives each surface, as `light_sample` works it out.
                let dirs = lanes.map(|(_, ray, _)| ray.dir);
                let lit = Surfaces::new(b, (&surfaces, met), &hits, &dirs);
                for (j, &li) in shadowed.iter().enumerate() {
                    packet.clear();
                    let rays = light_rays(b, &lit, &b.lights[li], &mut packet);
                    let packed = if packet.lanes() == 0 {
                        0
                    } else {
                        kernels.transmissions(b, &packet, &mut light, &mut shadow_nodes)
                    };
                    for k in lanes_of(met) {
                        eye_lights[k * shadowed.len() + j] = if rays.live & 1 << k != 0 {
                            // `light_sample`'s product, in its order.
                            Lit {
                                sample: Some(light[k] * rays.intensity * rays.term(k)),
                                nodes: shadow_nodes[k],
                                packed: packed & 1 << k != 0,
                            }
                        } else {
                            unlit
                        };
                    }
                }
                // Reflections off flat mirrors, where the depth lets the shading trace them.
                packet.clear();
                if g.max_depth > 1 {
                    for k in lanes_of(met) {
                        let s = &surfaces[k];
                        if b.materials[s.material as usize].ks > 0.0 && flat(b, &hits[k]) {
                            let dir = reflect_dir(lanes[k].1.dir, s.ns);
                            let ray = Ray {
                                origin: offset_origin(s, dir, g.epsilon),
                                dir,
                            };
                            packet.set(k, &ray, 0.0, NO_HIT);
                        }
                    }
                }
                let mut mirror_hits = hits;
                let mirror_packed = if packet.lanes() != 0 {
                    kernels.closest_hits(b, &packet, &mut mirror_hits)
                } else {
                    0
                };
                for (k, (i, ray, rng)) in lanes[..n].iter().enumerate() {
                    let (i, mut rng) = (*i, *rng);
                    if met & 1 << k == 0 {
                        // A camera ray that met nothing (most of a scene with sky around
                        // it): what `trace` gives it and counts for it, `0 + 1 *
                        // background`, without setting up its stack and answers.
                        sums[i] += g.background;
                        count_nodes(counts, 1, hits[k].nodes);
                        counts.eye_packed += u64::from(eye_packed & 1 << k != 0);
                        continue;
                    }
                    let mut known = Known {
                        eye: Some(answer(k, *ray, g.hither, hits[k], eye_packed)),
                        mirror: (packet.lanes() & 1 << k != 0)
                            .then(|| answer(k, packet.ray(k), 0.0, mirror_hits[k], mirror_packed)),
                        eye_surface: Some(&surfaces[k]),
                        eye_lights: &eye_lights[k * shadowed.len()..(k + 1) * shadowed.len()],
                        counts: RayCounts::default(),
                    };
                    sums[i] += trace(b, &mut known, ray, &mut rng, counts);
                    counts.add(&known.counts);
                }
            }
        }
    }
}
