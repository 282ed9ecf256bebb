//! CPU twin of `shaders/wavefront.wgsl`: the wavefront kernels over a tile's paths, with
//! the same records, the same rounds (a generation of rays each) and the same order of
//! rays in them, each kernel run over its whole dispatch before the next (on one thread:
//! the shader's invocations one after another, a workgroup's scan as the shader's
//! workgroup computes it). A path's rays and light are those of the CPU renderer's
//! `trace`; its sums add a generation at a time where `trace` adds depth first, so they
//! differ from `sample_sum`'s by rounding, and are the shader's to the bit. What this
//! twin lets the tests check without a GPU is the bookkeeping: the scan that keeps a
//! round's rays in path order, the shadow slots and queue, the gathering, the capacity.

use glam::Vec3;

use super::pixel::sample_ray;
use super::shade::{
    Pending, light_ray, light_samples, reflect_dir, refracted_dir, secondary, surface, unlit,
};
use super::texture::textured;
use super::traverse::{closest_hit, transmission};
use super::types::{Bindings, Ray, RayCounts};
use super::wave::{W, Wave, WaveHit, WavePath, WaveRay, WaveShadow};
use crate::gpu_types::*;

impl Wave<'_, '_> {
    fn wf_generate(&mut self, p: u32) {
        let t = self.tile;
        let paths = t.width * t.height * t.sample_count;
        if p == 0 {
            self.counts[WAVE_NEXT as usize] = paths;
        }
        if p >= paths {
            return;
        }
        let g = self.b.globals;
        let (x, y, _) = self.wave_xy(p / t.sample_count);
        let s = t.sample_start + p % t.sample_count;
        let mut rng = 0;
        let ray = sample_ray(g, x, y, s, &mut rng);
        let eye = RayCounts {
            eye: 1,
            ..RayCounts::default()
        };
        self.paths[p as usize] = WavePath {
            colour: Vec3::ZERO,
            rays: 1,
            counts: eye,
            cut: 0,
        };
        let at = self.wave_ray_index(1, p);
        self.rays[at] = WaveRay {
            origin: ray.origin,
            weight: 1.0,
            dir: ray.dir,
            path: p,
        };
    }

    fn wf_advance(&mut self) {
        self.counts[WAVE_ROUND as usize] += 1;
        let next = std::mem::take(&mut self.counts[WAVE_NEXT as usize]);
        let n = next.min(self.wave_capacity());
        self.counts[WAVE_RAYS as usize] = n;
        self.counts[WAVE_SHADOWS as usize] = 0;
        self.wave_dispatch(0, n);
    }

    /// One workgroup of `wf_extend`: each invocation's closest hit, then the workgroup's
    /// inclusive scan of the rays of the next round they send.
    fn wf_extend(&mut self, group: u32) {
        let d = self.counts[WAVE_ROUND as usize];
        let n = self.counts[WAVE_RAYS as usize];
        let mut local = [0u32; W as usize];
        for (i, sum) in local.iter_mut().enumerate() {
            let k = group * W + i as u32;
            if k >= n {
                continue;
            }
            let r = self.rays[self.wave_ray_index(d, k)];
            let tmin = if d == 1 { self.b.globals.hither } else { 0.0 };
            let ray = Ray {
                origin: r.origin,
                dir: r.dir,
            };
            let hit = closest_hit(self.b, &ray, tmin, NO_HIT);
            *sum = self.wave_children(d, &hit);
            self.hits[k as usize] = WaveHit {
                hit,
                flags: *sum << WAVE_SENDS_SHIFT,
                children: 0,
                ambient: Vec3::ZERO,
            };
        }
        let mut total = 0;
        for (i, &children) in local.iter().enumerate() {
            let k = group * W + i as u32;
            if k < n {
                self.hits[k as usize].children = total;
            }
            total += children;
        }
        self.scan[group as usize] = total;
    }

    /// `wf_scan`'s one workgroup: where each workgroup's rays of the next round begin.
    fn wf_scan(&mut self) {
        let n = self.counts[WAVE_RAYS as usize];
        let groups = n.div_ceil(W) as usize;
        let mut at = 0;
        for g in 0..groups {
            let t = self.scan[g];
            self.scan[g] = at;
            at += t;
        }
        self.counts[WAVE_NEXT as usize] = at;
    }

