// wavefront.wgsl: the wavefront path. The work `main` does for a tile's
// pixels, cut into kernels that each do one kind of work for a queue of pixels:
// `wf_generate` starts every pixel's first sample; `wf_extend` finds the closest hit of
// each pixel's ray under way; `wf_shadow` traces each pixel's shadow ray under way;
// `wf_shade` shades the hits and the light samples they bring back, takes the next
// light sample, pushes reflected and refracted rays, starts the next sample, and writes
// the pixel out when its samples are done. Each kernel appends the pixels to the queue
// of the kernel they need next; `wf_advance_rays` and `wf_advance_shade` (one
// invocation each) turn the queues just filled into the next inputs and the indirect
// dispatch sizes, so that the host encodes rounds without reading anything back.
//
// A pixel's steps are those of `trace` and `direct` (and `resume`), in the same order
// with the same arithmetic, so its sum is the megakernel's to the bit; only which pixels
// run together changes: a warp traces rays alone, with no lanes idle in shading code or
// waiting on a neighbour's deeper ray tree. Each invocation does one traversal or one
// shading step, the bounded work lavapipe's loop limit and GPU watchdogs need.
// (CPU twin: src/cpu/wavefront.rs, the same kernels over the same queues, run one after
// another; the CPU renderer itself runs the same steps in one loop, `trace`.)

// Where a pixel of the wave stands: its samples so far, the sample under way (its
// colour, random stream and pending rays), the hit being shaded and its light so far,
// the ray `wf_extend` traces next, the light sample whose shadow ray `wf_shadow` traces,
// and what came back (src/gpu_types.rs: GpuWaveState).
struct WaveState {
    sum: vec3<f32>,
    sample: u32,
    colour: vec3<f32>,
    rng: u32,
    lit: vec3<f32>,
    rays: u32,
    point: vec3<f32>,
    sp: u32,
    ng: vec3<f32>,
    light: u32,
    ns: vec3<f32>,
    light_sample: u32,
    ray_in: Pending,
    shadow: LightRay,
    shadow_light: vec3<f32>,
    hit: Hit,
    material: u32,
    entering: u32,
    cut: u32,
    // What `wf_shade` has to do: PHASE_RAY, shade `hit`; PHASE_LIGHT, add the light
    // `shadow` brought back.
    phase: u32,
    counts: PixelCounts,
    stack: array<Pending, TRACE_STACK>,
}

// The wave's pixels, its queues and their lengths; and the sizes of the indirect
// dispatches, in a group of their own, bound only for the two kernels that write them
// (a buffer may not be storage and the source of a dispatch's size at once). Queue q (0:
// extend, 1: shadow, 2: shade) has two halves of arrayLength / 6 entries: kernels read
// the half `wave_counts[q]` names (its length in wave_counts[3 + q]) and append to the
// other (its length in wave_counts[6 + q]).
@group(2) @binding(0) var<storage, read_write> wave: array<WaveState>;
@group(2) @binding(1) var<storage, read_write> wave_queues: array<u32>;
@group(2) @binding(2) var<storage, read_write> wave_counts: array<atomic<u32>, 9>;
@group(3) @binding(0) var<storage, read_write> wave_args: array<u32, 9>;

fn wave_half(q: u32, next: bool) -> u32 {
    let size = arrayLength(&wave_queues) / 6u;
    let half = atomicLoad(&wave_counts[q]) ^ u32(next);
    return (2u * q + half) * size;
}

// Appends pixel `i` to queue q, for the kernel of the next round.
fn wave_push(q: u32, i: u32) {
    let k = atomicAdd(&wave_counts[6u + q], 1u);
    wave_queues[wave_half(q, true) + k] = i;
}

// The pixel of entry `k` of queue q, or none past its length.
fn wave_pixel(q: u32, k: u32) -> u32 {
    if (k >= atomicLoad(&wave_counts[3u + q])) {
        return NO_PRIM;
    }
    return wave_queues[wave_half(q, false) + k];
}

