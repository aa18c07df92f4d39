//! Run-time choice of vector width for the baker's hot loops.

/// Defines a function whose body is compiled twice, portable and for AVX2
/// (4-wide f64 vectors), and runs the AVX2 copy when the CPU has it
/// (checked at run time, so one binary serves every x86-64 machine). Both
/// copies inline the same body, and Rust never fuses a multiply and an add
/// on its own, so they give the same result bit for bit.
///
/// Arguments are `name: Type` only (no `self`: a method calls a free
/// function defined with this).
macro_rules! avx2_dispatch {
    (
        $(#[$attr:meta])*
        $vis:vis fn $name:ident($($arg:ident: $ty:ty),* $(,)?) $body:block
    ) => {
        $(#[$attr])*
        $vis fn $name($($arg: $ty),*) {
            #[inline(always)]
            fn body($($arg: $ty),*) $body

            #[cfg(target_arch = "x86_64")]
            #[target_feature(enable = "avx2")]
            fn avx2($($arg: $ty),*) {
                body($($arg),*)
            }

            #[cfg(target_arch = "x86_64")]
            if std::arch::is_x86_feature_detected!("avx2") {
                // SAFETY: the CPU has AVX2 (checked just above).
                return unsafe { avx2($($arg),*) };
            }
            body($($arg),*)
        }
    };
}

pub(crate) use avx2_dispatch;
