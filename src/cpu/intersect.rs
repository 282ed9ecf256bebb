//! CPU twin of `shaders/intersect.wgsl`: ray against sphere, triangle (Möller-Trumbore),
//! cone, box and plane, and the geometric normal at a hit. Each bounded test returns both
//! crossings `(t0, t1)`, nearest first, `NO_HIT` where there is none: closest-hit takes the
//! first one past `tmin`, shadow rays count every crossing of the segment.

use glam::{Mat4, Vec2, Vec3, Vec3A, Vec4};

use super::types::Ray;
use crate::bvh::blocks::TriangleBlock;
use crate::gpu_types::*;

/// Replaces zero direction components so slab tests never compute 0 * inf: a component
/// below 1e-30 in size becomes 1e-30 (a NaN stays NaN). In SIMD lanes, one compare and
/// one divide for the three (per component it was a fifth of a shadow ray's setup); the
/// division rounds each lane as the scalar one.
#[inline]
pub fn safe_inverse(d: Vec3) -> Vec3 {
    let d = Vec3A::from(d);
    let tiny = Vec3A::splat(1e-30);
    Vec3::from(Vec3A::ONE / Vec3A::select(d.abs().cmplt(tiny), tiny, d))
}

/// Ray (unit direction) against a sphere, in the form that keeps precision for small
/// spheres far from the origin (the chord's half-length from the closest approach).
pub fn intersect_sphere(center: Vec3, radius: f32, ray: &Ray) -> Vec2 {
    let oc = ray.origin - center;
    let b = oc.dot(ray.dir);
    let qc = oc - b * ray.dir;
    let h = radius * radius - qc.dot(qc);
    if h < 0.0 {
        return Vec2::splat(NO_HIT);
    }
    let h = h.sqrt();
    Vec2::new(-b - h, -b + h)
}

/// Möller-Trumbore, two-sided: `(t, u, v)` with `t = NO_HIT` on a miss.
#[inline]
pub fn intersect_triangle(p: &GpuPrim, ray: &Ray) -> Vec3 {
    let (e1, e2) = (p.p1, p.p2);
    let pvec = ray.dir.cross(e2);
    let det = e1.dot(pvec);
    if det == 0.0 {
        return Vec3::splat(NO_HIT);
    }
    let inv = 1.0 / det;
    let tvec = ray.origin - p.p0;
    let u = tvec.dot(pvec) * inv;
    if !(0.0..=1.0).contains(&u) {
        return Vec3::splat(NO_HIT);
    }
    let qvec = tvec.cross(e1);
    let v = ray.dir.dot(qvec) * inv;
    if v < 0.0 || u + v > 1.0 {
        return Vec3::splat(NO_HIT);
    }
    Vec3::new(e2.dot(qvec) * inv, u, v)
}

/// The lanes whose bits are set, lowest first.
#[inline(always)]
pub fn lanes_of(mut bits: u32) -> impl Iterator<Item = usize> {
    std::iter::from_fn(move || {
        (bits != 0).then(|| {
            let k = bits.trailing_zeros() as usize;
            bits &= bits - 1;
            k
        })
    })
}

/// The words of a leaf of two to four primitives of `kind`, a lane each (lanes past the
/// leaf repeat its first primitive), for the four-lane tests; `None` for any other leaf.
#[inline(always)]
fn leaf_words(leaf: &[GpuPrim], kind: u32) -> Option<[&[f32; 12]; 4]> {
    if !(2..=4).contains(&leaf.len()) || leaf.iter().any(|p| p.kind() != kind) {
        return None;
    }
    Some(std::array::from_fn(|k| {
        bytemuck::cast_ref(leaf.get(k).unwrap_or(&leaf[0]))
    }))
}

/// Words `4 * row..4 * row + 4` of the four lanes' primitives, transposed: a coordinate
/// (or the fourth word) a column.
#[inline(always)]
fn transposed(words: &[&[f32; 12]; 4], row: usize) -> Mat4 {
    let lane = |k: usize| Vec4::from_slice(&words[k][4 * row..4 * row + 4]);
    Mat4::from_cols(lane(0), lane(1), lane(2), lane(3)).transpose()
}

