//! The `Lanes` of x86-64: SSE (four lanes, every x86-64 has it), AVX2 (eight) and AVX-512
//! (sixteen), on `std::arch`'s intrinsics. The AVX2 and AVX-512 tokens are made only
//! after `is_x86_feature_detected!` has found their instructions, and their kernels are
//! compiled with those features enabled (`x86_walks.rs`), so that these `inline(always)`
//! bodies become single instructions there.

use std::arch::x86_64::*;

use super::lanes::{Lanes, Row};
use crate::cpu::fast::isa;

/// SSE2, the x86-64 baseline: four lanes.
#[derive(Clone, Copy, Debug)]
pub struct Sse(());

impl Sse {
    pub fn new() -> Self {
        Sse(())
    }
}

/// AVX2 (with the rest of x86-64-v3): eight lanes.
#[derive(Clone, Copy, Debug)]
pub struct Avx2(());

impl Avx2 {
    pub fn detect() -> Option<Self> {
        isa::x86_64_v3().then_some(Avx2(()))
    }
}

/// AVX-512 Foundation (with x86-64-v3): sixteen lanes, comparisons into mask registers.
#[derive(Clone, Copy, Debug)]
pub struct Avx512(());

impl Avx512 {
    pub fn detect() -> Option<Self> {
        isa::x86_64_v4().then_some(Avx512(()))
    }
}

// SAFETY (every `unsafe` block below): SSE2 is part of x86-64; an `Avx2` or `Avx512`
// exists only where `detect` found its instructions; loads and stores read and write the
// first lanes of a `Row`, which holds `MAX_LANES` >= 16 floats.

impl Lanes for Sse {
    const N: usize = 4;
    type F = __m128;
    type M = __m128;

    #[inline(always)]
    fn splat(self, x: f32) -> __m128 {
        unsafe { _mm_set1_ps(x) }
    }
    #[inline(always)]
    fn load(self, row: &Row) -> __m128 {
        unsafe { _mm_loadu_ps(row.as_ptr()) }
    }
    #[inline(always)]
    fn store(self, v: __m128, row: &mut Row) {
        unsafe { _mm_storeu_ps(row.as_mut_ptr(), v) }
    }
    #[inline(always)]
    fn add(self, a: __m128, b: __m128) -> __m128 {
        unsafe { _mm_add_ps(a, b) }
    }
    #[inline(always)]
    fn sub(self, a: __m128, b: __m128) -> __m128 {
        unsafe { _mm_sub_ps(a, b) }
    }
    #[inline(always)]
    fn mul(self, a: __m128, b: __m128) -> __m128 {
        unsafe { _mm_mul_ps(a, b) }
    }
    #[inline(always)]
    fn div(self, a: __m128, b: __m128) -> __m128 {
        unsafe { _mm_div_ps(a, b) }
    }
    #[inline(always)]
    fn neg(self, a: __m128) -> __m128 {
        unsafe { _mm_xor_ps(a, _mm_set1_ps(-0.0)) }
    }
    #[inline(always)]
    fn sqrt(self, a: __m128) -> __m128 {
        unsafe { _mm_sqrt_ps(a) }
    }
    #[inline(always)]
    fn min(self, a: __m128, b: __m128) -> __m128 {
        unsafe { _mm_min_ps(a, b) }
    }
    #[inline(always)]
    fn max(self, a: __m128, b: __m128) -> __m128 {
        unsafe { _mm_max_ps(a, b) }
    }
    #[inline(always)]
    fn lt(self, a: __m128, b: __m128) -> __m128 {
        unsafe { _mm_cmplt_ps(a, b) }
    }
    #[inline(always)]
    fn le(self, a: __m128, b: __m128) -> __m128 {
        unsafe { _mm_cmple_ps(a, b) }
    }
    #[inline(always)]
    fn gt(self, a: __m128, b: __m128) -> __m128 {
        unsafe { _mm_cmpgt_ps(a, b) }
    }
    #[inline(always)]
    fn eq(self, a: __m128, b: __m128) -> __m128 {
        unsafe { _mm_cmpeq_ps(a, b) }
    }
    #[inline(always)]
    fn ne(self, a: __m128, b: __m128) -> __m128 {
        unsafe { _mm_cmpneq_ps(a, b) }
    }
    #[inline(always)]
    fn and(self, a: __m128, b: __m128) -> __m128 {
        unsafe { _mm_and_ps(a, b) }
    }
    #[inline(always)]
    fn or(self, a: __m128, b: __m128) -> __m128 {
        unsafe { _mm_or_ps(a, b) }
    }
    #[inline(always)]
    fn and_not(self, a: __m128, b: __m128) -> __m128 {
        unsafe { _mm_andnot_ps(b, a) }
    }
    #[inline(always)]
    fn select(self, m: __m128, a: __m128, b: __m128) -> __m128 {
        unsafe { _mm_or_ps(_mm_and_ps(m, a), _mm_andnot_ps(m, b)) }
    }
    #[inline(always)]
    fn bits(self, m: __m128) -> u32 {
        unsafe { _mm_movemask_ps(m) as u32 }
    }
    #[inline(always)]
    fn mask(self, bits: u32) -> __m128 {
        unsafe {
            let lane = _mm_setr_epi32(1, 2, 4, 8);
            let set = _mm_and_si128(_mm_set1_epi32(bits as i32), lane);
            _mm_castsi128_ps(_mm_cmpeq_epi32(set, lane))
        }
    }
    #[inline(always)]
    fn least(self, v: __m128) -> f32 {
        unsafe {
            let m = _mm_min_ps(v, _mm_shuffle_ps::<0b01_00_11_10>(v, v));
            _mm_cvtss_f32(_mm_min_ps(m, _mm_shuffle_ps::<0b10_11_00_01>(m, m)))
        }
    }
    #[inline(always)]
    fn most(self, v: __m128) -> f32 {
        unsafe {
            let m = _mm_max_ps(v, _mm_shuffle_ps::<0b01_00_11_10>(v, v));
            _mm_cvtss_f32(_mm_max_ps(m, _mm_shuffle_ps::<0b10_11_00_01>(m, m)))
        }
    }
}

