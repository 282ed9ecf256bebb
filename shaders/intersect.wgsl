// intersect.wgsl: ray against sphere, triangle (Möller-Trumbore), cone, box and plane, and
// the geometric normal at a hit (CPU twin: src/cpu/intersect.rs). Bounded tests return both
// crossings (t0, t1), nearest first, NO_HIT where there is none.

fn safe_inverse(d: vec3<f32>) -> vec3<f32> {
    let fixed = select(d, vec3<f32>(1e-30), abs(d) < vec3<f32>(1e-30));
    return vec3<f32>(1.0) / fixed;
}

fn intersect_sphere(center: vec3<f32>, radius: f32, ray: Ray) -> vec2<f32> {
    let oc = ray.origin - center;
    let b = dot(oc, ray.dir);
    let qc = oc - b * ray.dir;
    var h = radius * radius - dot(qc, qc);
    if (h < 0.0) {
        return vec2<f32>(NO_HIT);
    }
    h = sqrt(h);
    return vec2<f32>(-b - h, -b + h);
}

// Two-sided Möller-Trumbore: (t, u, v), t = NO_HIT on a miss.
fn intersect_triangle(v0: vec3<f32>, e1: vec3<f32>, e2: vec3<f32>, ray: Ray) -> vec3<f32> {
    let pvec = cross(ray.dir, e2);
    let det = dot(e1, pvec);
    if (det == 0.0) {
        return vec3<f32>(NO_HIT);
    }
    let inv = 1.0 / det;
    let tvec = ray.origin - v0;
    let u = dot(tvec, pvec) * inv;
    if (!(u >= 0.0 && u <= 1.0)) {
        return vec3<f32>(NO_HIT);
    }
    let qvec = cross(tvec, e1);
    let v = dot(ray.dir, qvec) * inv;
    if (v < 0.0 || u + v > 1.0) {
        return vec3<f32>(NO_HIT);
    }
    return vec3<f32>(dot(e2, qvec) * inv, u, v);
}

fn cone_valid(t: f32, cv: f32, dv: f32, r0: f32, delta: f32) -> bool {
    let s = cv + t * dv;
    return t != NO_HIT && s >= 0.0 && s <= 1.0 && r0 + delta * s >= 0.0;
}

// Solved from the ray's closest approach to the cone's middle, as the sphere is: far from
// a thin cone the quadratic's terms would otherwise cancel away the hit's precision. Along
// the axis by `s`, 0 at the base and 1 at the apex (a point's offset from the base dotted
// with the axis, over the axis's squared length), where the radius is `r0 + delta * s`:
// one division, where a unit axis and the height took a square root and two.
fn intersect_cone(base: vec3<f32>, r0: f32, apex: vec3<f32>, r1: f32, ray: Ray) -> vec2<f32> {
    let axis = apex - base;
    let inv = 1.0 / dot(axis, axis);
    let delta = r1 - r0;
    let tc = dot(0.5 * (base + apex) - ray.origin, ray.dir);
    let co = ray.origin + tc * ray.dir - base;
    let dv = dot(ray.dir, axis) * inv;
    let cv = dot(co, axis) * inv;
    let dp = ray.dir - dv * axis;
    let cp = co - cv * axis;
    let rr = r0 + delta * cv;
    let kd = delta * dv;
    let qa = dot(dp, dp) - kd * kd;
    let qb = dot(cp, dp) - rr * kd;
    let qc = dot(cp, cp) - rr * rr;
    var t = vec2<f32>(NO_HIT);
    if (abs(qa) < 1e-12) {
        if (qb != 0.0) {
            t.x = -qc / (2.0 * qb);
        }
    } else {
        let disc = qb * qb - qa * qc;
        if (disc < 0.0) {
            return t;
        }
        let sq = sqrt(disc);
        let t0 = (-qb - sq) / qa;
        let t1 = (-qb + sq) / qa;
        t = vec2<f32>(min(t0, t1), max(t0, t1));
    }
    let ok0 = cone_valid(t.x, cv, dv, r0, delta);
    let ok1 = cone_valid(t.y, cv, dv, r0, delta);
    if (ok0 && ok1) {
        return t + vec2<f32>(tc);
    } else if (ok0) {
        return vec2<f32>(t.x + tc, NO_HIT);
    } else if (ok1) {
        return vec2<f32>(t.y + tc, NO_HIT);
    }
    return vec2<f32>(NO_HIT);
}

