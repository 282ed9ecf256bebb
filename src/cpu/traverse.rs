//! CPU twin of `shaders/traverse.wgsl`: closest-hit and shadow (any-hit) traversal of the
//! flattened BVH with a fixed stack, near child first, plus the planes kept outside it.

use glam::{Vec3, Vec4};

use super::cwide::next_leaf_cwide;
use super::intersect::{self, lanes_of};
#[cfg(target_arch = "x86_64")]
use super::isa;
use super::leaf::{crossings, leaf_triangles4, transmit_leaf};
use super::types::{Bindings, GpuWide, Hit, Ray};
use super::walk::{Walk, start_walk};
use super::wide::{self, Slabs};
use crate::bvh::qwide;
use crate::bvh::wide::WideNode;
use crate::gpu_types::{
    GpuNode, GpuQwideNode, GpuWideNode, NO_HIT, NO_PRIM, PLANE_FLAG, SLAB_WIDEN, TRAVERSAL_SINGLE,
    WIDE_COUNT_MASK, WIDE_EMPTY, WIDE_FIRST_SHIFT, WIDE_LEAF,
};

/// First crossing of `(t0, t1)` inside `(tmin, tmax)`, or `NO_HIT`.
fn first_in(t: Vec4, tmin: f32, tmax: f32) -> f32 {
    if t.x > tmin && t.x < tmax {
        t.x
    } else if t.y > tmin && t.y < tmax {
        t.y
    } else {
        NO_HIT
    }
}

impl Walk {
    /// Walks on until the ray reaches a leaf whose box overlaps `[tmin, tmax]`, entering
    /// the child nearer along the split axis first and pushing the other. Returns the
    /// leaf's (first primitive, count), count 0 when the tree is done; adds the nodes
    /// visited to `cost`. (The shader's SIMD batches then test primitives together; see
    /// traverse.wgsl.)
    fn next_leaf(
        &mut self,
        b: &Bindings,
        ray: &Ray,
        inv_dir: Vec3,
        tmin: f32,
        tmax: f32,
        cost: &mut u32,
    ) -> (u32, u32) {
        if let Some(cwide) = b.gpu_cwide {
            return next_leaf_cwide(self, cwide, ray, inv_dir, tmin, tmax, cost);
        }
        if let Some(wide) = b.gpu_wide {
            return self.next_leaf_wide(wide, ray, inv_dir, tmin, tmax, cost);
        }
        if b.globals.traversal != TRAVERSAL_SINGLE {
            return self.next_leaf_pairs(b, ray, inv_dir, tmin, tmax, cost);
        }
        let neg = [ray.dir.x < 0.0, ray.dir.y < 0.0, ray.dir.z < 0.0];
        loop {
            let node = self.node;
            let n = &b.nodes[node as usize];
            *cost += 1;
            self.fetched += 1;
            if intersect::overlaps(n.min, n.max, ray.origin, inv_dir, tmin, tmax) {
                let count = n.count();
                if count > 0 {
                    return (n.offset, count);
                }
                let second_first = neg[n.axis() as usize];
                self.stack_store(self.sp, if second_first { node + 1 } else { n.offset });
                self.node = if second_first { n.offset } else { node + 1 };
                self.sp += 1;
            } else if !self.pop() {
                return (0, 0);
            }
        }
    }

