// traverse.wgsl: closest-hit and shadow (any-hit) traversal of the flattened BVH with a
// fixed stack, near child first, plus the planes kept outside it
// (CPU twin: src/cpu/traverse.rs).
//
// The traversal stacks live in workgroup memory, one TRAVERSAL_STACK slice per invocation
// (the CPU twin uses a local array). On lavapipe a function-local array indexed at run
// time costs time in proportion to its length at every push and pop (halving it made
// traversal 1.6x faster); workgroup memory is indexed directly everywhere. 64 invocations
// x 64 entries x 4 bytes = 16 KiB, the WebGPU minimum of max_compute_workgroup_storage_size.
var<workgroup> traversal_stack: array<u32, WORKGROUP_INVOCATIONS * TRAVERSAL_STACK>;
// First entry of this invocation's slice (set once in main).
var<private> stack_base: u32;

fn first_in(t: vec4<f32>, tmin: f32, tmax: f32) -> f32 {
    if (t.x > tmin && t.x < tmax) {
        return t.x;
    } else if (t.y > tmin && t.y < tmax) {
        return t.y;
    }
    return NO_HIT;
}

// Where a traversal stands: the node to visit next and how many nodes wait on its stack
// (this invocation's slice of traversal_stack).
struct Walk {
    node: u32,
    sp: u32,
}

// Takes the next waiting node; false when the traversal is done.
fn pop(walk: ptr<function, Walk>) -> bool {
    if ((*walk).sp == 0u) {
        return false;
    }
    (*walk).sp -= 1u;
    (*walk).node = traversal_stack[(*walk).sp * WORKGROUP_INVOCATIONS + stack_base];
    return true;
}

// Walks on until the ray reaches a leaf whose box overlaps [tmin, tmax], entering the
// child nearer along the split axis first and pushing the other. Returns the leaf's
// (first primitive, count), count 0 when the tree is done; adds the nodes visited to
// `cost`. Every ray of a SIMD batch reaches a leaf before any tests primitives, so they
// test them together instead of taking turns (Aila & Laine's while-while traversal).
fn next_leaf(
    walk: ptr<function, Walk>,
    ray: Ray,
    inv_dir: vec3<f32>,
    tmin: f32,
    tmax: f32,
    cost: ptr<function, u32>,
) -> vec2<u32> {
    let neg = ray.dir < vec3<f32>(0.0);
    loop {
        let node = (*walk).node;
        let n = load_node(node);
        *cost += 1u;
        work += 1u;
        if (overlaps(n.min, n.max, ray.origin, inv_dir, tmin, tmax)) {
            let count = node_count(n);
            if (count > 0u) {
                return vec2<u32>(n.offset, count);
            }
            // Branch-free: lavapipe would run both arms of an `if`.
            let second_first = neg[node_axis(n)];
            traversal_stack[(*walk).sp * WORKGROUP_INVOCATIONS + stack_base] = select(n.offset, node + 1u, second_first);
            (*walk).node = select(node + 1u, n.offset, second_first);
            (*walk).sp += 1u;
        } else if (!pop(walk)) {
            return vec2<u32>(0u);
        }
    }
    // Reached only when the driver ends the loop.
    cut_short = true;
    return vec2<u32>(0u);
}

fn closest_hit(ray: Ray, tmin: f32, tmax: f32) -> Hit {
    var hit = Hit(tmax, NO_PRIM, 0.0, 0.0, 0u);
    if (PLANES) {
        var i = 0u;
        for (; i < globals.n_planes; i++) {
            let t = intersect_plane(planes[i], ray);
            if (t > tmin && t < hit.t) {
                hit.t = t;
                hit.prim = PLANE_FLAG | i;
            }
        }
        cut_short = cut_short || i < globals.n_planes;
    }
    if (globals.n_nodes == 0u) {
        return hit;
    }
    let inv_dir = safe_inverse(ray.dir);
    var walk = Walk(0u, 0u);
    // A pointer to hit.cost itself trips naga's SPIR-V writer (an uncached access).
    var cost = 0u;
    var done = false;
    loop {
        let leaf = next_leaf(&walk, ray, inv_dir, tmin, hit.t, &cost);
        if (leaf.y == 0u) {
            done = true;
            break;
        }
        var i = leaf.x;
        for (; i < leaf.x + leaf.y; i++) {
            work += 1u;
            let t = intersect_prim(i, ray, inv_dir);
            let t_first = first_in(t, tmin, hit.t);
            if (t_first != NO_HIT) {
                hit.t = t_first;
                hit.prim = i;
                hit.u = t.z;
                hit.v = t.w;
            }
        }
        cut_short = cut_short || i < leaf.x + leaf.y;
        if (!pop(&walk)) {
            done = true;
            break;
        }
    }
    cut_short = cut_short || !done;
    hit.cost = cost;
    return hit;
}

// Light reaching the end of the segment origin + t*dir, t in (0, tmax): an opaque occluder
// blocks it, each crossing of a transmitting surface multiplies it by T * C.
fn transmission(ray: Ray, tmax: f32) -> vec3<f32> {
    var light = vec3<f32>(1.0);
    if (PLANES) {
        var i = 0u;
        for (; i < globals.n_planes; i++) {
            let pl = planes[i];
            let t = intersect_plane(pl, ray);
            if (t > 0.0 && t < tmax) {
                let m = materials[pl.material];
                if (m.t <= 0.0) {
                    return vec3<f32>(0.0);
                }
                light *= m.t * m.color;
            }
        }
        cut_short = cut_short || i < globals.n_planes;
    }
    if (globals.n_nodes == 0u) {
        return light;
    }
    let inv_dir = safe_inverse(ray.dir);
    var walk = Walk(0u, 0u);
    var visited = 0u;
    var done = false;
    loop {
        let leaf = next_leaf(&walk, ray, inv_dir, 0.0, tmax, &visited);
        if (leaf.y == 0u) {
            done = true;
            break;
        }
        var i = leaf.x;
        for (; i < leaf.x + leaf.y; i++) {
            work += 1u;
            let t = intersect_prim(i, ray, inv_dir);
            let crossings = u32(t.x > 0.0 && t.x < tmax) + u32(t.y > 0.0 && t.y < tmax);
            if (crossings > 0u) {
                let m = materials[load_prim_tag(i) & PRIM_MATERIAL_MASK];
                if (m.t <= 0.0) {
                    return vec3<f32>(0.0);
                }
                var c = 0u;
                for (; c < crossings; c++) {
                    light *= m.t * m.color;
                }
                cut_short = cut_short || c < crossings;
            }
        }
        cut_short = cut_short || i < leaf.x + leaf.y;
        if (!pop(&walk)) {
            done = true;
            break;
        }
    }
    cut_short = cut_short || !done;
    return light;
}
