//! The packet walks compiled for each x86-64 instruction set: `walk.rs`'s generic walks
//! instantiated with a `Lanes` token inside a `#[target_feature]` function, so that the
//! whole walk, inlined, uses that set's registers and instructions; SSE needs no such
//! function, being the baseline.

use super::rays::{Found, Occluded, Rows};
use super::walk;
use super::x86::{Avx2, Avx512, Sse};
use crate::bvh::wide::WideNode;
use crate::cpu::types::Bindings;

/// The kernels of one instruction set: `walk`'s two walks compiled for it.
pub trait Kernels {
    fn closest(self, b: &Bindings, wide: &[WideNode], rows: &Rows, lanes: u32, found: &mut Found);
    fn occluded(self, b: &Bindings, wide: &[WideNode], rows: &Rows, lanes: u32) -> Occluded;
}

impl Kernels for Sse {
    fn closest(self, b: &Bindings, wide: &[WideNode], rows: &Rows, lanes: u32, found: &mut Found) {
        walk::closest(self, b, wide, rows, lanes, found)
    }
    fn occluded(self, b: &Bindings, wide: &[WideNode], rows: &Rows, lanes: u32) -> Occluded {
        walk::occluded(self, b, wide, rows, lanes)
    }
}

// The features of x86-64-v3, which `Avx2::detect` checks; v4's adds AVX-512F.
#[target_feature(enable = "avx2,fma,bmi1,bmi2,lzcnt,popcnt")]
fn closest_v3(
    l: Avx2,
    b: &Bindings,
    wide: &[WideNode],
    rows: &Rows,
    lanes: u32,
    found: &mut Found,
) {
    walk::closest(l, b, wide, rows, lanes, found)
}

#[target_feature(enable = "avx2,fma,bmi1,bmi2,lzcnt,popcnt")]
fn occluded_v3(l: Avx2, b: &Bindings, wide: &[WideNode], rows: &Rows, lanes: u32) -> Occluded {
    walk::occluded(l, b, wide, rows, lanes)
}

#[target_feature(enable = "avx512f,avx2,fma,bmi1,bmi2,lzcnt,popcnt")]
fn closest_v4(
    l: Avx512,
    b: &Bindings,
    wide: &[WideNode],
    rows: &Rows,
    lanes: u32,
    found: &mut Found,
) {
    walk::closest(l, b, wide, rows, lanes, found)
}

#[target_feature(enable = "avx512f,avx2,fma,bmi1,bmi2,lzcnt,popcnt")]
fn occluded_v4(l: Avx512, b: &Bindings, wide: &[WideNode], rows: &Rows, lanes: u32) -> Occluded {
    walk::occluded(l, b, wide, rows, lanes)
}

// SAFETY (the four calls below): a token exists only where `detect` found the features
// the called function is compiled for.
impl Kernels for Avx2 {
    fn closest(self, b: &Bindings, wide: &[WideNode], rows: &Rows, lanes: u32, found: &mut Found) {
        unsafe { closest_v3(self, b, wide, rows, lanes, found) }
    }
    fn occluded(self, b: &Bindings, wide: &[WideNode], rows: &Rows, lanes: u32) -> Occluded {
        unsafe { occluded_v3(self, b, wide, rows, lanes) }
    }
}

impl Kernels for Avx512 {
    fn closest(self, b: &Bindings, wide: &[WideNode], rows: &Rows, lanes: u32, found: &mut Found) {
        unsafe { closest_v4(self, b, wide, rows, lanes, found) }
    }
    fn occluded(self, b: &Bindings, wide: &[WideNode], rows: &Rows, lanes: u32) -> Occluded {
        unsafe { occluded_v4(self, b, wide, rows, lanes) }
    }
}