// The queue filled last becomes the input: its half, its length, its dispatch size.
fn wave_advance(q: u32) {
    atomicXor(&wave_counts[q], 1u);
    let n = atomicExchange(&wave_counts[6u + q], 0u);
    atomicStore(&wave_counts[3u + q], n);
    wave_args[3u * q] = (n + WORKGROUP_INVOCATIONS - 1u) / WORKGROUP_INVOCATIONS;
    wave_args[3u * q + 1u] = 1u;
    wave_args[3u * q + 2u] = 1u;
}

// Pixel i of the tile, as (x, y) in the image, and its slot in the band's output.
fn wave_xy(i: u32) -> vec3<u32> {
    let x = i % tile.width;
    let y = i / tile.width;
    return vec3<u32>(tile.x + x, tile.y + y, tile.out_base + y * tile.out_stride + x);
}

// Starts pixel i's sample `wave[i].sample`: its eye ray is the ray to extend.
fn wave_start_sample(i: u32) {
    let p = wave_xy(i);
    let s = wave[i].sample;
    var rng = rng_seed(p.y * globals.width + p.x, s, globals.seed);
    let off = sample_offset(s, globals.spp, &rng);
    let ray = camera_ray(f32(p.x) + off.x, f32(p.y) + off.y, &rng);
    wave[i].rng = rng;
    wave[i].rays += 1u;
    if (COUNTERS) {
        wave[i].counts.eye_rays += 1u;
    }
    wave[i].colour = vec3<f32>(0.0);
    wave[i].sp = 0u;
    wave[i].ray_in = Pending(ray.origin, ray.dir, 1.0, 1u, globals.hither);
    wave_push(0u, i);
}

// The next pending ray of pixel i's sample, or its next sample, or its output.
fn wave_next_ray(i: u32) {
    let sp = wave[i].sp;
    if (sp > 0u) {
        wave[i].sp = sp - 1u;
        wave[i].ray_in = wave[i].stack[sp - 1u];
        wave_push(0u, i);
        return;
    }
    wave[i].sum += wave[i].colour;
    wave[i].sample += 1u;
    if (wave[i].sample < tile.sample_start + tile.sample_count) {
        wave_start_sample(i);
        return;
    }
    let slot = wave_xy(i).z;
    let cut = wave[i].cut != 0u || cut_short;
    output[slot] = PixelOut(wave[i].sum, wave[i].rays | select(0u, PIXEL_CUT_SHORT, cut));
    if (COUNTERS) {
        counters[slot] = wave[i].counts;
    }
}

// Takes pixel i's next light sample that sends a shadow ray, to `wf_shadow`; once every
// light is sampled, adds the hit's light to the sample and pushes its reflected and
// refracted rays, as `trace` does.
fn wave_next_light(i: u32) {
    let s = Surface(wave[i].point, wave[i].ng, wave[i].ns, wave[i].entering != 0u, wave[i].material);
    let ray_in = wave[i].ray_in;
    let m = materials[s.material];
    let r = reflect_dir(ray_in.dir, s.ns);
    var li = wave[i].light;
    var k = wave[i].light_sample;
    var rng = wave[i].rng;
    for (; li < globals.n_lights; li++) {
        let light = lights[li];
        let samples = light_samples(light);
        for (; k < samples; k++) {
            let lr = light_ray(s, m, ray_in.dir, r, light, k, &rng);
            if (lr.traced != 0u) {
                wave[i].rng = rng;
                wave[i].light = li;
                wave[i].light_sample = k + 1u;
                wave[i].shadow = lr;
                wave_push(1u, i);
                return;
            }
        }
        k = 0u;
    }
    wave[i].rng = rng;
    wave[i].colour += ray_in.weight * wave[i].lit;
    if (ray_in.depth < globals.max_depth) {
        var sp = wave[i].sp;
        if (REFLECTION && m.ks > 0.0) {
            wave[i].rays += 1u;
            if (COUNTERS) {
                wave[i].counts.secondary_rays += 1u;
            }
            wave[i].stack[sp] = secondary(s, reflect_dir(ray_in.dir, s.ns), ray_in, m.ks);
            sp += 1u;
        }
        if (REFRACTION && m.t > 0.0) {
            wave[i].rays += 1u;
            if (COUNTERS) {
                wave[i].counts.secondary_rays += 1u;
            }
            wave[i].stack[sp] = secondary(s, refracted_dir(s, m, ray_in.dir), ray_in, m.t);
            sp += 1u;
        }
        wave[i].sp = sp;
    }
    wave_next_ray(i);
}

