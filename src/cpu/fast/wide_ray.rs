//! One ray through the CPU's eight-wide tree (`fast/wide.rs`): `traverse`'s
//! `closest_hit` and `transmission` as the CPU renders them, the same hits as the binary
//! walk of the twin, with the x86-64-v4 and v3 copies chosen at run time.

use glam::Vec3;

#[cfg(target_arch = "x86_64")]
use super::isa;
use super::leaf::{blocks, closest_in_leaf, transmit_leaf};
use super::wide::{self, Slabs};
use crate::bvh::wide::Tree;
use crate::cpu::types::{Bindings, Hit, Ray};
use crate::cpu::{intersect, traverse};

/// `traverse::closest_hit` as the CPU renders it: through the eight-wide tree where the
/// bindings hold one (`Bindings::wide`), else the binary walk.
#[inline(always)]
pub fn closest_hit(b: &Bindings, ray: &Ray, tmin: f32, tmax: f32) -> Hit {
    let Some(wide) = b.wide.filter(|_| b.globals.n_nodes > 0) else {
        return traverse::closest_hit(b, ray, tmin, tmax);
    };
    // The planes' answer goes over as its two values, not as a `Hit`: read back whole,
    // in other widths than its fields were written in, it stalled on store forwarding.
    let planes = traverse::closest_plane(b, ray, tmin, tmax);
    #[cfg(target_arch = "x86_64")]
    if isa::single_ray_v4() {
        // SAFETY: the processor has the features the function is compiled for.
        return unsafe { closest_wide_v4(b, wide, ray, tmin, planes) };
    }
    #[cfg(target_arch = "x86_64")]
    if isa::x86_64_v3() {
        // SAFETY: the processor has the features the function is compiled for.
        return unsafe { closest_wide_v3(b, wide, ray, tmin, planes) };
    }
    let inv_dir = intersect::safe_inverse(ray.dir);
    let slabs = Slabs::new(ray.origin, inv_dir);
    closest_wide(b, wide, ray, (inv_dir, &slabs), tmin, planes)
}

/// `traverse::transmission` as the CPU renders it, as `closest_hit` is. `hint` is the
/// primitive that blocked the caller's last shadow ray to the same light, if it kept one:
/// tested before the walk (a ray it blocks walks no tree, with the same answer, since an
/// opaque crossing anywhere blocks), and set to the primitive that blocks this ray.
#[inline(always)]
pub fn transmission(
    b: &Bindings,
    ray: &Ray,
    tmax: f32,
    nodes: &mut u32,
    hint: &mut Option<u32>,
) -> Vec3 {
    let Some(wide) = b.wide.filter(|_| b.globals.n_nodes > 0) else {
        return traverse::transmission(b, ray, tmax, nodes);
    };
    let Some(light) = traverse::transmit_planes(b, ray, tmax) else {
        return Vec3::ZERO;
    };
    #[cfg(target_arch = "x86_64")]
    if isa::single_ray_v4() {
        // SAFETY: as in `closest_hit`.
        return unsafe { transmission_wide_v4(b, wide, ray, (tmax, nodes, hint), light) };
    }
    #[cfg(target_arch = "x86_64")]
    if isa::x86_64_v3() {
        // SAFETY: as in `closest_hit`.
        return unsafe { transmission_wide_v3(b, wide, ray, (tmax, nodes, hint), light) };
    }
    let inv_dir = intersect::safe_inverse(ray.dir);
    let slabs = Slabs::new(ray.origin, inv_dir);
    transmission_wide(b, wide, ray, (inv_dir, &slabs), (tmax, nodes, hint), light)
}

