// traverse.wgsl: closest-hit and shadow (any-hit) traversal of the flattened BVH with a
// fixed stack, near child first, plus the planes kept outside it
// (CPU twin: src/cpu/traverse.rs).

fn first_in(t: vec4<f32>, tmin: f32, tmax: f32) -> f32 {
    if (t.x > tmin && t.x < tmax) {
        return t.x;
    } else if (t.y > tmin && t.y < tmax) {
        return t.y;
    }
    return NO_HIT;
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
    if (CWIDE) {
        return next_leaf_cwide(walk, ray, inv_dir, tmin, tmax, cost);
    }
    if (WIDE) {
        return next_leaf_wide(walk, ray, inv_dir, tmin, tmax, cost);
    }
    if (PAIRS) {
        return next_leaf_pairs(walk, ray, inv_dir, tmin, tmax, cost);
    }
    let neg = ray.dir < vec3<f32>(0.0);
    loop {
        let node = (*walk).node;
        let n = load_node(node);
        *cost += 1u;
        work += 1u;
        if (COUNTERS) {
            fetched += 1u;
        }
        if (overlaps(n.min, n.max, ray.origin, inv_dir, tmin, tmax)) {
            let count = node_count(n);
            if (count > 0u) {
                return vec2<u32>(n.offset, count);
            }
            // Branch-free: lavapipe would run both arms of an `if`.
            let second_first = neg[node_axis(n)];
            stack_store((*walk).sp, select(n.offset, node + 1u, second_first));
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

// `next_leaf` for TRAVERSAL_PAIRS: a node's two children are fetched and tested together
// and the nearer entry entered first, the other pushed; a popped node is fetched and tested
// again, against the nearest hit found since it was pushed. A ray waits on about half as
// many dependent fetches as with one node per step, which is what a hardware GPU waits
// on; lavapipe runs every lane through both children's tests and keeps one node per step.
// `cost` counts the boxes tested.
fn next_leaf_pairs(
    walk: ptr<function, Walk>,
    ray: Ray,
    inv_dir: vec3<f32>,
    tmin: f32,
    tmax: f32,
    cost: ptr<function, u32>,
) -> vec2<u32> {
    // The node to go on from: the root, or the node popped after the last leaf.
    var n = load_node((*walk).node);
    var live = overlaps(n.min, n.max, ray.origin, inv_dir, tmin, tmax);
    *cost += 1u;
    work += 1u;
    if (COUNTERS) {
        fetched += 1u;
    }
    loop {
        if (!live) {
            if (!pop(walk)) {
                return vec2<u32>(0u);
            }
            n = load_node((*walk).node);
            live = overlaps(n.min, n.max, ray.origin, inv_dir, tmin, tmax);
            *cost += 1u;
            work += 1u;
            if (COUNTERS) {
                fetched += 1u;
            }
            continue;
        }
        let count = node_count(n);
        if (count > 0u) {
            return vec2<u32>(n.offset, count);
        }
        let first = (*walk).node + 1u;
        let second = n.offset;
        let a = load_node(first);
        let b = load_node(second);
        *cost += 2u;
        work += 2u;
        if (COUNTERS) {
            fetched += 2u;
        }
        let ta = slab_entry(a.min, a.max, ray.origin, inv_dir, tmin, tmax);
        let tb = slab_entry(b.min, b.max, ray.origin, inv_dir, tmin, tmax);
        let hit_a = ta != NO_HIT;
        let hit_b = tb != NO_HIT;
        // Branch-free, as in `next_leaf`: enter b when it alone is hit or is nearer.
        let enter_b = hit_b && (!hit_a || tb < ta);
        stack_store((*walk).sp, select(second, first, enter_b));
        (*walk).sp += u32(hit_a && hit_b);
        (*walk).node = select(first, second, enter_b);
        n = Node(
            select(a.min, b.min, enter_b),
            select(a.offset, b.offset, enter_b),
            select(a.max, b.max, enter_b),
            select(a.count_axis, b.count_axis, enter_b),
        );
        live = hit_a || hit_b;
    }
    // Reached only when the driver ends the loop.
    cut_short = true;
    return vec2<u32>(0u);
}

// Orders two lanes of a wide node, (entry distance as bits, stack entry), nearer first;
// of two at the same distance the first stays first.
fn nearer_first(a: ptr<function, vec2<u32>>, b: ptr<function, vec2<u32>>) {
    let swap = bitcast<f32>((*b).x) < bitcast<f32>((*a).x);
    let near = select(*a, *b, swap);
    *b = select(*b, *a, swap);
    *a = near;
}

// Wide node `i` of the quantised tree (TRAVERSAL_QWIDE: four texels, src/gpu_types.rs:
// GpuQwideNode): the grid's origin and exponents, then each child's box a byte a lane and
// axis, low then high, then the entries; each grid line `origin + q * scale`, exact but for
// the add's rounding, so a fused multiply-add decodes the same.
fn qwide_node(i: u32) -> WideNode {
    let b = 4u * i;
    let head = node_texel(b);
    let q0 = node_texel(b + 1u);
    let q1 = node_texel(b + 2u);
    let o = bitcast<vec3<f32>>(head.xyz);
    let step = bitcast<vec3<f32>>(((vec3<u32>(head.w) >> vec3<u32>(0u, 8u, 16u)) & vec3<u32>(255u)) << vec3<u32>(23u));
    // No loop over the axes: lavapipe counts every loop iteration against its limit.
    let s = vec4<u32>(0u, 8u, 16u, 24u);
    let m = vec4<u32>(255u);
    return WideNode(
        array<vec4<f32>, 3>(
            vec4<f32>(o.x) + vec4<f32>((vec4<u32>(q0.x) >> s) & m) * step.x,
            vec4<f32>(o.y) + vec4<f32>((vec4<u32>(q0.y) >> s) & m) * step.y,
            vec4<f32>(o.z) + vec4<f32>((vec4<u32>(q0.z) >> s) & m) * step.z,
        ),
        array<vec4<f32>, 3>(
            vec4<f32>(o.x) + vec4<f32>((vec4<u32>(q0.w) >> s) & m) * step.x,
            vec4<f32>(o.y) + vec4<f32>((vec4<u32>(q1.x) >> s) & m) * step.y,
            vec4<f32>(o.z) + vec4<f32>((vec4<u32>(q1.y) >> s) & m) * step.z,
        ),
        node_texel(b + 3u),
    );
}

// `next_leaf` for TRAVERSAL_WIDE, over the four-wide tree (node_texels holds WideNodes):
// `walk.node` is a stack entry (WideNode::entry). A node's four boxes are tested
// together, the children reached are sorted by entry distance (a sorting network), the
// nearest is entered and the others pushed farthest first. A ray waits on half as many
// dependent fetches as with pairs. A leaf entry, entered or popped, is returned as it is:
// its box is not on hand to test again, so a popped leaf may be tested past the nearest
// hit. The pushes are branch-free: each writes the top slot and keeps it only when its
// lane was reached, so a node writes up to two slots past those it keeps
// (`bvh::wide::gpu_nodes` checks that the stack holds them). `cost` counts the boxes tested.
fn next_leaf_wide(
    walk: ptr<function, Walk>,
    ray: Ray,
    inv_dir: vec3<f32>,
    tmin: f32,
    tmax: f32,
    cost: ptr<function, u32>,
) -> vec2<u32> {
    let miss = bitcast<u32>(NO_HIT);
    loop {
        let e = (*walk).node;
        if ((e & WIDE_LEAF) != 0u) {
            return vec2<u32>((e & ~WIDE_LEAF) >> WIDE_FIRST_SHIFT, (e & WIDE_COUNT_MASK) + 1u);
        }
        var n: WideNode;
        if (QWIDE) {
            n = qwide_node(e);
        } else {
            n = load_wide_node(e);
        }
        *cost += 4u;
        work += 1u;
        if (COUNTERS) {
            fetched += 1u;
        }
        let slabs = slab4(n.lo, n.hi, ray.origin, inv_dir, tmin, tmax);
        // WGSL requires the parentheses (Chrome's compiler rejects a relational and a bitwise
        // operator side by side without them; naga reads them as here).
        let reached = slabs.reached & (n.entry != vec4<u32>(WIDE_EMPTY));
        let t = bitcast<vec4<u32>>(select(vec4<f32>(NO_HIT), slabs.near, reached));
        var a = vec2<u32>(t.x, n.entry.x);
        var b = vec2<u32>(t.y, n.entry.y);
        var c = vec2<u32>(t.z, n.entry.z);
        var d = vec2<u32>(t.w, n.entry.w);
        nearer_first(&a, &b);
        nearer_first(&c, &d);
        nearer_first(&a, &c);
        nearer_first(&b, &d);
        nearer_first(&b, &c);
        var sp = (*walk).sp;
        stack_store(sp, d.y);
        sp += u32(d.x != miss);
        stack_store(sp, c.y);
        sp += u32(c.x != miss);
        stack_store(sp, b.y);
        sp += u32(b.x != miss);
        (*walk).sp = sp;
        if (a.x != miss) {
            (*walk).node = a.y;
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
    var walk = start_walk(ray);
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
        if (!walk_on(&walk)) {
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
    var walk = start_walk(ray);
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
        if (!walk_on(&walk)) {
            done = true;
            break;
        }
    }
    cut_short = cut_short || !done;
    return light;
}
