//! CPU twin of `shaders/wavefront.wgsl`: the wavefront kernels' steps for a tile's pixels,
//! over the same three queues of two halves, each kernel run over its whole queue before
//! the next (on one thread: the shader's invocations one after another). A pixel's steps
//! are `trace`'s and `direct`'s in their order, so each pixel's sum, rays and counts are
//! `sample_sum`'s to the bit; what this twin lets the tests check without a GPU is the
//! bookkeeping of the queues and of a pixel's state between kernels.

use glam::Vec3;

use super::main::{camera_ray, sample_offset};
use super::shade::{
    LightRay, Pending, Surface, count_nodes, light_ray, light_samples, reflect_dir, refracted_dir,
    secondary, surface,
};
use super::traverse::{closest_hit, transmission};
use super::types::{Bindings, Hit, Ray, RayCounts, rng_seed};
use crate::gpu_types::*;

/// Where a pixel of the wave stands (the shader's `WaveState`; `GpuWaveState` on the
/// host): its samples so far, the sample under way, the hit being shaded and its light so
/// far, the ray `wf_extend` traces next, the light sample whose shadow ray `wf_shadow`
/// traces, and what came back.
#[derive(Clone, Copy, Default)]
struct WaveState {
    sum: Vec3,
    sample: u32,
    colour: Vec3,
    rng: u32,
    lit: Vec3,
    rays: u32,
    point: Vec3,
    sp: usize,
    ng: Vec3,
    light: usize,
    ns: Vec3,
    light_sample: u32,
    ray_in: Pending,
    shadow: Option<LightRay>,
    shadow_light: Vec3,
    hit: Option<Hit>,
    material: u32,
    entering: bool,
    phase: u32,
    counts: RayCounts,
    stack: [Pending; RAY_STACK],
}

/// A tile's wave: a state per pixel, the queues (queue q, 0: extend, 1: shadow, 2:
/// shade, has two halves of `pixels` entries), their counts as the shader's
/// `wave_counts` has them, and the pixels written out.
struct Wave<'w, 'a> {
    b: &'w Bindings<'a>,
    tile: GpuTile,
    wave: Vec<WaveState>,
    queues: Vec<u32>,
    counts: [u32; 9],
    out: Vec<(Vec3, u32, RayCounts)>,
}

impl Wave<'_, '_> {
    fn wave_half(&self, q: usize, next: bool) -> usize {
        let size = self.queues.len() / 6;
        let half = (self.counts[q] ^ u32::from(next)) as usize;
        (2 * q + half) * size
    }

    /// Appends pixel `i` to queue q, for the kernel of the next round.
    fn wave_push(&mut self, q: usize, i: u32) {
        let k = self.counts[6 + q] as usize;
        self.counts[6 + q] += 1;
        let at = self.wave_half(q, true) + k;
        self.queues[at] = i;
    }

    /// The pixel of entry `k` of queue q, or none past its length.
    fn wave_pixel(&self, q: usize, k: u32) -> u32 {
        if k >= self.counts[3 + q] {
            return NO_PRIM;
        }
        self.queues[self.wave_half(q, false) + k as usize]
    }

    /// The queue filled last becomes the input (the shader also writes the size of the
    /// kernel's indirect dispatch; here the host loops to the queue's length).
    fn wave_advance(&mut self, q: usize) {
        self.counts[q] ^= 1;
        self.counts[3 + q] = std::mem::take(&mut self.counts[6 + q]);
    }

    /// Pixel i of the tile, as (x, y) in the image, and its slot in the output.
    fn wave_xy(&self, i: u32) -> (u32, u32, usize) {
        let t = &self.tile;
        let (x, y) = (i % t.width, i / t.width);
        (
            t.x + x,
            t.y + y,
            (t.out_base + y * t.out_stride + x) as usize,
        )
    }

