// shade.wgsl: the Whitted model of docs/shading.md, iterative with an explicit stack of
// pending rays, pushed and popped in the same order as the CPU (twin: src/cpu/shade.rs).

struct Pending {
    origin: vec3<f32>,
    dir: vec3<f32>,
    weight: f32,
    depth: u32,
    tmin: f32,
}

struct Surface {
    point: vec3<f32>,
    ng: vec3<f32>,
    ns: vec3<f32>,
    entering: bool,
    material: u32,
}

fn surface(ray: Ray, hit: Hit) -> Surface {
    let point = ray.origin + hit.t * ray.dir;
    var outward: vec3<f32>;
    var ns: vec3<f32>;
    var material: u32;
    if (PLANES && (hit.prim & PLANE_FLAG) != 0u) {
        let pl = planes[hit.prim & ~PLANE_FLAG];
        outward = pl.normal;
        ns = pl.normal;
        material = pl.material;
    } else {
        let p = load_prim(hit.prim);
        outward = prim_normal(p, point);
        // Where the geometry has no normal, the surface faces the ray.
        if (all(outward == vec3<f32>(0.0))) {
            outward = -ray.dir;
        }
        ns = outward;
        if (NORMALS && prim_kind(p) == PRIM_TRIANGLE && p.f1 >= 0.0) {
            let n = load_tri_normals(u32(p.f1));
            // Opposite vertex normals can cancel: the geometric normal stands in.
            let s = unit_or_zero((1.0 - hit.u - hit.v) * n.n0 + hit.u * n.n1 + hit.v * n.n2);
            ns = select(outward, s, any(s != vec3<f32>(0.0)));
        }
        material = prim_material(p);
    }
    let entering = dot(outward, ray.dir) < 0.0;
    let ng = select(-outward, outward, entering);
    if (dot(ns, ray.dir) > 0.0) {
        ns = -ns;
    }
    return Surface(point, ng, ns, entering, material);
}

fn offset_origin(s: Surface, dir: vec3<f32>, eps: f32) -> vec3<f32> {
    if (dot(s.ng, dir) >= 0.0) {
        return s.point + eps * s.ng;
    }
    return s.point - eps * s.ng;
}

// A ray leaving surface `s` along `dir`, one level deeper than `parent`, its weight scaled
// by `factor` (Ks or T).
fn secondary(s: Surface, dir: vec3<f32>, parent: Pending, factor: f32) -> Pending {
    return Pending(offset_origin(s, dir, globals.epsilon), dir, parent.weight * factor, parent.depth + 1u, 0.0);
}

fn reflect_dir(d: vec3<f32>, n: vec3<f32>) -> vec3<f32> {
    return d - 2.0 * dot(n, d) * n;
}

// Samples a light takes: nu x nv for an area light, nu x nu for an emitter, else one.
fn light_samples(light: Light) -> u32 {
    if (AREA_LIGHTS && light.kind == LIGHT_AREA) {
        return light.nu * light.nv;
    }
    if (EMITTERS && light.kind == LIGHT_EMITTER) {
        return light.nu * light.nu;
    }
    return 1u;
}

// What surface `s` of material m gives before any light sample: the ambient term, and
// its own light where the ray meets its front (an emitter's).
fn unlit(s: Surface, m: Material) -> vec3<f32> {
    var c = globals.ambient * m.ambient;
    if (EMITTERS && s.entering) {
        c += m.emission;
    }
    return c;
}

// Emitter triangle i, after the lights in their buffer (src/gpu_types.rs: GpuLight).
fn emitter_triangle(i: u32) -> Light {
    return lights[globals.n_lights + i];
}

// A point on an emitter, and the emitter's whole area along the front normal there.
struct EmitterPoint {
    point: vec3<f32>,
    area_normal: vec3<f32>,
}

// Where sample k of emitter `light` lands, cell (k % nu, k / nu) of an nu x nu grid,
// jittered: the first coordinate along the emitter's summed area chooses the triangle by
// area and where within its share, the second runs across; the two map onto the triangle
// uniformly, cells onto equal areas (the square root warp).
fn emitter_point(light: Light, k: u32, rng: ptr<function, u32>) -> EmitterPoint {
    let total = emitter_triangle(light.first + light.nv - 1u).color.x;
    let goal = (f32(k % light.nu) + rand(rng)) / f32(light.nu) * total;
    // The first triangle whose summed area passes the goal.
    var lo = 0u;
    var hi = light.nv - 1u;
    while (lo < hi) {
        let mid = (lo + hi) / 2u;
        if (emitter_triangle(light.first + mid).color.x > goal) {
            hi = mid;
        } else {
            lo = mid + 1u;
        }
    }
    let t = emitter_triangle(light.first + lo);
    let along = clamp((goal - (t.color.x - t.color.y)) / t.color.y, 0.0, 1.0);
    let across = (f32(k / light.nu) + rand(rng)) / f32(light.nu);
    let r = sqrt(along);
    return EmitterPoint(t.pos + r * (1.0 - across) * t.u + r * across * t.v, normalize(cross(t.u, t.v)) * total);
}