/// `intersect_triangle` for a leaf of two to four triangles at once, lane by lane the same
/// arithmetic in the same order (so the same bits; x86 and Arm round each SIMD lane as a
/// scalar): `(t, u, v)` per lane, `t = NO_HIT` where the ray misses (lanes past the leaf
/// repeat its first triangle). `None` for any other leaf, which is tested one primitive
/// at a time. A leaf holds up to four primitives, and on meshes they are triangles: four
/// tests in the time of about one and a half (`closest_in_leaf`, `transmit_leaf`, which
/// take the leaf's `TriangleBlock` ready made where the scene has them).
#[inline(always)]
pub fn intersect_triangles4(leaf: &[GpuPrim], ray: &Ray) -> Option<(Vec4, Vec4, Vec4)> {
    TriangleBlock::of_leaf(leaf).map(|block| triangles4(&block, ray))
}

/// `intersect_triangles4` of a leaf's `TriangleBlock`.
#[inline(always)]
pub fn triangles4(block: &TriangleBlock, ray: &Ray) -> (Vec4, Vec4, Vec4) {
    let TriangleBlock { v0, e1, e2 } = block;
    let (o, d) = (ray.origin, ray.dir);
    let [dx, dy, dz] = [d.x, d.y, d.z].map(Vec4::splat);
    // pvec = dir x e2
    let px = dy * e2[2] - e2[1] * dz;
    let py = dz * e2[0] - e2[2] * dx;
    let pz = dx * e2[1] - e2[0] * dy;
    let det = e1[0] * px + e1[1] * py + e1[2] * pz;
    let inv = Vec4::ONE / det;
    let tx = Vec4::splat(o.x) - v0[0];
    let ty = Vec4::splat(o.y) - v0[1];
    let tz = Vec4::splat(o.z) - v0[2];
    let u = (tx * px + ty * py + tz * pz) * inv;
    // qvec = tvec x e1
    let qx = ty * e1[2] - e1[1] * tz;
    let qy = tz * e1[0] - e1[2] * tx;
    let qz = tx * e1[1] - e1[0] * ty;
    let v = (dx * qx + dy * qy + dz * qz) * inv;
    let t = (e2[0] * qx + e2[1] * qy + e2[2] * qz) * inv;
    let hit = det.cmpne(Vec4::ZERO)
        & u.cmpge(Vec4::ZERO)
        & u.cmple(Vec4::ONE)
        & !v.cmplt(Vec4::ZERO)
        & !(u + v).cmpgt(Vec4::ONE);
    (Vec4::select(hit, t, Vec4::splat(NO_HIT)), u, v)
}

/// `intersect_sphere` for a leaf of two to four spheres at once, lane by lane the same
/// arithmetic in the same order (as `intersect_triangles4`): both crossings per lane,
/// `NO_HIT` where the ray misses (lanes past the leaf repeat its first sphere). `None` for
/// any other leaf.
#[inline(always)]
pub fn intersect_spheres4(leaf: &[GpuPrim], ray: &Ray) -> Option<(Vec4, Vec4)> {
    // Centre and radius by coordinate.
    let c = transposed(&leaf_words(leaf, PRIM_SPHERE)?, 0);
    let (o, d) = (ray.origin, ray.dir);
    let [dx, dy, dz] = [d.x, d.y, d.z].map(Vec4::splat);
    let ocx = Vec4::splat(o.x) - c.x_axis;
    let ocy = Vec4::splat(o.y) - c.y_axis;
    let ocz = Vec4::splat(o.z) - c.z_axis;
    let b = ocx * dx + ocy * dy + ocz * dz;
    let (qx, qy, qz) = (ocx - b * dx, ocy - b * dy, ocz - b * dz);
    let h = c.w_axis * c.w_axis - (qx * qx + qy * qy + qz * qz);
    let miss = h.cmplt(Vec4::ZERO);
    let h = h.sqrt();
    let no = Vec4::splat(NO_HIT);
    Some((
        Vec4::select(miss, no, -b - h),
        Vec4::select(miss, no, -b + h),
    ))
}

