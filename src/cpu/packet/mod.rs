//! Packets of coherent rays: up to sixteen rays of neighbouring pixels (or their shadow
//! rays to one light, or their reflections off one flat mirror) traced together through
//! the eight-wide tree, one SIMD lane a ray, where `traverse.rs` traces one ray at a time.
//!
//! - `lanes`: the SIMD operations, one trait over the instruction sets, `Portable` for
//!   machines without one of `x86`'s (AVX-512: 16 lanes, AVX2: 8, SSE: 4).
//! - `walk`: the closest-hit and occlusion walks, written once over `Lanes`; `frustum`:
//!   the interval test that culls children for the whole packet; `leaf`: primitives
//!   against the lanes; `single`: lanes that walk on alone where few are left.
//! - here: the instruction set chosen at run time (`Isa`, `Kernels`, `GPURT_SIMD`), and the
//!   packet API the renderer calls, which answers exactly what `closest_hit` and
//!   `transmission` answer for each ray: the lanes whose answer depends on the order of
//!   the walk (two surfaces at one distance; a shadow ray through transmitting surfaces
//!   of two materials, whose factors multiply in visiting order) are traced again alone.
//!
//! The dispatch is `is_x86_feature_detected!` and `#[target_feature]` functions, not a
//! crate: `pulp` (already built, through `exr`) has no lane bit mask in its generic
//! vectors, which the walk reads at every node, and `multiversion` or `wide` would still
//! leave the register types to write per instruction set. `x86.rs` holds the packets'
//! intrinsics (the single-ray walk's one AVX box test is `wide::SlabsAvx`), `x86_walks.rs`
//! compiles the walks for each set.

mod frustum;
pub mod lanes;
mod leaf;
mod rays;
mod single;
mod walk;
#[cfg(target_arch = "x86_64")]
mod x86;
#[cfg(target_arch = "x86_64")]
mod x86_walks;

use glam::Vec3;

use super::intersect::lanes_of;
use super::traverse::{closest_hit, transmission, transmit_planes};
use super::types::{Bindings, Hit, Ray};
use crate::bvh::wide::WideNode;
use crate::error::{Error, Result};
pub use lanes::MAX_LANES;
use rays::{Found, Occluded, Rows};

/// The instruction sets the packet kernels are compiled for, widest first.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Isa {
    Avx512,
    Avx2,
    Sse,
    /// Plain arrays of four (NEON on AArch64, through LLVM).
    Portable,
}

impl Isa {
    pub const ALL: [Isa; 4] = [Isa::Avx512, Isa::Avx2, Isa::Sse, Isa::Portable];

    /// Its name in `GPURT_SIMD` and `--stats`.
    pub fn name(self) -> &'static str {
        match self {
            Isa::Avx512 => "avx512",
            Isa::Avx2 => "avx2",
            Isa::Sse => "sse",
            Isa::Portable => "portable",
        }
    }

    /// Rays a packet holds.
    pub fn lanes(self) -> usize {
        match self {
            Isa::Avx512 => 16,
            Isa::Avx2 => 8,
            Isa::Sse | Isa::Portable => 4,
        }
    }

    /// Whether this machine runs it.
    pub fn available(self) -> bool {
        Kernels::new(self).is_some()
    }

    /// The widest this machine runs.
    pub fn best() -> Isa {
        Isa::ALL
            .into_iter()
            .find(|i| i.available())
            .unwrap_or(Isa::Portable)
    }
}

/// The kernels of one instruction set, found on this machine.
#[derive(Clone, Copy, Debug)]
pub struct Kernels {
    kind: Kind,
}

/// The token of an instruction set, proof that this machine has it.
#[derive(Clone, Copy, Debug)]
enum Kind {
    #[cfg(target_arch = "x86_64")]
    Avx512(x86::Avx512),
    #[cfg(target_arch = "x86_64")]
    Avx2(x86::Avx2),
    #[cfg(target_arch = "x86_64")]
    Sse(x86::Sse),
    Portable,
}

/// Fewer lanes than this in a packet, and its rays are traced one at a time.
const MIN_LANES: u32 = 2;

impl Kernels {
    /// `isa`'s kernels, where this machine has its instructions.
    pub fn new(isa: Isa) -> Option<Self> {
        #[cfg(target_arch = "x86_64")]
        let kind = match isa {
            Isa::Avx512 => x86::Avx512::detect().map(Kind::Avx512),
            Isa::Avx2 => x86::Avx2::detect().map(Kind::Avx2),
            Isa::Sse => Some(Kind::Sse(x86::Sse::new())),
            Isa::Portable => Some(Kind::Portable),
        };
        #[cfg(not(target_arch = "x86_64"))]
        let kind = (isa == Isa::Portable).then_some(Kind::Portable);
        kind.map(|kind| Kernels { kind })
    }