@compute @workgroup_size(WORKGROUP_INVOCATIONS, 1, 1)
fn wf_generate(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x;
    if (i >= tile.width * tile.height) {
        return;
    }
    let slot = wave_xy(i).z;
    let before = output[slot];
    wave[i].sum = before.color;
    wave[i].rays = before.rays & ~PIXEL_CUT_SHORT;
    wave[i].cut = u32((before.rays & PIXEL_CUT_SHORT) != 0u);
    if (COUNTERS) {
        wave[i].counts = counters[slot];
    }
    wave[i].sample = tile.sample_start;
    wave_start_sample(i);
}

@compute @workgroup_size(1, 1, 1)
fn wf_advance_rays() {
    wave_advance(0u);
    wave_advance(1u);
}

@compute @workgroup_size(1, 1, 1)
fn wf_advance_shade() {
    wave_advance(2u);
}

@compute @workgroup_size(WORKGROUP_INVOCATIONS, 1, 1)
fn wf_extend(
    @builtin(global_invocation_id) gid: vec3<u32>,
    @builtin(local_invocation_index) local_index: u32,
) {
    stack_base = local_index;
    let i = wave_pixel(0u, gid.x);
    if (i == NO_PRIM) {
        return;
    }
    let ray_in = wave[i].ray_in;
    let hit = closest_hit(Ray(ray_in.origin, ray_in.dir), ray_in.tmin, NO_HIT);
    wave[i].hit = hit;
    wave[i].phase = PHASE_RAY;
    if (COUNTERS) {
        if (ray_in.depth == 1u) {
            wave[i].counts.eye_nodes += fetched;
        } else {
            wave[i].counts.secondary_nodes += fetched;
        }
    }
    wave[i].cut |= u32(cut_short);
    wave_push(2u, i);
}

@compute @workgroup_size(WORKGROUP_INVOCATIONS, 1, 1)
fn wf_shadow(
    @builtin(global_invocation_id) gid: vec3<u32>,
    @builtin(local_invocation_index) local_index: u32,
) {
    stack_base = local_index;
    let i = wave_pixel(1u, gid.x);
    if (i == NO_PRIM) {
        return;
    }
    let lr = wave[i].shadow;
    wave[i].shadow_light = transmission(Ray(lr.origin, lr.dir), lr.dist);
    wave[i].phase = PHASE_LIGHT;
    if (COUNTERS) {
        wave[i].counts.shadow_rays += 1u;
        wave[i].counts.shadow_nodes += fetched;
    }
    wave[i].cut |= u32(cut_short);
    wave_push(2u, i);
}

@compute @workgroup_size(WORKGROUP_INVOCATIONS, 1, 1)
fn wf_shade(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = wave_pixel(2u, gid.x);
    if (i == NO_PRIM) {
        return;
    }
    if (wave[i].phase == PHASE_LIGHT) {
        // `light_sample`'s product, in its order, added as `direct` adds it.
        let lr = wave[i].shadow;
        wave[i].rays += 1u;
        wave[i].lit += wave[i].shadow_light * lr.intensity * lr.term;
        wave_next_light(i);
        return;
    }
    let ray_in = wave[i].ray_in;
    let hit = wave[i].hit;
    if (hit.prim == NO_PRIM) {
        wave[i].colour += ray_in.weight * globals.background;
        wave_next_ray(i);
        return;
    }
    let s = surface(Ray(ray_in.origin, ray_in.dir), hit);
    let m = materials[s.material];
    wave[i].point = s.point;
    wave[i].ng = s.ng;
    wave[i].ns = s.ns;
    wave[i].entering = u32(s.entering);
    wave[i].material = s.material;
    wave[i].lit = globals.ambient * m.kd * m.color;
    wave[i].light = 0u;
    wave[i].light_sample = 0u;
    wave_next_light(i);
}