/// `closest_hit` through the CPU's eight-wide tree (`fast/wide.rs`), the planes done (the
/// nearest plane's distance, or `tmax`, and its `prim`), with the slab test `slabs`:
/// inlined whole into its callers, so that `closest_wide_v3` is the same walk in AVX's
/// encoding.
#[inline(always)]
fn closest_wide(
    b: &Bindings,
    wide: &Tree,
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

/// `transmission` through the eight-wide tree, the planes' factor `light` done; inlined
/// as `closest_wide` is.
#[inline(always)]
fn transmission_wide(
    b: &Bindings,
    wide: &Tree,
    ray: &Ray,
    (inv_dir, slabs): (Vec3, &impl wide::Boxes),
    (tmax, nodes, hint): (f32, &mut u32, &mut Option<u32>),
    mut light: Vec3,
) -> Vec3 {
    if hint.is_some_and(|p| blocks(b, ray, inv_dir, p, tmax)) {
        return Vec3::ZERO;
    }
    let mut blocker = None;
    wide::walk::<false>(
        wide,
        slabs,
        0.0,
        tmax,
        nodes,
        #[inline(always)]
        |first, count| {
            blocker = transmit_leaf(b, ray, inv_dir, (first, count), tmax, &mut light);
            blocker.is_none().then_some(tmax)
        },
    );
    match blocker {
        Some(_) => {
            *hint = blocker;
            Vec3::ZERO
        }
        None => light,
    }
}

/// The copies of `closest_wide` and `transmission_wide` compiled for one instruction set,
/// `$features`, whose test is `wide::SlabsAvx` (AVX2 or wider); `$doc` says which and why.
macro_rules! compiled_for {
    ($(#[doc = $doc:literal])* $closest:ident, $transmission:ident, $features:literal) => {
        $(#[doc = $doc])*
        #[cfg(target_arch = "x86_64")]
        #[target_feature(enable = $features)]
        fn $closest(
            b: &Bindings,
            wide: &Tree,
            ray: &Ray,
            tmin: f32,
            planes: (f32, u32),
        ) -> Hit {
            let inv_dir = intersect::safe_inverse(ray.dir);
            // SAFETY: the function's features include AVX2.
            let slabs = unsafe { wide::SlabsAvx::new(Slabs::new(ray.origin, inv_dir)) };
            closest_wide(b, wide, ray, (inv_dir, &slabs), tmin, planes)
        }

        /// `transmission_wide` compiled as the closest-hit copy beside it is.
        #[cfg(target_arch = "x86_64")]
        #[target_feature(enable = $features)]
        fn $transmission(
            b: &Bindings,
            wide: &Tree,
            ray: &Ray,
            (tmax, nodes, hint): (f32, &mut u32, &mut Option<u32>),
            light: Vec3,
        ) -> Vec3 {
            let inv_dir = intersect::safe_inverse(ray.dir);
            // SAFETY: as above.
            let slabs = unsafe { wide::SlabsAvx::new(Slabs::new(ray.origin, inv_dir)) };
            transmission_wide(b, wide, ray, (inv_dir, &slabs), (tmax, nodes, hint), light)
        }
    };
}

compiled_for!(
    /// `closest_wide` compiled for x86-64-v3 (`isa::x86_64_v3`), eight boxes in one AVX
    /// register (`wide::SlabsAvx`) and the rest in three-operand VEX form: 7 to 10% fewer
    /// instructions a walk. Rust never fuses a multiply and an add, so FMA changes no
    /// result: the hits are the baseline's to the bit (the boxes overlapped too, but for
    /// `SlabsAvx`'s one case of a box more).
    closest_wide_v3,
    transmission_wide_v3,
    "avx2,fma,bmi1,bmi2,lzcnt,popcnt"
);

compiled_for!(
    /// `closest_wide_v3` compiled for x86-64-v4 (`isa::single_ray_v4`): the same walk in
    /// AVX's widths, with AVX-512's 32 vector registers (AVX2 has 16, and the v3 walk keeps
    /// some of the ray's constants on the stack) and its encodings. The same operations, so
    /// the same hits to the bit (`tests`). Mirror rays 2 to 13% faster, shadow rays 3 to 10%
    /// (docs/bvh.md).
    closest_wide_v4,
    transmission_wide_v4,
    "avx2,fma,bmi1,bmi2,lzcnt,popcnt,avx512f,avx512vl,avx512bw,avx512dq,avx512cd"
);

#[cfg(test)]
mod tests {
    /// The v4 copies find the v3 copies' hits to the bit (distance, primitive,
    /// barycentrics, nodes fetched) and let the same light through, blocked by the same
    /// primitive, on rays from all over the bundled scenes of mirrors, glass, cones and
    /// meshes. Skipped, saying so, where the processor has no AVX-512.
    #[cfg(target_arch = "x86_64")]
    #[test]
    fn the_v4_walks_answer_as_the_v3_walks() {
        use std::path::Path;

        use super::*;
        use crate::frame::{RenderOptions, globals};

        if !isa::single_ray_v4() {
            eprintln!("skipped: this processor has no AVX-512 (or GPURT_SIMD holds it back)");
            return;
        }
        let scenes = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
        let mut rand = crate::cpu::xorshift(0x853c_49e6_748f_ea9b);
        let (mut hits, mut blocked) = (0, 0);
        for name in ["spheres", "mirrors", "glass", "cones", "mesh", "patches"] {
            let path = scenes.join(format!("{name}.nff"));
            let scene = crate::scene::load(&path).expect("loads");
            let opts = RenderOptions::for_camera(&scene.camera);
            let buffers = crate::pack::pack(scene).expect("packs");
            let g = globals(&buffers, &opts);
            let b = Bindings::new(&buffers, &g);
            let wide = b.wide.expect("the CPU's tree");
            // Origins in and around the scene's box, the binary tree's root.
            let (lo, hi) = (buffers.nodes[0].min, buffers.nodes[0].max);
            for _ in 0..4000 {
                let at = |r: f32, a: usize| lo[a] + (hi[a] - lo[a]) * (0.5 + 0.6 * r);
                let origin = Vec3::new(at(rand(), 0), at(rand(), 1), at(rand(), 2));
                let dir = Vec3::new(rand(), rand(), rand()).normalize_or(Vec3::X);
                let ray = Ray { origin, dir };
                let planes = traverse::closest_plane(&b, &ray, 1e-4, f32::MAX);
                // SAFETY: the processor has both copies' features (checked above).
                let (v3, v4) = unsafe {
                    (
                        closest_wide_v3(&b, wide, &ray, 1e-4, planes),
                        closest_wide_v4(&b, wide, &ray, 1e-4, planes),
                    )
                };
                let bits = |h: &Hit| (h.t.to_bits(), h.prim, h.u.to_bits(), h.v.to_bits());
                assert_eq!((bits(&v3), v3.nodes), (bits(&v4), v4.nodes), "{name}");
                hits += usize::from(v3.t < f32::MAX);
                let Some(light) = traverse::transmit_planes(&b, &ray, 5.0) else {
                    continue;
                };
                let (mut n3, mut n4, mut h3, mut h4) = (0, 0, None, None);
                // SAFETY: as above.
                let (l3, l4) = unsafe {
                    (
                        transmission_wide_v3(&b, wide, &ray, (5.0, &mut n3, &mut h3), light),
                        transmission_wide_v4(&b, wide, &ray, (5.0, &mut n4, &mut h4), light),
                    )
                };
                let bits = |l: Vec3| l.to_array().map(f32::to_bits);
                assert_eq!((bits(l3), n3, h3), (bits(l4), n4, h4), "{name}");
                blocked += usize::from(h3.is_some());
            }
        }
        assert!(
            hits > 5_000 && blocked > 1_000,
            "{hits} hits, {blocked} blocked"
        );
    }
}
