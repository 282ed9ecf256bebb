// pixel.wgsl: the compute entry point. One invocation per pixel of the current tile
// (workgroups of 8x8 pixels; the host dispatches one bounded tile at a time, a band of
// tiles per submission): camera rays (stratified, jittered samples and the thin lens,
// from the shared hash), traced and averaged, or an AOV (CPU twin: src/cpu/pixel.rs).
// `pooled` computes the same colours with a larger square of pixels a workgroup, shared
// out among its lanes, and `resume` finishes pixels a driver's loop limit cut short (both
// GPU only).

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
    let phi = 2.0 * PI * rand(rng);
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
    // Rows of k cells, the last row holding the rest (n - k * (rows - 1) cells): each row
    // is as tall as its share of the n cells, so every cell has area 1/n and the cells
    // tile the pixel (a k x rows grid with empty cells would shift the image).
    let row = s / k;
    let cells = min(k, n - row * k);
    let jx = rand(rng);
    let jy = rand(rng);
    return vec2<f32>((f32(s % k) + jx) / f32(cells), (f32(row * k) + jy * f32(cells)) / f32(n));
}

// The camera ray of sample s of pixel (px, py), with the sample's random stream seeded
// in `rng`, which the sample's shading goes on drawing from.
fn sample_ray(px: u32, py: u32, s: u32, rng: ptr<function, u32>) -> Ray {
    *rng = rng_seed(py * globals.width + px, s, globals.seed);
    let off = sample_offset(s, globals.spp, rng);
    return camera_ray(f32(px) + off.x, f32(py) + off.y, rng);
}

fn aov(ray: Ray) -> vec3<f32> {
    let fetched_before = fetched;
    let hit = closest_hit(ray, globals.hither, NO_HIT);
    if (COUNTERS) {
        count_nodes(1u, fetched - fetched_before);
    }
    if (AOV == AOV_COST) {
        return vec3<f32>(f32(hit.cost));
    }
    if (hit.prim == NO_PRIM) {
        return vec3<f32>(0.0);
    }
    if (AOV == AOV_DEPTH) {
        return vec3<f32>(hit.t);
    }
    if (AOV == AOV_UV) {
        return vec3<f32>(hit_uv(hit), 0.0);
    }
    return 0.5 * (surface(ray, hit).ns + vec3<f32>(1.0));
}

// The block of 8x8 pixels of the tile the workgroup `group` traces: workgroup i traces
// block i * scatter mod n (the host's `cut::scatter` spreads each software thread's run
// of workgroups over the whole tile).
fn workgroup_block(group: vec3<u32>, groups: vec3<u32>) -> u32 {
    let n = groups.x * groups.y;
    return (group.y * groups.x + group.x) * max(tile.scatter, 1u) % n;
}

// The pixel of the tile that invocation `q` of the workgroup tracing block `b` (of
// `groups_x` across) traces. Consecutive invocations cover 4x2 pixel blocks rather than
// rows of 8: the lanes a SIMD unit runs together then trace neighbouring, more coherent
// rays (and a 32-lane warp 8x4 pixels, `counters::WARP_PIXELS`).
fn block_pixel(b: u32, q: u32, groups_x: u32) -> vec2<u32> {
    let block = q / 8u;
    let lane = q % 8u;
    return vec2<u32>(
        (b % groups_x) * WORKGROUP_SIDE + (block % 2u) * 4u + lane % 4u,
        (b / groups_x) * WORKGROUP_SIDE + (block / 2u) * 2u + lane / 4u,
    );
}