    /// What `GPURT_SIMD` asks for: unset or empty, the widest kernels this machine runs;
    /// `avx512`, `avx2`, `sse` or `portable`, those (an error where the machine lacks
    /// them); `none`, no packets: every ray traced alone, as before packets.
    pub fn from_env() -> Result<Option<Self>> {
        let v = std::env::var("GPURT_SIMD").unwrap_or_default();
        if v.is_empty() {
            return Ok(Kernels::new(Isa::best()));
        }
        if v == "none" {
            return Ok(None);
        }
        let names: Vec<&str> = Isa::ALL.iter().map(|i| i.name()).collect();
        let isa = Isa::ALL
            .into_iter()
            .find(|i| i.name() == v)
            .ok_or_else(|| {
                Error::Render(format!(
                    "GPURT_SIMD={v}: expected none or one of {}",
                    names.join(", ")
                ))
            })?;
        Kernels::new(isa)
            .map(Some)
            .ok_or_else(|| Error::Render(format!("GPURT_SIMD={v}: this processor lacks {v}")))
    }

    pub fn isa(&self) -> Isa {
        match self.kind {
            #[cfg(target_arch = "x86_64")]
            Kind::Avx512(_) => Isa::Avx512,
            #[cfg(target_arch = "x86_64")]
            Kind::Avx2(_) => Isa::Avx2,
            #[cfg(target_arch = "x86_64")]
            Kind::Sse(_) => Isa::Sse,
            Kind::Portable => Isa::Portable,
        }
    }

    /// Rays a packet holds.
    pub fn lanes(&self) -> usize {
        self.isa().lanes()
    }

    fn closest_kernel(
        &self,
        b: &Bindings,
        wide: &[WideNode],
        rows: &Rows,
        lanes: u32,
        found: &mut Found,
    ) {
        #[cfg(target_arch = "x86_64")]
        use x86_walks::Kernels as _;
        match self.kind {
            #[cfg(target_arch = "x86_64")]
            Kind::Avx512(l) => l.closest(b, wide, rows, lanes, found),
            #[cfg(target_arch = "x86_64")]
            Kind::Avx2(l) => l.closest(b, wide, rows, lanes, found),
            #[cfg(target_arch = "x86_64")]
            Kind::Sse(l) => l.closest(b, wide, rows, lanes, found),
            Kind::Portable => walk::closest(lanes::Portable, b, wide, rows, lanes, found),
        }
    }

    fn occluded_kernel(
        &self,
        b: &Bindings,
        wide: &[WideNode],
        rows: &Rows,
        lanes: u32,
    ) -> Occluded {
        #[cfg(target_arch = "x86_64")]
        use x86_walks::Kernels as _;
        match self.kind {
            #[cfg(target_arch = "x86_64")]
            Kind::Avx512(l) => l.occluded(b, wide, rows, lanes),
            #[cfg(target_arch = "x86_64")]
            Kind::Avx2(l) => l.occluded(b, wide, rows, lanes),
            #[cfg(target_arch = "x86_64")]
            Kind::Sse(l) => l.occluded(b, wide, rows, lanes),
            Kind::Portable => walk::occluded(lanes::Portable, b, wide, rows, lanes),
        }
    }

    /// `closest_hit(b, ray, tmin, tmax)` of every ray of `p`, into `hits` (lane by lane;
    /// `cost` 0, as the wide walk counts none; `nodes`, the packet's node fetches shared
    /// among the lanes it traced, `share`, plus a lane's own walk if it took one). Returns the lanes the packet answered; the
    /// others went alone: all of them where `b` has no wide tree or the packet is nearly
    /// empty, rays from or towards infinity, and lanes that met two surfaces at one distance.
    pub fn closest_hits(&self, b: &Bindings, p: &Packet, hits: &mut [Hit; MAX_LANES]) -> u32 {
        let mut found = Found::default();
        let packed = match b.wide {
            Some(wide) if p.rows.lanes.count_ones() >= MIN_LANES => {
                self.closest_kernel(b, wide, &p.rows, p.rows.lanes, &mut found);
                found.traced & !found.tied
            }
            _ => 0,
        };
        let nodes = share(found.nodes, found.traced);
        // Field by field: a `Hit` built whole on the stack and copied stalls on store
        // forwarding, a tenth of a packet's time.
        for k in lanes_of(packed) {
            let h = &mut hits[k];
            (h.t, h.prim, h.u, h.v, h.cost, h.nodes) = (
                found.t[k],
                found.prim[k],
                found.u[k],
                found.v[k],
                0,
                nodes[k],
            );
        }
        for k in lanes_of(p.rows.lanes & !packed) {
            hits[k] = closest_hit(b, &p.rows.ray(k), p.rows.tmin[k], p.rows.tmax[k]);
            hits[k].nodes += nodes[k];
        }
        packed
    }

