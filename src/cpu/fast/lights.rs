//! The surfaces a packet's rays met, lit by one point or directional light, lane by
//! lane in plain arrays (which the compiler turns into SIMD instructions): what
//! `shade::light_ray` makes for each surface (its shadow ray and the Lambert and highlight
//! terms), for the whole packet at once (`coherent.rs`, which then traces the shadow rays
//! as one occlusion packet).
//!
//! Each lane does `light_ray`'s operations in `light_ray`'s order (glam's `Vec3` methods
//! written out: `dot` adds x, y then z; `normalize` multiplies by the reciprocal of the
//! length), and none of them is fused or approximated, so each lane gets the bits
//! `light_ray` gets for its surface; the tests compare the images and the packets'
//! rays with the per-pixel renderer's to the bit (tests/gpurt/packet.rs).
//! Made once per packet, not per surface and light: the call, its `Option` and the copy
//! of its result cost more than the arithmetic.

// A lane `k` or a coordinate `a` indexes several arrays at once here.
#![allow(clippy::needless_range_loop)]

use glam::Vec3;

use super::packet::{MAX_LANES, Packet};
use crate::cpu::intersect::lanes_of;
use crate::cpu::shade::{Surface, light_samples};
use crate::cpu::texture::textured;
use crate::cpu::types::{Bindings, Hit};
use crate::gpu_types::{GpuLight, LIGHT_DIRECTIONAL, LIGHT_POINT, NO_HIT, SHADING_BLINN_PHONG};

/// One value a lane.
type Row = [f32; MAX_LANES];

/// A vector a lane, by coordinate.
type Rows = [Row; 3];

/// `a . b` lane by lane, as `Vec3::dot` adds it.
#[inline(always)]
fn dot(a: &Rows, b: &Rows, k: usize) -> f32 {
    (a[0][k] * b[0][k]) + (a[1][k] * b[1][k]) + (a[2][k] * b[2][k])
}

/// The surfaces a packet's rays met, with what `light_ray` reads of them and of
/// their materials, lane by lane; `live` has a bit for each lane with a surface. (The
/// first `N` lanes of the arrays are worked out, `N` the packet's width, whichever lanes
/// hold a surface: fixed bounds vectorise without a remainder loop, which cost more than
/// the unused lanes; the arrays' other lanes are never read.)
pub struct Surfaces {
    live: u32,
    point: Rows,
    ng: Rows,
    ns: Rows,
    /// The ray's direction, and its mirror direction about `ns` (`reflect_dir`).
    dir: Rows,
    r: Rows,
    kd: Row,
    color: Rows,
    ks: Row,
    shine: Row,
}

impl Surfaces {
    /// The surfaces `surfaces` of the lanes in `met` (a lane each; the others met
    /// nothing) of the rays with directions `dirs`, met at `hits` (their materials
    /// `textured`).
    pub fn new<const N: usize>(
        b: &Bindings,
        (surfaces, met): (&[Surface; MAX_LANES], u32),
        hits: &[Hit; MAX_LANES],
        dirs: &[Vec3],
    ) -> Self {
        let zero = [[0.0; MAX_LANES]; 3];
        let mut all = Surfaces {
            live: 0,
            point: zero,
            ng: zero,
            ns: zero,
            dir: zero,
            r: zero,
            kd: [0.0; MAX_LANES],
            color: zero,
            ks: [0.0; MAX_LANES],
            shine: [0.0; MAX_LANES],
        };
        for k in lanes_of(met) {
            let s = &surfaces[k];
            let m = &textured(b, &b.materials[s.material as usize], &hits[k]);
            all.live |= 1 << k;
            for a in 0..3 {
                all.point[a][k] = s.point[a];
                all.ng[a][k] = s.ng[a];
                all.ns[a][k] = s.ns[a];
                all.dir[a][k] = dirs[k][a];
                all.color[a][k] = m.color[a];
            }
            (all.kd[k], all.ks[k], all.shine[k]) = (m.kd, m.ks, m.shine);
        }
        // `reflect_dir(dir, ns)`: d - 2 (n.d) n.
        for k in 0..N {
            let twice = 2.0 * dot(&all.ns, &all.dir, k);
            for a in 0..3 {
                all.r[a][k] = all.dir[a][k] - twice * all.ns[a][k];
            }
        }
        all
    }
}

