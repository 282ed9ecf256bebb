//! One `f32` per ray of a packet, in the widest SIMD register the machine has: the
//! operations the packet walk needs, and nothing else, behind one trait (`Lanes`) that
//! the walk is written against once and compiled for each instruction set (`x86.rs`:
//! AVX-512, AVX2, SSE; `Portable` here for the rest, which LLVM turns into NEON on
//! AArch64, whose baseline it is).
//!
//! Every operation is the IEEE one lane by lane (no fused multiply-add, no approximate
//! reciprocal), and comparisons are those of Rust's scalar operators (ordered, but `ne`),
//! so that a lane computes the bits the single-ray code computes for its ray.
//!
//! A value of a `Lanes` type is a token: it exists only where its instructions do
//! (`x86.rs` makes them after `is_x86_feature_detected!`), which is what makes calling
//! its intrinsics sound.

/// Lanes of the widest kernel (AVX-512): the size of the packets' arrays.
pub const MAX_LANES: usize = 16;

/// A packet's per-ray values, as the kernels load and store them.
pub type Row = [f32; MAX_LANES];

pub trait Lanes: Copy {
    /// Rays a vector holds.
    const N: usize;
    /// `N` floats.
    type F: Copy;
    /// `N` booleans, one a lane.
    type M: Copy;

    fn splat(self, x: f32) -> Self::F;
    /// A float vector holding the bits `x` in every lane (primitive indices).
    #[inline(always)]
    fn splat_bits(self, x: u32) -> Self::F {
        self.splat(f32::from_bits(x))
    }
    /// The first `N` values of `row`.
    fn load(self, row: &Row) -> Self::F;
    /// Writes the `N` lanes to the first `N` values of `row`.
    fn store(self, v: Self::F, row: &mut Row);
    fn add(self, a: Self::F, b: Self::F) -> Self::F;
    fn sub(self, a: Self::F, b: Self::F) -> Self::F;
    fn mul(self, a: Self::F, b: Self::F) -> Self::F;
    fn div(self, a: Self::F, b: Self::F) -> Self::F;
    /// `-a`, the sign bit flipped (as the scalar `-`, also on zeros).
    fn neg(self, a: Self::F) -> Self::F;
    fn sqrt(self, a: Self::F) -> Self::F;
    /// x86's `minps` / `maxps`: `a < b ? a : b` and `a > b ? a : b` (glam's `Vec4::min` and
    /// `max` on x86; on finite values, any minimum).
    fn min(self, a: Self::F, b: Self::F) -> Self::F;
    fn max(self, a: Self::F, b: Self::F) -> Self::F;
    fn lt(self, a: Self::F, b: Self::F) -> Self::M;
    fn le(self, a: Self::F, b: Self::F) -> Self::M;
    fn gt(self, a: Self::F, b: Self::F) -> Self::M;
    fn eq(self, a: Self::F, b: Self::F) -> Self::M;
    /// True where `a != b` or either is NaN, as Rust's `!=`.
    fn ne(self, a: Self::F, b: Self::F) -> Self::M;
    fn and(self, a: Self::M, b: Self::M) -> Self::M;
    fn or(self, a: Self::M, b: Self::M) -> Self::M;
    /// `a & !b`.
    fn and_not(self, a: Self::M, b: Self::M) -> Self::M;
    /// `a` where `m`, else `b`.
    fn select(self, m: Self::M, a: Self::F, b: Self::F) -> Self::F;
    /// Lane `k` as bit `k`.
    fn bits(self, m: Self::M) -> u32;
    /// The mask whose lane `k` is bit `k` of `bits`.
    fn mask(self, bits: u32) -> Self::M;

    /// The smallest and the largest of the lanes (by `min` and `max`).
    fn least(self, v: Self::F) -> f32;
    fn most(self, v: Self::F) -> f32;

    /// The smallest value of the lanes in `bits` (infinity for none).
    #[inline(always)]
    fn min_of(self, v: Self::F, bits: u32) -> f32 {
        self.least(self.select(self.mask(bits), v, self.splat(f32::INFINITY)))
    }
    /// The largest value of the lanes in `bits` (minus infinity for none).
    #[inline(always)]
    fn max_of(self, v: Self::F, bits: u32) -> f32 {
        self.most(self.select(self.mask(bits), v, self.splat(f32::NEG_INFINITY)))
    }
}

