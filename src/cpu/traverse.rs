//! CPU twin of `shaders/traverse.wgsl`: closest-hit and shadow (any-hit) traversal of the
//! flattened BVH with a fixed stack, near child first, plus the planes kept outside it.

use glam::{Vec3, Vec4};

use super::intersect;
use super::types::{Bindings, Hit, NO_HIT, NO_PRIM, PLANE_FLAG, Ray};
use crate::gpu_types::TRAVERSAL_STACK;

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

/// Nearest surface along the ray within `(tmin, tmax)`.
pub fn closest_hit(b: &Bindings, ray: &Ray, tmin: f32, tmax: f32) -> Hit {
    let mut hit = Hit {
        t: tmax,
        prim: NO_PRIM,
        u: 0.0,
        v: 0.0,
        cost: 0,
    };
    for (i, pl) in b.planes.iter().enumerate() {
        let t = intersect::plane(pl, ray);
        if t > tmin && t < hit.t {
            hit.t = t;
            hit.prim = PLANE_FLAG | i as u32;
        }
    }
    if b.globals.n_nodes == 0 {
        return hit;
    }
    let inv_dir = intersect::safe_inverse(ray.dir);
    let neg = [ray.dir.x < 0.0, ray.dir.y < 0.0, ray.dir.z < 0.0];
    let mut stack = [0u32; TRAVERSAL_STACK];
    let mut sp = 0usize;
    let mut node = 0u32;
    loop {
        // Descend until this ray reaches a leaf it overlaps (the shader's SIMD batches then
        // test primitives together; see traverse.wgsl).
        let mut first = 0u32;
        let mut count = 0u32;
        loop {
            let n = &b.nodes[node as usize];
            hit.cost += 1;
            if intersect::overlaps(n.min, n.max, ray.origin, inv_dir, tmin, hit.t) {
                count = n.count();
                if count > 0 {
                    first = n.offset;
                    break;
                }
                // Visit the child nearer along the split axis first.
                let second_first = neg[n.axis() as usize];
                stack[sp] = if second_first { node + 1 } else { n.offset };
                node = if second_first { n.offset } else { node + 1 };
                sp += 1;
                continue;
            }
            if sp == 0 {
                break;
            }
            sp -= 1;
            node = stack[sp];
        }
        if count == 0 {
            break;
        }
        for i in first..first + count {
            let p = &b.prims[i as usize];
            let t = intersect::prim(p, ray, inv_dir);
            let t_first = first_in(t, tmin, hit.t);
            if t_first != NO_HIT {
                hit.t = t_first;
                hit.prim = i;
                hit.u = t.z;
                hit.v = t.w;
            }
        }
        if sp == 0 {
            break;
        }
        sp -= 1;
        node = stack[sp];
    }
    hit
}

/// Light reaching the end of the segment `origin + t*dir, t in (0, tmax)`: an opaque
/// occluder blocks it, each crossing of a transmitting surface multiplies it by `T * C`.
pub fn transmission(b: &Bindings, ray: &Ray, tmax: f32) -> Vec3 {
    let mut light = Vec3::ONE;
    for pl in b.planes {
        let t = intersect::plane(pl, ray);
        if t > 0.0 && t < tmax {
            let m = &b.materials[pl.material as usize];
            if m.t <= 0.0 {
                return Vec3::ZERO;
            }
            light *= m.t * m.color;
        }
    }
    if b.globals.n_nodes == 0 {
        return light;
    }
    let inv_dir = intersect::safe_inverse(ray.dir);
    let neg = [ray.dir.x < 0.0, ray.dir.y < 0.0, ray.dir.z < 0.0];
    let mut stack = [0u32; TRAVERSAL_STACK];
    let mut sp = 0usize;
    let mut node = 0u32;
    loop {
        let mut first = 0u32;
        let mut count = 0u32;
        loop {
            let n = &b.nodes[node as usize];
            if intersect::overlaps(n.min, n.max, ray.origin, inv_dir, 0.0, tmax) {
                count = n.count();
                if count > 0 {
                    first = n.offset;
                    break;
                }
                let second_first = neg[n.axis() as usize];
                stack[sp] = if second_first { node + 1 } else { n.offset };
                node = if second_first { n.offset } else { node + 1 };
                sp += 1;
                continue;
            }
            if sp == 0 {
                break;
            }
            sp -= 1;
            node = stack[sp];
        }
        if count == 0 {
            break;
        }
        for i in first..first + count {
            let p = &b.prims[i as usize];
            let t = intersect::prim(p, ray, inv_dir);
            let crossings = (t.x > 0.0 && t.x < tmax) as u32 + (t.y > 0.0 && t.y < tmax) as u32;
            if crossings > 0 {
                let m = &b.materials[p.material() as usize];
                if m.t <= 0.0 {
                    return Vec3::ZERO;
                }
                for _ in 0..crossings {
                    light *= m.t * m.color;
                }
            }
        }
        if sp == 0 {
            break;
        }
        sp -= 1;
        node = stack[sp];
    }
    light
}