    fn wf_shade(&mut self, k: u32) {
        let d = self.counts[WAVE_ROUND as usize];
        if k >= self.counts[WAVE_RAYS as usize] {
            return;
        }
        let hit = self.hits[k as usize].hit;
        if hit.prim == NO_PRIM {
            return;
        }
        let b = self.b;
        let g = b.globals;
        let r = self.rays[self.wave_ray_index(d, k)];
        let ray = Ray {
            origin: r.origin,
            dir: r.dir,
        };
        let s = surface(b, &ray, &hit);
        let m = &textured(b, &b.materials[s.material as usize], &hit);
        self.hits[k as usize].ambient = unlit(g, &s, m);
        let mirror = reflect_dir(ray.dir, s.ns);
        // Area lights and emitters take the one kernel: no light here draws from the random
        // stream.
        let mut rng = 0;
        let n_lights = b.lights.len() as u32;
        for (li, light) in b.lights.iter().enumerate() {
            let slot = k * n_lights + li as u32;
            let lr = light_ray(b, &s, m, ray.dir, mirror, light, 0, &mut rng);
            self.shadows[slot as usize] = match lr {
                Some(lr) => WaveShadow {
                    origin: lr.ray.origin,
                    dist: lr.dist,
                    dir: lr.ray.dir,
                    flags: WAVE_TRACED,
                    light: lr.term,
                    nodes: 0,
                },
                None => WaveShadow::default(),
            };
            if lr.is_some() {
                let q = self.counts[WAVE_SHADOWS as usize];
                self.counts[WAVE_SHADOWS as usize] += 1;
                self.queue[q as usize] = slot;
            }
        }
        if d >= g.max_depth {
            return;
        }
        let parent = Pending {
            origin: r.origin,
            dir: r.dir,
            weight: r.weight,
            depth: d,
            tmin: 0.0,
        };
        let mut at = self.wave_child_index(k);
        let push = |w: &mut Self, at: u32, c: Pending| {
            let i = w.wave_ray_index(d + 1, at);
            w.rays[i] = WaveRay {
                origin: c.origin,
                weight: c.weight,
                dir: c.dir,
                path: r.path,
            };
        };
        if m.ks > 0.0 {
            if at < self.wave_capacity() {
                push(self, at, secondary(&s, mirror, &parent, m.ks, g.epsilon));
            }
            at += 1;
        }
        if m.t > 0.0 && at < self.wave_capacity() {
            let dir = refracted_dir(&s, m, ray.dir);
            push(self, at, secondary(&s, dir, &parent, m.t, g.epsilon));
        }
    }

    fn wf_advance_shadows(&mut self) {
        self.wave_dispatch(3, self.counts[WAVE_SHADOWS as usize]);
    }

    fn wf_shadow(&mut self, q: u32) {
        if q >= self.counts[WAVE_SHADOWS as usize] {
            return;
        }
        let slot = self.queue[q as usize] as usize;
        let sh = self.shadows[slot];
        let light = &self.b.lights[slot % self.b.lights.len()];
        let intensity = light.color / light_samples(light) as f32;
        let ray = Ray {
            origin: sh.origin,
            dir: sh.dir,
        };
        let mut nodes = 0;
        let shadow = transmission(self.b, &ray, sh.dist, &mut nodes);
        self.shadows[slot].light = shadow * intensity * sh.light;
        self.shadows[slot].nodes = nodes;
    }