@compute @workgroup_size(WORKGROUP_INVOCATIONS, 1, 1)
fn main(
    @builtin(workgroup_id) group: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) local_index: u32,
) {
    stack_base = local_index;
    let b = workgroup_block(group, groups);
    let id = block_pixel(b, local_index, groups.x);
    if (id.x >= tile.width || id.y >= tile.height) {
        return;
    }
    let px = tile.x + id.x;
    let py = tile.y + id.y;
    let g = globals;
    let slot = tile.out_base + id.y * tile.out_stride + id.x;
    // Each pass continues the sum the earlier passes of this band left (the host clears
    // the band first), in sample order, so the result does not depend on how the samples
    // were split. The host divides by the number of samples.
    let before = output[slot];
    var sum = before.color;
    var rays = before.rays & ~PIXEL_CUT_SHORT;
    cut_short = (before.rays & PIXEL_CUT_SHORT) != 0u;
    if (COUNTERS) {
        counts = counters[slot];
    }
    let end = tile.sample_start + tile.sample_count;
    var s = tile.sample_start;
    for (; s < end; s++) {
        var rng: u32;
        let ray = sample_ray(px, py, s, &rng);
        rays += 1u;
        if (COUNTERS) {
            counts.eye_rays += 1u;
        }
        if (AOV == AOV_COLOR) {
            sum += trace(ray, &rng, &rays);
        } else {
            sum += aov(ray);
        }
    }
    cut_short = cut_short || s < end;
    output[slot] = PixelOut(sum, rays | select(0u, PIXEL_CUT_SHORT, cut_short));
    if (COUNTERS) {
        counters[slot] = counts;
    }
}

// The pixel of the tile that pixel `p` of the square traced by workgroup `b` (of
// `groups_x` across, `blocks` 8x8 blocks a side) is under `pooled`: the square's blocks
// in row order, each laid out as `block_pixel` lays out a workgroup of `main`, so that
// pixels 0 to 63, each lane's first, are one block.
fn pool_pixel(b: u32, p: u32, groups_x: u32, blocks: u32) -> vec2<u32> {
    let sub = p / WORKGROUP_INVOCATIONS;
    let across = groups_x * blocks;
    let row = (b / groups_x) * blocks + sub / blocks;
    let block = row * across + (b % groups_x) * blocks + sub % blocks;
    return block_pixel(block, p % WORKGROUP_INVOCATIONS, across);
}

// The next pixel of a `pooled` workgroup's square to hand out (lanes take pixels in
// order, each its own first, 0 to 63, the rest from here), and a bit for each pixel that
// an earlier pass cut short.
var<workgroup> pool_next: atomic<u32>;
var<workgroup> pool_cut: array<atomic<u32>, POOL_MAX_SIDE * POOL_MAX_SIDE / 32u>;

