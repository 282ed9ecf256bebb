//! CPU twin of `shaders/traverse.wgsl`: closest-hit and shadow (any-hit) traversal of the
//! flattened BVH with a fixed stack, near child first, plus the planes kept outside it.

use glam::{Vec3, Vec4};

use super::cwide::next_leaf_cwide;
use super::intersect;
use super::types::{Bindings, GpuWide, Hit, Ray};
use super::walk::{Walk, start_walk};
use crate::bvh::qwide;
use crate::gpu_types::{
    GpuNode, GpuQwideNode, GpuWideNode, NO_HIT, NO_PRIM, PLANE_FLAG, TRAVERSAL_SINGLE,
    WIDE_COUNT_MASK, WIDE_EMPTY, WIDE_FIRST_SHIFT, WIDE_LEAF,
};

/// First crossing of `(t0, t1)` inside `(tmin, tmax)`, or `NO_HIT`.
pub fn first_in(t: Vec4, tmin: f32, tmax: f32) -> f32 {
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
            let (near, reached) = intersect::slab4(n.lo, n.hi, ray.origin, inv_dir, tmin, tmax);
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

/// The nearest plane within `(tmin, tmax)`: its distance (`tmax` where none) and `prim`
/// (`NO_PRIM`). The planes' share of `closest_hit`, which the CPU's eight-wide walk
/// starts from too (`fast::wide_ray`).
#[inline(always)]
pub fn closest_plane(b: &Bindings, ray: &Ray, tmin: f32, tmax: f32) -> (f32, u32) {
    let (mut t_near, mut prim) = (tmax, NO_PRIM);
    for (i, pl) in b.planes.iter().enumerate() {
        let t = intersect::intersect_plane(pl, ray);
        if t > tmin && t < t_near {
            t_near = t;
            prim = PLANE_FLAG | i as u32;
        }
    }
    (t_near, prim)
}

/// The leaf's primitives `first..first + count` one at a time, the nearest kept in `hit`:
/// `closest_hit`'s loop, which the CPU's leaf test (`fast::leaf::closest_in_leaf`) falls
/// back to where it cannot take a leaf's primitives several at once.
#[inline(always)]
pub fn closest_in_prims(
    b: &Bindings,
    ray: &Ray,
    inv_dir: Vec3,
    (first, count): (u32, u32),
    tmin: f32,
    hit: &mut Hit,
) {
    for i in first..first + count {
        let t = intersect::intersect_prim(&b.prims[i as usize], ray, inv_dir);
        let t_first = first_in(t, tmin, hit.t);
        if t_first != NO_HIT {
            hit.t = t_first;
            hit.prim = i;
            hit.u = t.z;
            hit.v = t.w;
        }
    }
}

/// Nearest surface along the ray within `(tmin, tmax)`, through the binary tree a
/// primitive at a time, as the shader walks it (the CPU renders through its eight-wide
/// tree: `fast::wide_ray`).
pub fn closest_hit(b: &Bindings, ray: &Ray, tmin: f32, tmax: f32) -> Hit {
    let (t, prim) = closest_plane(b, ray, tmin, tmax);
    let mut hit = Hit {
        t,
        prim,
        u: 0.0,
        v: 0.0,
        cost: 0,
        nodes: 0,
    };
    if b.globals.n_nodes == 0 {
        return hit;
    }
    let inv_dir = intersect::safe_inverse(ray.dir);
    let mut walk = start_walk(ray);
    loop {
        let (first, count) = walk.next_leaf(b, ray, inv_dir, tmin, hit.t, &mut hit.cost);
        if count == 0 {
            break;
        }
        closest_in_prims(b, ray, inv_dir, (first, count), tmin, &mut hit);
        if !walk.walk_on(b) {
            break;
        }
    }
    hit.nodes = walk.fetched;
    hit
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
/// Adds the nodes the walk fetched to `nodes`. Through the binary tree, as the shader
/// walks it (the CPU renders through its eight-wide tree: `fast::wide_ray`).
pub fn transmission(b: &Bindings, ray: &Ray, tmax: f32, nodes: &mut u32) -> Vec3 {
    let Some(mut light) = transmit_planes(b, ray, tmax) else {
        return Vec3::ZERO;
    };
    if b.globals.n_nodes == 0 {
        return light;
    }
    let inv_dir = intersect::safe_inverse(ray.dir);
    let mut walk = start_walk(ray);
    let mut visited = 0;
    loop {
        let (first, count) = walk.next_leaf(b, ray, inv_dir, 0.0, tmax, &mut visited);
        if count == 0 {
            break;
        }
        for i in first..first + count {
            let p = &b.prims[i as usize];
            let t = intersect::intersect_prim(p, ray, inv_dir);
            let crossings = u32::from(t.x > 0.0 && t.x < tmax) + u32::from(t.y > 0.0 && t.y < tmax);
            if crossings > 0 {
                let m = &b.materials[p.material() as usize];
                if m.t <= 0.0 {
                    *nodes += walk.fetched;
                    return Vec3::ZERO;
                }
                for _ in 0..crossings {
                    light *= m.t * m.color;
                }
            }
        }
        if !walk.walk_on(b) {
            break;
        }
    }
    *nodes += walk.fetched;
    light
}
