//! The x86-64 lane types: [`Avx2`], one `__m256d` per quantity, and
//! [`Avx512`], one `__m512d`. Every function here is inlined into the
//! kernel copies compiled with the matching features enabled, which run
//! only once the CPU is known to have them. Both perform, lane by lane, the
//! IEEE operations of the portable copy.
#![allow(unsafe_code)]

use std::arch::x86_64::*;

use super::arith::{Lanes, MAX_LANES, ROUND_MAGIC};

#[derive(Clone, Copy, Debug)]
pub(crate) struct Avx2(__m256d);

// SAFETY (every `unsafe` block below): these intrinsics need AVX or
// AVX2, and code built from them runs only inside the kernel copies
// compiled with AVX2 enabled, entered after
// `is_x86_feature_detected!("avx2")`.
impl Avx2 {
    #[inline(always)]
    fn rounded(sum: Self) -> __m256i {
        // SAFETY: AVX2 is present; see the note above `impl Avx2`.
        unsafe {
            _mm256_sub_epi64(
                _mm256_castpd_si256(sum.0),
                _mm256_set1_epi64x(ROUND_MAGIC.to_bits() as i64),
            )
        }
    }
}

impl Lanes for Avx2 {
    type Mask = __m256d;
    const WIDTH: usize = 4;
    #[inline(always)]
    fn splat(x: f64) -> Self {
        // SAFETY: AVX2 is present; see the note above `impl Avx2`.
        unsafe { Avx2(_mm256_set1_pd(x)) }
    }
    #[inline(always)]
    fn from_array(a: [f64; MAX_LANES]) -> Self {
        // SAFETY: AVX2 is present; see the note above `impl Avx2`.
        unsafe { Avx2(_mm256_loadu_pd(a.as_ptr())) }
    }
    #[inline(always)]
    fn to_array(self) -> [f64; MAX_LANES] {
        let mut a = [0.0; MAX_LANES];
        // SAFETY: AVX2 is present; see the note above `impl Avx2`.
        unsafe { _mm256_storeu_pd(a.as_mut_ptr(), self.0) };
        a
    }
    #[inline(always)]
    fn load(s: &[f64]) -> Self {
        let s = &s[..4];
        // SAFETY: AVX2 is present; see the note above `impl Avx2`; `s`
        // holds the four values read.
        unsafe { Avx2(_mm256_loadu_pd(s.as_ptr())) }
    }
    #[inline(always)]
    fn add(self, o: Self) -> Self {
        // SAFETY: AVX2 is present; see the note above `impl Avx2`.
        unsafe { Avx2(_mm256_add_pd(self.0, o.0)) }
    }
    #[inline(always)]
    fn sub(self, o: Self) -> Self {
        // SAFETY: AVX2 is present; see the note above `impl Avx2`.
        unsafe { Avx2(_mm256_sub_pd(self.0, o.0)) }
    }
    #[inline(always)]
    fn mul(self, o: Self) -> Self {
        // SAFETY: AVX2 is present; see the note above `impl Avx2`.
        unsafe { Avx2(_mm256_mul_pd(self.0, o.0)) }
    }
    #[inline(always)]
    fn div(self, o: Self) -> Self {
        // SAFETY: AVX2 is present; see the note above `impl Avx2`.
        unsafe { Avx2(_mm256_div_pd(self.0, o.0)) }
    }
    #[inline(always)]
    fn mul_add(self, b: Self, c: Self) -> Self {
        // SAFETY: AVX2 and FMA are present; see the note above `impl Avx2`.
        unsafe { Avx2(_mm256_fmadd_pd(self.0, b.0, c.0)) }
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        // SAFETY: AVX2 is present; see the note above `impl Avx2`.
        unsafe { Avx2(_mm256_sqrt_pd(self.0)) }
    }
    #[inline(always)]
    fn abs(self) -> Self {
        // SAFETY: AVX2 is present; see the note above `impl Avx2`.
        unsafe { Avx2(_mm256_andnot_pd(_mm256_set1_pd(-0.0), self.0)) }
    }
    #[inline(always)]
    fn neg(self) -> Self {
        // SAFETY: AVX2 is present; see the note above `impl Avx2`.
        unsafe { Avx2(_mm256_xor_pd(_mm256_set1_pd(-0.0), self.0)) }
    }
    #[inline(always)]
    fn lt(self, o: Self) -> Self::Mask {
        // SAFETY: AVX2 is present; see the note above `impl Avx2`.
        unsafe { _mm256_cmp_pd::<_CMP_LT_OQ>(self.0, o.0) }
    }
    #[inline(always)]
    fn ge(self, o: Self) -> Self::Mask {
        // SAFETY: AVX2 is present; see the note above `impl Avx2`.
        unsafe { _mm256_cmp_pd::<_CMP_GE_OQ>(self.0, o.0) }
    }
    #[inline(always)]
    fn eq(self, o: Self) -> Self::Mask {
        // SAFETY: AVX2 is present; see the note above `impl Avx2`.
        unsafe { _mm256_cmp_pd::<_CMP_EQ_OQ>(self.0, o.0) }
    }
    #[inline(always)]
    fn select(m: Self::Mask, a: Self, b: Self) -> Self {
        // SAFETY: AVX2 is present; see the note above `impl Avx2`.
        unsafe { Avx2(_mm256_blendv_pd(b.0, a.0, m)) }
    }
    #[inline(always)]
    fn bits(m: Self::Mask) -> u32 {
        // SAFETY: AVX2 is present; see the note above `impl Avx2`.
        unsafe { _mm256_movemask_pd(m) as u32 }
    }
    #[inline(always)]
    fn exp2_of_rounded(sum: Self) -> Self {
        // SAFETY: AVX2 is present; see the note above `impl Avx2`.
        unsafe {
            let n = Self::rounded(sum);
            let e = _mm256_slli_epi64::<52>(_mm256_add_epi64(n, _mm256_set1_epi64x(1023)));
            Avx2(_mm256_castsi256_pd(e))
        }
    }
    #[inline(always)]
    fn quadrant(sum: Self, sin_r: Self, cos_r: Self) -> (Self, Self) {
        // SAFETY: AVX2 is present; see the note above `impl Avx2`.
        unsafe {
            let k = Self::rounded(sum);
            let one = _mm256_set1_epi64x(1);
            let two = _mm256_set1_epi64x(2);
            let odd = _mm256_castsi256_pd(_mm256_cmpeq_epi64(_mm256_and_si256(k, one), one));
            let s = _mm256_blendv_pd(sin_r.0, cos_r.0, odd);
            let c = _mm256_blendv_pd(cos_r.0, sin_r.0, odd);
            let sin_sign = _mm256_slli_epi64::<62>(_mm256_and_si256(k, two));
            let cos_sign = _mm256_slli_epi64::<62>(_mm256_and_si256(_mm256_add_epi64(k, one), two));
            (
                Avx2(_mm256_xor_pd(s, _mm256_castsi256_pd(sin_sign))),
                Avx2(_mm256_xor_pd(c, _mm256_castsi256_pd(cos_sign))),
            )
        }
    }
}