/// Four lanes in plain arrays: the kernel of machines without one of `x86.rs`'s (LLVM
/// vectorises it: NEON on AArch64), and a reference the others are tested against.
#[derive(Clone, Copy, Debug)]
pub struct Portable;

type F4 = [f32; 4];

#[inline(always)]
fn map(a: F4, b: F4, f: impl Fn(f32, f32) -> f32) -> F4 {
    std::array::from_fn(|k| f(a[k], b[k]))
}

#[inline(always)]
fn test(a: F4, b: F4, f: impl Fn(f32, f32) -> bool) -> u32 {
    (0..4).fold(0, |m, k| m | (u32::from(f(a[k], b[k])) << k))
}

impl Lanes for Portable {
    const N: usize = 4;
    type F = F4;
    type M = u32;

    #[inline(always)]
    fn splat(self, x: f32) -> F4 {
        [x; 4]
    }
    #[inline(always)]
    fn load(self, row: &Row) -> F4 {
        [row[0], row[1], row[2], row[3]]
    }
    #[inline(always)]
    fn store(self, v: F4, row: &mut Row) {
        row[..4].copy_from_slice(&v);
    }
    #[inline(always)]
    fn add(self, a: F4, b: F4) -> F4 {
        map(a, b, |a, b| a + b)
    }
    #[inline(always)]
    fn sub(self, a: F4, b: F4) -> F4 {
        map(a, b, |a, b| a - b)
    }
    #[inline(always)]
    fn mul(self, a: F4, b: F4) -> F4 {
        map(a, b, |a, b| a * b)
    }
    #[inline(always)]
    fn div(self, a: F4, b: F4) -> F4 {
        map(a, b, |a, b| a / b)
    }
    #[inline(always)]
    fn neg(self, a: F4) -> F4 {
        a.map(|a| -a)
    }
    #[inline(always)]
    fn sqrt(self, a: F4) -> F4 {
        a.map(f32::sqrt)
    }
    #[inline(always)]
    fn min(self, a: F4, b: F4) -> F4 {
        map(a, b, |a, b| if a < b { a } else { b })
    }
    #[inline(always)]
    fn max(self, a: F4, b: F4) -> F4 {
        map(a, b, |a, b| if a > b { a } else { b })
    }
    #[inline(always)]
    fn lt(self, a: F4, b: F4) -> u32 {
        test(a, b, |a, b| a < b)
    }
    #[inline(always)]
    fn le(self, a: F4, b: F4) -> u32 {
        test(a, b, |a, b| a <= b)
    }
    #[inline(always)]
    fn gt(self, a: F4, b: F4) -> u32 {
        test(a, b, |a, b| a > b)
    }
    #[inline(always)]
    fn eq(self, a: F4, b: F4) -> u32 {
        test(a, b, |a, b| a == b)
    }
    #[inline(always)]
    fn ne(self, a: F4, b: F4) -> u32 {
        test(a, b, |a, b| a != b)
    }
    #[inline(always)]
    fn and(self, a: u32, b: u32) -> u32 {
        a & b
    }
    #[inline(always)]
    fn or(self, a: u32, b: u32) -> u32 {
        a | b
    }
    #[inline(always)]
    fn and_not(self, a: u32, b: u32) -> u32 {
        a & !b
    }
    #[inline(always)]
    fn select(self, m: u32, a: F4, b: F4) -> F4 {
        std::array::from_fn(|k| if m & (1 << k) != 0 { a[k] } else { b[k] })
    }
    #[inline(always)]
    fn bits(self, m: u32) -> u32 {
        m
    }
    #[inline(always)]
    fn mask(self, bits: u32) -> u32 {
        bits & 0xf
    }
    #[inline(always)]
    fn least(self, v: F4) -> f32 {
        let m = self.min(v, [v[2], v[3], v[0], v[1]]);
        self.min(m, [m[1], m[0], m[3], m[2]])[0]
    }
    #[inline(always)]
    fn most(self, v: F4) -> f32 {
        let m = self.max(v, [v[2], v[3], v[0], v[1]]);
        self.max(m, [m[1], m[0], m[3], m[2]])[0]
    }
}