    /// `next_leaf` for `TRAVERSAL_PAIRS`: a node's two children are fetched and tested
    /// together and the nearer entry entered first, the other pushed; a popped node is
    /// tested again, against the nearest hit found since it was pushed. `cost` counts the
    /// boxes tested. (Why the GPU walks this way: traverse.wgsl.)
    fn next_leaf_pairs(
        &mut self,
        b: &Bindings,
        ray: &Ray,
        inv_dir: Vec3,
        tmin: f32,
        tmax: f32,
        cost: &mut u32,
    ) -> (u32, u32) {
        let overlaps =
            |n: &GpuNode| intersect::overlaps(n.min, n.max, ray.origin, inv_dir, tmin, tmax);
        // The node to go on from: the root, or the node popped after the last leaf.
        let mut n = &b.nodes[self.node as usize];
        let mut live = overlaps(n);
        *cost += 1;
        self.fetched += 1;
        loop {
            if !live {
                if !self.pop() {
                    return (0, 0);
                }
                n = &b.nodes[self.node as usize];
                live = overlaps(n);
                *cost += 1;
                self.fetched += 1;
                continue;
            }
            let count = n.count();
            if count > 0 {
                return (n.offset, count);
            }
            let (first, second) = (self.node + 1, n.offset);
            let (a, c) = (&b.nodes[first as usize], &b.nodes[second as usize]);
            *cost += 2;
            self.fetched += 2;
            let ta = intersect::slab_entry(a.min, a.max, ray.origin, inv_dir, tmin, tmax);
            let tc = intersect::slab_entry(c.min, c.max, ray.origin, inv_dir, tmin, tmax);
            let (hit_a, hit_c) = (ta != NO_HIT, tc != NO_HIT);
            let enter_c = hit_c && (!hit_a || tc < ta);
            // Written whatever the hits, as the shader does; kept when both are hit.
            self.stack_store(self.sp, if enter_c { first } else { second });
            self.sp += usize::from(hit_a && hit_c);
            (self.node, n) = if enter_c { (second, c) } else { (first, a) };
            live = hit_a || hit_c;
        }
    }

    /// Orders two lanes of a wide node, (entry distance as bits, stack entry), nearer
    /// first; of two at the same distance the first stays first.
    fn nearer_first(a: &mut (u32, u32), b: &mut (u32, u32)) {
        if f32::from_bits(b.0) < f32::from_bits(a.0) {
            std::mem::swap(a, b);
        }
    }

    /// Wide node `i` of the quantised tree, decoded as the shader decodes it
    /// (`bvh::qwide::decode`).
    fn qwide_node(nodes: &[GpuQwideNode], i: u32) -> GpuWideNode {
        qwide::decode(&nodes[i as usize])
    }

    /// `next_leaf` for `TRAVERSAL_WIDE` and `TRAVERSAL_QWIDE`, over the GPU's four-wide
    /// tree (its nodes decoded as they are fetched for the latter): `node` is a stack
    /// entry (`GpuWideNode::entry`). A node's four boxes are tested together, the children
    /// reached sorted by entry distance, the nearest entered and the others pushed
    /// farthest first; a leaf entry, entered or popped, is returned untested. The pushes
    /// are the shader's, branch-free (each writes the top slot, kept only when its lane
    /// was reached). `cost` counts the boxes tested. (Why the GPU walks this way:
    /// traverse.wgsl.)
    fn next_leaf_wide(
        &mut self,
        wide: GpuWide,
        ray: &Ray,
        inv_dir: Vec3,
        tmin: f32,
        tmax: f32,
        cost: &mut u32,
    ) -> (u32, u32) {
        let miss = NO_HIT.to_bits();
        loop {
            let e = self.node;
            if e & WIDE_LEAF != 0 {
                return (
                    (e & !WIDE_LEAF) >> WIDE_FIRST_SHIFT,
                    (e & WIDE_COUNT_MASK) + 1,
                );
            }
            let n = &match wide {
                GpuWide::Plain(nodes) => nodes[e as usize],
                GpuWide::Quantised(nodes) => Self::qwide_node(nodes, e),
            };
            *cost += 4;
            self.fetched += 1;
            // `intersect::slab` for the four boxes, lane by lane the same arithmetic.
            let o = ray.origin;
            let (x0, x1) = ((n.lo[0] - o.x) * inv_dir.x, (n.hi[0] - o.x) * inv_dir.x);
            let (y0, y1) = ((n.lo[1] - o.y) * inv_dir.y, (n.hi[1] - o.y) * inv_dir.y);
            let (z0, z1) = ((n.lo[2] - o.z) * inv_dir.z, (n.hi[2] - o.z) * inv_dir.z);
            let near = x0
                .min(x1)
                .max(y0.min(y1))
                .max(z0.min(z1))
                .max(Vec4::splat(tmin));
            let far = x0
                .max(x1)
                .min(y0.max(y1))
                .min(z0.max(z1))
                .min(Vec4::splat(tmax));
            let reached = near.cmple(far * SLAB_WIDEN).bitmask();
            let lane = |l: usize| {
                let hit = reached & (1 << l) != 0 && n.entry[l] != WIDE_EMPTY;
                (if hit { near[l].to_bits() } else { miss }, n.entry[l])
            };
            let [mut a, mut b, mut c, mut d] = [lane(0), lane(1), lane(2), lane(3)];
            Self::nearer_first(&mut a, &mut b);
            Self::nearer_first(&mut c, &mut d);
            Self::nearer_first(&mut a, &mut c);
            Self::nearer_first(&mut b, &mut d);
            Self::nearer_first(&mut b, &mut c);
            for (t, entry) in [d, c, b] {
                self.stack_store(self.sp, entry);
                self.sp += usize::from(t != miss);
            }
            if a.0 != miss {
                self.node = a.1;
            } else if !self.pop() {
                return (0, 0);
            }
        }
    }
}

