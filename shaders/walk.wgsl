// walk.wgsl: where a traversal of the BVH stands and its stack, shared by every walk
// (traverse.wgsl, cwide.wgsl; CPU twin: src/cpu/walk.rs).
//
// The traversal stacks live in workgroup memory, one slice of STACK entries per
// invocation (the CPU twin uses a local array of TRAVERSAL_STACK). On lavapipe a
// function-local array indexed at run time costs time in proportion to its length at
// every push and pop (halving it made traversal 1.6x faster); workgroup memory is indexed
// directly everywhere. STACK is what the scene's walk needs, at most TRAVERSAL_STACK:
// 64 invocations x 64 entries x 4 bytes = 16 KiB, the WebGPU minimum of
// max_compute_workgroup_storage_size; on a real GPU a smaller stack leaves room for more
// workgroups at once.
var<workgroup> traversal_stack: array<u32, WORKGROUP_INVOCATIONS * STACK>;
// First entry of this invocation's slice (set once in main).
var<private> stack_base: u32;

// Where a traversal stands: the node to visit next and how many nodes wait on its stack
// (this invocation's slice of traversal_stack). The compressed walk (CWIDE) keeps
// instead, in registers, the group of inner children it has still to visit of the node
// it entered last (its first child; its inner lanes << 8 | a bit per child reached, at
// `lane ^ octant`) and the primitives of that node's leaves the ray reached (the first;
// a bit each), and on the stack a group (two words) per level above.
struct Walk {
    node: u32,
    sp: u32,
    group: vec2<u32>,
    leaves: vec2<u32>,
    // The ray's octant: bit 2 set when it goes towards -x, bit 1 -y, bit 0 -z.
    octant: u32,
}

// The walk from the root: for the compressed walk, a group holding the root alone, as an
// inner child in lane 0.
fn start_walk(ray: Ray) -> Walk {
    let neg = ray.dir < vec3<f32>(0.0);
    let octant = (u32(neg.x) << 2u) | (u32(neg.y) << 1u) | u32(neg.z);
    return Walk(0u, 0u, vec2<u32>(0u, (1u << 8u) | (1u << octant)), vec2<u32>(0u), octant);
}

// Writes entry `k` of this invocation's stack slice.
fn stack_store(k: u32, entry: u32) {
    traversal_stack[k * WORKGROUP_INVOCATIONS + stack_base] = entry;
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

// Takes the group of children waiting on the compressed walk's stack; false when none is.
fn pop_group(walk: ptr<function, Walk>) -> bool {
    if ((*walk).sp == 0u) {
        return false;
    }
    (*walk).sp -= 1u;
    let k = 2u * (*walk).sp;
    (*walk).group = vec2<u32>(
        traversal_stack[k * WORKGROUP_INVOCATIONS + stack_base],
        traversal_stack[(k + 1u) * WORKGROUP_INVOCATIONS + stack_base],
    );
    return true;
}

// Goes on after a leaf's primitives: the next waiting node, or for the compressed walk,
// which holds what waits itself, simply on. False when the traversal is done.
fn walk_on(walk: ptr<function, Walk>) -> bool {
    if (CWIDE) {
        return true;
    }
    return pop(walk);
}
