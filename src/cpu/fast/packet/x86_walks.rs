//! The packet kernels compiled for each x86-64 instruction set: `answer.rs`'s generic
//! answers (and so `walk.rs`'s walks) instantiated with a `Lanes` token inside a
//! `#[target_feature]` function, so that the whole of it, inlined, uses that set's
//! registers and instructions.

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
        hint: &mut Option<u32>,
    ) -> u32;
}

/// `Kernels` for the token type `$token`, `answer`'s functions compiled with `$features`,
/// the features its `detect` checks (SSE2, the baseline, needs no check).
macro_rules! kernels {
    ($token:ty, $features:literal) => {
        impl Kernels for $token {
            fn closest_hits(self, b: &Bindings, rows: &Rows, hits: &mut [Hit; MAX_LANES]) -> u32 {
                #[target_feature(enable = $features)]
                fn compiled(
                    l: $token,
                    b: &Bindings,
                    rows: &Rows,
                    hits: &mut [Hit; MAX_LANES],
                ) -> u32 {
                    answer::closest_hits(l, b, rows, hits)
                }
                // SAFETY: a token exists only where its features are.
                unsafe { compiled(self, b, rows, hits) }
            }

            fn transmissions(
                self,
                b: &Bindings,
                rows: &Rows,
                light: &mut [Vec3; MAX_LANES],
                nodes: &mut [u32; MAX_LANES],
                hint: &mut Option<u32>,
            ) -> u32 {
                #[target_feature(enable = $features)]
                fn compiled(
                    l: $token,
                    b: &Bindings,
                    rows: &Rows,
                    light: &mut [Vec3; MAX_LANES],
                    nodes: &mut [u32; MAX_LANES],
                    hint: &mut Option<u32>,
                ) -> u32 {
                    answer::transmissions(l, b, rows, light, nodes, hint)
                }
                // SAFETY: as in `closest_hits`.
                unsafe { compiled(self, b, rows, light, nodes, hint) }
            }
        }
    };
}

kernels!(Sse, "sse2");
// The features of x86-64-v3, which `Avx2::detect` checks; v4's adds AVX-512F.
kernels!(Avx2, "avx2,fma,bmi1,bmi2,lzcnt,popcnt");
kernels!(Avx512, "avx512f,avx2,fma,bmi1,bmi2,lzcnt,popcnt");
