//! Run-time choice of vector width for the baker's hot loops.

/// Defines a function whose body is compiled three times, portable, for AVX2
/// (4-wide f64 vectors) and for AVX-512 (F, VL, DQ: 8-wide), and runs the
/// widest copy the CPU has (checked at run time, so one binary serves every
/// x86-64 machine). The loops are auto-vectorised; even on a CPU that splits
/// 512-bit operations in two (Zen 4) the AVX-512 copy, issuing half the
/// instructions, made a checked bake 1.17× faster than the AVX2 one (see
/// docs/performance.md). All copies inline the same body, and Rust never
/// fuses a multiply and an add on its own (not even where AVX-512 implies
/// FMA), so they give the same result bit for bit. Where a body fuses on
/// purpose (`f64::mul_add`, one rounding), the AVX copies run one FMA
/// instruction (the AVX2 copy therefore also needs FMA, which every CPU with
/// AVX2 in practice has) and the portable one the C library's `fma`, which
/// rounds the same way.
///
/// Arguments are `name: Type` only (no `self`: a method calls a free
/// function defined with this).
macro_rules! simd_dispatch {
    (
        $(#[$attr:meta])*
        $vis:vis fn $name:ident($($arg:ident: $ty:ty),* $(,)?) $body:block
    ) => {
        $(#[$attr])*
        $vis fn $name($($arg: $ty),*) {
            #[inline(always)]
            fn body($($arg: $ty),*) $body

            #[cfg(target_arch = "x86_64")]
            #[target_feature(enable = "avx2,fma")]
            fn avx2($($arg: $ty),*) {
                body($($arg),*)
            }

            #[cfg(target_arch = "x86_64")]
            #[target_feature(enable = "avx512f,avx512vl,avx512dq")]
            fn avx512($($arg: $ty),*) {
                body($($arg),*)
            }

            #[cfg(target_arch = "x86_64")]
            if std::arch::is_x86_feature_detected!("avx512f")
                && std::arch::is_x86_feature_detected!("avx512vl")
                && std::arch::is_x86_feature_detected!("avx512dq")
            {
                // SAFETY: the CPU has these AVX-512 extensions (checked just above).
                return unsafe { avx512($($arg),*) };
            }
            #[cfg(target_arch = "x86_64")]
            if std::arch::is_x86_feature_detected!("avx2")
                && std::arch::is_x86_feature_detected!("fma")
            {
                // SAFETY: the CPU has AVX2 and FMA (checked just above).
                return unsafe { avx2($($arg),*) };
            }
            body($($arg),*)
        }
    };
}

pub(crate) use simd_dispatch;