impl Lanes for Avx2 {
    const N: usize = 8;
    type F = __m256;
    type M = __m256;

    #[inline(always)]
    fn splat(self, x: f32) -> __m256 {
        unsafe { _mm256_set1_ps(x) }
    }
    #[inline(always)]
    fn load(self, row: &Row) -> __m256 {
        unsafe { _mm256_loadu_ps(row.as_ptr()) }
    }
    #[inline(always)]
    fn store(self, v: __m256, row: &mut Row) {
        unsafe { _mm256_storeu_ps(row.as_mut_ptr(), v) }
    }
    #[inline(always)]
    fn add(self, a: __m256, b: __m256) -> __m256 {
        unsafe { _mm256_add_ps(a, b) }
    }
    #[inline(always)]
    fn sub(self, a: __m256, b: __m256) -> __m256 {
        unsafe { _mm256_sub_ps(a, b) }
    }
    #[inline(always)]
    fn mul(self, a: __m256, b: __m256) -> __m256 {
        unsafe { _mm256_mul_ps(a, b) }
    }
    #[inline(always)]
    fn div(self, a: __m256, b: __m256) -> __m256 {
        unsafe { _mm256_div_ps(a, b) }
    }
    #[inline(always)]
    fn neg(self, a: __m256) -> __m256 {
        unsafe { _mm256_xor_ps(a, _mm256_set1_ps(-0.0)) }
    }
    #[inline(always)]
    fn sqrt(self, a: __m256) -> __m256 {
        unsafe { _mm256_sqrt_ps(a) }
    }
    #[inline(always)]
    fn min(self, a: __m256, b: __m256) -> __m256 {
        unsafe { _mm256_min_ps(a, b) }
    }
    #[inline(always)]
    fn max(self, a: __m256, b: __m256) -> __m256 {
        unsafe { _mm256_max_ps(a, b) }
    }
    #[inline(always)]
    fn lt(self, a: __m256, b: __m256) -> __m256 {
        unsafe { _mm256_cmp_ps::<_CMP_LT_OQ>(a, b) }
    }
    #[inline(always)]
    fn le(self, a: __m256, b: __m256) -> __m256 {
        unsafe { _mm256_cmp_ps::<_CMP_LE_OQ>(a, b) }
    }
    #[inline(always)]
    fn gt(self, a: __m256, b: __m256) -> __m256 {
        unsafe { _mm256_cmp_ps::<_CMP_GT_OQ>(a, b) }
    }
    #[inline(always)]
    fn eq(self, a: __m256, b: __m256) -> __m256 {
        unsafe { _mm256_cmp_ps::<_CMP_EQ_OQ>(a, b) }
    }
    #[inline(always)]
    fn ne(self, a: __m256, b: __m256) -> __m256 {
        unsafe { _mm256_cmp_ps::<_CMP_NEQ_UQ>(a, b) }
    }
    #[inline(always)]
    fn and(self, a: __m256, b: __m256) -> __m256 {
        unsafe { _mm256_and_ps(a, b) }
    }
    #[inline(always)]
    fn or(self, a: __m256, b: __m256) -> __m256 {
        unsafe { _mm256_or_ps(a, b) }
    }
    #[inline(always)]
    fn and_not(self, a: __m256, b: __m256) -> __m256 {
        unsafe { _mm256_andnot_ps(b, a) }
    }
    #[inline(always)]
    fn select(self, m: __m256, a: __m256, b: __m256) -> __m256 {
        unsafe { _mm256_blendv_ps(b, a, m) }
    }
    #[inline(always)]
    fn bits(self, m: __m256) -> u32 {
        unsafe { _mm256_movemask_ps(m) as u32 }
    }
    #[inline(always)]
    fn mask(self, bits: u32) -> __m256 {
        unsafe {
            let lane = _mm256_setr_epi32(1, 2, 4, 8, 16, 32, 64, 128);
            let set = _mm256_and_si256(_mm256_set1_epi32(bits as i32), lane);
            _mm256_castsi256_ps(_mm256_cmpeq_epi32(set, lane))
        }
    }
    #[inline(always)]
    fn least(self, v: __m256) -> f32 {
        unsafe {
            let h = _mm_min_ps(_mm256_castps256_ps128(v), _mm256_extractf128_ps::<1>(v));
            Sse(()).least(h)
        }
    }
    #[inline(always)]
    fn most(self, v: __m256) -> f32 {
        unsafe {
            let h = _mm_max_ps(_mm256_castps256_ps128(v), _mm256_extractf128_ps::<1>(v));
            Sse(()).most(h)
        }
    }
}

