// main.wgsl: the compute entry point. One invocation per pixel of the current tile
// (workgroups of 8x8 pixels; the host dispatches one bounded tile at a time, a band of
// tiles per submission): camera rays
// (stratified, jittered samples and the thin lens, from the shared hash), traced and
// averaged, or an AOV (CPU twin: src/cpu/main.rs).

fn camera_ray(x: f32, y: f32, rng: ptr<function, u32>) -> Ray {
    let g = globals;
    let sx = (x - 0.5 * f32(g.width)) * g.pixel_pitch;
    let sy = (0.5 * f32(g.height) - y) * g.pixel_pitch;
    let dir = normalize(g.cam_forward + sx * g.cam_right + sy * g.cam_up);
    if (!LENS || g.aperture <= 0.0) {
        return Ray(g.cam_pos, dir);
    }
    // Thin lens: aim at the point on the focal plane, from a point on the lens disc.
    let focus = g.cam_pos + dir * (g.focal / dot(dir, g.cam_forward));
    let r = 0.5 * g.aperture * sqrt(rand(rng));
    let phi = 2.0 * 3.14159265358979323846 * rand(rng);
    let origin = g.cam_pos + r * cos(phi) * g.cam_right + r * sin(phi) * g.cam_up;
    return Ray(origin, normalize(focus - origin));
}

fn sample_offset(s: u32, n: u32, rng: ptr<function, u32>) -> vec2<f32> {
    if (!MULTISAMPLE || n <= 1u) {
        return vec2<f32>(0.5);
    }
    var k = 1u;
    while (k * k < n) {
        k += 1u;
    }
    cut_short = cut_short || k * k < n;
    let rows = (n + k - 1u) / k;
    let jx = rand(rng);
    let jy = rand(rng);
    return vec2<f32>((f32(s % k) + jx) / f32(k), (f32(s / k) + jy) / f32(rows));
}

fn aov(ray: Ray) -> vec3<f32> {
    let hit = closest_hit(ray, globals.hither, NO_HIT);
    if (AOV == AOV_COST) {
        return vec3<f32>(f32(hit.cost));
    }
    if (hit.prim == NO_PRIM) {
        return vec3<f32>(0.0);
    }
    if (AOV == AOV_DEPTH) {
        return vec3<f32>(hit.t);
    }
    return 0.5 * (surface(ray, hit).ns + vec3<f32>(1.0));
}

@compute @workgroup_size(64, 1, 1)
fn main(
    @builtin(workgroup_id) group: vec3<u32>,
    @builtin(local_invocation_index) local_index: u32,
) {
    stack_base = local_index;
    // Consecutive invocations cover 4x2 pixel blocks rather than rows of 8: the lanes
    // a SIMD unit runs together then trace neighbouring, more coherent rays.
    let block = local_index / 8u;
    let lane = local_index % 8u;
    let id = vec2<u32>(
        group.x * 8u + (block % 2u) * 4u + lane % 4u,
        group.y * 8u + (block / 2u) * 2u + lane / 4u,
    );
    if (id.x >= tile.width || id.y >= tile.height) {
        return;
    }
    let px = tile.x + id.x;
    let py = tile.y + id.y;
    let g = globals;
    let slot = tile.out_base + id.y * tile.out_stride + id.x;
    var rays = 0u;
    var sum = vec3<f32>(0.0);
    // Later passes continue the sum where the earlier ones left it, in sample order, so
    // the result does not depend on how the samples were split.
    if (tile.sample_start > 0u) {
        let before = output[slot];
        sum = before.color;
        rays = before.rays & ~PIXEL_CUT_SHORT;
        cut_short = (before.rays & PIXEL_CUT_SHORT) != 0u;
    }
    let end = tile.sample_start + tile.sample_count;
    var s = tile.sample_start;
    for (; s < end; s++) {
        var rng = rng_seed(py * g.width + px, s, g.seed);
        let off = sample_offset(s, g.spp, &rng);
        let ray = camera_ray(f32(px) + off.x, f32(py) + off.y, &rng);
        rays += 1u;
        if (AOV == AOV_COLOR) {
            sum += trace(ray, &rng, &rays);
        } else {
            sum += aov(ray);
        }
    }
    cut_short = cut_short || s < end;
    if (end == g.spp) {
        sum /= f32(g.spp);
    }
    output[slot] = PixelOut(sum, rays | select(0u, PIXEL_CUT_SHORT, cut_short));
}
