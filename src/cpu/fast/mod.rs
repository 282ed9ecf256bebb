//! The CPU's fast paths: what only the CPU renderer has, with no shader to mirror, each
//! finding the hits its twin in `cpu/` finds (the tests compare them bit for bit).
//!
//! - `wide`: the walk of the CPU's eight-wide tree (`bvh::wide`), a ray at a time, its
//!   boxes in SIMD lanes; `wide_ray` one ray's closest hit and transmission through it;
//!   `leaf` its leaves' primitives several at once; `isa` the x86-64-v3 and v4 copies
//!   chosen at run time; `simd` the instruction sets' names in `GPURT_SIMD`.
//! - `packet`: coherent rays in SIMD lanes (packets of 4 to 16) through the same tree;
//!   `coherent` renders tiles with them, a `stage` a kind of ray at a time, `lights`
//!   their shadow rays.
//! - `tracer`: the seam where `shade` gets its rays' answers, from one ray's walk or from
//!   a packet's.

pub(crate) mod coherent;
#[cfg(target_arch = "x86_64")]
pub(crate) mod isa;
pub(crate) mod leaf;
pub(crate) mod lights;
pub mod packet;
pub mod simd;
mod stage;
pub mod tracer;
pub mod wide;
pub mod wide_ray;