impl Lanes for Avx512 {
    const N: usize = 16;
    type F = __m512;
    type M = __mmask16;

    #[inline(always)]
    fn splat(self, x: f32) -> __m512 {
        unsafe { _mm512_set1_ps(x) }
    }
    #[inline(always)]
    fn load(self, row: &Row) -> __m512 {
        unsafe { _mm512_loadu_ps(row.as_ptr()) }
    }
    #[inline(always)]
    fn store(self, v: __m512, row: &mut Row) {
        unsafe { _mm512_storeu_ps(row.as_mut_ptr(), v) }
    }
    #[inline(always)]
    fn add(self, a: __m512, b: __m512) -> __m512 {
        unsafe { _mm512_add_ps(a, b) }
    }
    #[inline(always)]
    fn sub(self, a: __m512, b: __m512) -> __m512 {
        unsafe { _mm512_sub_ps(a, b) }
    }
    #[inline(always)]
    fn mul(self, a: __m512, b: __m512) -> __m512 {
        unsafe { _mm512_mul_ps(a, b) }
    }
    #[inline(always)]
    fn div(self, a: __m512, b: __m512) -> __m512 {
        unsafe { _mm512_div_ps(a, b) }
    }
    #[inline(always)]
    fn neg(self, a: __m512) -> __m512 {
        // `_mm512_xor_ps` needs AVX-512 DQ; the integer one is Foundation.
        unsafe {
            let sign = _mm512_set1_epi32(i32::MIN);
            _mm512_castsi512_ps(_mm512_xor_si512(_mm512_castps_si512(a), sign))
        }
    }
    #[inline(always)]
    fn sqrt(self, a: __m512) -> __m512 {
        unsafe { _mm512_sqrt_ps(a) }
    }
    #[inline(always)]
    fn min(self, a: __m512, b: __m512) -> __m512 {
        unsafe { _mm512_min_ps(a, b) }
    }
    #[inline(always)]
    fn max(self, a: __m512, b: __m512) -> __m512 {
        unsafe { _mm512_max_ps(a, b) }
    }
    #[inline(always)]
    fn lt(self, a: __m512, b: __m512) -> __mmask16 {
        unsafe { _mm512_cmp_ps_mask::<_CMP_LT_OQ>(a, b) }
    }
    #[inline(always)]
    fn le(self, a: __m512, b: __m512) -> __mmask16 {
        unsafe { _mm512_cmp_ps_mask::<_CMP_LE_OQ>(a, b) }
    }
    #[inline(always)]
    fn gt(self, a: __m512, b: __m512) -> __mmask16 {
        unsafe { _mm512_cmp_ps_mask::<_CMP_GT_OQ>(a, b) }
    }
    #[inline(always)]
    fn eq(self, a: __m512, b: __m512) -> __mmask16 {
        unsafe { _mm512_cmp_ps_mask::<_CMP_EQ_OQ>(a, b) }
    }
    #[inline(always)]
    fn ne(self, a: __m512, b: __m512) -> __mmask16 {
        unsafe { _mm512_cmp_ps_mask::<_CMP_NEQ_UQ>(a, b) }
    }
    #[inline(always)]
    fn and(self, a: __mmask16, b: __mmask16) -> __mmask16 {
        a & b
    }
    #[inline(always)]
    fn or(self, a: __mmask16, b: __mmask16) -> __mmask16 {
        a | b
    }
    #[inline(always)]
    fn and_not(self, a: __mmask16, b: __mmask16) -> __mmask16 {
        a & !b
    }
    #[inline(always)]
    fn select(self, m: __mmask16, a: __m512, b: __m512) -> __m512 {
        // The blend takes its second operand where the mask is set.
        unsafe { _mm512_mask_blend_ps(m, b, a) }
    }
    #[inline(always)]
    fn bits(self, m: __mmask16) -> u32 {
        u32::from(m)
    }
    #[inline(always)]
    fn mask(self, bits: u32) -> __mmask16 {
        bits as __mmask16
    }
    #[inline(always)]
    fn least(self, v: __m512) -> f32 {
        unsafe {
            let lo = _mm512_castps512_ps256(v);
            let hi = _mm256_castpd_ps(_mm512_extractf64x4_pd::<1>(_mm512_castps_pd(v)));
            Avx2(()).least(_mm256_min_ps(lo, hi))
        }
    }
    #[inline(always)]
    fn most(self, v: __m512) -> f32 {
        unsafe {
            let lo = _mm512_castps512_ps256(v);
            let hi = _mm256_castpd_ps(_mm512_extractf64x4_pd::<1>(_mm512_castps_pd(v)));
            Avx2(()).most(_mm256_max_ps(lo, hi))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::lanes::{MAX_LANES, Portable};
    use super::*;

    /// Every operation of `l`, lane by lane, against `Portable`'s on the same four values:
    /// the same bits, masks and selections, zeros of both signs, infinities, NaN and
    /// denormals included.
    fn agrees_with_portable<L: Lanes>(l: L) {
        let special = [
            0.0,
            -0.0,
            1.0,
            -1.0,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NAN,
            1e-40,
            f32::MAX,
            0.1,
            3.0,
            -7.5,
        ];
        let mut state = 0x1234_5678_9abc_def1_u64;
        let mut next = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state
        };
        for _ in 0..2000 {
            let mut pick = || {
                let r = next();
                if r % 3 == 0 {
                    special[(r >> 8) as usize % special.len()]
                } else {
                    f32::from_bits((r >> 16) as u32 & 0x3fff_ffff)
                        * if r & 1 == 0 { 1.0 } else { -1.0 }
                }
            };
            let a: Row = std::array::from_fn(|_| pick());
            let b: Row = std::array::from_fn(|_| pick());
            let bits = (next() & 0xffff) as u32 & ((1u64 << L::N) - 1) as u32;
            for base in (0..L::N).step_by(4) {
                let sub = |r: &Row| -> Row {
                    let mut s = [0.0; MAX_LANES];
                    s[..4].copy_from_slice(&r[base..base + 4]);
                    s
                };
                let (pa, pb) = (Portable.load(&sub(&a)), Portable.load(&sub(&b)));
                let (va, vb) = (l.load(&a), l.load(&b));
                let out = |v: L::F| {
                    let mut r = [0.0; MAX_LANES];
                    l.store(v, &mut r);
                    std::array::from_fn::<u32, 4, _>(|k| r[base + k].to_bits())
                };
                let want = |v: [f32; 4]| v.map(f32::to_bits);
                assert_eq!(out(l.add(va, vb)), want(Portable.add(pa, pb)));
                assert_eq!(out(l.sub(va, vb)), want(Portable.sub(pa, pb)));
                assert_eq!(out(l.mul(va, vb)), want(Portable.mul(pa, pb)));
                assert_eq!(out(l.div(va, vb)), want(Portable.div(pa, pb)));
                assert_eq!(out(l.neg(va)), want(Portable.neg(pa)));
                assert_eq!(out(l.min(va, vb)), want(Portable.min(pa, pb)));
                assert_eq!(out(l.max(va, vb)), want(Portable.max(pa, pb)));
                let sqrt = |v: [u32; 4]| {
                    v.map(|b| {
                        if f32::from_bits(b).is_nan() {
                            u32::MAX
                        } else {
                            b
                        }
                    })
                };
                assert_eq!(sqrt(out(l.sqrt(va))), sqrt(want(Portable.sqrt(pa))));
                let quad = |m: u32| (m >> base) & 0xf;
                for (got, portable) in [
                    (l.bits(l.lt(va, vb)), Portable.lt(pa, pb)),
                    (l.bits(l.le(va, vb)), Portable.le(pa, pb)),
                    (l.bits(l.gt(va, vb)), Portable.gt(pa, pb)),
                    (l.bits(l.eq(va, vb)), Portable.eq(pa, pb)),
                    (l.bits(l.ne(va, vb)), Portable.ne(pa, pb)),
                ] {
                    assert_eq!(quad(got), portable);
                }
                let (m, n) = (l.mask(bits), l.lt(va, vb));
                assert_eq!(l.bits(m), bits);
                assert_eq!(l.bits(l.and(m, n)), bits & l.bits(n));
                assert_eq!(l.bits(l.or(m, n)), bits | l.bits(n));
                assert_eq!(l.bits(l.and_not(m, n)), bits & !l.bits(n));
                let sel = l.select(m, va, vb);
                assert_eq!(out(sel), want(Portable.select(quad(bits), pa, pb)));
            }
        }
    }

    #[test]
    fn every_instruction_set_computes_the_portable_bits() {
        agrees_with_portable(Sse::new());
        match Avx2::detect() {
            Some(l) => agrees_with_portable(l),
            None => eprintln!("SKIPPED the AVX2 lanes: this processor lacks AVX2"),
        }
        match Avx512::detect() {
            Some(l) => agrees_with_portable(l),
            None => eprintln!("SKIPPED the AVX-512 lanes: this processor lacks AVX-512F"),
        }
    }
}
