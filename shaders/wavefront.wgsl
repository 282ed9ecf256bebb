// wavefront.wgsl: the wavefront path. A wave holds a tile's paths, one per pixel sample
// of the pass, and traces them a generation of rays at a time: round d takes every ray of
// depth d. `wf_generate` starts each path with its eye ray. A round then runs
// `wf_advance` (the rays written last round become the input), `wf_extend` (closest hits,
// and how many reflected and refracted rays each hit sends, summed over its workgroup),
// `wf_scan` (where each workgroup's rays of the next round begin), `wf_shade` (each
// hit's shadow rays, in a slot per light, and its rays of the next round, written in
// path order), `wf_advance_shadows`, `wf_shadow` (any hit: each shadow ray's light) and
// `wf_gather` (each path adds its rays' light, in queue order); `wf_finish` adds the
// paths' colours to their pixels in sample order. The host encodes a wave's rounds
// ahead, a fixed count of indirect dispatches, without reading anything back.
//
// The rays of a round stay in path order (a prefix sum places them, no atomic counter),
// so a path's rays are contiguous and one invocation adds their light: the sums are the
// same every run, with no float atomics (WGSL has none). A path adds its light a
// generation at a time, where the one kernel adds it depth first: the rays and their
// light are the same, the sums differ by rounding. A round keeps at most
// `WAVE_RAYS_PER_PATH` rays a path on average; a path whose rays do not fit is flagged
// cut short, and `resume` traces its pixel again.
//
// Area lights and emitters take the one kernel (`policy::wavefront_for`): their samples
// draw from a path's random stream in the depth-first order of its ray tree, which rounds
// by depth cannot follow. The wave's records and bindings, and the kernels' shared steps, are in
// wave.wgsl. (CPU twin: src/cpu/wavefront.rs, the same kernels run one after another.)

// Path p is sample `tile.sample_start + p % tile.sample_count` of pixel
// `p / tile.sample_count`: its eye ray is ray p of the first round.
@compute @workgroup_size(WORKGROUP_INVOCATIONS, 1, 1)
fn wf_generate(@builtin(global_invocation_id) gid: vec3<u32>) {
    let p = gid.x;
    let paths = tile.width * tile.height * tile.sample_count;
    if (p == 0u) {
        atomicStore(&wave_counts[WAVE_NEXT], paths);
    }
    if (p >= paths) {
        return;
    }
    let xy = wave_xy(p / tile.sample_count);
    let s = tile.sample_start + p % tile.sample_count;
    var rng: u32;
    let ray = sample_ray(xy.x, xy.y, s, &rng);
    var eye = PixelCounts();
    if (COUNTERS) {
        eye.eye_rays = 1u;
    }
    wave_paths[p] = WavePath(vec3<f32>(0.0), 1u, eye, u32(cut_short), 0u, 0u, 0u);
    wave_rays[wave_ray_index(1u, p)] = WaveRay(ray.origin, 1.0, ray.dir, p);
}

// The next round: the rays written last round are its input, and the dispatches over
// them are sized.
@compute @workgroup_size(1, 1, 1)
fn wf_advance() {
    atomicAdd(&wave_counts[WAVE_ROUND], 1u);
    let n = min(atomicExchange(&wave_counts[WAVE_NEXT], 0u), wave_capacity());
    atomicStore(&wave_counts[WAVE_RAYS], n);
    atomicStore(&wave_counts[WAVE_SHADOWS], 0u);
    wave_dispatch(0u, n);
}

// The closest hit of each ray of the round, and how many rays of the next round it sends,
// summed over the workgroup (an inclusive scan in workgroup memory): every invocation
// reaches the barriers, those past the round's rays with nothing to add.
@compute @workgroup_size(WORKGROUP_INVOCATIONS, 1, 1)
fn wf_extend(
    @builtin(global_invocation_id) gid: vec3<u32>,
    @builtin(local_invocation_index) local_index: u32,
    @builtin(workgroup_id) group: vec3<u32>,
) {
    stack_base = local_index;
    let k = gid.x;
    let d = atomicLoad(&wave_counts[WAVE_ROUND]);
    let n = atomicLoad(&wave_counts[WAVE_RAYS]);
    var children = 0u;
    if (k < n) {
        let r = wave_rays[wave_ray_index(d, k)];
        let tmin = select(0.0, globals.hither, d == 1u);
        let hit = closest_hit(Ray(r.origin, r.dir), tmin, NO_HIT);
        children = wave_children(d, hit);
        let flags = select(0u, WAVE_CUT, cut_short) | (children << WAVE_SENDS_SHIFT);
        wave_hits[k] = WaveHit(hit, fetched, flags, 0u, vec3<f32>(0.0));
    }
    wave_local[local_index] = children;
    for (var step = 1u; step < WORKGROUP_INVOCATIONS; step *= 2u) {
        workgroupBarrier();
        var add = 0u;
        if (local_index >= step) {
            add = wave_local[local_index - step];
        }
        workgroupBarrier();
        wave_local[local_index] += add;
    }
    if (k < n) {
        wave_hits[k].children = wave_local[local_index] - children;
    }
    if (local_index == WORKGROUP_INVOCATIONS - 1u) {
        wave_scan[group.x] = wave_local[local_index];
    }
}