#[derive(Clone, Copy, Debug)]
pub(crate) struct Avx512(__m512d);

// SAFETY (every `unsafe` block below): these intrinsics need AVX-512F, and
// code built from them runs only inside the kernel copies compiled with
// AVX-512F enabled, entered after `is_x86_feature_detected!("avx512f")`.
impl Avx512 {
    #[inline(always)]
    fn rounded(sum: Self) -> __m512i {
        // SAFETY: AVX-512F is present; see the note above `impl Avx512`.
        unsafe {
            _mm512_sub_epi64(
                _mm512_castpd_si512(sum.0),
                _mm512_set1_epi64(ROUND_MAGIC.to_bits() as i64),
            )
        }
    }

    /// Flips the sign bits where `bits` has them (an integer XOR: the
    /// floating-point one needs AVX-512DQ).
    #[inline(always)]
    fn xor_bits(x: __m512d, bits: __m512i) -> __m512d {
        // SAFETY: AVX-512F is present; see the note above `impl Avx512`.
        unsafe { _mm512_castsi512_pd(_mm512_xor_si512(_mm512_castpd_si512(x), bits)) }
    }
}

impl Lanes for Avx512 {
    type Mask = __mmask8;
    const WIDTH: usize = 8;
    #[inline(always)]
    fn splat(x: f64) -> Self {
        // SAFETY: AVX-512F is present; see the note above `impl Avx512`.
        unsafe { Avx512(_mm512_set1_pd(x)) }
    }
    #[inline(always)]
    fn from_array(a: [f64; MAX_LANES]) -> Self {
        // SAFETY: AVX-512F is present; see the note above `impl Avx512`.
        unsafe { Avx512(_mm512_loadu_pd(a.as_ptr())) }
    }
    #[inline(always)]
    fn to_array(self) -> [f64; MAX_LANES] {
        let mut a = [0.0; MAX_LANES];
        // SAFETY: AVX-512F is present; see the note above `impl Avx512`.
        unsafe { _mm512_storeu_pd(a.as_mut_ptr(), self.0) };
        a
    }
    #[inline(always)]
    fn load(s: &[f64]) -> Self {
        let s = &s[..8];
        // SAFETY: AVX-512F is present; see the note above `impl Avx512`;
        // `s` holds the eight values read.
        unsafe { Avx512(_mm512_loadu_pd(s.as_ptr())) }
    }
    #[inline(always)]
    fn add(self, o: Self) -> Self {
        // SAFETY: AVX-512F is present; see the note above `impl Avx512`.
        unsafe { Avx512(_mm512_add_pd(self.0, o.0)) }
    }
    #[inline(always)]
    fn sub(self, o: Self) -> Self {
        // SAFETY: AVX-512F is present; see the note above `impl Avx512`.
        unsafe { Avx512(_mm512_sub_pd(self.0, o.0)) }
    }
    #[inline(always)]
    fn mul(self, o: Self) -> Self {
        // SAFETY: AVX-512F is present; see the note above `impl Avx512`.
        unsafe { Avx512(_mm512_mul_pd(self.0, o.0)) }
    }
    #[inline(always)]
    fn div(self, o: Self) -> Self {
        // SAFETY: AVX-512F is present; see the note above `impl Avx512`.
        unsafe { Avx512(_mm512_div_pd(self.0, o.0)) }
    }
    #[inline(always)]
    fn mul_add(self, b: Self, c: Self) -> Self {
        // SAFETY: AVX-512F is present; see the note above `impl Avx512`.
        unsafe { Avx512(_mm512_fmadd_pd(self.0, b.0, c.0)) }
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        // SAFETY: AVX-512F is present; see the note above `impl Avx512`.
        unsafe { Avx512(_mm512_sqrt_pd(self.0)) }
    }
    #[inline(always)]
    fn abs(self) -> Self {
        // SAFETY: AVX-512F is present; see the note above `impl Avx512`.
        unsafe { Avx512(_mm512_abs_pd(self.0)) }
    }
    #[inline(always)]
    fn neg(self) -> Self {
        // SAFETY: AVX-512F is present; see the note above `impl Avx512`.
        let sign = unsafe { _mm512_set1_epi64(i64::MIN) };
        Avx512(Self::xor_bits(self.0, sign))
    }
    #[inline(always)]
    fn lt(self, o: Self) -> Self::Mask {
        // SAFETY: AVX-512F is present; see the note above `impl Avx512`.
        unsafe { _mm512_cmp_pd_mask::<_CMP_LT_OQ>(self.0, o.0) }
    }
    #[inline(always)]
    fn ge(self, o: Self) -> Self::Mask {
        // SAFETY: AVX-512F is present; see the note above `impl Avx512`.
        unsafe { _mm512_cmp_pd_mask::<_CMP_GE_OQ>(self.0, o.0) }
    }
    #[inline(always)]
    fn eq(self, o: Self) -> Self::Mask {
        // SAFETY: AVX-512F is present; see the note above `impl Avx512`.
        unsafe { _mm512_cmp_pd_mask::<_CMP_EQ_OQ>(self.0, o.0) }
    }
    #[inline(always)]
    fn select(m: Self::Mask, a: Self, b: Self) -> Self {
        // SAFETY: AVX-512F is present; see the note above `impl Avx512`.
        unsafe { Avx512(_mm512_mask_blend_pd(m, b.0, a.0)) }
    }
    #[inline(always)]
    fn bits(m: Self::Mask) -> u32 {
        u32::from(m)
    }
    #[inline(always)]
    fn exp2_of_rounded(sum: Self) -> Self {
        // SAFETY: AVX-512F is present; see the note above `impl Avx512`.
        unsafe {
            let n = Self::rounded(sum);
            let e = _mm512_slli_epi64::<52>(_mm512_add_epi64(n, _mm512_set1_epi64(1023)));
            Avx512(_mm512_castsi512_pd(e))
        }
    }
    #[inline(always)]
    fn quadrant(sum: Self, sin_r: Self, cos_r: Self) -> (Self, Self) {
        // SAFETY: AVX-512F is present; see the note above `impl Avx512`.
        unsafe {
            let k = Self::rounded(sum);
            let one = _mm512_set1_epi64(1);
            let two = _mm512_set1_epi64(2);
            let odd = _mm512_cmpeq_epi64_mask(_mm512_and_si512(k, one), one);
            let s = _mm512_mask_blend_pd(odd, sin_r.0, cos_r.0);
            let c = _mm512_mask_blend_pd(odd, cos_r.0, sin_r.0);
            let sin_sign = _mm512_slli_epi64::<62>(_mm512_and_si512(k, two));
            let cos_sign = _mm512_slli_epi64::<62>(_mm512_and_si512(_mm512_add_epi64(k, one), two));
            (
                Avx512(Self::xor_bits(s, sin_sign)),
                Avx512(Self::xor_bits(c, cos_sign)),
            )
        }
    }
}