/// Side of a truncated cone (or cylinder) between `p0` (radius `f0`) and `p1` (radius `f1`).
/// Solved from the ray's closest approach to the cone's middle, as `sphere` is: far from a
/// thin cone the quadratic's terms would otherwise cancel away the hit's precision.
/// Inlined into the walks: a call in a walk's loop may overwrite every vector register,
/// and the compiler then kept the ray's constants on the stack from the start of every
/// walk, a cone in its leaves or not (docs/bvh.md).
#[inline(always)]
pub fn intersect_cone(p: &GpuPrim, ray: &Ray) -> Vec2 {
    // Along the axis by `s`, 0 at the base and 1 at the apex (a point's offset from the
    // base dotted with the axis, over the axis's squared length), where the radius is
    // `f0 + delta * s`: one division, where a unit axis and the height took a square root
    // and two (rings-7's single rays 4 to 13% faster, docs/bvh.md). The division's
    // reciprocal, not the axis divided by it: a second vector kept live made the AVX-512
    // walks store ray constants on the stack at the start of every walk.
    let axis = p.p1 - p.p0;
    let inv = 1.0 / axis.dot(axis);
    let delta = p.f1 - p.f0;
    let tc = (0.5 * (p.p0 + p.p1) - ray.origin).dot(ray.dir);
    let co = ray.origin + tc * ray.dir - p.p0;
    let dv = ray.dir.dot(axis) * inv;
    let cv = co.dot(axis) * inv;
    let dp = ray.dir - dv * axis;
    let cp = co - cv * axis;
    let rr = p.f0 + delta * cv;
    let kd = delta * dv;
    let qa = dp.dot(dp) - kd * kd;
    let qb = cp.dot(dp) - rr * kd;
    let qc = cp.dot(cp) - rr * rr;
    let mut t = Vec2::splat(NO_HIT);
    if qa.abs() < 1e-12 {
        // Ray parallel to a generating line: one crossing at most.
        if qb != 0.0 {
            t.x = -qc / (2.0 * qb);
        }
    } else {
        let disc = qb * qb - qa * qc;
        if disc < 0.0 {
            return t;
        }
        let sq = disc.sqrt();
        let r0 = (-qb - sq) / qa;
        let r1 = (-qb + sq) / qa;
        t = Vec2::new(r0.min(r1), r0.max(r1));
    }
    // Keep crossings between the two caps, where the radius is not negative.
    let valid = |t: f32| {
        let s = cv + t * dv;
        t != NO_HIT && (0.0..=1.0).contains(&s) && p.f0 + delta * s >= 0.0
    };
    let (ok0, ok1) = (valid(t.x), valid(t.y));
    if ok0 && ok1 {
        t + Vec2::splat(tc)
    } else if ok0 {
        Vec2::new(t.x + tc, NO_HIT)
    } else if ok1 {
        Vec2::new(t.y + tc, NO_HIT)
    } else {
        Vec2::splat(NO_HIT)
    }
}

/// Slab test against `[lo, hi]`: `(t_near, t_far)`, or `NO_HIT` when the slabs miss.
pub fn slabs(lo: Vec3, hi: Vec3, origin: Vec3, inv_dir: Vec3) -> Vec2 {
    let t0 = (lo - origin) * inv_dir;
    let t1 = (hi - origin) * inv_dir;
    let near = t0.min(t1).max_element();
    let far = t0.max(t1).min_element();
    if near > far {
        Vec2::splat(NO_HIT)
    } else {
        Vec2::new(near, far)
    }
}

/// Where the ray enters and leaves the box, clamped to `[tmin, tmax]`: `(near, far)`.
///
/// The hottest code of the CPU renderer. Its minima and maxima are plain comparisons, not
/// `f32::min`/`max`, whose NaN rules cost extra instructions on x86: no NaN can arise
/// here (`safe_inverse` keeps the inverse direction finite, and node bounds are finite),
/// so the result is the shader's to the bit.
#[inline]
pub fn slab(lo: Vec3, hi: Vec3, origin: Vec3, inv_dir: Vec3, tmin: f32, tmax: f32) -> (f32, f32) {
    let min = |a: f32, b: f32| if a < b { a } else { b };
    let max = |a: f32, b: f32| if a > b { a } else { b };
    let t0 = (lo - origin) * inv_dir;
    let t1 = (hi - origin) * inv_dir;
    // The shader's order: max_element(min(t0, t1)), then tmin; min_element(max(..)), tmax.
    let near = max(
        max(max(min(t0.x, t1.x), min(t0.y, t1.y)), min(t0.z, t1.z)),
        tmin,
    );
    let far = min(
        min(min(max(t0.x, t1.x), max(t0.y, t1.y)), max(t0.z, t1.z)),
        tmax,
    );
    (near, far)
}

