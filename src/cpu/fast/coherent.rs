//! The CPU renderer's tiles traced with packets where rays are coherent: for each sample,
//! the camera rays of a block of pixels (4x4, 4x2 or 2x2, as many as the kernels' lanes)
//! go as one packet, then their shadow rays to each point or directional light as an
//! occlusion packet, then the mirror rays off the surfaces they met as another, and the
//! refracted rays as a third, and those rays' shadow rays to each light as more (a
//! `Stage` each: the camera rays, their mirror rays, their refracted rays and those rays'
//! refracted rays); every other ray (area light samples, deeper bounces) is walked alone
//! when the shading asks for it.
//! Mirror rays off curved surfaces diverge, but a block's still share most of their path
//! through the tree: traced in packets, teapot-6's 1080p render took 15% less time and
//! balls-4's 3% less (one run each way, alternating), and lanes that part from the rest go
//! on alone (`packet::single`). So do the rays through glass: gears-4's 1080p render took
//! 9% less time with the rays that enter it and their shadow rays in packets, and 7% less
//! again with the rays that leave it (docs/bvh.md).
//!
//! Each pixel is then shaded by `shade::trace`, the code every pixel runs, with a `Tracer`
//! (`Known`) that answers the rays traced beforehand from the packets' answers, which are
//! the single-ray walk's to the bit (`packet`), and walks the others alone: the image is the
//! per-pixel renderer's to the bit, and so are the rays counted. A ray is answered from a
//! packet only when it is that very ray (origin, direction and interval, bit for bit);
//! its surface and light samples, which the shadow packets needed, are handed over as
//! `shade::surface` and `shade::light_sample` made them there (the shading asks for the
//! surface of the ray it traced last, then for the light samples in the lights' order),
//! not made a second time. A camera ray that met nothing, or whose every ray was traced
//! ahead (`traced_ahead`), is summed from the stages as `trace` would sum it, without
//! `trace`.

use std::ops::Range;

use glam::Vec3;

use super::lights::{Surfaces, light_rays, packed};
use super::packet::{Kernels, MAX_LANES, Packet};
use super::tracer::Alone;
use super::wide_ray;
use crate::cpu::intersect::lanes_of;
use crate::cpu::pixel::{aov, sample_ray};
use crate::cpu::shade::{
    Shaded, Surface, Tracer, count_nodes, light_sample, offset_origin, reflect_dir, refracted_dir,
    surface, trace, unlit,
};
use crate::cpu::texture::textured;
use crate::cpu::types::{Bindings, Hit, Ray, RayCounts};
use crate::gpu_types::*;

/// What a point or directional light gives a surface met by a packet's ray, worked out
/// from its shadow packet: `light_sample`'s answer, with the node fetches of its shadow
/// ray and whether the packet traced it (rather than a walk of its own).
#[derive(Clone, Copy)]
struct Lit {
    sample: Option<Vec3>,
    nodes: u32,
    packed: bool,
}