/// Tests the leaf's primitives `first..first + count`, keeping the nearest in `hit`.
#[inline(always)]
fn closest_in_leaf(
    b: &Bindings,
    ray: &Ray,
    inv_dir: Vec3,
    first: u32,
    count: u32,
    tmin: f32,
    hit: &mut Hit,
) {
    let leaf = &b.prims[first as usize..(first + count) as usize];
    if let Some((t, u, v)) = leaf_triangles4(b, first, leaf, ray) {
        // Four lanes at once, then those in the interval taken in order, as the loop below
        // would (most leaves have none; `hit.t` only shrinks, so no other lane can pass).
        for k in lanes_of(crossings(t, tmin, hit.t, leaf.len())) {
            if t[k] < hit.t {
                hit.t = t[k];
                hit.prim = first + k as u32;
                hit.u = u[k];
                hit.v = v[k];
            }
        }
        return;
    }
    if let Some((t0, t1)) = intersect::intersect_spheres4(leaf, ray) {
        // Four spheres at once, then taken in order, as the loop below would.
        for k in 0..leaf.len() {
            let t_first = first_in(Vec4::new(t0[k], t1[k], 0.0, 0.0), tmin, hit.t);
            if t_first != NO_HIT {
                hit.t = t_first;
                hit.prim = first + k as u32;
                (hit.u, hit.v) = (0.0, 0.0);
            }
        }
        return;
    }
    for i in first..first + count {
        let p = &b.prims[i as usize];
        let t = intersect::intersect_prim(p, ray, inv_dir);
        let t_first = first_in(t, tmin, hit.t);
        if t_first != NO_HIT {
            hit.t = t_first;
            hit.prim = i;
            hit.u = t.z;
            hit.v = t.w;
        }
    }
}