fn max_element(v: vec3<f32>) -> f32 {
    return max(max(v.x, v.y), v.z);
}

fn min_element(v: vec3<f32>) -> f32 {
    return min(min(v.x, v.y), v.z);
}

fn slabs(lo: vec3<f32>, hi: vec3<f32>, origin: vec3<f32>, inv_dir: vec3<f32>) -> vec2<f32> {
    let t0 = (lo - origin) * inv_dir;
    let t1 = (hi - origin) * inv_dir;
    let near = max_element(min(t0, t1));
    let far = min_element(max(t0, t1));
    if (near > far) {
        return vec2<f32>(NO_HIT);
    }
    return vec2<f32>(near, far);
}

// The far end is widened by SLAB_WIDEN, 2^-16 (src/gpu_types.rs): rays grazing a box
// face, and boxes whose near face lies exactly at a hit, overlap on both renderers.

// Where the ray enters and leaves the box, clamped to [tmin, tmax]: (near, far).
fn slab(lo: vec3<f32>, hi: vec3<f32>, origin: vec3<f32>, inv_dir: vec3<f32>, tmin: f32, tmax: f32) -> vec2<f32> {
    let t0 = (lo - origin) * inv_dir;
    let t1 = (hi - origin) * inv_dir;
    return vec2<f32>(max(max_element(min(t0, t1)), tmin), min(min_element(max(t0, t1)), tmax));
}

fn overlaps(lo: vec3<f32>, hi: vec3<f32>, origin: vec3<f32>, inv_dir: vec3<f32>, tmin: f32, tmax: f32) -> bool {
    let s = slab(lo, hi, origin, inv_dir, tmin, tmax);
    return s.x <= s.y * SLAB_WIDEN;
}

// `slab4`'s answer: where the ray enters each of four boxes (clamped to tmin), and which
// it overlaps.
struct Slab4 {
    near: vec4<f32>,
    reached: vec4<bool>,
}

// `slab` then `overlaps` for four boxes, a box a lane, the same arithmetic lane by lane.
// lo[a] and hi[a] hold the four boxes' bounds on axis a. The wide and compressed wide
// walks test their nodes' children with it.
fn slab4(lo: array<vec4<f32>, 3>, hi: array<vec4<f32>, 3>, origin: vec3<f32>, inv_dir: vec3<f32>, tmin: f32, tmax: f32) -> Slab4 {
    let x0 = (lo[0] - origin.x) * inv_dir.x;
    let x1 = (hi[0] - origin.x) * inv_dir.x;
    let y0 = (lo[1] - origin.y) * inv_dir.y;
    let y1 = (hi[1] - origin.y) * inv_dir.y;
    let z0 = (lo[2] - origin.z) * inv_dir.z;
    let z1 = (hi[2] - origin.z) * inv_dir.z;
    let near = max(max(max(min(x0, x1), min(y0, y1)), min(z0, z1)), vec4<f32>(tmin));
    let far = min(min(min(max(x0, x1), max(y0, y1)), max(z0, z1)), vec4<f32>(tmax));
    return Slab4(near, near <= far * SLAB_WIDEN);
}

// `overlaps`, returning where the ray enters the box (clamped to tmin), NO_HIT when it
// does not overlap: the pairs traversal enters the nearer child first.
fn slab_entry(lo: vec3<f32>, hi: vec3<f32>, origin: vec3<f32>, inv_dir: vec3<f32>, tmin: f32, tmax: f32) -> f32 {
    let s = slab(lo, hi, origin, inv_dir, tmin, tmax);
    return select(NO_HIT, s.x, s.x <= s.y * SLAB_WIDEN);
}

