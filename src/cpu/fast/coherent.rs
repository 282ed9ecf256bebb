//! The CPU renderer's tiles traced with packets where rays are coherent: for each sample,
//! the camera rays of a block of pixels (4x4, 4x2 or 2x2, as many as the kernels' lanes)
//! go as one packet, then their shadow rays to each point or directional light as an
//! occlusion packet, then the mirror rays off the surfaces they met as another, and the
//! refracted rays as a third, and those rays' shadow rays to each light as more (a
//! `Stage` each: the camera rays, their mirror rays, their refracted rays and those rays'
//! refracted rays: `stage.rs`); every other ray (area light samples, deeper bounces) is
//! walked alone when the shading asks for it. Mirror rays off curved surfaces diverge, but
//! a block's still share most of their path through the tree: traced in packets,
//! teapot-6's 1080p render took 15% less time and balls-4's 3% less (one run each way,
//! alternating), and lanes that part from the rest go on alone (`packet::single`). So do
//! the rays through glass: gears-4's 1080p render took 9% less time with the rays that
//! enter it and their shadow rays in packets, and 7% less again with the rays that leave
//! it (docs/bvh.md).
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

use super::lights::packed;
use super::packet::{Kernels, MAX_LANES, Packet};
use super::stage::{Lit, Secondary, Stage};
use super::tracer::Alone;
use super::wide_ray;
use crate::cpu::intersect::lanes_of;
use crate::cpu::pixel::{aov, sample_ray};
use crate::cpu::shade::{Shaded, Surface, Tracer, count_nodes, light_sample, surface, trace};
use crate::cpu::types::{Bindings, Hit, Ray, RayCounts};
use crate::gpu_types::*;

/// The stages of rays traced ahead: the camera rays (`EYE`), their mirror rays
/// (`MIRROR`), their refracted rays (`REFRACTED`) and those rays' refracted rays
/// (through a pane or a gear of glass and out, as coherent as the rays
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
/// Each stage after the camera rays': the stage whose surfaces send its rays, and which.
const FOLLOW: [(usize, Secondary); STAGES - 1] = [
    (EYE, Secondary::Mirror),
    (EYE, Secondary::Refracted),
    (REFRACTED, Secondary::Refracted),
];

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
            match stage.kind {
                None => self.counts.eye_packed += packed,
                Some(Secondary::Mirror) => self.counts.reflected_packed += packed,
                Some(Secondary::Refracted) => self.counts.refracted_packed += packed,
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
    let kinds = std::iter::once(None).chain(FOLLOW.map(|(_, kind)| Some(kind)));
    let mut stages: Vec<Stage> = kinds
        .take(depth)
        .map(|kind| Stage::new(shadowed.len(), kind))
        .collect();
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