/// Nearest surface along the ray within `(tmin, tmax)`.
pub fn closest_hit(b: &Bindings, ray: &Ray, tmin: f32, tmax: f32) -> Hit {
    let mut hit = Hit {
        t: tmax,
        prim: NO_PRIM,
        u: 0.0,
        v: 0.0,
        cost: 0,
        nodes: 0,
    };
    for (i, pl) in b.planes.iter().enumerate() {
        let t = intersect::intersect_plane(pl, ray);
        if t > tmin && t < hit.t {
            hit.t = t;
            hit.prim = PLANE_FLAG | i as u32;
        }
    }
    if b.globals.n_nodes == 0 {
        return hit;
    }
    if let Some(wide) = b.wide {
        // The planes' answer goes over as its two values, not as the `Hit` just written:
        // read back whole, in other widths than its fields were written in, it stalled
        // on store forwarding.
        let planes = (hit.t, hit.prim);
        #[cfg(target_arch = "x86_64")]
        if isa::x86_64_v3() {
            // SAFETY: the processor has the features the function is compiled for.
            return unsafe { closest_wide_v3(b, wide, ray, tmin, planes) };
        }
        let inv_dir = intersect::safe_inverse(ray.dir);
        let slabs = Slabs::new(ray.origin, inv_dir);
        return closest_wide(b, wide, ray, (inv_dir, &slabs), tmin, planes);
    }
    let inv_dir = intersect::safe_inverse(ray.dir);
    let mut walk = start_walk(ray);
    loop {
        let (first, count) = walk.next_leaf(b, ray, inv_dir, tmin, hit.t, &mut hit.cost);
        if count == 0 {
            break;
        }
        closest_in_leaf(b, ray, inv_dir, first, count, tmin, &mut hit);
        if !walk.walk_on(b) {
            break;
        }
    }
    hit.nodes = walk.fetched;
    hit
}

/// `closest_hit` through the CPU's eight-wide tree (`wide.rs`), the planes done (the
/// nearest plane's distance, or `tmax`, and its `prim`), with the slab test `slabs`:
/// inlined whole into its callers, so that `closest_wide_v3` is the same walk in AVX's
/// encoding.
#[inline(always)]
fn closest_wide(
    b: &Bindings,
    wide: &[WideNode],
    ray: &Ray,
    (inv_dir, slabs): (Vec3, &impl wide::Boxes),
    tmin: f32,
    (tmax, prim): (f32, u32),
) -> Hit {
    let mut hit = Hit {
        t: tmax,
        prim,
        u: 0.0,
        v: 0.0,
        cost: 0,
        nodes: 0,
    };
    let mut nodes = 0;
    // The closure inlined too: called once a leaf, it would otherwise stay a call.
    wide::walk::<true>(
        wide,
        slabs,
        tmin,
        tmax,
        &mut nodes,
        #[inline(always)]
        |first, count| {
            closest_in_leaf(b, ray, inv_dir, first, count, tmin, &mut hit);
            Some(hit.t)
        },
    );
    // Built whole, `nodes` from its register: writing it into `hit` and returning that
    // made the copy out read it back in one load with `cost`, which stalls on the store
    // just made (store forwarding), a twentieth of a walk.
    Hit {
        t: hit.t,
        prim: hit.prim,
        u: hit.u,
        v: hit.v,
        cost: hit.cost,
        nodes,
    }
}

/// `closest_wide` compiled for x86-64-v3 (`isa::x86_64_v3`), eight boxes in one AVX
/// register (`wide::SlabsAvx`) and the rest in three-operand VEX form: 7 to 10% fewer
/// instructions a walk. Rust never fuses a multiply and an add, so FMA changes no
/// result: the bits are the baseline's.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma,bmi1,bmi2,lzcnt,popcnt")]
fn closest_wide_v3(
    b: &Bindings,
    wide: &[WideNode],
    ray: &Ray,
    tmin: f32,
    planes: (f32, u32),
) -> Hit {
    let inv_dir = intersect::safe_inverse(ray.dir);
    // SAFETY: the function's features include AVX.
    let slabs = unsafe { wide::SlabsAvx::new(Slabs::new(ray.origin, inv_dir)) };
    closest_wide(b, wide, ray, (inv_dir, &slabs), tmin, planes)
}

/// `transmission` through the eight-wide tree, the planes' factor `light` done; inlined
/// as `closest_wide` is.
#[inline(always)]
fn transmission_wide(
    b: &Bindings,
    wide: &[WideNode],
    ray: &Ray,
    (inv_dir, slabs): (Vec3, &impl wide::Boxes),
    (tmax, nodes): (f32, &mut u32),
    mut light: Vec3,
) -> Vec3 {
    let mut blocked = false;
    wide::walk::<false>(
        wide,
        slabs,
        0.0,
        tmax,
        nodes,
        #[inline(always)]
        |first, count| {
            blocked = !transmit_leaf(b, ray, inv_dir, (first, count), tmax, &mut light);
            (!blocked).then_some(tmax)
        },
    );
    if blocked { Vec3::ZERO } else { light }
}