// The specular highlight of material m towards a light in direction l, for a ray that
// came along `dir` and mirrors to `r` about the shading normal n: Phong, Ks (R.L)^Shine,
// or with SHADING_BLINN_PHONG Blinn-Phong, Ks (N.H)^Shine with H halfway between L and
// the way back to the viewer. SHADING is an override, so Phong pipelines hold only the
// first branch and Phong images stay as they were.
fn highlight(m: Material, n: vec3<f32>, dir: vec3<f32>, r: vec3<f32>, l: vec3<f32>) -> f32 {
    var c: f32;
    if (SHADING == SHADING_BLINN_PHONG) {
        // N.L > 0 and N.dir <= 0 here, so L - dir is never zero.
        c = dot(n, normalize(l - dir));
    } else {
        c = dot(r, l);
    }
    // No power where there is no highlight (SPD's `Ks 0` with a `Shine` of 1e5).
    if (c > 0.0 && m.ks != 0.0) {
        return m.ks * pow(c, m.shine);
    }
    return 0.0;
}

// A light sample's shadow ray and what the sample gives where nothing blocks it,
// `intensity * term` (kept apart: `light_sample` multiplies the transmission in first);
// `traced` is 0 when the light is below the surface: no ray, no light.
struct LightRay {
    origin: vec3<f32>,
    dist: f32,
    dir: vec3<f32>,
    traced: u32,
    intensity: vec3<f32>,
    term: vec3<f32>,
}

// The shadow ray of sample k of `light` at surface `s` (material m, incoming direction
// dir, mirror direction r), and the Lambert and highlight terms it carries.
fn light_ray(s: Surface, m: Material, dir: vec3<f32>, r: vec3<f32>, light: Light, k: u32, rng: ptr<function, u32>) -> LightRay {
    var intensity = light.color / f32(light_samples(light));
    var l: vec3<f32>;
    var dist: f32;
    if (DIRECTIONAL_LIGHTS && light.kind == LIGHT_DIRECTIONAL) {
        l = light.pos;
        dist = NO_HIT;
    } else {
        var lp = light.pos;
        if (AREA_LIGHTS && light.kind == LIGHT_AREA) {
            let su = (f32(k % light.nu) + rand(rng)) / f32(light.nu);
            let sv = (f32(k / light.nu) + rand(rng)) / f32(light.nv);
            lp += su * light.u + sv * light.v;
        }
        var area_normal = vec3<f32>(0.0);
        if (EMITTERS && light.kind == LIGHT_EMITTER) {
            let e = emitter_point(light, k, rng);
            lp = e.point;
            area_normal = e.area_normal;
        }
        let to = lp - s.point;
        l = normalize(to);
        dist = length(to);
        if (EMITTERS && light.kind == LIGHT_EMITTER) {
            // Radiance over the emitter's area, seen at its cosine from the surface, as
            // intensity: that area times the cosine over pi r^2 (an emitter lights a
            // Lambertian surface as a physically based renderer's would). Emitters light
            // from their front only.
            let cos_e = -dot(area_normal, l);
            if (cos_e <= 0.0) {
                return LightRay();
            }
            intensity *= cos_e / (PI * dist * dist);
            // The shadow ray stops short of the emitter it aims at.
            dist -= 2.0 * globals.epsilon;
        }
    }
    let ndotl = dot(s.ns, l);
    if (ndotl <= 0.0) {
        return LightRay();
    }
    let spec = highlight(m, s.ns, dir, r, l);
    let term = m.kd * m.color * ndotl + vec3<f32>(spec);
    return LightRay(offset_origin(s, l, globals.epsilon), dist, l, 1u, intensity, term);
}

// Sample k of `light` at surface `s` (material m, incoming direction dir, mirror
// direction r): in xyz Lambert and the highlight scaled by the shadow ray's transmission
// (0 where the light is below the surface; with SHADOW_RAYS off the light is taken as
// unblocked); w is 1 where a shadow ray was traced, else 0.
fn light_sample(s: Surface, m: Material, dir: vec3<f32>, r: vec3<f32>, light: Light, k: u32, rng: ptr<function, u32>) -> vec4<f32> {
    let lr = light_ray(s, m, dir, r, light, k, rng);
    if (lr.traced == 0u) {
        return vec4<f32>(0.0);
    }
    if (!SHADOW_RAYS) {
        return vec4<f32>(lr.intensity * lr.term, 0.0);
    }
    let fetched_before = fetched;
    let shadow = transmission(Ray(lr.origin, lr.dir), lr.dist);
    if (COUNTERS) {
        counts.shadow_rays += 1u;
        counts.shadow_nodes += fetched - fetched_before;
    }
    return vec4<f32>(shadow * lr.intensity * lr.term, 1.0);
}

