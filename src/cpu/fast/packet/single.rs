//! A lane that walks on alone: where few of a packet's lanes reach a node, each walks the
//! node's subtree with the single-ray walk (`wide::walk_from`) from the hit it holds, and
//! hands its answer back to the packet (the hybrid traversal of Benthin's thesis and
//! Embree). A closest-hit lane tests its leaves as `traverse.rs`'s `closest_in_leaf` does,
//! but for noticing ties, which the packet's caller leaves to the single-ray walk itself;
//! a shadow lane crosses them through the single-ray walk's own `leaf::leaf_crossings`.

use glam::Vec3;

use super::rays::Occluded;
use crate::bvh::wide::{Link, Tree};
use crate::cpu::fast::leaf::{leaf_crossings, leaf_triangles4};
use crate::cpu::fast::wide::{self, Slabs};
use crate::cpu::intersect;
use crate::cpu::types::{Bindings, Ray};

/// One lane's nearest hit so far, as `Best` holds it in lanes.
#[derive(Clone, Copy, Debug)]
pub struct LaneHit {
    pub t: f32,
    pub prim: u32,
    pub u: f32,
    pub v: f32,
    pub tied: bool,
}

impl LaneHit {
    /// `Best::offer` for one lane: `t` is the first crossing past `tmin`; `t0` the walk's
    /// first interval end.
    #[inline]
    fn offer(&mut self, t: f32, (u, v): (f32, f32), prim: u32, tmin: f32, t0: f32) {
        if t > tmin {
            self.tied |= t == self.t && self.t < t0;
            if t < self.t {
                (self.t, self.prim, self.u, self.v) = (t, prim, u, v);
            }
        }
    }
}

/// The ray's walk of the subtree under wide node `node`, from the hit `h` it holds.
#[allow(clippy::too_many_arguments)]
pub fn closest_from(
    b: &Bindings,
    wide: &Tree,
    ray: &Ray,
    inv_dir: Vec3,
    (tmin, t0): (f32, f32),
    node: Link,
    h: &mut LaneHit,
    nodes: &mut u32,
) {
    let slabs = Slabs::new(ray.origin, inv_dir);
    wide::walk_from::<true>(wide, &slabs, node, tmin, h.t, nodes, |first, count| {
        let leaf = &b.prims[first as usize..(first + count) as usize];
        if let Some((t, u, v)) = leaf_triangles4(b, first, leaf, ray) {
            for k in 0..leaf.len() {
                h.offer(t[k], (u[k], v[k]), first + k as u32, tmin, t0);
            }
        } else {
            for i in first..first + count {
                let t = intersect::intersect_prim(&b.prims[i as usize], ray, inv_dir);
                let first_past = if t.x > tmin { t.x } else { t.y };
                h.offer(first_past, (t.z, t.w), i, tmin, t0);
            }
        }
        Some(h.t)
    });
}

/// The walk of lane `lane`'s shadow ray over `(0, tmax)` through the subtree under wide
/// node `node`: its crossings go into `out` (`Occluded::cross`), until one closes the lane.
#[allow(clippy::too_many_arguments)]
pub fn occluded_from(
    b: &Bindings,
    wide: &Tree,
    ray: &Ray,
    inv_dir: Vec3,
    tmax: f32,
    node: Link,
    lane: usize,
    out: &mut Occluded,
) {
    let slabs = Slabs::new(ray.origin, inv_dir);
    let bit = 1 << lane;
    let mut nodes = 0;
    wide::walk_from::<false>(wide, &slabs, node, 0.0, tmax, &mut nodes, |first, count| {
        let open = leaf_crossings(
            b,
            ray,
            inv_dir,
            (first, count),
            tmax,
            |prim, material, times| {
                out.cross(b, (prim, material), bit, if times == 2 { bit } else { 0 });
                out.open(bit) != 0
            },
        );
        open.then_some(tmax)
    });
    out.nodes += nodes;
}