impl Lit {
    /// Its sample, with its shadow ray's node fetches, and whether a packet traced it,
    /// added to `counts` as `light_sample` counts a shadow ray (which `direct` then
    /// counts as a ray).
    #[inline(always)]
    fn counted(&self, counts: &mut RayCounts) -> Option<Vec3> {
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
/// or those rays' refracted rays) traced as a packet and shaded ahead of the pixels' own shading: each lane's ray
/// and hit, the surface it met, and what each point or directional light gives that
/// surface, its shadow rays traced as one packet a light. Kept from block to block and
/// written in place: arrays built afresh for each block were copied through temporaries a
/// field at a time, and the wide loads after the narrow stores stalled (a tenth of
/// teapot-6's render, by `perf`).
struct Stage {
    rays: [Ray; MAX_LANES],
    tmin: f32,
    /// The lanes holding a ray.
    traced: u32,
    hits: [Hit; MAX_LANES],
    /// The lanes the packet answered (rather than walks of their own).
    packed: u32,
    /// The surfaces of the lanes in `met` (those whose ray met one).
    surfaces: [Surface; MAX_LANES],
    met: u32,
    /// `lights.len() / MAX_LANES` a lane: one a point or directional light, in the
    /// lights' order.
    lights: Vec<Lit>,
    /// The primitive that blocked a lane of the last shadow packet to each of the
    /// `shadowed` lights, tested first by the next (`Kernels::transmissions`' hint).
    blockers: Vec<Option<u32>>,
}

impl Stage {
    fn new(shadowed: usize) -> Self {
        Stage {
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
    fn trace(&mut self, b: &Bindings, kernels: &Kernels, packet: &Packet, tmin: f32) {
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
    fn light(&mut self, b: &Bindings, kernels: &Kernels, shadowed: &[usize], packet: &mut Packet) {
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
    fn direct(&self, b: &Bindings, k: usize, m: &GpuMaterial, counts: &mut RayCounts) -> Vec3 {
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
    fn material(&self, b: &Bindings, k: usize) -> GpuMaterial {
        let m = &b.materials[self.surfaces[k].material as usize];
        textured(b, m, &self.hits[k])
    }

    /// Sets `packet` to the `kind` rays that the shading sends on from the surfaces the
    /// stage's rays met, as `trace` makes them (`shade::secondary`), in the lanes of those
    /// rays. A ray made otherwise would be walked alone, not answered wrongly: the
    /// shading's rays are matched to the packets' bit for bit (`holds`).
    fn secondary(&self, b: &Bindings, kind: Secondary, packet: &mut Packet) {
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
    fn holds(&self, k: usize, ray: &Ray, tmin: f32, tmax: f32) -> bool {
        let same =
            |a: Vec3, b: Vec3| a.to_array().map(f32::to_bits) == b.to_array().map(f32::to_bits);
        same(self.rays[k].origin, ray.origin)
            && same(self.rays[k].dir, ray.dir)
            && self.tmin.to_bits() == tmin.to_bits()
            && NO_HIT.to_bits() == tmax.to_bits()
    }
}

/// The stages of rays traced ahead: the camera rays (`EYE`), their mirror rays
/// (`MIRROR`), their refracted rays (`REFRACTED`) and those rays' refracted rays
/// (`REFRACTED_TWICE`: through a pane or a gear of glass and out, as coherent as the rays
/// that went in; gears-4's 1080p render 7% faster with them); other rays are walked alone.
/// The mirror rays' mirror rays, and theirs, were measured as further stages on a Zen 4 EPYC
/// (2026-11-29): 1080p, 4 spp, five alternating runs each, no change beyond the machine's
/// swing on balls-4, teapot-6 and gears-4, and 0.3 to 11% more instructions (valgrind,
/// 480x270): more of balls-4's rays in packets (its shadow rays 27.7 of 27.8 M with
/// five), but each stage's packets emptier.
const STAGES: usize = 4;
const EYE: usize = 0;
const MIRROR: usize = 1;
const REFRACTED: usize = 2;
const REFRACTED_TWICE: usize = 3;
/// Each stage after the camera rays': the stage whose surfaces send its rays, and which.
const FOLLOW: [(usize, Secondary); STAGES - 1] = [
    (EYE, Secondary::Mirror),
    (EYE, Secondary::Refracted),
    (REFRACTED, Secondary::Refracted),
];

/// The rays a stage after the camera rays' holds.
#[derive(Clone, Copy)]
enum Secondary {
    Mirror,
    Refracted,
}

/// One pixel's rays traced beforehand (lane `k` of each stage: its camera ray, its mirror
/// and its refracted ray and that ray's refracted ray, with their surfaces and what each
/// point or directional light gives them); any other ray is walked alone.
struct Known<'a> {
    stages: &'a [Stage],
    k: usize,
    /// The stages whose ray of lane `k` the shading has yet to trace (it traces each once).
    waiting: u32,
    /// The stage whose ray `closest_hit` answered last, where that ray met a surface: the
    /// shading asks for that surface next.
    next: Option<usize>,
    /// The light samples of the surface being shaded, handed out in the lights' order
    /// (until the shading asks for the next surface).
    lights: &'a [Lit],
    /// Rays answered from packets, by kind.
    counts: RayCounts,
    /// The primitive that blocked the last shadow ray walked alone to each light from a
    /// pixel's `n`-th ray, `HINTS` a light.
    blockers: &'a mut [Option<u32>],
    /// The light whose sample the shading is taking, where it is one of `b.lights`.
    light: Option<usize>,
    /// Rays the shading has traced so far (its last one the `rays`-th).
    rays: usize,
}

impl<'a> Known<'a> {
    fn new(stages: &'a [Stage], k: usize, blockers: &'a mut [Option<u32>]) -> Self {
        let waiting = (0..stages.len())
            .filter(|&i| stages[i].traced & 1 << k != 0)
            .fold(0, |w, i| w | 1 << i);
        Known {
            stages,
            k,
            waiting,
            next: None,
            lights: &[],
            counts: RayCounts::default(),
            blockers,
            light: None,
            rays: 0,
        }
    }
}

/// `Alone`'s walk, kept out of line so that `Known::closest_hit` can be inlined.
#[inline(never)]
fn walk_alone(b: &Bindings, ray: &Ray, tmin: f32, tmax: f32) -> Hit {
    Alone.closest_hit(b, ray, tmin, tmax)
}

impl Tracer for Known<'_> {
    /// Inlined into the shading, which has just made `ray`: called, it read the ray back
    /// in loads wider than the stores that made it, which waited for both (store
    /// forwarding; 2% of balls-4's render, by `perf`).
    #[inline]
    fn closest_hit(&mut self, b: &Bindings, ray: &Ray, tmin: f32, tmax: f32) -> Hit {
        let k = self.k;
        self.rays += 1;
        self.next = None;
        for i in lanes_of(self.waiting) {
            let stage = &self.stages[i];
            if !stage.holds(k, ray, tmin, tmax) {
                continue;
            }
            self.waiting &= !(1 << i);
            self.next = (stage.met & 1 << k != 0).then_some(i);
            let packed = u64::from(stage.packed & 1 << k != 0);
            match i {
                EYE => self.counts.eye_packed += packed,
                MIRROR => self.counts.reflected_packed += packed,
                REFRACTED | REFRACTED_TWICE => self.counts.refracted_packed += packed,
                _ => unreachable!("{STAGES} stages"),
            }
            return stage.hits[k];
        }
        walk_alone(b, ray, tmin, tmax)
    }

    fn transmission(&mut self, b: &Bindings, ray: &Ray, tmax: f32, nodes: &mut u32) -> Vec3 {
        let mut none = None;
        let hint = match self.light {
            Some(i) => {
                let n = self.rays.clamp(1, HINTS) - 1;
                &mut self.blockers[i * HINTS + n]
            }
            None => &mut none,
        };
        wide_ray::transmission(b, ray, tmax, nodes, hint)
    }

    fn surface(&mut self, b: &Bindings, ray: &Ray, hit: &Hit) -> Surface {
        match self.next.take() {
            Some(i) => {
                let stage = &self.stages[i];
                let shadowed = stage.lights.len() / MAX_LANES;
                self.lights = &stage.lights[self.k * shadowed..(self.k + 1) * shadowed];
                stage.surfaces[self.k]
            }
            None => {
                self.lights = &[];
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
            && let Some((lit, rest)) = self.lights.split_first()
        {
            // `light_sample` on the same surface, its shadow ray answered by the packet
            // (the images are the per-pixel renderer's to the bit: tests/gpurt/packet.rs).
            self.lights = rest;
            return lit.counted(counts);
        }
        self.light = index_in(b.lights, light);
        light_sample(b, self, at, (light, k), rng, counts)
    }
}

/// What `trace` gives lane `k`'s camera ray, which met a surface, where every ray it
/// traces was traced ahead and every light is packed: the surface sends no ray on (neither
/// mirror nor transmission, or the depth ends there), or only its mirror ray, which meets
/// nothing or a surface that sends no ray on. Summed from the stages in `trace`'s order and
/// counted as `trace` counts it; `None` for any other pixel. Most of a frame's pixels are
/// such (balls-4's floor, teapot-6's floor under the sky), and their shading from the
/// stages' arrays skips `trace`'s set-up and its look-ups of the answers (a twelfth of
/// balls-4's render).
#[inline]
fn traced_ahead(b: &Bindings, stages: &[Stage], k: usize, counts: &mut RayCounts) -> Option<Vec3> {
    let g = b.globals;
    let sends_on = |m: &GpuMaterial, depth: u32| depth < g.max_depth && (m.ks > 0.0 || m.t > 0.0);
    let eye = &stages[EYE];
    let m = eye.material(b, k);
    // The mirror ray's stage, and its surface's material where it met one.
    let mut mirror = None;
    if sends_on(&m, 1) {
        let next = stages.get(MIRROR).filter(|_| m.t <= 0.0)?;
        debug_assert!(next.traced & 1 << k != 0, "a mirror ray traced ahead");
        let met = next.met & 1 << k != 0;
        let next_m = met.then(|| next.material(b, k));
        if next_m.as_ref().is_some_and(|next_m| sends_on(next_m, 2)) {
            return None;
        }
        mirror = Some((next, next_m));
    }
    count_nodes(counts, 1, eye.hits[k].nodes);
    counts.eye_packed += u64::from(eye.packed & 1 << k != 0);
    // `trace`'s sums: `0 + weight * direct`, the camera ray's weight 1 (to the bit: a -0
    // comes out +0), its mirror ray's `1 * Ks`.
    let mut colour = Vec3::ZERO + 1.0 * eye.direct(b, k, &m, counts);
    if let Some((next, next_m)) = mirror {
        let weight = 1.0 * m.ks;
        counts.reflected += 1;
        count_nodes(counts, 2, next.hits[k].nodes);
        counts.reflected_packed += u64::from(next.packed & 1 << k != 0);
        colour += match next_m {
            Some(next_m) => weight * next.direct(b, k, &next_m, counts),
            None => weight * g.background,
        };
    }
    #[cfg(test)]
    tests::SUMMED_AHEAD.with(|n| n.set(n.get() + 1));
    Some(colour)
}

/// Blockers kept a light for the shadow rays walked alone (`Known::blockers`): one for the
/// surfaces met by each of a pixel's first `HINTS - 1` rays, and one for all its later
/// ones. A pixel's `n`-th ray tends to meet a surface near its neighbour's `n`-th (the same
/// path through a scene of mirrors and glass), and so does its shadow ray's blocker. Kept
/// apart so, rather than one a light for every ray, gears-4's shadow rays fetched 326 node
/// bytes instead of 364 and its render took 2% less time (960x540, 4 spp, one thread,
/// AVX2); balls-4's and teapot-6's within the machine's swing.
const HINTS: usize = 8;

/// Where `light` lies in `lights`, if it is one of them (an emitter's triangles are not).
fn index_in(lights: &[GpuLight], light: &GpuLight) -> Option<usize> {
    let at = std::ptr::from_ref(light) as usize;
    let first = lights.as_ptr() as usize;
    let i = at.checked_sub(first)? / std::mem::size_of::<GpuLight>();
    (i < lights.len()).then_some(i)
}

/// Pixels of a packet, `(columns, rows)`, for `lanes` lanes.
fn block(lanes: usize) -> (u32, u32) {
    match lanes {
        16 => (4, 4),
        8 => (4, 2),
        _ => (2, 2),
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
    render_tile_with::<true>(b, kernels, (x0, x1), rows, samples, sums, counts);
}

/// `render_tile`, with the pixels whose rays were all traced ahead summed without `trace`
/// where `AHEAD` (always, but in the test that compares the two).
fn render_tile_with<const AHEAD: bool>(
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
    // Whether every light's samples come from the packets (then a pixel whose rays were
    // all traced ahead is shaded from the stages alone: `traced_ahead`).
    let all_packed = AHEAD && shadowed.len() == b.lights.len();
    let mut packet = Packet::default();
    // The camera rays, then, where the shading traces deeper, their mirror rays and, where
    // a material refracts, their refracted rays and (deeper still) those rays' refracted
    // rays: an empty stage for every block of a scene without glass cost balls-4's and
    // teapot-6's renders 1% (1080p, 4 spp).
    let refracts = b.materials.iter().any(|m| m.t > 0.0);
    let depth = match g.max_depth {
        0 | 1 => 1,
        _ if !refracts => 2,
        2 => 3,
        _ => STAGES,
    };
    let mut stages: Vec<Stage> = (0..depth).map(|_| Stage::new(shadowed.len())).collect();
    let mut blockers = vec![None; b.lights.len() * HINTS];
    for s in samples {
        for by in rows.clone().step_by(bh as usize) {
            for bx in (x0..x1).step_by(bw as usize) {
                // The block's pixels: (sums index, random stream), lane by lane.
                let mut pixels = [(0usize, 0u32); MAX_LANES];
                let mut n = 0;
                packet.clear();
                for y in by..(by + bh).min(rows.end) {
                    for x in bx..(bx + bw).min(x1) {
                        let mut rng = 0;
                        let ray = sample_ray(g, x, y, s, &mut rng);
                        pixels[n] = (((y - rows.start) * (x1 - x0) + x - x0) as usize, rng);
                        packet.set(n, &ray, g.hither, NO_HIT);
                        n += 1;
                    }
                }
                counts.eye += n as u64;
                stages[EYE].trace(b, kernels, &packet, g.hither);
                if g.aov != AOV_COLOR {
                    let eye = &stages[EYE];
                    for (k, &(i, _)) in pixels[..n].iter().enumerate() {
                        let mut known = Known::new(&stages[..1], k, &mut blockers);
                        sums[i] += aov(b, &mut known, &eye.rays[k], counts);
                        counts.add(&known.counts);
                    }
                    continue;
                }
                stages[EYE].light(b, kernels, &shadowed, &mut packet);
                for (i, &(from, kind)) in FOLLOW.iter().enumerate().take(depth - 1) {
                    let (done, next) = stages.split_at_mut(i + 1);
                    done[from].secondary(b, kind, &mut packet);
                    next[0].trace(b, kernels, &packet, 0.0);
                    next[0].light(b, kernels, &shadowed, &mut packet);
                }
                let eye = &stages[EYE];
                for (k, &(i, rng)) in pixels[..n].iter().enumerate() {
                    if eye.met & 1 << k == 0 {
                        // A camera ray that met nothing (most of a scene with sky around
                        // it): what `trace` gives it and counts for it, `0 + 1 *
                        // background`, without setting up its stack and answers.
                        sums[i] += g.background;
                        count_nodes(counts, 1, eye.hits[k].nodes);
                        counts.eye_packed += u64::from(eye.packed & 1 << k != 0);
                        continue;
                    }
                    if all_packed && let Some(colour) = traced_ahead(b, &stages, k, counts) {
                        sums[i] += colour;
                        continue;
                    }
                    let mut known = Known::new(&stages, k, &mut blockers);
                    let mut rng = rng;
                    sums[i] += trace(b, &mut known, &eye.rays[k], &mut rng, counts);
                    counts.add(&known.counts);
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use std::cell::Cell;
    use std::path::Path;

    use super::*;
    use crate::cpu::fast::packet::Isa;
    use crate::frame::{RenderOptions, globals};

    thread_local! {
        /// Pixels `traced_ahead` summed on this thread.
        pub(super) static SUMMED_AHEAD: Cell<u64> = const { Cell::new(0) };
    }

    /// A whole frame as one tile: each pixel's sum, as bits, and the rays counted.
    fn render_frame<const AHEAD: bool>(
        b: &Bindings,
        kernels: &Kernels,
    ) -> (Vec<[u32; 3]>, RayCounts) {
        let g = b.globals;
        let mut sums = vec![Vec3::ZERO; (g.width * g.height) as usize];
        let mut counts = RayCounts::default();
        let (x, rows, samples) = ((0, g.width), 0..g.height, 0..g.spp);
        render_tile_with::<AHEAD>(b, kernels, x, rows, samples, &mut sums, &mut counts);
        let bits = sums.iter().map(|s| s.to_array().map(f32::to_bits));
        (bits.collect(), counts)
    }

    /// The pixels summed without `trace` (`traced_ahead`) get `trace`'s colour to the bit
    /// and are counted as `trace` counts them, every count (rays by kind, node fetches by
    /// kind, rays in packets): frames rendered both ways, on scenes of mirrors, glass,
    /// cones and meshes, at depths from one to six, with every kernel this machine runs.
    #[test]
    fn pixels_traced_ahead_sum_and_count_as_trace_does() {
        let scenes = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
        let summed = || SUMMED_AHEAD.with(Cell::get);
        let mut ahead = 0;
        for name in ["spheres", "mirrors", "glass", "cones", "mesh", "patches"] {
            let path = scenes.join(format!("{name}.nff"));
            let buffers =
                crate::pack::pack(crate::scene::load(&path).expect("loads")).expect("packs");
            for max_depth in [1, 2, 3, 6] {
                let opts = RenderOptions {
                    width: 21,
                    height: 13,
                    spp: 2,
                    max_depth,
                    ..RenderOptions::for_camera(&buffers.camera)
                };
                let g = globals(&buffers, &opts);
                let b = Bindings::new(&buffers, &g);
                for kernels in Isa::ALL.into_iter().filter_map(Kernels::new) {
                    let what = format!("{name}, depth {max_depth}, {}", kernels.isa().name());
                    let before = summed();
                    let (want, want_counts) = render_frame::<false>(&b, &kernels);
                    assert_eq!(summed(), before, "{what}: none summed ahead");
                    let (got, counts) = render_frame::<true>(&b, &kernels);
                    assert_eq!(got, want, "{what}: sums");
                    assert_eq!(counts, want_counts, "{what}: counts");
                    ahead += summed() - before;
                }
            }
        }
        // The comparison has something to compare: many pixels were summed ahead.
        assert!(ahead > 1000, "only {ahead} pixels traced ahead");
    }
}