// `main` for colour frames with a workgroup's pixels shared out among its lanes: a
// workgroup traces a square of `tile.group_side` pixels a side (`POOL_SIDE`, 4 pixels a
// lane), and a lane whose pixel is done takes the square's next one, so that a warp's
// lanes are not left idle while its mirror pixels reflect or a few of its hits cast
// shadow rays (docs/gpu.md, "Counters"). Every lane traces one ray a loop iteration. A
// pixel's samples are traced by one lane in sample order, and its sum and counts kept as
// `main` keeps them, so films, rays and counts are `main`'s to the bit.
@compute @workgroup_size(WORKGROUP_INVOCATIONS, 1, 1)
fn pooled(
    @builtin(workgroup_id) group: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) local_index: u32,
) {
    stack_base = local_index;
    let b = workgroup_block(group, groups);
    let g = globals;
    let blocks = max(tile.group_side, WORKGROUP_SIDE) / WORKGROUP_SIDE;
    let pixels = WORKGROUP_INVOCATIONS * blocks * blocks;
    let end = tile.sample_start + tile.sample_count;
    if (local_index == 0u) {
        atomicStore(&pool_next, WORKGROUP_INVOCATIONS);
    }
    for (var w = local_index; w < pixels / 32u; w += WORKGROUP_INVOCATIONS) {
        atomicStore(&pool_cut[w], 0u);
    }
    workgroupBarrier();
    // Every pixel of the square is cut short until a lane finishes it, so that one the
    // driver's loop limit (lavapipe's) leaves unfinished or never handed out is traced
    // again by `resume`, never left darker. Marked here, before any lane can have run
    // into the limit, which ends every later loop of the invocation.
    for (var p = local_index; p < pixels; p += WORKGROUP_INVOCATIONS) {
        let id = pool_pixel(b, p, groups.x, blocks);
        if (id.x < tile.width && id.y < tile.height) {
            let slot = tile.out_base + id.y * tile.out_stride + id.x;
            let r = output[slot].rays;
            if ((r & PIXEL_CUT_SHORT) != 0u) {
                atomicOr(&pool_cut[p / 32u], 1u << (p % 32u));
            }
            output[slot].rays = r | PIXEL_CUT_SHORT;
        }
    }
    // The marks are in storage memory, before another lane's own write of the same pixel.
    storageBarrier();
    workgroupBarrier();

    var stack: array<Pending, TRACE_STACK>;
    var sp = 0u;
    var colour = vec3<f32>(0.0);
    var rng = 0u;
    // The pixel under way (`pixels` when none), where its sum goes, the sample being
    // traced, and the pixel's sum and rays as `main` keeps them.
    var pixel = pixels;
    var slot = 0u;
    var s = 0u;
    var px = 0u;
    var py = 0u;
    var sum = vec3<f32>(0.0);
    var rays = 0u;
    var taken = local_index;
    loop {
        if (sp == 0u) {
            if (pixel < pixels) {
                // A sample done.
                sum += colour;
                s++;
                if (s >= end) {
                    output[slot] = PixelOut(sum, rays | select(0u, PIXEL_CUT_SHORT, cut_short));
                    if (COUNTERS) {
                        counters[slot] = counts;
                    }
                    pixel = pixels;
                    taken = atomicAdd(&pool_next, 1u);
                }
            }
            if (pixel == pixels) {
                if (taken >= pixels) {
                    break;
                }
                let id = pool_pixel(b, taken, groups.x, blocks);
                if (id.x >= tile.width || id.y >= tile.height) {
                    taken = atomicAdd(&pool_next, 1u);
                    continue;
                }
                pixel = taken;
                px = tile.x + id.x;
                py = tile.y + id.y;
                slot = tile.out_base + id.y * tile.out_stride + id.x;
                let before = output[slot];
                sum = before.color;
                rays = before.rays & ~PIXEL_CUT_SHORT;
                cut_short = ((atomicLoad(&pool_cut[pixel / 32u]) >> (pixel % 32u)) & 1u) != 0u;
                if (COUNTERS) {
                    counts = counters[slot];
                }
                s = tile.sample_start;
            }
            let eye = sample_ray(px, py, s, &rng);
            rays += 1u;
            if (COUNTERS) {
                counts.eye_rays += 1u;
            }
            stack[0] = Pending(eye.origin, eye.dir, 1.0, 1u, g.hither);
            sp = 1u;
            colour = vec3<f32>(0.0);
        }
        // One ray of the sample, as `trace` takes it.
        colour += trace_ray(&stack, &sp, &rng, &rays);
    }
}

