//! CPU twin of `shaders/shade.wgsl`: the Whitted model of ../shared/docs/shading.md, iterative with
//! an explicit stack of pending rays, pushed and popped in the same order as the shader.

use std::mem::MaybeUninit;

use glam::Vec3;

use super::intersect;
use super::texture::textured;
use super::types::{Bindings, Hit, Ray, RayCounts, rand};
use crate::gpu_types::*;

/// A ray waiting to be traced, with the product of the Ks / T factors on its path.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Pending {
    pub(super) origin: Vec3,
    pub(super) dir: Vec3,
    pub(super) weight: f32,
    pub(super) depth: u32,
    pub(super) tmin: f32,
}

/// Where the shading gets the answers of the rays it traces (`closest_hit`,
/// `transmission`): each walked alone (`tracer::Alone`), or those traced beforehand in
/// packets (`coherent::Known`), whose answers are the same. Also where it gets the surface
/// at a hit and what each light gives it, which a tracer that worked them out with its
/// packets hands back rather than have them made twice. Defined here, by the code that
/// asks, so that the tracers depend on the shading and not the other way round.
pub trait Tracer {
    fn closest_hit(&mut self, b: &Bindings, ray: &Ray, tmin: f32, tmax: f32) -> Hit;
    /// Adds the node fetches of the shadow ray's walk to `nodes`.
    fn transmission(&mut self, b: &Bindings, ray: &Ray, tmax: f32, nodes: &mut u32) -> Vec3;

    /// `shade::surface`.
    #[inline]
    fn surface(&mut self, b: &Bindings, ray: &Ray, hit: &Hit) -> Surface {
        surface(b, ray, hit)
    }

    /// `shade::light_sample`.
    #[inline]
    fn light_sample(
        &mut self,
        b: &Bindings,
        at: &Shaded,
        (light, k): (&GpuLight, u32),
        rng: &mut u32,
        counts: &mut RayCounts,
    ) -> Option<Vec3>
    where
        Self: Sized,
    {
        light_sample(b, self, at, (light, k), rng, counts)
    }
}

/// A surface being shaded, what every light sample there shares: the surface, its material,
/// the incoming direction and the mirror direction about the shading normal.
#[derive(Clone, Copy, Debug)]
pub struct Shaded<'a> {
    pub s: &'a Surface,
    pub m: &'a GpuMaterial,
    pub dir: Vec3,
    pub r: Vec3,
}

/// Surface data at a hit.
#[derive(Clone, Copy, Debug)]
pub struct Surface {
    pub point: Vec3,
    /// Geometric normal facing the incoming ray.
    pub ng: Vec3,
    /// Shading normal facing the incoming ray.
    pub ns: Vec3,
    /// Whether the ray meets the outward side (it enters a solid).
    pub entering: bool,
    pub material: u32,
}

/// Hit point, normals (two-sided: flipped to face the ray) and material. Inlined: returned
/// through memory, the caller's copy of it read back wider than it was written and stalled
/// (store forwarding; a tenth of a packet's lighting, `fast::coherent`).
#[inline(always)]
pub fn surface(b: &Bindings, ray: &Ray, hit: &Hit) -> Surface {
    let point = ray.origin + hit.t * ray.dir;
    let (outward, mut ns, material) = if hit.prim & PLANE_FLAG != 0 {
        let pl = &b.planes[(hit.prim & !PLANE_FLAG) as usize];
        (pl.normal, pl.normal, pl.material)
    } else {
        let p = &b.prims[hit.prim as usize];
        let mut ng = intersect::prim_normal(p, point);
        // Where the geometry has no normal, the surface faces the ray.
        if ng == Vec3::ZERO {
            ng = -ray.dir;
        }
        let mut ns = ng;
        if p.kind() == PRIM_TRIANGLE && p.f1 >= 0.0 {
            let n = &b.tri_normals[p.f1 as usize];
            // Opposite vertex normals can cancel: the geometric normal stands in.
            let s = (1.0 - hit.u - hit.v) * n.n0 + hit.u * n.n1 + hit.v * n.n2;
            ns = intersect::unit_or_zero(s);
            if ns == Vec3::ZERO {
                ns = ng;
            }
        }
        (ng, ns, p.material())
    };
    let entering = outward.dot(ray.dir) < 0.0;
    let ng = if entering { outward } else { -outward };
    if ns.dot(ray.dir) > 0.0 {
        ns = -ns;
    }
    Surface {
        point,
        ng,
        ns,
        entering,
        material,
    }
}