/// `transmission_wide` compiled for x86-64-v3, as `closest_wide_v3` is.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma,bmi1,bmi2,lzcnt,popcnt")]
fn transmission_wide_v3(
    b: &Bindings,
    wide: &[WideNode],
    ray: &Ray,
    tmax: f32,
    nodes: &mut u32,
    light: Vec3,
) -> Vec3 {
    let inv_dir = intersect::safe_inverse(ray.dir);
    // SAFETY: as in `closest_wide_v3`.
    let slabs = unsafe { wide::SlabsAvx::new(Slabs::new(ray.origin, inv_dir)) };
    transmission_wide(b, wide, ray, (inv_dir, &slabs), (tmax, nodes), light)
}

/// Stack entries the GPU's walk (`b.globals.traversal`) writes for a ray that visits every
/// leaf it overlaps in `(tmin, tmax)` without narrowing the interval: at least what its
/// closest-hit and shadow walks write, which the shader's stack slice must hold (checked
/// against `SceneBuffers::stack_entries` by the tests).
pub fn stack_high_water(b: &Bindings, ray: &Ray, tmin: f32, tmax: f32) -> usize {
    if b.globals.n_nodes == 0 {
        return 0;
    }
    let inv_dir = intersect::safe_inverse(ray.dir);
    let mut walk = start_walk(ray);
    let mut cost = 0;
    while walk.next_leaf(b, ray, inv_dir, tmin, tmax, &mut cost).1 > 0 && walk.walk_on(b) {}
    walk.high
}

/// The planes' share of `transmission`, which tests them first: the product of their
/// crossings' factors, `None` when an opaque one blocks the segment.
pub fn transmit_planes(b: &Bindings, ray: &Ray, tmax: f32) -> Option<Vec3> {
    let mut light = Vec3::ONE;
    for pl in b.planes {
        let t = intersect::intersect_plane(pl, ray);
        if t > 0.0 && t < tmax {
            let m = &b.materials[pl.material as usize];
            if m.t <= 0.0 {
                return None;
            }
            light *= m.t * m.color;
        }
    }
    Some(light)
}

/// Light reaching the end of the segment `origin + t*dir, t in (0, tmax)`: an opaque
/// occluder blocks it, each crossing of a transmitting surface multiplies it by `T * C`.
/// Adds the nodes the walk fetched to `nodes`.
pub fn transmission(b: &Bindings, ray: &Ray, tmax: f32, nodes: &mut u32) -> Vec3 {
    let Some(mut light) = transmit_planes(b, ray, tmax) else {
        return Vec3::ZERO;
    };
    if b.globals.n_nodes == 0 {
        return light;
    }
    if let Some(wide) = b.wide {
        #[cfg(target_arch = "x86_64")]
        if isa::x86_64_v3() {
            // SAFETY: as in `closest_hit`.
            return unsafe { transmission_wide_v3(b, wide, ray, tmax, nodes, light) };
        }
        let inv_dir = intersect::safe_inverse(ray.dir);
        let slabs = Slabs::new(ray.origin, inv_dir);
        return transmission_wide(b, wide, ray, (inv_dir, &slabs), (tmax, nodes), light);
    }
    let inv_dir = intersect::safe_inverse(ray.dir);
    let mut walk = start_walk(ray);
    let mut visited = 0;
    loop {
        let (first, count) = walk.next_leaf(b, ray, inv_dir, 0.0, tmax, &mut visited);
        if count == 0 {
            break;
        }
        if !transmit_leaf(b, ray, inv_dir, (first, count), tmax, &mut light) {
            *nodes += walk.fetched;
            return Vec3::ZERO;
        }
        if !walk.walk_on(b) {
            break;
        }
    }
    *nodes += walk.fetched;
    light
}
