//! The packet kernels compiled for each x86-64 instruction set: `answer.rs`'s generic
//! answers (and so `walk.rs`'s walks) instantiated with a `Lanes` token inside a
//! `#[target_feature]` function, so that the whole of it, inlined, uses that set's
//! registers and instructions; SSE needs no such function, being the baseline.

use glam::Vec3;

use super::answer;
use super::lanes::MAX_LANES;
use super::rays::Rows;
use super::x86::{Avx2, Avx512, Sse};
use crate::cpu::types::{Bindings, Hit};

/// The kernels of one instruction set: `answer`'s two compiled for it.
pub trait Kernels {
    fn closest_hits(self, b: &Bindings, rows: &Rows, hits: &mut [Hit; MAX_LANES]) -> u32;
    fn transmissions(
        self,
        b: &Bindings,
        rows: &Rows,
        light: &mut [Vec3; MAX_LANES],
        nodes: &mut [u32; MAX_LANES],
    ) -> u32;
}

impl Kernels for Sse {
    fn closest_hits(self, b: &Bindings, rows: &Rows, hits: &mut [Hit; MAX_LANES]) -> u32 {
        answer::closest_hits(self, b, rows, hits)
    }
    fn transmissions(
        self,
        b: &Bindings,
        rows: &Rows,
        light: &mut [Vec3; MAX_LANES],
        nodes: &mut [u32; MAX_LANES],
    ) -> u32 {
        answer::transmissions(self, b, rows, light, nodes)
    }
}

// The features of x86-64-v3, which `Avx2::detect` checks; v4's adds AVX-512F.
#[target_feature(enable = "avx2,fma,bmi1,bmi2,lzcnt,popcnt")]
fn closest_hits_v3(l: Avx2, b: &Bindings, rows: &Rows, hits: &mut [Hit; MAX_LANES]) -> u32 {
    answer::closest_hits(l, b, rows, hits)
}

#[target_feature(enable = "avx2,fma,bmi1,bmi2,lzcnt,popcnt")]
fn transmissions_v3(
    l: Avx2,
    b: &Bindings,
    rows: &Rows,
    light: &mut [Vec3; MAX_LANES],
    nodes: &mut [u32; MAX_LANES],
) -> u32 {
    answer::transmissions(l, b, rows, light, nodes)
}

#[target_feature(enable = "avx512f,avx2,fma,bmi1,bmi2,lzcnt,popcnt")]
fn closest_hits_v4(l: Avx512, b: &Bindings, rows: &Rows, hits: &mut [Hit; MAX_LANES]) -> u32 {
    answer::closest_hits(l, b, rows, hits)
}

#[target_feature(enable = "avx512f,avx2,fma,bmi1,bmi2,lzcnt,popcnt")]
fn transmissions_v4(
    l: Avx512,
    b: &Bindings,
    rows: &Rows,
    light: &mut [Vec3; MAX_LANES],
    nodes: &mut [u32; MAX_LANES],
) -> u32 {
    answer::transmissions(l, b, rows, light, nodes)
}

// SAFETY (the four calls below): a token exists only where `detect` found the features
// the called function is compiled for.
impl Kernels for Avx2 {
    fn closest_hits(self, b: &Bindings, rows: &Rows, hits: &mut [Hit; MAX_LANES]) -> u32 {
        unsafe { closest_hits_v3(self, b, rows, hits) }
    }
    fn transmissions(
        self,
        b: &Bindings,
        rows: &Rows,
        light: &mut [Vec3; MAX_LANES],
        nodes: &mut [u32; MAX_LANES],
    ) -> u32 {
        unsafe { transmissions_v3(self, b, rows, light, nodes) }
    }
}

impl Kernels for Avx512 {
    fn closest_hits(self, b: &Bindings, rows: &Rows, hits: &mut [Hit; MAX_LANES]) -> u32 {
        unsafe { closest_hits_v4(self, b, rows, hits) }
    }
    fn transmissions(
        self,
        b: &Bindings,
        rows: &Rows,
        light: &mut [Vec3; MAX_LANES],
        nodes: &mut [u32; MAX_LANES],
    ) -> u32 {
        unsafe { transmissions_v4(self, b, rows, light, nodes) }
    }
}