/// Start of a secondary ray: off the surface along the geometric normal, on the side the
/// ray leaves towards.
pub fn offset_origin(s: &Surface, dir: Vec3, eps: f32) -> Vec3 {
    if s.ng.dot(dir) >= 0.0 {
        s.point + eps * s.ng
    } else {
        s.point - eps * s.ng
    }
}

/// A ray leaving surface `s` along `dir`, one level deeper than `parent`, its weight
/// scaled by `factor` (Ks or T).
pub(super) fn secondary(
    s: &Surface,
    dir: Vec3,
    parent: &Pending,
    factor: f32,
    eps: f32,
) -> Pending {
    Pending {
        origin: offset_origin(s, dir, eps),
        dir,
        weight: parent.weight * factor,
        depth: parent.depth + 1,
        tmin: 0.0,
    }
}

pub fn reflect_dir(d: Vec3, n: Vec3) -> Vec3 {
    d - 2.0 * n.dot(d) * n
}

/// Samples a light takes: nu x nv for an area light, nu x nu for an emitter, else one.
pub fn light_samples(light: &GpuLight) -> u32 {
    match light.kind {
        LIGHT_AREA => light.nu * light.nv,
        LIGHT_EMITTER => light.nu * light.nu,
        _ => 1,
    }
}

/// What surface `s` of material `m` gives before any light sample: the ambient term, and
/// its own light where the ray meets its front (an emitter's).
pub fn unlit(g: &GpuGlobals, s: &Surface, m: &GpuMaterial) -> Vec3 {
    let mut c = g.ambient * m.ambient;
    if s.entering {
        c += m.emission;
    }
    c
}

/// Emitter triangle `i` (`GpuLight`).
pub fn emitter_triangle<'a>(b: &Bindings<'a>, i: u32) -> &'a GpuLight {
    &b.emitter_triangles[i as usize]
}

/// A point on an emitter, and the emitter's whole area along the front normal there.
#[derive(Clone, Copy, Debug)]
pub struct EmitterPoint {
    pub point: Vec3,
    pub area_normal: Vec3,
}

/// Where sample `k` of emitter `light` lands, cell `(k % nu, k / nu)` of an `nu x nu`
/// grid, jittered: the first coordinate along the emitter's summed area chooses the
/// triangle by area and where within its share, the second runs across; the two map onto
/// the triangle uniformly, cells onto equal areas (the square root warp).
pub fn emitter_point(b: &Bindings, light: &GpuLight, k: u32, rng: &mut u32) -> EmitterPoint {
    let total = emitter_triangle(b, light.first + light.nv - 1).color.x;
    let goal = ((k % light.nu) as f32 + rand(rng)) / light.nu as f32 * total;
    // The first triangle whose summed area passes the goal.
    let (mut lo, mut hi) = (0, light.nv - 1);
    while lo < hi {
        let mid = (lo + hi) / 2;
        if emitter_triangle(b, light.first + mid).color.x > goal {
            hi = mid;
        } else {
            lo = mid + 1;
        }
    }
    let t = emitter_triangle(b, light.first + lo);
    let along = ((goal - (t.color.x - t.color.y)) / t.color.y).clamp(0.0, 1.0);
    let across = ((k / light.nu) as f32 + rand(rng)) / light.nu as f32;
    let r = along.sqrt();
    EmitterPoint {
        point: t.pos + r * (1.0 - across) * t.u + r * across * t.v,
        area_normal: t.u.cross(t.v).normalize() * total,
    }
}

/// The specular highlight of material `m` towards a light in direction `l`, for a ray
/// that came along `dir` and mirrors to `r` about the shading normal `n`: Phong,
/// `Ks (R.L)^Shine`, or under `SHADING_BLINN_PHONG` Blinn-Phong, `Ks (N.H)^Shine` with H
/// halfway between L and the way back to the viewer.
pub fn highlight(shading: u32, m: &GpuMaterial, n: Vec3, dir: Vec3, r: Vec3, l: Vec3) -> f32 {
    let c = if shading == SHADING_BLINN_PHONG {
        // N.L > 0 and N.dir <= 0 here, so L - dir is never zero.
        n.dot((l - dir).normalize())
    } else {
        r.dot(l)
    };
    // No power where there is no highlight: SPD files give `Ks 0` with a `Shine` of 1e5,
    // whose power underflows on libm's slow path (a tenth of gears-4's whole render).
    if c > 0.0 && m.ks != 0.0 {
        m.ks * c.powf(m.shine)
    } else {
        0.0
    }
}