/// Whether the ray's interval `[tmin, tmax]` overlaps the box (BVH node test).
#[inline]
pub fn overlaps(lo: Vec3, hi: Vec3, origin: Vec3, inv_dir: Vec3, tmin: f32, tmax: f32) -> bool {
    let (near, far) = slab(lo, hi, origin, inv_dir, tmin, tmax);
    near <= far * SLAB_WIDEN
}

/// `slab` then `overlaps` for four boxes, a box a lane, the same arithmetic lane by lane:
/// where the ray enters each box (clamped to `tmin`) and, as bits, the boxes it
/// overlaps. `lo[a]` and `hi[a]` hold the four boxes' bounds on axis `a`. The wide and
/// compressed wide walks test their nodes' children with it.
#[inline]
pub fn slab4(
    lo: [Vec4; 3],
    hi: [Vec4; 3],
    origin: Vec3,
    inv_dir: Vec3,
    tmin: f32,
    tmax: f32,
) -> (Vec4, u32) {
    let t = |a: usize| {
        (
            (lo[a] - origin[a]) * inv_dir[a],
            (hi[a] - origin[a]) * inv_dir[a],
        )
    };
    let ((x0, x1), (y0, y1), (z0, z1)) = (t(0), t(1), t(2));
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
    (near, near.cmple(far * SLAB_WIDEN).bitmask())
}

/// `overlaps`, returning where the ray enters the box (clamped to `tmin`), `NO_HIT` when
/// it does not overlap: the pairs traversal enters the nearer child first.
#[inline]
pub fn slab_entry(lo: Vec3, hi: Vec3, origin: Vec3, inv_dir: Vec3, tmin: f32, tmax: f32) -> f32 {
    let (near, far) = slab(lo, hi, origin, inv_dir, tmin, tmax);
    if near <= far * SLAB_WIDEN {
        near
    } else {
        NO_HIT
    }
}

/// Any bounded primitive: `(t0, t1, u, v)`; only triangles fill `u, v`.
#[inline(always)]
pub fn intersect_prim(p: &GpuPrim, ray: &Ray, inv_dir: Vec3) -> Vec4 {
    match p.kind() {
        PRIM_SPHERE => intersect_sphere(p.p0, p.f0, ray).extend(0.0).extend(0.0),
        PRIM_TRIANGLE => {
            let h = intersect_triangle(p, ray);
            Vec4::new(h.x, NO_HIT, h.y, h.z)
        }
        PRIM_CONE => intersect_cone(p, ray).extend(0.0).extend(0.0),
        _ => slabs(p.p0, p.p1, ray.origin, inv_dir)
            .extend(0.0)
            .extend(0.0),
    }
}

/// Ray against the plane `dot(n, x) = d`.
pub fn intersect_plane(pl: &GpuPlane, ray: &Ray) -> f32 {
    let denom = pl.normal.dot(ray.dir);
    if denom == 0.0 {
        return NO_HIT;
    }
    (pl.d - pl.normal.dot(ray.origin)) / denom
}

/// `v` normalised, or zero where that is undefined: no length, or one whose square
/// overflows (`normalize` would give NaN or zero components).
pub fn unit_or_zero(v: Vec3) -> Vec3 {
    let l2 = v.dot(v);
    if l2 > 0.0 && l2 <= F32_MAX {
        v.normalize()
    } else {
        Vec3::ZERO
    }
}