// Turns the workgroups' totals of `wf_extend` into where each workgroup's rays of the next
// round begin (an exclusive scan: each invocation sums a run of workgroups, the runs'
// sums are scanned, and each run is scanned from its start), and counts the next round's
// rays. One workgroup.
@compute @workgroup_size(WORKGROUP_INVOCATIONS, 1, 1)
fn wf_scan(@builtin(local_invocation_index) local_index: u32) {
    let n = atomicLoad(&wave_counts[WAVE_RAYS]);
    let groups = (n + WORKGROUP_INVOCATIONS - 1u) / WORKGROUP_INVOCATIONS;
    let run = (groups + WORKGROUP_INVOCATIONS - 1u) / WORKGROUP_INVOCATIONS;
    let first = local_index * run;
    let end = min(first + run, groups);
    var total = 0u;
    for (var g = first; g < end; g++) {
        total += wave_scan[g];
    }
    wave_local[local_index] = total;
    workgroupBarrier();
    if (local_index == 0u) {
        var sum = 0u;
        for (var i = 0u; i < WORKGROUP_INVOCATIONS; i++) {
            let t = wave_local[i];
            wave_local[i] = sum;
            sum += t;
        }
        atomicStore(&wave_counts[WAVE_NEXT], sum);
    }
    workgroupBarrier();
    var at = wave_local[local_index];
    for (var g = first; g < end; g++) {
        let t = wave_scan[g];
        wave_scan[g] = at;
        at += t;
    }
}

// Shades the hit of each ray of the round: a shadow slot for every light, queued where the
// light is above the surface, and its reflected and refracted rays, where the next
// round's rays hold them (as `trace` pushes them: reflected first).
@compute @workgroup_size(WORKGROUP_INVOCATIONS, 1, 1)
fn wf_shade(@builtin(global_invocation_id) gid: vec3<u32>) {
    let k = gid.x;
    let d = atomicLoad(&wave_counts[WAVE_ROUND]);
    if (k >= atomicLoad(&wave_counts[WAVE_RAYS])) {
        return;
    }
    let hit = wave_hits[k].hit;
    if (hit.prim == NO_PRIM) {
        return;
    }
    let r = wave_rays[wave_ray_index(d, k)];
    let ray = Ray(r.origin, r.dir);
    let s = surface(ray, hit);
    let m = textured(materials[s.material], hit);
    wave_hits[k].ambient = unlit(s, m);
    let mirror = reflect_dir(ray.dir, s.ns);
    // Area lights and emitters take the one kernel: no light here draws from the random
    // stream.
    var rng = 0u;
    for (var li = 0u; li < globals.n_lights; li++) {
        let lr = light_ray(s, m, ray.dir, mirror, lights[li], 0u, &rng);
        let slot = k * globals.n_lights + li;
        let flags = select(0u, WAVE_TRACED, lr.traced != 0u);
        wave_shadows[slot] = WaveShadow(lr.origin, lr.dist, lr.dir, flags, lr.term, 0u);
        if (lr.traced != 0u) {
            wave_queue[atomicAdd(&wave_counts[WAVE_SHADOWS], 1u)] = slot;
        }
    }
    if (d >= globals.max_depth) {
        return;
    }
    let parent = Pending(r.origin, r.dir, r.weight, d, 0.0);
    var at = wave_child_index(k);
    if (REFLECTION && m.ks > 0.0) {
        if (at < wave_capacity()) {
            let c = secondary(s, mirror, parent, m.ks);
            wave_rays[wave_ray_index(d + 1u, at)] = WaveRay(c.origin, c.weight, c.dir, r.path);
        }
        at += 1u;
    }
    if (REFRACTION && m.t > 0.0 && at < wave_capacity()) {
        let c = secondary(s, refracted_dir(s, m, ray.dir), parent, m.t);
        wave_rays[wave_ray_index(d + 1u, at)] = WaveRay(c.origin, c.weight, c.dir, r.path);
    }
}

@compute @workgroup_size(1, 1, 1)
fn wf_advance_shadows() {
    wave_dispatch(3u, atomicLoad(&wave_counts[WAVE_SHADOWS]));
}

