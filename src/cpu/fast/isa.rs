//! Which of x86-64's instruction sets this processor has, found once: the packet kernels
//! (`packet::x86`) and the single-ray walks (`traverse`) each have a copy compiled for
//! x86-64-v3 (AVX2, FMA, BMI) and take it where these say so.

use std::sync::LazyLock;

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