    fn wf_gather(&mut self, first: u32) {
        let d = self.counts[WAVE_ROUND as usize];
        let n = self.counts[WAVE_RAYS as usize];
        if first >= n {
            return;
        }
        let p = self.rays[self.wave_ray_index(d, first)].path;
        if first > 0 && self.rays[self.wave_ray_index(d, first - 1)].path == p {
            return;
        }
        let g = self.b.globals;
        let n_lights = self.b.lights.len() as u32;
        let mut path = self.paths[p as usize];
        for k in first..n {
            let r = self.rays[self.wave_ray_index(d, k)];
            if r.path != p {
                break;
            }
            let h = self.hits[k as usize];
            path.cut |= u32::from(h.flags & WAVE_CUT != 0);
            if d == 1 {
                path.counts.eye_nodes += u64::from(h.hit.nodes);
            } else {
                path.counts.secondary_nodes += u64::from(h.hit.nodes);
            }
            if h.hit.prim == NO_PRIM {
                path.colour += r.weight * g.background;
                continue;
            }
            let mut lit = h.ambient;
            for li in 0..n_lights {
                let sh = &self.shadows[(k * n_lights + li) as usize];
                if sh.flags & WAVE_TRACED != 0 {
                    path.rays += 1;
                    lit += sh.light;
                    path.cut |= u32::from(sh.flags & WAVE_CUT != 0);
                    path.counts.shadow += 1;
                    path.counts.shadow_nodes += u64::from(sh.nodes);
                }
            }
            path.colour += r.weight * lit;
            let children = h.flags >> WAVE_SENDS_SHIFT;
            path.rays += children;
            if children > 0 {
                // The CPU counts the two kinds apart; the GPU counts them together.
                let m = self.wave_material(&h.hit);
                path.counts.reflected += u64::from(m.ks > 0.0);
                path.counts.refracted += u64::from(m.t > 0.0);
            }
            let past = self.wave_child_index(k) + children > self.wave_capacity();
            path.cut |= u32::from(children > 0 && past);
        }
        self.paths[p as usize] = path;
    }

    fn wf_finish(&mut self, i: u32) {
        let t = self.tile;
        if i >= t.width * t.height {
            return;
        }
        let slot = self.wave_xy(i).2;
        let (mut sum, mut rays, mut total) = self.out[slot];
        let mut cut = rays & PIXEL_CUT_SHORT != 0;
        rays &= !PIXEL_CUT_SHORT;
        for j in 0..t.sample_count {
            let path = &self.paths[(i * t.sample_count + j) as usize];
            sum += path.colour;
            rays += path.rays;
            cut = cut || path.cut != 0;
            total.add(&path.counts);
        }
        let flag = if cut { PIXEL_CUT_SHORT } else { 0 };
        self.out[slot] = (sum, rays | flag, total);
    }
}

/// Traces `tile`'s paths (its pixels times its samples; `out_base` and `out_stride`
/// place its pixels in the returned array, which starts at zero) through the kernels,
/// dispatched as the host dispatches them (`gpu::waves`), each kernel over the
/// invocations its dispatch size gives, with room for `room` rays a round (the GPU's wave
/// has `WAVE_RAYS_PER_PATH` for each path it holds): each pixel's sum of its samples, its
/// rays (`PIXEL_CUT_SHORT` set where a path's rays did not fit) and counts.
pub fn wave_sums(
    b: &Bindings,
    tile: &GpuTile,
    room: u32,
    out_len: usize,
) -> Vec<(Vec3, u32, RayCounts)> {
    let paths = tile.width * tile.height * tile.sample_count;
    let rays = room.max(paths) as usize;
    let slots = rays * b.lights.len().max(1);
    let mut w = Wave {
        b,
        tile: *tile,
        paths: vec![WavePath::default(); paths as usize],
        rays: vec![WaveRay::default(); 2 * rays],
        // Written by `wf_extend` before anything reads them.
        hits: vec![WaveHit::default(); rays],
        shadows: vec![WaveShadow::default(); slots],
        queue: vec![0; slots],
        scan: vec![0; rays.div_ceil(W as usize)],
        counts: [0; WAVE_COUNT_WORDS as usize],
        args: [0; 6],
        out: vec![(Vec3::ZERO, 0, RayCounts::default()); out_len],
    };
    for p in 0..paths.div_ceil(W) * W {
        w.wf_generate(p);
    }
    for _ in 0..b.globals.max_depth.max(1) {
        w.wf_advance();
        let invocations = w.args[0] * W;
        for group in 0..w.args[0] {
            w.wf_extend(group);
        }
        w.wf_scan();
        for k in 0..invocations {
            w.wf_shade(k);
        }
        w.wf_advance_shadows();
        for q in 0..w.args[3] * W {
            w.wf_shadow(q);
        }
        for k in 0..invocations {
            w.wf_gather(k);
        }
    }
    for i in 0..(tile.width * tile.height).div_ceil(W) * W {
        w.wf_finish(i);
    }
    w.out
}