// Takes the primitive's index rather than the primitive, so that only the texels its
// kind uses are fetched; kinds the scene lacks are compiled out (see the overrides).
fn intersect_prim(i: u32, ray: Ray, inv_dir: vec3<f32>) -> vec4<f32> {
    let kind = load_prim_tag(i) >> PRIM_KIND_SHIFT;
    let a = prim_texel(3u * i);
    let p0 = bitcast<vec3<f32>>(a.xyz);
    var t = vec4<f32>(NO_HIT, NO_HIT, 0.0, 0.0);
    if (SPHERES && kind == PRIM_SPHERE) {
        t = vec4<f32>(intersect_sphere(p0, bitcast<f32>(a.w), ray), 0.0, 0.0);
    }
    if (TRIANGLES && kind == PRIM_TRIANGLE) {
        let e1 = bitcast<vec3<f32>>(prim_texel(3u * i + 1u).xyz);
        let e2 = bitcast<vec3<f32>>(prim_texel(3u * i + 2u).xyz);
        let h = intersect_triangle(p0, e1, e2, ray);
        t = vec4<f32>(h.x, NO_HIT, h.y, h.z);
    }
    if (CONES && kind == PRIM_CONE) {
        let b = prim_texel(3u * i + 1u);
        t = vec4<f32>(intersect_cone(p0, bitcast<f32>(a.w), bitcast<vec3<f32>>(b.xyz), bitcast<f32>(b.w), ray), 0.0, 0.0);
    }
    if (BOXES && kind == PRIM_BOX) {
        let hi = bitcast<vec3<f32>>(prim_texel(3u * i + 1u).xyz);
        t = vec4<f32>(slabs(p0, hi, ray.origin, inv_dir), 0.0, 0.0);
    }
    return t;
}

fn intersect_plane(pl: Plane, ray: Ray) -> f32 {
    let denom = dot(pl.normal, ray.dir);
    if (denom == 0.0) {
        return NO_HIT;
    }
    return (pl.d - dot(pl.normal, ray.origin)) / denom;
}

fn sign_of(c: f32) -> f32 {
    return select(-1.0, 1.0, c >= 0.0);
}

// v normalised, or zero where that is undefined: no length, or one whose square overflows.
fn unit_or_zero(v: vec3<f32>) -> vec3<f32> {
    let l2 = dot(v, v);
    return select(vec3<f32>(0.0), normalize(v), l2 > 0.0 && l2 <= F32_MAX);
}

// Zero where the normal is undefined (a hit point rounded onto a sphere's centre or a
// cone's axis); `surface` then faces the ray.
fn prim_normal(p: Prim, x: vec3<f32>) -> vec3<f32> {
    let kind = prim_kind(p);
    var n = vec3<f32>(0.0, 0.0, 1.0);
    if (SPHERES && kind == PRIM_SPHERE) {
        n = unit_or_zero(x - p.p0);
    }
    if (TRIANGLES && kind == PRIM_TRIANGLE) {
        n = unit_or_zero(cross(p.p1, p.p2));
    }
    if (CONES && kind == PRIM_CONE) {
        let axis = p.p1 - p.p0;
        let height = length(axis);
        let a = axis / height;
        let k = (p.f1 - p.f0) / height;
        let q = x - p.p0;
        let radial = q - dot(q, a) * a;
        n = unit_or_zero(unit_or_zero(radial) - k * a);
    }
    if (BOXES && kind == PRIM_BOX) {
        let c = 0.5 * (p.p0 + p.p1);
        let local = (x - c) / max(0.5 * (p.p1 - p.p0), vec3<f32>(1e-30));
        let m = abs(local);
        if (m.x >= m.y && m.x >= m.z) {
            n = vec3<f32>(sign_of(local.x), 0.0, 0.0);
        } else if (m.y >= m.z) {
            n = vec3<f32>(0.0, sign_of(local.y), 0.0);
        } else {
            n = vec3<f32>(0.0, 0.0, sign_of(local.z));
        }
    }
    return n;
}