    /// Starts pixel i's sample `sample`: its eye ray is the ray to extend.
    fn wave_start_sample(&mut self, i: u32) {
        let g = self.b.globals;
        let (px, py, _) = self.wave_xy(i);
        let w = &mut self.wave[i as usize];
        let s = w.sample;
        let mut rng = rng_seed(py * g.width + px, s, g.seed);
        let off = sample_offset(s, g.spp, &mut rng);
        let ray = camera_ray(g, px as f32 + off.x, py as f32 + off.y, &mut rng);
        w.rng = rng;
        w.rays += 1;
        w.counts.eye += 1;
        w.colour = Vec3::ZERO;
        w.sp = 0;
        w.ray_in = Pending {
            origin: ray.origin,
            dir: ray.dir,
            weight: 1.0,
            depth: 1,
            tmin: g.hither,
        };
        self.wave_push(0, i);
    }

    /// The next pending ray of pixel i's sample, or its next sample, or its output.
    fn wave_next_ray(&mut self, i: u32) {
        let w = &mut self.wave[i as usize];
        if w.sp > 0 {
            w.sp -= 1;
            w.ray_in = w.stack[w.sp];
            self.wave_push(0, i);
            return;
        }
        w.sum += w.colour;
        w.sample += 1;
        if w.sample < self.tile.sample_start + self.tile.sample_count {
            self.wave_start_sample(i);
            return;
        }
        let (sum, rays, counts) = (w.sum, w.rays, w.counts);
        let slot = self.wave_xy(i).2;
        self.out[slot] = (sum, rays, counts);
    }

    /// Takes pixel i's next light sample that sends a shadow ray, to `wf_shadow`; once
    /// every light is sampled, adds the hit's light to the sample and pushes its reflected
    /// and refracted rays, as `trace` does.
    fn wave_next_light(&mut self, i: u32) {
        let b = self.b;
        let g = b.globals;
        let w = &mut self.wave[i as usize];
        let s = Surface {
            point: w.point,
            ng: w.ng,
            ns: w.ns,
            entering: w.entering,
            material: w.material,
        };
        let ray_in = w.ray_in;
        let m = &b.materials[s.material as usize];
        let r = reflect_dir(ray_in.dir, s.ns);
        let mut rng = w.rng;
        while w.light < b.lights.len() {
            let light = &b.lights[w.light];
            while w.light_sample < light_samples(light) {
                let k = w.light_sample;
                w.light_sample += 1;
                if let Some(lr) = light_ray(b, &s, m, ray_in.dir, r, light, k, &mut rng) {
                    w.rng = rng;
                    w.shadow = Some(lr);
                    self.wave_push(1, i);
                    return;
                }
            }
            w.light += 1;
            w.light_sample = 0;
        }
        w.rng = rng;
        w.colour += ray_in.weight * w.lit;
        if ray_in.depth < g.max_depth {
            if m.ks > 0.0 {
                w.rays += 1;
                w.counts.reflected += 1;
                w.stack[w.sp] =
                    secondary(&s, reflect_dir(ray_in.dir, s.ns), &ray_in, m.ks, g.epsilon);
                w.sp += 1;
            }
            if m.t > 0.0 {
                w.rays += 1;
                w.counts.refracted += 1;
                let dir = refracted_dir(&s, m, ray_in.dir);
                w.stack[w.sp] = secondary(&s, dir, &ray_in, m.t, g.epsilon);
                w.sp += 1;
            }
        }
        self.wave_next_ray(i);
    }

    /// Starts pixel i: its first sample of the tile.
    fn wf_generate(&mut self, i: u32) {
        self.wave[i as usize].sample = self.tile.sample_start;
        self.wave_start_sample(i);
    }

    fn wf_advance_rays(&mut self) {
        self.wave_advance(0);
        self.wave_advance(1);
    }

    fn wf_advance_shade(&mut self) {
        self.wave_advance(2);
    }

