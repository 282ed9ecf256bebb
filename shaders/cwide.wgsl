// cwide.wgsl: the walk of the compressed eight-wide tree, TRAVERSAL_CWIDE
// (src/bvh/cwide.rs builds it; CPU twin: src/cpu/cwide.rs).

// Lanes `4 * half` to `4 * half + 3` of compressed node `n`: the inner children the ray
// reaches within [tmin, tmax], as bits at `lane ^ octant` (x), and the primitives of
// the leaves it reaches, as bits at their offsets from n.prim_base (y). Each box is
// decoded from its grid and tested as `next_leaf_wide` tests its four.
fn cwide_reached(n: CwideNode, half: u32, ray: Ray, inv_dir: vec3<f32>, tmin: f32, tmax: f32, octant: u32) -> vec2<u32> {
    let shifts = vec4<u32>(0u, 8u, 16u, 24u);
    let byte = vec4<u32>(255u);
    let sx = bitcast<f32>((n.exp_inner & 255u) << 23u);
    let sy = bitcast<f32>(((n.exp_inner >> 8u) & 255u) << 23u);
    let sz = bitcast<f32>(((n.exp_inner >> 16u) & 255u) << 23u);
    let qx0 = vec4<f32>((vec4<u32>(n.quant[0][half]) >> shifts) & byte);
    let qx1 = vec4<f32>((vec4<u32>(n.quant[0][2u + half]) >> shifts) & byte);
    let qy0 = vec4<f32>((vec4<u32>(n.quant[1][half]) >> shifts) & byte);
    let qy1 = vec4<f32>((vec4<u32>(n.quant[1][2u + half]) >> shifts) & byte);
    let qz0 = vec4<f32>((vec4<u32>(n.quant[2][half]) >> shifts) & byte);
    let qz1 = vec4<f32>((vec4<u32>(n.quant[2][2u + half]) >> shifts) & byte);
    let lo = array<vec4<f32>, 3>(n.origin.x + qx0 * sx, n.origin.y + qy0 * sy, n.origin.z + qz0 * sz);
    let hi = array<vec4<f32>, 3>(n.origin.x + qx1 * sx, n.origin.y + qy1 * sy, n.origin.z + qz1 * sz);
    let tag = (vec4<u32>(n.tags[half]) >> shifts) & byte;
    let reached = slab4(lo, hi, ray.origin, inv_dir, tmin, tmax).reached & (tag != vec4<u32>(0u));
    let lane = vec4<u32>(0u, 1u, 2u, 3u) + vec4<u32>(4u * half);
    let inner = select(vec4<u32>(0u), vec4<u32>(1u) << (lane ^ vec4<u32>(octant)), reached & (tag == vec4<u32>(CWIDE_INNER)));
    let count = tag >> vec4<u32>(CWIDE_COUNT_SHIFT);
    let prims = ((vec4<u32>(1u) << count) - vec4<u32>(1u)) << (tag & vec4<u32>(CWIDE_OFFSET_MASK));
    let leaves = select(vec4<u32>(0u), prims, reached & (count != vec4<u32>(0u)));
    return vec2<u32>(inner.x | inner.y | inner.z | inner.w, leaves.x | leaves.y | leaves.z | leaves.w);
}

// `next_leaf` for TRAVERSAL_CWIDE, over the compressed eight-wide tree (node_texels holds
// CwideNodes): hands over the primitives of the leaves reached at the node entered last,
// a run of consecutive ones at a time; then enters the next inner child of its group in
// the order of the ray's octant (`bvh::cwide` put each child in the lane of the octant
// that should meet it first), the rest of the group waiting on the stack, one entry a
// level; then a waiting group. A node's eight boxes are tested in two halves of four
// lanes. `cost` counts the boxes tested.
fn next_leaf_cwide(
    walk: ptr<function, Walk>,
    ray: Ray,
    inv_dir: vec3<f32>,
    tmin: f32,
    tmax: f32,
    cost: ptr<function, u32>,
) -> vec2<u32> {
    loop {
        let m = (*walk).leaves.y;
        if (m != 0u) {
            let first = firstTrailingBit(m);
            let rest = m >> first;
            let run = select(firstTrailingBit(~rest), 32u, rest == ~0u);
            (*walk).leaves.y = m & ~(((2u << (run - 1u)) - 1u) << first);
            return vec2<u32>((*walk).leaves.x + first, run);
        }
        let hits = (*walk).group.y & 255u;
        if (hits == 0u) {
            if (!pop_group(walk)) {
                return vec2<u32>(0u);
            }
            continue;
        }
        let bit = firstTrailingBit(hits);
        let group = vec2<u32>((*walk).group.x, (*walk).group.y & ~(1u << bit));
        let lane = bit ^ (*walk).octant;
        let node = group.x + countOneBits((group.y >> 8u) & ((1u << lane) - 1u));
        // Branch-free, as in `next_leaf_wide`: the rest of the group is written, and kept
        // when any of it is left.
        let k = 2u * (*walk).sp;
        stack_store(k, group.x);
        stack_store(k + 1u, group.y);
        (*walk).sp += u32((group.y & 255u) != 0u);
        let n = load_cwide_node(node);
        *cost += 8u;
        work += 1u;
        if (COUNTERS) {
            fetched += 1u;
        }
        let a = cwide_reached(n, 0u, ray, inv_dir, tmin, tmax, (*walk).octant);
        let b = cwide_reached(n, 1u, ray, inv_dir, tmin, tmax, (*walk).octant);
        (*walk).group = vec2<u32>(n.child_base, ((n.exp_inner >> 24u) << 8u) | a.x | b.x);
        (*walk).leaves = vec2<u32>(n.prim_base, a.y | b.y);
    }
    // Reached only when the driver ends the loop.
    cut_short = true;
    return vec2<u32>(0u);
}
