//! A leaf's primitives against one ray, for the CPU's single-ray walks of either tree
//! (`traverse.rs`) and the packets' lanes that walk alone (`packet/single.rs`): four
//! triangles at once from the leaf's block, and the surfaces a shadow ray crosses in the
//! order `transmission` multiplies their factors, and the closest hit in a leaf
//! (`closest_in_leaf`, with traverse.wgsl's `first_in` from its twin).

use glam::{Vec3, Vec4};

use crate::cpu::intersect::{self, lanes_of};
use crate::cpu::traverse::{closest_in_prims, first_in};
use crate::cpu::types::{Bindings, Hit, Ray};
use crate::gpu_types::{GpuPrim, NO_HIT};

/// The lanes of the first `len` whose `t` lies in `(tmin, tmax)`, a bit each.
#[inline(always)]
pub(crate) fn crossings(t: Vec4, tmin: f32, tmax: f32, len: usize) -> u32 {
    let inside = t.cmpgt(Vec4::splat(tmin)) & t.cmplt(Vec4::splat(tmax));
    inside.bitmask() & ((1 << len) - 1)
}

/// `intersect_triangles4` of the leaf `leaf` starting at primitive `first`: from its
/// block where the scene has one (`bvh::blocks`, made once), else gathered from `leaf`.
/// Every single-ray walk of the CPU's leaves tests them here.
#[inline(always)]
pub(crate) fn leaf_triangles4(
    b: &Bindings,
    first: u32,
    leaf: &[GpuPrim],
    ray: &Ray,
) -> Option<(Vec4, Vec4, Vec4)> {
    match b
        .blocks
        .and_then(|blocks| blocks.get(first, leaf.len() as u32))
    {
        Some(block) => Some(intersect::triangles4(&block, ray)),
        None => intersect::intersect_triangles4(leaf, ray),
    }
}

/// Each primitive of the leaf that the segment `(0, tmax)` crosses, in the order
/// `transmission` multiplies their factors, and how many times (a sphere or a cone can be
/// passed through): `cross(prim, material, times)`, until it returns false; false when it
/// did.
/// The packets' lone shadow lanes (`packet/single.rs`) cross leaves here too.
#[inline(always)]
pub(crate) fn leaf_crossings(
    b: &Bindings,
    ray: &Ray,
    inv_dir: Vec3,
    (first, count): (u32, u32),
    tmax: f32,
    cross: impl FnMut(u32, u32, u32) -> bool,
) -> bool {
    let leaf = &b.prims[first as usize..(first + count) as usize];
    let triangles = leaf_triangles4(b, first, leaf, ray);
    crossings_of((ray, inv_dir), (first, leaf), triangles, tmax, cross)
}

/// Whether the opaque primitive `prim` blocks the segment `(0, tmax)`: `leaf_crossings`'
/// test of it alone, from the primitive itself (its leaf's block, which it may share with
/// others, holds it in another lane).
#[inline(always)]
pub(crate) fn blocks(b: &Bindings, ray: &Ray, inv_dir: Vec3, prim: u32, tmax: f32) -> bool {
    let leaf = &b.prims[prim as usize..prim as usize + 1];
    let triangles = intersect::intersect_triangles4(leaf, ray);
    let opaque = |material: u32| b.materials[material as usize].t <= 0.0;
    !crossings_of((ray, inv_dir), (prim, leaf), triangles, tmax, |_, m, _| {
        !opaque(m)
    })
}

/// `leaf_crossings` of the primitives `leaf`, the first of them `first`, with the four
/// triangles' distances `triangles` where the leaf is of triangles.
#[inline(always)]
fn crossings_of(
    (ray, inv_dir): (&Ray, Vec3),
    (first, leaf): (u32, &[GpuPrim]),
    triangles: Option<(Vec4, Vec4, Vec4)>,
    tmax: f32,
    mut cross: impl FnMut(u32, u32, u32) -> bool,
) -> bool {
    // Loops, not `Iterator::all`, which the compiler leaves out of line, where it loses
    // the single-ray walk's instruction set (`closest_wide_v3`).
    if let Some((t, _, _)) = triangles {
        // As in `closest_in_leaf`: four at once, then in order. A triangle is crossed once.
        for k in lanes_of(crossings(t, 0.0, tmax, leaf.len())) {
            if !cross(first + k as u32, leaf[k].material(), 1) {
                return false;
            }
        }
        return true;
    }
    if let Some((t0, t1)) = intersect::intersect_spheres4(leaf, ray) {
        // Four spheres at once, then in order, as the loop below would.
        let in0 = crossings(t0, 0.0, tmax, leaf.len());
        let in1 = crossings(t1, 0.0, tmax, leaf.len());
        for k in lanes_of(in0 | in1) {
            let times = (in0 >> k & 1) + (in1 >> k & 1);
            if !cross(first + k as u32, leaf[k].material(), times) {
                return false;
            }
        }
        return true;
    }
    for (i, p) in (first..).zip(leaf) {
        let t = intersect::intersect_prim(p, ray, inv_dir);
        let times = (t.x > 0.0 && t.x < tmax) as u32 + (t.y > 0.0 && t.y < tmax) as u32;
        if times > 0 && !cross(i, p.material(), times) {
            return false;
        }
    }
    true
}

/// Multiplies `light` by the transmission of each crossing of the leaf's primitives within
/// `(0, tmax)`; the primitive that blocks it, where one of them is opaque.
#[inline(always)]
pub(crate) fn transmit_leaf(
    b: &Bindings,
    ray: &Ray,
    inv_dir: Vec3,
    leaf: (u32, u32),
    tmax: f32,
    light: &mut Vec3,
) -> Option<u32> {
    let mut blocker = None;
    leaf_crossings(
        b,
        ray,
        inv_dir,
        leaf,
        tmax,
        #[inline(always)]
        |prim, material, times| {
            let m = &b.materials[material as usize];
            if m.t <= 0.0 {
                blocker = Some(prim);
                return false;
            }
            for _ in 0..times {
                *light *= m.t * m.color;
            }
            true
        },
    );
    blocker
}

/// Tests the leaf's primitives `first..first + count`, keeping the nearest in `hit`.
#[inline(always)]
pub(crate) fn closest_in_leaf(
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
        // Read from arrays: a `Vec4` indexed by a lane known only at run time is a jump
        // table, an indirect branch a lane.
        let crossed = crossings(t, tmin, hit.t, leaf.len());
        let (t, u, v) = (t.to_array(), u.to_array(), v.to_array());
        for k in lanes_of(crossed) {
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
        let (t0, t1) = (t0.to_array(), t1.to_array());
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
    closest_in_prims(b, ray, inv_dir, (first, count), tmin, hit);
}