    /// `transmission(b, ray, tmax)` of every ray of `p` (whose `tmin` must be 0), into
    /// `light`, and the node fetches of each lane into `nodes` (as `closest_hits` counts
    /// them). Returns the lanes the occlusion packet answered: blocked, crossing nothing,
    /// or crossing surfaces of one material that transmits light; the planes are each
    /// lane's own, and lanes crossing two such materials go alone, as do all where the
    /// packet cannot (see `closest_hits`).
    pub fn transmissions(
        &self,
        b: &Bindings,
        p: &Packet,
        light: &mut [Vec3; MAX_LANES],
        nodes: &mut [u32; MAX_LANES],
    ) -> u32 {
        debug_assert!(
            lanes_of(p.rows.lanes).all(|k| p.rows.tmin[k] == 0.0),
            "a shadow ray starts at its origin"
        );
        // The planes first, lane by lane (most scenes have none: all lanes open).
        let mut open = if b.planes.is_empty() { p.rows.lanes } else { 0 };
        light.fill(Vec3::ONE);
        for k in lanes_of(p.rows.lanes & !open) {
            match transmit_planes(b, &p.rows.ray(k), p.rows.tmax[k]) {
                Some(l) => {
                    light[k] = l;
                    open |= 1 << k;
                }
                None => light[k] = Vec3::ZERO,
            }
        }
        let found = match b.wide {
            Some(wide) if open.count_ones() >= MIN_LANES => {
                self.occluded_kernel(b, wide, &p.rows, open)
            }
            _ => Occluded::default(),
        };
        let packed = found.traced;
        *nodes = share(found.nodes, found.traced);
        for k in lanes_of(open) {
            let bit = 1 << k;
            if packed & bit == 0 || found.mixed & bit != 0 {
                light[k] = transmission(b, &p.rows.ray(k), p.rows.tmax[k], &mut nodes[k]);
            } else if found.blocked & bit != 0 {
                light[k] = Vec3::ZERO;
            } else if found.transmits & bit != 0 {
                // `transmission`'s product: the same factor each time, so in any order.
                let m = &b.materials[found.material[k] as usize];
                for _ in 0..found.crossings[k] {
                    light[k] *= m.t * m.color;
                }
            }
        }
        packed & !found.mixed
    }
}

/// A packet's `nodes` fetches shared among its `lanes` (a bit each), so that they add up
/// to the packet's: a node fetched once for the packet serves each of its rays, and the
/// count per ray is the memory traffic a ray cost (`counters`). The first lanes take the
/// remainder; lanes outside `lanes` take none.
fn share(nodes: u32, lanes: u32) -> [u32; MAX_LANES] {
    let mut out = [0; MAX_LANES];
    let n = lanes.count_ones();
    if let Some(each) = nodes.checked_div(n) {
        for (i, k) in lanes_of(lanes).enumerate() {
            out[k] = each + u32::from((i as u32) < nodes % n);
        }
    }
    out
}

/// Up to `MAX_LANES` rays with their intervals, lane `k` the `k`-th.
#[derive(Clone, Debug, Default)]
pub struct Packet {
    rows: Rows,
}

impl Packet {
    /// Empties the packet.
    pub fn clear(&mut self) {
        self.rows.lanes = 0;
    }

    /// Puts `ray`, over `(tmin, tmax)`, in lane `k` (below `MAX_LANES`).
    #[inline]
    pub fn set(&mut self, k: usize, ray: &Ray, tmin: f32, tmax: f32) {
        let r = &mut self.rows;
        let k = k % MAX_LANES;
        (r.origin[0][k], r.origin[1][k], r.origin[2][k]) =
            (ray.origin.x, ray.origin.y, ray.origin.z);
        (r.dir[0][k], r.dir[1][k], r.dir[2][k]) = (ray.dir.x, ray.dir.y, ray.dir.z);
        (r.tmin[k], r.tmax[k]) = (tmin, tmax);
        r.lanes |= 1 << k;
    }

    /// The lanes holding a ray.
    pub fn lanes(&self) -> u32 {
        self.rows.lanes
    }

    /// Lane `k`'s ray.
    pub fn ray(&self, k: usize) -> Ray {
        self.rows.ray(k)
    }

    /// Lane `k`'s interval end.
    pub fn tmax(&self, k: usize) -> f32 {
        self.rows.tmax[k]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A packet's fetches are all counted, once, and shared within one a lane.
    #[test]
    fn a_packets_node_fetches_are_shared_and_add_up() {
        for (nodes, lanes) in [(0, 0b1011), (7, 0), (7, 0b1), (10, 0b1011), (37, 0xffff)] {
            let s = share(nodes, lanes);
            let total: u32 = s.iter().sum();
            assert_eq!(
                total,
                if lanes == 0 { 0 } else { nodes },
                "{nodes} over {lanes:b}"
            );
            let mine: Vec<u32> = lanes_of(lanes).map(|k| s[k]).collect();
            if let (Some(lo), Some(hi)) = (mine.iter().min(), mine.iter().max()) {
                assert!(hi - lo <= 1, "{mine:?}");
            }
            for (k, &n) in s.iter().enumerate() {
                assert!(
                    lanes & 1 << k != 0 || n == 0,
                    "lane {k} is not in the packet"
                );
            }
        }
    }
}
