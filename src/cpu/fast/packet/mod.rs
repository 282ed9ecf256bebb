//! Packets of coherent rays: up to sixteen rays of neighbouring pixels (or their shadow
//! rays to one light, or their mirror rays) traced together through
//! the eight-wide tree, one SIMD lane a ray, where `traverse.rs` traces one ray at a time.
//!
//! - `lanes`: the SIMD operations, one trait over the instruction sets, `Portable` for
//!   machines without one of `x86`'s (AVX-512: 16 lanes, AVX2: 8, SSE: 4).
//! - `walk`: the closest-hit and occlusion walks, written once over `Lanes`; `frustum`:
//!   the interval test that culls children for the whole packet; `leaf`: primitives
//!   against the lanes; `single`: lanes that walk on alone where few are left.
//! - here: the kernels chosen at run time (`Kernels`, of a `simd::Isa`, `GPURT_SIMD`), and the
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

mod answer;
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

pub use super::simd::Isa;
use crate::cpu::intersect::lanes_of;
use crate::cpu::types::{Bindings, Hit, Ray};
use crate::util::error::{Error, Result};
pub use lanes::MAX_LANES;
use lanes::Row;
use rays::Rows;

/// Which of the instruction sets the kernels run here: the kernels' own question (their
/// tokens, `x86`), so asked here.
impl Isa {
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
        let isa = Isa::named(&v).ok_or_else(|| {
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

    /// `closest_hit(b, ray, tmin, tmax)` of every ray of `p`, into `hits`: see
    /// `answer::closest_hits`. Returns the lanes the packet answered.
    pub fn closest_hits(&self, b: &Bindings, p: &Packet, hits: &mut [Hit; MAX_LANES]) -> u32 {
        #[cfg(target_arch = "x86_64")]
        use x86_walks::Kernels as _;
        match self.kind {
            #[cfg(target_arch = "x86_64")]
            Kind::Avx512(l) => l.closest_hits(b, &p.rows, hits),
            #[cfg(target_arch = "x86_64")]
            Kind::Avx2(l) => l.closest_hits(b, &p.rows, hits),
            #[cfg(target_arch = "x86_64")]
            Kind::Sse(l) => l.closest_hits(b, &p.rows, hits),
            Kind::Portable => answer::closest_hits(lanes::Portable, b, &p.rows, hits),
        }
    }

    /// `transmission(b, ray, tmax, _, hint)` of every ray of `p` (whose `tmin` must be 0),
    /// into `light`, and each lane's node fetches into `nodes`: see
    /// `answer::transmissions`.
    /// Returns the lanes the occlusion packet answered.
    pub fn transmissions(
        &self,
        b: &Bindings,
        p: &Packet,
        light: &mut [Vec3; MAX_LANES],
        nodes: &mut [u32; MAX_LANES],
        hint: &mut Option<u32>,
    ) -> u32 {
        debug_assert!(
            lanes_of(p.rows.lanes).all(|k| p.rows.tmin[k] == 0.0),
            "a shadow ray starts at its origin"
        );
        #[cfg(target_arch = "x86_64")]
        use x86_walks::Kernels as _;
        match self.kind {
            #[cfg(target_arch = "x86_64")]
            Kind::Avx512(l) => l.transmissions(b, &p.rows, light, nodes, hint),
            #[cfg(target_arch = "x86_64")]
            Kind::Avx2(l) => l.transmissions(b, &p.rows, light, nodes, hint),
            #[cfg(target_arch = "x86_64")]
            Kind::Sse(l) => l.transmissions(b, &p.rows, light, nodes, hint),
            Kind::Portable => {
                answer::transmissions(lanes::Portable, b, &p.rows, light, nodes, hint)
            }
        }
    }
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

    /// Puts the rays of `origin` and `dir` (a row a coordinate), each over `(tmin,
    /// tmax[k])`, in the lanes `lanes`, in place of the packet's: whole rows at once,
    /// where `set` writes a lane at a time. The other lanes' values are not read.
    pub fn set_rows(
        &mut self,
        (origin, dir): (&[Row; 3], &[Row; 3]),
        tmin: f32,
        tmax: &Row,
        lanes: u32,
    ) {
        let r = &mut self.rows;
        (r.origin, r.dir) = (*origin, *dir);
        (r.tmin, r.tmax) = ([tmin; MAX_LANES], *tmax);
        r.lanes = lanes;
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
