//! CPU twin of `shaders/pixel.wgsl`: one pixel = its camera rays (stratified, jittered
//! samples and the thin lens, drawn from the shared hash), traced and averaged, or an AOV.

use glam::{Vec2, Vec3};

use super::shade::{Tracer, count_nodes, surface, trace};
use super::texture::hit_uv;
use super::types::{Bindings, Ray, RayCounts, rand, rng_seed};
use crate::gpu_types::*;

/// Camera ray through image point `(x, y)` (pixels, y down), shading.md's convention.
pub fn camera_ray(g: &GpuGlobals, x: f32, y: f32, rng: &mut u32) -> Ray {
    let sx = (x - 0.5 * g.width as f32) * g.pixel_pitch;
    let sy = (0.5 * g.height as f32 - y) * g.pixel_pitch;
    let dir = (g.cam_forward + sx * g.cam_right + sy * g.cam_up).normalize();
    if g.aperture <= 0.0 {
        return Ray {
            origin: g.cam_pos,
            dir,
        };
    }
    // Thin lens: aim at the point on the focal plane, from a point on the lens disc.
    let focus = g.cam_pos + dir * (g.focal / dir.dot(g.cam_forward));
    let r = 0.5 * g.aperture * rand(rng).sqrt();
    let phi = 2.0 * PI * rand(rng);
    let origin = g.cam_pos + r * phi.cos() * g.cam_right + r * phi.sin() * g.cam_up;
    Ray {
        origin,
        dir: (focus - origin).normalize(),
    }
}

/// Offset of sample `s` of `n` inside the pixel: the centre for one sample, otherwise a
/// jittered point in cell `s` of n equal cells: rows of k = ceil(sqrt(n)) cells, the last
/// row holding the rest, each row as tall as its share of the cells. Every cell has area
/// 1/n and the cells tile the pixel, so the estimate is unbiased for every n (a k x
/// ceil(n/k) grid with empty cells shifted the image by up to a tenth of a pixel).
pub fn sample_offset(s: u32, n: u32, rng: &mut u32) -> Vec2 {
    if n <= 1 {
        return Vec2::splat(0.5);
    }
    let mut k = 1;
    while k * k < n {
        k += 1;
    }
    let row = s / k;
    let cells = k.min(n - row * k);
    let jx = rand(rng);
    let jy = rand(rng);
    Vec2::new(
        ((s % k) as f32 + jx) / cells as f32,
        ((row * k) as f32 + jy * cells as f32) / n as f32,
    )
}

/// The camera ray of sample `s` of pixel (`px`, `py`), with the sample's random stream
/// seeded in `rng`, which the sample's shading goes on drawing from.
pub fn sample_ray(g: &GpuGlobals, px: u32, py: u32, s: u32, rng: &mut u32) -> Ray {
    *rng = rng_seed(py * g.width + px, s, g.seed);
    let off = sample_offset(s, g.spp, rng);
    camera_ray(g, px as f32 + off.x, py as f32 + off.y, rng)
}

/// `sum` plus samples `samples` of one pixel, added in sample order (as `main` in
/// pixel.wgsl does within a band), and the rays traced for them, each answered by
/// `tracer` (`fast::tracer::Alone` when the CPU renders).
pub fn sample_sum(
    b: &Bindings,
    tracer: &mut impl Tracer,
    (px, py): (u32, u32),
    samples: std::ops::Range<u32>,
    mut sum: Vec3,
    counts: &mut RayCounts,
) -> Vec3 {
    let g = b.globals;
    for s in samples {
        let mut rng = 0;
        let ray = sample_ray(g, px, py, s, &mut rng);
        counts.eye += 1;
        sum += if g.aov == AOV_COLOR {
            trace(b, tracer, &ray, &mut rng, counts)
        } else {
            aov(b, tracer, &ray, counts)
        };
    }
    sum
}

/// Debug outputs of the eye ray: shading normal, distance, BVH nodes visited, or texture
/// coordinates.
pub fn aov(b: &Bindings, tracer: &mut impl Tracer, ray: &Ray, counts: &mut RayCounts) -> Vec3 {
    let g = b.globals;
    let hit = tracer.closest_hit(b, ray, g.hither, NO_HIT);
    count_nodes(counts, 1, hit.nodes);
    match g.aov {
        AOV_COST => Vec3::splat(hit.cost as f32),
        _ if hit.prim == NO_PRIM => Vec3::ZERO,
        AOV_DEPTH => Vec3::splat(hit.t),
        AOV_UV => hit_uv(b, &hit).extend(0.0),
        _ => 0.5 * (surface(b, ray, &hit).ns + Vec3::ONE),
    }
}
