//! Which of x86-64's instruction sets this processor has, found once: the packet kernels
//! (`packet::x86`) and the single-ray walks (`wide_ray`) each have a copy compiled for
//! x86-64-v3 (AVX2, FMA, BMI), and the walks one for x86-64-v4 (AVX-512), and take them
//! where these say so.

use std::sync::LazyLock;

use super::simd::Isa;

/// x86-64-v3: the features the v3 copies are compiled with
/// (`#[target_feature(enable = "avx2,fma,bmi1,bmi2,lzcnt,popcnt")]`).
pub fn x86_64_v3() -> bool {
    static V3: LazyLock<bool> = LazyLock::new(|| {
        is_x86_feature_detected!("avx2")
            && is_x86_feature_detected!("fma")
            && is_x86_feature_detected!("bmi1")
            && is_x86_feature_detected!("bmi2")
            && is_x86_feature_detected!("lzcnt")
            && is_x86_feature_detected!("popcnt")
    });
    *V3
}

/// x86-64-v3 and AVX-512 Foundation, the features of the sixteen-lane packet kernels.
pub fn x86_64_v4() -> bool {
    x86_64_v3() && is_x86_feature_detected!("avx512f")
}

/// Whether the single-ray walks take their x86-64-v4 copies (`wide_ray`: v3 and AVX-512
/// F, VL, BW, DQ and CD): where the processor has those features, unless `GPURT_SIMD`
/// holds the renderer to a narrower set (`avx2`, `sse`, `portable`; the packet kernels'
/// choice, `packet::Kernels::from_env`), so that a run held to AVX2 is that throughout.
/// Read once.
pub fn single_ray_v4() -> bool {
    static V4: LazyLock<bool> = LazyLock::new(|| {
        let held = std::env::var("GPURT_SIMD")
            .ok()
            .and_then(|v| Isa::named(&v));
        let narrower = held.is_some_and(|isa| isa != Isa::Avx512);
        !narrower
            && x86_64_v4()
            && is_x86_feature_detected!("avx512vl")
            && is_x86_feature_detected!("avx512bw")
            && is_x86_feature_detected!("avx512dq")
            && is_x86_feature_detected!("avx512cd")
    });
    *V4
}