    /// The closest hit of the ray of entry `k` of the extend queue's pixel.
    fn wf_extend(&mut self, k: u32) {
        let i = self.wave_pixel(0, k);
        if i == NO_PRIM {
            return;
        }
        let w = &mut self.wave[i as usize];
        let ray_in = w.ray_in;
        let ray = Ray {
            origin: ray_in.origin,
            dir: ray_in.dir,
        };
        let hit = closest_hit(self.b, &ray, ray_in.tmin, NO_HIT);
        count_nodes(&mut w.counts, ray_in.depth, hit.nodes);
        w.hit = Some(hit);
        w.phase = PHASE_RAY;
        self.wave_push(2, i);
    }

    /// The transmission of the shadow ray of entry `k` of the shadow queue's pixel.
    fn wf_shadow(&mut self, k: u32) {
        let i = self.wave_pixel(1, k);
        if i == NO_PRIM {
            return;
        }
        let w = &mut self.wave[i as usize];
        let lr = w
            .shadow
            .expect("a pixel in the shadow queue has a shadow ray");
        let mut nodes = 0;
        w.shadow_light = transmission(self.b, &lr.ray, lr.dist, &mut nodes);
        w.phase = PHASE_LIGHT;
        w.counts.shadow += 1;
        w.counts.shadow_nodes += u64::from(nodes);
        self.wave_push(2, i);
    }

    /// Shades the hit, or adds the light sample, of entry `k` of the shade queue's pixel.
    fn wf_shade(&mut self, k: u32) {
        let i = self.wave_pixel(2, k);
        if i == NO_PRIM {
            return;
        }
        let b = self.b;
        let g = b.globals;
        let w = &mut self.wave[i as usize];
        if w.phase == PHASE_LIGHT {
            // `light_sample`'s product, in its order, added as `direct` adds it.
            let lr = w.shadow.expect("a light sample came back");
            w.rays += 1;
            w.lit += w.shadow_light * lr.intensity * lr.term;
            self.wave_next_light(i);
            return;
        }
        let ray_in = w.ray_in;
        let hit = w.hit.expect("an extended ray has a hit");
        if hit.prim == NO_PRIM {
            w.colour += ray_in.weight * g.background;
            self.wave_next_ray(i);
            return;
        }
        let ray = Ray {
            origin: ray_in.origin,
            dir: ray_in.dir,
        };
        let s = surface(b, &ray, &hit);
        let m = &b.materials[s.material as usize];
        w.point = s.point;
        w.ng = s.ng;
        w.ns = s.ns;
        w.entering = s.entering;
        w.material = s.material;
        w.lit = g.ambient * m.kd * m.color;
        w.light = 0;
        w.light_sample = 0;
        self.wave_next_light(i);
    }
}

/// Traces `tile`'s pixels (its `out_base` and `out_stride` place them in the returned
/// array) through the kernels' steps, round after round as the host dispatches them
/// (`gpu::waves`), until every queue is empty: each pixel's sum of its samples, rays and
/// counts.
pub fn wave_sums(b: &Bindings, tile: &GpuTile, out_len: usize) -> Vec<(Vec3, u32, RayCounts)> {
    let pixels = (tile.width * tile.height) as usize;
    let mut w = Wave {
        b,
        tile: *tile,
        wave: vec![WaveState::default(); pixels],
        queues: vec![0; 6 * pixels.max(1)],
        counts: [0; 9],
        out: vec![(Vec3::ZERO, 0, RayCounts::default()); out_len],
    };
    for i in 0..pixels as u32 {
        w.wf_generate(i);
    }
    while w.counts[6..].iter().any(|&n| n > 0) {
        w.wf_advance_rays();
        for k in 0..w.counts[3] {
            w.wf_extend(k);
        }
        for k in 0..w.counts[4] {
            w.wf_shadow(k);
        }
        w.wf_advance_shade();
        for k in 0..w.counts[5] {
            w.wf_shade(k);
        }
    }
    w.out
}