// What each queued shadow ray's light gives through the scene: its transmission times the
// light's intensity times the term, in `light_sample`'s order.
@compute @workgroup_size(WORKGROUP_INVOCATIONS, 1, 1)
fn wf_shadow(
    @builtin(global_invocation_id) gid: vec3<u32>,
    @builtin(local_invocation_index) local_index: u32,
) {
    stack_base = local_index;
    if (gid.x >= atomicLoad(&wave_counts[WAVE_SHADOWS])) {
        return;
    }
    let slot = wave_queue[gid.x];
    let sh = wave_shadows[slot];
    let light = lights[slot % globals.n_lights];
    let intensity = light.color / f32(light_samples(light));
    let shadow = transmission(Ray(sh.origin, sh.dir), sh.dist);
    wave_shadows[slot].light = shadow * intensity * sh.light;
    wave_shadows[slot].nodes = fetched;
    wave_shadows[slot].flags = sh.flags | select(0u, WAVE_CUT, cut_short);
}

// Each path adds its rays of the round (contiguous, in path order) to its colour: for a
// hit, the ambient term (from `wf_shade`) plus each light that came through, in light
// order, as `direct` sums them, times the ray's weight; for a miss, the background. The
// invocation of a path's first ray does it; the path's rays, counts, and whether its
// work was cut short (a walk cut short, or rays of the next round past the capacity) go
// with it.
@compute @workgroup_size(WORKGROUP_INVOCATIONS, 1, 1)
fn wf_gather(@builtin(global_invocation_id) gid: vec3<u32>) {
    let first = gid.x;
    let d = atomicLoad(&wave_counts[WAVE_ROUND]);
    let n = atomicLoad(&wave_counts[WAVE_RAYS]);
    if (first >= n) {
        return;
    }
    let p = wave_rays[wave_ray_index(d, first)].path;
    if (first > 0u && wave_rays[wave_ray_index(d, first - 1u)].path == p) {
        return;
    }
    var path = wave_paths[p];
    for (var k = first; k < n; k++) {
        // Field by field: lavapipe loads a whole struct read from a buffer, used or not.
        let at = wave_ray_index(d, k);
        if (wave_rays[at].path != p) {
            break;
        }
        let weight = wave_rays[at].weight;
        let prim = wave_hits[k].hit.prim;
        let sends = wave_hits[k].flags;
        path.cut |= u32((sends & WAVE_CUT) != 0u);
        if (COUNTERS) {
            if (d == 1u) {
                path.counts.eye_nodes += wave_hits[k].nodes;
            } else {
                path.counts.secondary_nodes += wave_hits[k].nodes;
            }
        }
        if (prim == NO_PRIM) {
            path.colour += weight * globals.background;
            continue;
        }
        var lit = wave_hits[k].ambient;
        for (var li = 0u; li < globals.n_lights; li++) {
            let slot = k * globals.n_lights + li;
            let flags = wave_shadows[slot].flags;
            if ((flags & WAVE_TRACED) != 0u) {
                path.rays += 1u;
                lit += wave_shadows[slot].light;
                path.cut |= u32((flags & WAVE_CUT) != 0u);
                if (COUNTERS) {
                    path.counts.shadow_rays += 1u;
                    path.counts.shadow_nodes += wave_shadows[slot].nodes;
                }
            }
        }
        path.colour += weight * lit;
        let children = sends >> WAVE_SENDS_SHIFT;
        path.rays += children;
        if (COUNTERS) {
            path.counts.secondary_rays += children;
        }
        path.cut |= u32(children > 0u && wave_child_index(k) + children > wave_capacity());
    }
    wave_paths[p] = path;
}

// Adds each pixel's paths to what the passes before left, in sample order, as `main`
// adds its samples, and writes it out.
@compute @workgroup_size(WORKGROUP_INVOCATIONS, 1, 1)
fn wf_finish(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x;
    if (i >= tile.width * tile.height) {
        return;
    }
    let slot = wave_xy(i).z;
    let before = output[slot];
    var sum = before.color;
    var rays = before.rays & ~PIXEL_CUT_SHORT;
    var cut = (before.rays & PIXEL_CUT_SHORT) != 0u;
    var total = PixelCounts();
    if (COUNTERS) {
        total = counters[slot];
    }
    for (var j = 0u; j < tile.sample_count; j++) {
        let path = wave_paths[i * tile.sample_count + j];
        sum += path.colour;
        rays += path.rays;
        cut = cut || path.cut != 0u;
        if (COUNTERS) {
            total.eye_rays += path.counts.eye_rays;
            total.eye_nodes += path.counts.eye_nodes;
            total.shadow_rays += path.counts.shadow_rays;
            total.shadow_nodes += path.counts.shadow_nodes;
            total.secondary_rays += path.counts.secondary_rays;
            total.secondary_nodes += path.counts.secondary_nodes;
        }
    }
    output[slot] = PixelOut(sum, rays | select(0u, PIXEL_CUT_SHORT, cut));
    if (COUNTERS) {
        counters[slot] = total;
    }
}
