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

fn closest_hit(ray: Ray, tmin: f32, tmax: f32) -> Hit {
    var hit = Hit(tmax, NO_PRIM, 0.0, 0.0, 0u);
    if (PLANES) {
        for (var i = 0u; i < globals.n_planes; i++) {
            let t = intersect_plane(planes[i], ray);
            if (t > tmin && t < hit.t) {
                hit.t = t;
                hit.prim = PLANE_FLAG | i;
            }
        }
    }
    if (globals.n_nodes == 0u) {
        return hit;
    }
    let inv_dir = safe_inverse(ray.dir);
    let neg = ray.dir < vec3<f32>(0.0);
    var sp = 0u;
    var node = 0u;
    loop {
        // Descend until this ray reaches a leaf it overlaps: the rays of a SIMD batch then
        // test primitives together instead of taking turns (Aila & Laine's while-while).
        var first = 0u;
        var count = 0u;
        loop {
            let n = load_node(node);
            hit.cost += 1u;
            if (overlaps(n.min, n.max, ray.origin, inv_dir, tmin, hit.t)) {
                count = node_count(n);
                if (count > 0u) {
                    first = n.offset;
                    break;
                }
                // Visit the child nearer along the split axis first. Branch-free: lavapipe
                // would run both arms of an `if`.
                let second_first = neg[node_axis(n)];
                traversal_stack[stack_base + sp] = select(n.offset, node + 1u, second_first);
                node = select(node + 1u, n.offset, second_first);
                sp += 1u;
                continue;
            }
            if (sp == 0u) {
                break;
            }
            sp -= 1u;
            node = traversal_stack[stack_base + sp];
        }
        if (count == 0u) {
            break;
        }
        for (var i = first; i < first + count; i++) {
            let t = intersect_prim(i, ray, inv_dir);
            let t_first = first_in(t, tmin, hit.t);
            if (t_first != NO_HIT) {
                hit.t = t_first;
                hit.prim = i;
                hit.u = t.z;
                hit.v = t.w;
            }
        }
        if (sp == 0u) {
            break;
        }
        sp -= 1u;
        node = traversal_stack[stack_base + sp];
    }
    return hit;
}

// Light reaching the end of the segment origin + t*dir, t in (0, tmax): an opaque occluder
// blocks it, each crossing of a transmitting surface multiplies it by T * C.
fn transmission(ray: Ray, tmax: f32) -> vec3<f32> {
    var light = vec3<f32>(1.0);
    if (PLANES) {
        for (var i = 0u; i < globals.n_planes; i++) {
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
    }
    if (globals.n_nodes == 0u) {
        return light;
    }
    let inv_dir = safe_inverse(ray.dir);
    let neg = ray.dir < vec3<f32>(0.0);
    var sp = 0u;
    var node = 0u;
    loop {
        var first = 0u;
        var count = 0u;
        loop {
            let n = load_node(node);
            if (overlaps(n.min, n.max, ray.origin, inv_dir, 0.0, tmax)) {
                count = node_count(n);
                if (count > 0u) {
                    first = n.offset;
                    break;
                }
                let second_first = neg[node_axis(n)];
                traversal_stack[stack_base + sp] = select(n.offset, node + 1u, second_first);
                node = select(node + 1u, n.offset, second_first);
                sp += 1u;
                continue;
            }
            if (sp == 0u) {
                break;
            }
            sp -= 1u;
            node = traversal_stack[stack_base + sp];
        }
        if (count == 0u) {
            break;
        }
        for (var i = first; i < first + count; i++) {
            let t = intersect_prim(i, ray, inv_dir);
            let crossings = u32(t.x > 0.0 && t.x < tmax) + u32(t.y > 0.0 && t.y < tmax);
            if (crossings > 0u) {
                let m = materials[load_prim_tag(i) & PRIM_MATERIAL_MASK];
                if (m.t <= 0.0) {
                    return vec3<f32>(0.0);
                }
                for (var c = 0u; c < crossings; c++) {
                    light *= m.t * m.color;
                }
            }
        }
        if (sp == 0u) {
            break;
        }
        sp -= 1u;
        node = traversal_stack[stack_base + sp];
    }
    return light;
}