// Direct light at surface `s` of material m (`textured`).
fn direct(s: Surface, m: Material, dir: vec3<f32>, rng: ptr<function, u32>, rays: ptr<function, u32>) -> vec3<f32> {
    var colour = unlit(s, m);
    let r = reflect_dir(dir, s.ns);
    var li = 0u;
    for (; li < globals.n_lights; li++) {
        let light = lights[li];
        let samples = light_samples(light);
        var k = 0u;
        for (; k < samples; k++) {
            let c = light_sample(s, m, dir, r, light, k, rng);
            colour += c.xyz;
            if (c.w > 0.0) {
                *rays += 1u;
            }
        }
        cut_short = cut_short || k < samples;
    }
    cut_short = cut_short || li < globals.n_lights;
    return colour;
}

// The transmitted direction at `s` for material m; total internal reflection sends the
// transmitted weight along the mirror ray.
fn refracted_dir(s: Surface, m: Material, dir: vec3<f32>) -> vec3<f32> {
    let eta = select(m.ior, 1.0 / m.ior, s.entering);
    let cos_i = -dot(s.ns, dir);
    let k = 1.0 - eta * eta * (1.0 - cos_i * cos_i);
    if (k < 0.0) {
        return reflect_dir(dir, s.ns);
    }
    return normalize(eta * dir + (eta * cos_i - sqrt(k)) * s.ns);
}

// Adds the nodes a ray of depth `depth` fetched to its kind's count (COUNTERS): the eye
// ray's, or a reflected or refracted ray's.
fn count_nodes(depth: u32, nodes: u32) {
    if (depth == 1u) {
        counts.eye_nodes += nodes;
    } else {
        counts.secondary_nodes += nodes;
    }
}

// One ray of a camera sample's tree, the top of `stack` (`sp` rays waiting): traced, its
// hit shaded, its reflected and refracted rays pushed; returns the light it brings. (Its
// loop is `trace`'s, and `pooled` takes one ray a loop iteration from any sample.)
fn trace_ray(stack: ptr<function, array<Pending, TRACE_STACK>>, sp: ptr<function, u32>, rng: ptr<function, u32>, rays: ptr<function, u32>) -> vec3<f32> {
    *sp -= 1u;
    let ray_in = (*stack)[*sp];
    let ray = Ray(ray_in.origin, ray_in.dir);
    let fetched_before = fetched;
    let hit = closest_hit(ray, ray_in.tmin, NO_HIT);
    if (COUNTERS) {
        count_nodes(ray_in.depth, fetched - fetched_before);
    }
    if (hit.prim == NO_PRIM) {
        return ray_in.weight * globals.background;
    }
    let s = surface(ray, hit);
    let m = textured(materials[s.material], hit);
    let colour = ray_in.weight * direct(s, m, ray.dir, rng, rays);
    if (ray_in.depth >= globals.max_depth) {
        return colour;
    }
    if (REFLECTION && m.ks > 0.0) {
        let dir = reflect_dir(ray.dir, s.ns);
        *rays += 1u;
        if (COUNTERS) {
            counts.secondary_rays += 1u;
        }
        (*stack)[*sp] = secondary(s, dir, ray_in, m.ks);
        *sp += 1u;
    }
    if (REFRACTION && m.t > 0.0) {
        *rays += 1u;
        if (COUNTERS) {
            counts.secondary_rays += 1u;
        }
        (*stack)[*sp] = secondary(s, refracted_dir(s, m, ray.dir), ray_in, m.t);
        *sp += 1u;
    }
    return colour;
}

// The stack holds at most TRACE_STACK rays on the scene in hand (the host writes that
// constant into the source: `SceneBuffers::trace_stack`), which keeps lavapipe's compile
// short where few rays wait.
fn trace(eye: Ray, rng: ptr<function, u32>, rays: ptr<function, u32>) -> vec3<f32> {
    var stack: array<Pending, TRACE_STACK>;
    stack[0] = Pending(eye.origin, eye.dir, 1.0, 1u, globals.hither);
    var sp = 1u;
    var colour = vec3<f32>(0.0);
    while (sp > 0u) {
        colour += trace_ray(&stack, &sp, rng, rays);
    }
    cut_short = cut_short || sp > 0u;
    return colour;
}