/// A light sample's shadow ray and what the sample gives where nothing blocks it,
/// `intensity * term` (kept apart: `light_sample` multiplies the transmission in first).
#[derive(Clone, Copy, Debug)]
pub struct LightRay {
    pub ray: Ray,
    pub dist: f32,
    pub intensity: Vec3,
    pub term: Vec3,
}

/// The shadow ray of sample `k` of `light` at surface `s` (material `m`, incoming
/// direction `dir`, mirror direction `r`) and the Lambert and highlight terms it carries,
/// or `None` when the light is below the surface (no shadow ray is traced).
#[allow(clippy::too_many_arguments)]
pub fn light_ray(
    b: &Bindings,
    s: &Surface,
    m: &GpuMaterial,
    dir: Vec3,
    r: Vec3,
    light: &GpuLight,
    k: u32,
    rng: &mut u32,
) -> Option<LightRay> {
    let mut intensity = light.color / light_samples(light) as f32;
    let (l, dist) = if light.kind == LIGHT_DIRECTIONAL {
        (light.pos, NO_HIT)
    } else {
        let mut lp = light.pos;
        if light.kind == LIGHT_AREA {
            let su = ((k % light.nu) as f32 + rand(rng)) / light.nu as f32;
            let sv = ((k / light.nu) as f32 + rand(rng)) / light.nv as f32;
            lp += su * light.u + sv * light.v;
        }
        let mut area_normal = Vec3::ZERO;
        if light.kind == LIGHT_EMITTER {
            let e = emitter_point(b, light, k, rng);
            lp = e.point;
            area_normal = e.area_normal;
        }
        let to = lp - s.point;
        let (l, mut dist) = (to.normalize(), to.length());
        if light.kind == LIGHT_EMITTER {
            // Radiance over the emitter's area, seen at its cosine from the surface, as
            // intensity: that area times the cosine over pi r^2 (an emitter lights a
            // Lambertian surface as a physically based renderer's would). Emitters light
            // from their front only.
            let cos_e = -area_normal.dot(l);
            if cos_e <= 0.0 {
                return None;
            }
            intensity *= cos_e / (PI * dist * dist);
            // The shadow ray stops short of the emitter it aims at.
            dist -= 2.0 * b.globals.epsilon;
        }
        (l, dist)
    };
    let ndotl = s.ns.dot(l);
    if ndotl <= 0.0 {
        return None;
    }
    let spec = highlight(b.globals.shading, m, s.ns, dir, r, l);
    Some(LightRay {
        ray: Ray {
            origin: offset_origin(s, l, b.globals.epsilon),
            dir: l,
        },
        dist,
        intensity,
        term: m.kd * m.color * ndotl + Vec3::splat(spec),
    })
}

/// Sample `k` of `light` at the surface `at`: Lambert and the highlight scaled by the
/// shadow ray's transmission, or `None` when the light is below the surface (no shadow
/// ray is traced). The shadow ray is answered by `tracer`; adds its node fetches to
/// `counts`.
pub fn light_sample(
    b: &Bindings,
    tracer: &mut impl Tracer,
    at: &Shaded,
    (light, k): (&GpuLight, u32),
    rng: &mut u32,
    counts: &mut RayCounts,
) -> Option<Vec3> {
    let Shaded { s, m, dir, r } = *at;
    let lr = light_ray(b, s, m, dir, r, light, k, rng)?;
    let mut nodes = 0;
    let shadow = tracer.transmission(b, &lr.ray, lr.dist, &mut nodes);
    counts.shadow_nodes += u64::from(nodes);
    Some(shadow * lr.intensity * lr.term)
}