/// What one light gives each surface of a packet before its shadow ray is traced: the
/// lanes whose surface faces the light (`live`: those `light_ray` makes a shadow ray
/// for), `LightRay::intensity` (one for all) and `LightRay::term` by lane.
pub struct Lights {
    pub live: u32,
    pub intensity: Vec3,
    term: Rows,
}

impl Lights {
    /// `LightRay::term` of lane `k`.
    pub fn term(&self, k: usize) -> Vec3 {
        Vec3::new(self.term[0][k], self.term[1][k], self.term[2][k])
    }
}

/// Whether `light`'s shadow rays go in packets: a point or a directional light, one sample
/// and no random numbers (an area light's or an emitter's samples are drawn one by one).
pub fn packed(light: &GpuLight) -> bool {
    matches!(light.kind, LIGHT_POINT | LIGHT_DIRECTIONAL)
}

/// `light_ray(b, s, m, dir, r, light, 0, _)` for every surface of `all`: puts the shadow
/// rays in `packet` (lane by lane, over `(0, dist)`, in place of its rays) and returns
/// the rest. `light` is `packed`; `N` is the packet's width, as in `Surfaces::new`.
pub fn light_rays<const N: usize>(
    b: &Bindings,
    all: &Surfaces,
    light: &GpuLight,
    packet: &mut Packet,
) -> Lights {
    debug_assert!(packed(light));
    let g = b.globals;
    let mut l: Rows = [[0.0; MAX_LANES]; 3];
    let mut dist = [NO_HIT; MAX_LANES];
    if light.kind == LIGHT_DIRECTIONAL {
        for (a, row) in l.iter_mut().enumerate() {
            *row = [light.pos[a]; MAX_LANES];
        }
    } else {
        // `(lp - point).normalize()` and its length.
        let mut to: Rows = [[0.0; MAX_LANES]; 3];
        for k in 0..N {
            for a in 0..3 {
                to[a][k] = light.pos[a] - all.point[a][k];
            }
            let length = dot(&to, &to, k).sqrt();
            let recip = 1.0 / length;
            for a in 0..3 {
                l[a][k] = to[a][k] * recip;
            }
            dist[k] = length;
        }
    }
    let mut ndotl = [0.0; MAX_LANES];
    let mut live = 0;
    for (k, n) in ndotl[..N].iter_mut().enumerate() {
        *n = dot(&all.ns, &l, k);
        // `light_ray` gives up where `ndotl <= 0` (not where it is NaN, as at a surface
        // point on the light itself).
        live |= u32::from(*n > 0.0 || n.is_nan()) << k;
    }
    live &= all.live;
    // `highlight`: the power only where there is a highlight, as there.
    let mut cosine = [0.0; MAX_LANES];
    for (k, c) in cosine[..N].iter_mut().enumerate() {
        *c = if g.shading == SHADING_BLINN_PHONG {
            let h = [0, 1, 2].map(|a| l[a][k] - all.dir[a][k]);
            let recip = 1.0 / ((h[0] * h[0]) + (h[1] * h[1]) + (h[2] * h[2])).sqrt();
            (all.ns[0][k] * (h[0] * recip))
                + (all.ns[1][k] * (h[1] * recip))
                + (all.ns[2][k] * (h[2] * recip))
        } else {
            dot(&all.r, &l, k)
        };
    }
    let mut spec = [0.0; MAX_LANES];
    for k in lanes_of(live) {
        if cosine[k] > 0.0 && all.ks[k] != 0.0 {
            spec[k] = all.ks[k] * cosine[k].powf(all.shine[k]);
        }
    }
    // `offset_origin(s, l, epsilon)`, and the terms.
    let mut term: Rows = [[0.0; MAX_LANES]; 3];
    let mut origin: Rows = [[0.0; MAX_LANES]; 3];
    for k in 0..N {
        let out = dot(&all.ng, &l, k) >= 0.0;
        for a in 0..3 {
            let step = g.epsilon * all.ng[a][k];
            let (above, below) = (all.point[a][k] + step, all.point[a][k] - step);
            origin[a][k] = if out { above } else { below };
            term[a][k] = all.kd[k] * all.color[a][k] * ndotl[k] + spec[k];
        }
    }
    packet.set_rows((&origin, &l), 0.0, &dist, live);
    Lights {
        live,
        intensity: light.color / light_samples(light) as f32,
        term,
    }
}