/// Outward geometric normal of a bounded primitive at the hit point `x`; zero where it
/// is undefined (rounding can put a hit point on a sphere's centre or a cone's axis).
/// Inlined into `shade::surface`, its one caller on the CPU: the call cost more than a
/// sphere's normal.
#[inline]
pub fn prim_normal(p: &GpuPrim, x: Vec3) -> Vec3 {
    match p.kind() {
        PRIM_SPHERE => unit_or_zero(x - p.p0),
        PRIM_TRIANGLE => unit_or_zero(p.p1.cross(p.p2)),
        PRIM_CONE => {
            let axis = p.p1 - p.p0;
            let height = axis.length();
            let a = axis / height;
            let k = (p.f1 - p.f0) / height;
            let q = x - p.p0;
            let radial = q - q.dot(a) * a;
            unit_or_zero(unit_or_zero(radial) - k * a)
        }
        _ => {
            let c = 0.5 * (p.p0 + p.p1);
            let local = (x - c) / (0.5 * (p.p1 - p.p0)).max(Vec3::splat(1e-30));
            let m = local.abs();
            let sign = |c: f32| if c >= 0.0 { 1.0 } else { -1.0 };
            if m.x >= m.y && m.x >= m.z {
                Vec3::X * sign(local.x)
            } else if m.y >= m.z {
                Vec3::Y * sign(local.y)
            } else {
                Vec3::Z * sign(local.z)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cpu::xorshift;

    /// The four-lane triangle test gives the scalar one's bits, hit or miss, on random
    /// triangles (some degenerate, some edge-on) and rays aimed near them.
    #[test]
    fn four_triangles_at_once_match_one_at_a_time_to_the_bit() {
        let mut rand = xorshift(0x2545_f491_4f6c_dd1d);
        let mut hits = 0;
        for n in 0..20_000 {
            let tri = |rand: &mut dyn FnMut() -> f32| {
                let v0 = Vec3::new(rand(), rand(), rand()) * 10.0;
                let mut e1 = Vec3::new(rand(), rand(), rand()) * 3.0;
                let e2 = Vec3::new(rand(), rand(), rand()) * 3.0;
                if n % 7 == 0 {
                    e1 = e2 * 0.5; // zero area
                }
                GpuPrim {
                    p0: v0,
                    p1: e1,
                    p2: e2,
                    f1: -1.0,
                    tag: PRIM_TRIANGLE << PRIM_KIND_SHIFT,
                    ..Default::default()
                }
            };
            let prims = [
                tri(&mut rand),
                tri(&mut rand),
                tri(&mut rand),
                tri(&mut rand),
            ];
            let aim = prims[n % 4].p0 + 0.3 * prims[n % 4].p1 + 0.3 * prims[n % 4].p2;
            let origin = Vec3::new(rand(), rand(), rand()) * 30.0;
            let wobble = Vec3::new(rand(), rand(), rand()) * 0.5;
            let ray = Ray {
                origin,
                dir: (aim + wobble - origin).normalize(),
            };
            let (t, u, v) = intersect_triangles4(&prims, &ray).expect("four triangles");
            for (k, p) in prims.iter().enumerate() {
                let one = intersect_triangle(p, &ray);
                assert_eq!(t[k].to_bits(), one.x.to_bits(), "t, case {n} lane {k}");
                if one.x != NO_HIT {
                    hits += 1;
                    assert_eq!(u[k].to_bits(), one.y.to_bits(), "u, case {n} lane {k}");
                    assert_eq!(v[k].to_bits(), one.z.to_bits(), "v, case {n} lane {k}");
                }
            }
        }
        assert!(hits > 10_000, "only {hits} hits");
    }

    /// The four-lane sphere test gives the scalar one's bits, hit or miss, on random
    /// spheres (tiny to large, some grazed) and rays aimed near them.
    #[test]
    fn four_spheres_at_once_match_one_at_a_time_to_the_bit() {
        let mut rand = xorshift(0x9e37_79b9_7f4a_7c15);
        let mut hits = 0;
        for n in 0..20_000 {
            let spheres: Vec<GpuPrim> = (0..2 + n % 3)
                .map(|_| GpuPrim {
                    p0: Vec3::new(rand(), rand(), rand()) * 10.0,
                    f0: (rand() + 1.0) * [0.01, 1.0, 4.0][n % 3],
                    tag: PRIM_SPHERE << PRIM_KIND_SHIFT,
                    ..Default::default()
                })
                .collect();
            let aim = spheres[n % spheres.len()].p0;
            let origin = Vec3::new(rand(), rand(), rand()) * 30.0;
            let wobble = Vec3::new(rand(), rand(), rand()) * 2.0;
            let ray = Ray {
                origin,
                dir: (aim + wobble - origin).normalize(),
            };
            let (t0, t1) = intersect_spheres4(&spheres, &ray).expect("spheres");
            for (k, p) in spheres.iter().enumerate() {
                let one = intersect_sphere(p.p0, p.f0, &ray);
                assert_eq!(t0[k].to_bits(), one.x.to_bits(), "t0, case {n} lane {k}");
                assert_eq!(t1[k].to_bits(), one.y.to_bits(), "t1, case {n} lane {k}");
                hits += usize::from(one.x != NO_HIT);
            }
        }
        assert!(hits > 5_000, "only {hits} hits");
    }
}