/// Direct light at surface `s` of material `m` (`textured`): ambient plus, per light
/// sample, Lambert and the highlight, each scaled by the shadow ray's transmission.
fn direct(
    b: &Bindings,
    tracer: &mut impl Tracer,
    (s, m): (&Surface, &GpuMaterial),
    dir: Vec3,
    rng: &mut u32,
    counts: &mut RayCounts,
) -> Vec3 {
    let g = b.globals;
    let mut colour = unlit(g, s, m);
    let at = Shaded {
        s,
        m,
        dir,
        r: reflect_dir(dir, s.ns),
    };
    for light in b.lights {
        for k in 0..light_samples(light) {
            if let Some(c) = tracer.light_sample(b, &at, (light, k), rng, counts) {
                counts.shadow += 1;
                colour += c;
            }
        }
    }
    colour
}

/// The transmitted direction at `s` for material `m`; total internal reflection sends the
/// transmitted weight along the mirror ray.
pub fn refracted_dir(s: &Surface, m: &GpuMaterial, dir: Vec3) -> Vec3 {
    let eta = if s.entering { 1.0 / m.ior } else { m.ior };
    let cos_i = -s.ns.dot(dir);
    let k = 1.0 - eta * eta * (1.0 - cos_i * cos_i);
    if k < 0.0 {
        reflect_dir(dir, s.ns)
    } else {
        (eta * dir + (eta * cos_i - k.sqrt()) * s.ns).normalize()
    }
}

/// Adds the nodes a ray of depth `depth` fetched to its kind's count: the eye ray's, or a
/// reflected or refracted ray's.
pub fn count_nodes(counts: &mut RayCounts, depth: u32, nodes: u32) {
    if depth == 1 {
        counts.eye_nodes += u64::from(nodes);
    } else {
        counts.secondary_nodes += u64::from(nodes);
    }
}

/// Colour seen along an eye ray: Whitted shading with reflection and refraction, the
/// rays' answers from `tracer`.
pub fn trace(
    b: &Bindings,
    tracer: &mut impl Tracer,
    eye: &Ray,
    rng: &mut u32,
    counts: &mut RayCounts,
) -> Vec3 {
    let g = b.globals;
    // Not zeroed: clearing its 576 bytes for every camera ray was 2.6% of a render's
    // instructions (balls-4), and only entries below `sp` are ever read.
    let mut stack = [const { MaybeUninit::<Pending>::uninit() }; RAY_STACK];
    let mut sp = 0usize;
    // The ray being shaded: the eye ray first, then each waiting one, last in first out.
    // The eye ray does not go through the stack: writing it there and reading it back at
    // once made a copy whose loads straddled its stores, which stalled.
    let mut ray_in = Pending {
        origin: eye.origin,
        dir: eye.dir,
        weight: 1.0,
        depth: 1,
        tmin: g.hither,
    };
    // The most rays waiting at once: the shader's stack holds `trace_stack` of them.
    let mut most = 1usize;
    let mut colour = Vec3::ZERO;
    loop {
        'shade: {
            let ray = Ray {
                origin: ray_in.origin,
                dir: ray_in.dir,
            };
            let hit = tracer.closest_hit(b, &ray, ray_in.tmin, NO_HIT);
            count_nodes(counts, ray_in.depth, hit.nodes);
            if hit.prim == NO_PRIM {
                colour += ray_in.weight * g.background;
                break 'shade;
            }
            let s = tracer.surface(b, &ray, &hit);
            let m = &textured(b, &b.materials[s.material as usize], &hit);
            colour += ray_in.weight * direct(b, tracer, (&s, m), ray.dir, rng, counts);
            if ray_in.depth >= g.max_depth {
                break 'shade;
            }
            if m.ks > 0.0 {
                let dir = reflect_dir(ray.dir, s.ns);
                counts.reflected += 1;
                stack[sp].write(secondary(&s, dir, &ray_in, m.ks, g.epsilon));
                sp += 1;
            }
            if m.t > 0.0 {
                counts.refracted += 1;
                let dir = refracted_dir(&s, m, ray.dir);
                stack[sp].write(secondary(&s, dir, &ray_in, m.t, g.epsilon));
                sp += 1;
            }
            most = most.max(sp);
        }
        if sp == 0 {
            break;
        }
        sp -= 1;
        // SAFETY: entries below the old `sp` have been written.
        ray_in = unsafe { stack[sp].assume_init() };
    }
    debug_assert!(
        most <= crate::pack::trace_stack(b.materials, g.max_depth) as usize,
        "{most} rays waited at once, beyond the shader's ray stack"
    );
    colour
}