// The same computation as `main` for pixels whose work did not fit one invocation, in
// steps that can stop and continue in the next dispatch: start a sample, trace one
// pending ray, take one light sample. The pixel's state lives in `resume_state` between
// dispatches; each dispatch runs until RESUME_BUDGET loop iterations, so lavapipe's loop
// limit is never reached. Every step does what `main`, `trace` and `direct` do, in the
// same order, so the result is the same to the bit. (GPU only: the CPU has no such limit.)
// tile.width: how many pixels; tile.x and tile.y: the samples [x, y) to trace, from a sum
// of zero (the host adds the result to what it holds); tile.sample_start: 0 on the first
// dispatch.
@compute @workgroup_size(WORKGROUP_INVOCATIONS, 1, 1)
fn resume(
    @builtin(global_invocation_id) gid: vec3<u32>,
    @builtin(local_invocation_index) local_index: u32,
) {
    stack_base = local_index;
    let i = gid.x;
    if (i >= tile.width) {
        return;
    }
    let g = globals;
    let px = resume_pixels[i] & RESUME_X_MASK;
    let py = resume_pixels[i] >> RESUME_Y_SHIFT;
    var st: PixelState;
    if (tile.sample_start == 0u) {
        st.sum = vec3<f32>(0.0);
        st.sample = tile.x;
        st.rays = 0u;
        st.phase = PHASE_SAMPLE;
        st.cut = 0u;
        st.counts = PixelCounts();
    } else {
        st = resume_state[i];
    }
    if (st.phase == PHASE_DONE) {
        return;
    }
    work = 0u;
    counts = st.counts;
    loop {
        if (work >= RESUME_BUDGET) {
            break;
        }
        work += 1u;
        if (st.phase == PHASE_SAMPLE) {
            if (st.sample == tile.y) {
                st.phase = PHASE_DONE;
                break;
            }
            var rng: u32;
            let ray = sample_ray(px, py, st.sample, &rng);
            st.rays += 1u;
            if (COUNTERS) {
                counts.eye_rays += 1u;
            }
            if (AOV != AOV_COLOR) {
                st.sum += aov(ray);
                st.sample += 1u;
                continue;
            }
            st.rng = rng;
            st.stack[0] = Pending(ray.origin, ray.dir, 1.0, 1u, g.hither);
            st.sp = 1u;
            st.colour = vec3<f32>(0.0);
            st.phase = PHASE_RAY;
        } else if (st.phase == PHASE_RAY) {
            if (st.sp == 0u) {
                st.sum += st.colour;
                st.sample += 1u;
                st.phase = PHASE_SAMPLE;
                continue;
            }
            st.sp -= 1u;
            let ray_in = st.stack[st.sp];
            let ray = Ray(ray_in.origin, ray_in.dir);
            let fetched_before = fetched;
            let hit = closest_hit(ray, ray_in.tmin, NO_HIT);
            if (COUNTERS) {
                count_nodes(ray_in.depth, fetched - fetched_before);
            }
            if (hit.prim == NO_PRIM) {
                st.colour += ray_in.weight * g.background;
                continue;
            }
            let s = surface(ray, hit);
            let m = textured(materials[s.material], hit);
            st.albedo = m.color;
            st.ray_in = ray_in;
            st.point = s.point;
            st.ng = s.ng;
            st.ns = s.ns;
            st.entering = u32(s.entering);
            st.material = s.material;
            st.lit = unlit(s, m);
            st.light = 0u;
            st.light_sample = 0u;
            st.phase = PHASE_LIGHT;
        } else {
            let s = Surface(st.point, st.ng, st.ns, st.entering != 0u, st.material);
            let ray_in = st.ray_in;
            var m = materials[s.material];
            m.color = st.albedo;
            if (st.light < g.n_lights) {
                let light = lights[st.light];
                let samples = light_samples(light);
                if (st.light_sample < samples) {
                    var rng = st.rng;
                    let c = light_sample(s, m, ray_in.dir, reflect_dir(ray_in.dir, s.ns), light, st.light_sample, &rng);
                    st.rng = rng;
                    st.lit += c.xyz;
                    if (c.w > 0.0) {
                        st.rays += 1u;
                    }
                    st.light_sample += 1u;
                }
                if (st.light_sample >= samples) {
                    st.light += 1u;
                    st.light_sample = 0u;
                }
                continue;
            }
            st.colour += ray_in.weight * st.lit;
            st.phase = PHASE_RAY;
            if (ray_in.depth >= g.max_depth) {
                continue;
            }
            if (REFLECTION && m.ks > 0.0) {
                st.rays += 1u;
                if (COUNTERS) {
                    counts.secondary_rays += 1u;
                }
                st.stack[st.sp] = secondary(s, reflect_dir(ray_in.dir, s.ns), ray_in, m.ks);
                st.sp += 1u;
            }
            if (REFRACTION && m.t > 0.0) {
                st.rays += 1u;
                if (COUNTERS) {
                    counts.secondary_rays += 1u;
                }
                st.stack[st.sp] = secondary(s, refracted_dir(s, m, ray_in.dir), ray_in, m.t);
                st.sp += 1u;
            }
        }
    }
    st.cut = st.cut | u32(cut_short);
    st.counts = counts;
    resume_state[i] = st;
    if (st.phase != PHASE_DONE) {
        atomicAdd(&resume_pending, 1u);
    }
}
