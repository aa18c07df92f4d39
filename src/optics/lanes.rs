//! The solver of [`super::solver`] on four (wavelength, angle) pairs of one
//! stack at once: every complex quantity of the recursion is held as four
//! real parts and four imaginary parts, so that with AVX2 one instruction
//! advances all four lanes.
//!
//! The arithmetic is the scalar recursion's (the same products and sums in
//! the same order, the same branch of every square root). It departs from
//! [`solve`] only where speed asks: e^x, sin and cos come from a range
//! reduction and a polynomial instead of the C library, and a complex
//! reciprocal takes one division and two products instead of two divisions.
//! Each is within an ulp or a few; `tests/batched.rs` holds the lanes to the
//! scalar solver within 10⁻¹² over random and hard stacks.
//! What the lanes do not cover is handed, lane by lane, to the scalar solver,
//! which then gives that lane's answer exactly:
//! - grazing incidence (cos θ0 ≤ 0), which has its own closed form;
//! - a layer at or near its own critical angle (the scalar solver's field
//!   form, [`near_critical`](super::solver) there);
//!
//! For one layer of one lane only, the one-way phase factor of a layer whose
//! decay underflows (e^x below 2^−1022) or whose phase exceeds the
//! reduction's exact range ([`PHASE_LIMIT`]) is computed with the C library.
//!
//! Gain layers and evanescent gaps need nothing of their own: the branch
//! Im q ≥ 0 keeps every factor bounded, exactly as in the scalar solver.
//!
//! The kernel is generic over its lane type: [`avx2::Avx2`] (one AVX2
//! register per quantity, chosen at run time when the CPU has it) or
//! [`Portable`] (an array). Both perform the same IEEE operations in the same
//! order (Rust never fuses a multiply and an add on its own), so they agree
//! bit for bit.

use num_complex::Complex64 as C64;

use super::solver::{solve, Response};

/// Lanes per group: one AVX2 register of f64.
pub const LANES: usize = 4;

/// |phase| up to which sin and cos reduce the argument exactly: the
/// reduction multiplies the quadrant count by the first two 33-bit pieces
/// of π/2, exact while the count stays below 2^20 (phase ≈ 1.6 × 10⁶).
const PHASE_LIMIT: f64 = 1e5;

/// exp(x) for x at or above this stays a normal number, built from 2^n.
const EXP_NORMAL_MIN: f64 = -708.0;

/// 1.5 × 2^52: adding it rounds a float below 2^51 in magnitude to an
/// integer, which then sits in the low bits of the sum.
const ROUND_MAGIC: f64 = 6_755_399_441_055_744.0;

const LOG2_E: f64 = std::f64::consts::LOG2_E;
/// ln 2 in two pieces, the first with 32 significant bits so that n × LN2_HI
/// is exact for every exponent n a double can have.
const LN2_HI: f64 = 0.693_147_180_369_123_8;
const LN2_LO: f64 = 1.908_214_929_270_587_7e-10;
const TWO_OVER_PI: f64 = std::f64::consts::FRAC_2_PI;
/// π/2 in three pieces, the first two with 33 significant bits.
const PIO2_1: f64 = 1.570_796_326_734_125_6;
const PIO2_2: f64 = 6.077_100_506_303_966e-11;
const PIO2_3: f64 = 2.022_266_248_795_950_6e-21;

/// 1/k! for k = 0..=17, the Taylor coefficients of e^x, sin and cos.
const INV_FACTORIAL: [f64; 18] = {
    let mut f = [1.0; 18];
    let mut k = 1;
    while k < 18 {
        f[k] = f[k - 1] / k as f64;
        k += 1;
    }
    f
};

/// Four f64 lanes and the operations the recursion needs. Two
/// implementations perform the same IEEE operations: [`Portable`] (an
/// array, one lane after the other) and, on x86-64, [`Avx2`] (one register).
trait Lanes: Copy {
    type Mask: Copy;
    fn splat(x: f64) -> Self;
    fn from_array(a: [f64; LANES]) -> Self;
    fn to_array(self) -> [f64; LANES];
    fn add(self, o: Self) -> Self;
    fn sub(self, o: Self) -> Self;
    fn mul(self, o: Self) -> Self;
    fn div(self, o: Self) -> Self;
    fn sqrt(self) -> Self;
    fn abs(self) -> Self;
    fn neg(self) -> Self;
    /// Per lane a < b (false for NaN).
    fn lt(self, o: Self) -> Self::Mask;
    /// Per lane a >= b (false for NaN).
    fn ge(self, o: Self) -> Self::Mask;
    /// Per lane a == b (false for NaN).
    fn eq(self, o: Self) -> Self::Mask;
    /// `a` where the mask is set, `b` elsewhere.
    fn select(m: Self::Mask, a: Self, b: Self) -> Self;
    /// Bit l set when lane l of the mask is.
    fn bits(m: Self::Mask) -> u32;
    /// 2^n, n the integer that `x + ROUND_MAGIC` rounded to (as its low bits).
    fn exp2_of_rounded(sum: Self) -> Self;
    /// (sin, cos) of kπ/2 + r from those of r, k as in `exp2_of_rounded`.
    fn quadrant(sum: Self, sin_r: Self, cos_r: Self) -> (Self, Self);
}

/// The portable copy: plain per-lane loops.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Portable([f64; LANES]);

impl Portable {
    #[inline(always)]
    fn zip(self, o: Self, f: impl Fn(f64, f64) -> f64) -> Self {
        Portable(std::array::from_fn(|i| f(self.0[i], o.0[i])))
    }

    #[inline(always)]
    fn map(self, f: impl Fn(f64) -> f64) -> Self {
        Portable(self.0.map(f))
    }

    #[inline(always)]
    fn test(self, o: Self, f: impl Fn(f64, f64) -> bool) -> [bool; LANES] {
        std::array::from_fn(|i| f(self.0[i], o.0[i]))
    }

    /// The integer k that `sum` = x + ROUND_MAGIC holds in its low bits.
    #[inline(always)]
    fn rounded(sum: Self) -> [u64; LANES] {
        sum.0
            .map(|v| v.to_bits().wrapping_sub(ROUND_MAGIC.to_bits()))
    }
}

impl Lanes for Portable {
    type Mask = [bool; LANES];
    #[inline(always)]
    fn splat(x: f64) -> Self {
        Portable([x; LANES])
    }
    #[inline(always)]
    fn from_array(a: [f64; LANES]) -> Self {
        Portable(a)
    }
    #[inline(always)]
    fn to_array(self) -> [f64; LANES] {
        self.0
    }
    #[inline(always)]
    fn add(self, o: Self) -> Self {
        self.zip(o, |a, b| a + b)
    }
    #[inline(always)]
    fn sub(self, o: Self) -> Self {
        self.zip(o, |a, b| a - b)
    }
    #[inline(always)]
    fn mul(self, o: Self) -> Self {
        self.zip(o, |a, b| a * b)
    }
    #[inline(always)]
    fn div(self, o: Self) -> Self {
        self.zip(o, |a, b| a / b)
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        self.map(f64::sqrt)
    }
    #[inline(always)]
    fn abs(self) -> Self {
        self.map(f64::abs)
    }
    #[inline(always)]
    fn neg(self) -> Self {
        self.map(|a| -a)
    }
    #[inline(always)]
    fn lt(self, o: Self) -> Self::Mask {
        self.test(o, |a, b| a < b)
    }
    #[inline(always)]
    fn ge(self, o: Self) -> Self::Mask {
        self.test(o, |a, b| a >= b)
    }
    #[inline(always)]
    fn eq(self, o: Self) -> Self::Mask {
        self.test(o, |a, b| a == b)
    }
    #[inline(always)]
    fn select(m: Self::Mask, a: Self, b: Self) -> Self {
        let mut r = [0.0; LANES];
        for i in 0..LANES {
            r[i] = if m[i] { a.0[i] } else { b.0[i] };
        }
        Portable(r)
    }
    #[inline(always)]
    fn bits(m: Self::Mask) -> u32 {
        let mut b = 0;
        for (i, &x) in m.iter().enumerate() {
            b |= u32::from(x) << i;
        }
        b
    }
    #[inline(always)]
    fn exp2_of_rounded(sum: Self) -> Self {
        Portable(Self::rounded(sum).map(|n| f64::from_bits(n.wrapping_add(1023) << 52)))
    }
    #[inline(always)]
    fn quadrant(sum: Self, sin_r: Self, cos_r: Self) -> (Self, Self) {
        let k = Self::rounded(sum);
        let mut sin = [0.0; LANES];
        let mut cos = [0.0; LANES];
        for i in 0..LANES {
            let (s, c) = if k[i] & 1 == 0 {
                (sin_r.0[i], cos_r.0[i])
            } else {
                (cos_r.0[i], sin_r.0[i])
            };
            sin[i] = f64::from_bits(s.to_bits() ^ ((k[i] & 2) << 62));
            cos[i] = f64::from_bits(c.to_bits() ^ ((k[i].wrapping_add(1) & 2) << 62));
        }
        (Portable(sin), Portable(cos))
    }
}

#[cfg(target_arch = "x86_64")]
mod avx2 {
    //! The AVX2 copy: one `__m256d` per quantity. Every function here is
    //! inlined into `batch_avx2`, which is compiled with AVX2 enabled and
    //! only called once the CPU is known to have it.
    #![allow(unsafe_code)]

    use std::arch::x86_64::*;

    use super::{Lanes, LANES, ROUND_MAGIC};

    #[derive(Clone, Copy, Debug)]
    pub(crate) struct Avx2(__m256d);

    // SAFETY (every `unsafe` block below): these intrinsics need AVX or
    // AVX2, and the only caller of code built from them is `batch_avx2`,
    // entered after `is_x86_feature_detected!("avx2")`.
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
        #[inline(always)]
        fn splat(x: f64) -> Self {
            // SAFETY: AVX2 is present; see the note above `impl Avx2`.
            unsafe { Avx2(_mm256_set1_pd(x)) }
        }
        #[inline(always)]
        fn from_array(a: [f64; LANES]) -> Self {
            // SAFETY: AVX2 is present; see the note above `impl Avx2`.
            unsafe { Avx2(_mm256_loadu_pd(a.as_ptr())) }
        }
        #[inline(always)]
        fn to_array(self) -> [f64; LANES] {
            let mut a = [0.0; LANES];
            // SAFETY: AVX2 is present; see the note above `impl Avx2`.
            unsafe { _mm256_storeu_pd(a.as_mut_ptr(), self.0) };
            a
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
                let cos_sign =
                    _mm256_slli_epi64::<62>(_mm256_and_si256(_mm256_add_epi64(k, one), two));
                (
                    Avx2(_mm256_xor_pd(s, _mm256_castsi256_pd(sin_sign))),
                    Avx2(_mm256_xor_pd(c, _mm256_castsi256_pd(cos_sign))),
                )
            }
        }
    }
}

/// Four complex numbers, real and imaginary parts apart. The operations
/// repeat num_complex's formulas exactly (including 0 − x where it writes
/// that, which differs from −x in the sign of a zero).
#[derive(Clone, Copy, Debug)]
struct Cv<V> {
    re: V,
    im: V,
}

impl<V: Lanes> Cv<V> {
    #[inline(always)]
    fn real(re: V) -> Self {
        Cv {
            re,
            im: V::splat(0.0),
        }
    }

    #[inline(always)]
    fn add(self, o: Self) -> Self {
        Cv {
            re: self.re.add(o.re),
            im: self.im.add(o.im),
        }
    }

    #[inline(always)]
    fn sub(self, o: Self) -> Self {
        Cv {
            re: self.re.sub(o.re),
            im: self.im.sub(o.im),
        }
    }

    #[inline(always)]
    fn mul(self, o: Self) -> Self {
        Cv {
            re: self.re.mul(o.re).sub(self.im.mul(o.im)),
            im: self.re.mul(o.im).add(self.im.mul(o.re)),
        }
    }

    /// A real factor times a complex number (`f64 * C64`).
    #[inline(always)]
    fn scale(self, k: V) -> Self {
        Cv {
            re: k.mul(self.re),
            im: k.mul(self.im),
        }
    }

    /// `C64 - f64`.
    #[inline(always)]
    fn sub_real(self, x: V) -> Self {
        Cv {
            re: self.re.sub(x),
            im: self.im,
        }
    }

    #[inline(always)]
    fn norm_sqr(self) -> V {
        self.re.mul(self.re).add(self.im.mul(self.im))
    }

    /// 1/z with one division (num_complex divides twice; the results
    /// differ by at most an ulp).
    #[inline(always)]
    fn inv(self) -> Self {
        let r = V::splat(1.0).div(self.norm_sqr());
        Cv {
            re: self.re.mul(r),
            im: self.im.neg().mul(r),
        }
    }

    /// `one + self` with `one` = 1 + 0i.
    #[inline(always)]
    fn one_plus(self) -> Self {
        Cv {
            re: V::splat(1.0).add(self.re),
            im: V::splat(0.0).add(self.im),
        }
    }

    /// `one - self`.
    #[inline(always)]
    fn one_minus(self) -> Self {
        Cv {
            re: V::splat(1.0).sub(self.re),
            im: V::splat(0.0).sub(self.im),
        }
    }
}

/// The scalar solver's `sqrt_upper`, lane by lane: the principal root,
/// reflected into Im ≥ 0 when the argument lies below the real axis (a −0.0
/// imaginary part counts as above).
#[inline(always)]
fn sqrt_upper<V: Lanes>(z: Cv<V>) -> Cv<V> {
    let (x, y) = (z.re, z.im);
    let half = V::splat(0.5);
    let zero = V::splat(0.0);
    let t = half.mul(z.norm_sqr().sqrt().add(x.abs())).sqrt();
    let u = half.mul(y.abs()).div(t);
    let x_nonneg = x.ge(zero);
    let re = V::select(x_nonneg, t, u);
    let im = V::select(x_nonneg, u, t);
    let re = V::select(y.lt(zero), re.neg(), re);
    let root_zero = t.eq(zero);
    Cv {
        re: V::select(root_zero, zero, re),
        im: V::select(root_zero, zero, im),
    }
}

/// e^x for x in [EXP_NORMAL_MIN, 0] (anything else is the caller's to
/// handle): x = n ln 2 + r with |r| ≤ ln 2 / 2, e^r by its Taylor series to
/// r¹³ (the next term is below 5 × 10⁻¹⁸), times 2^n built in the exponent bits.
#[inline(always)]
fn exp_lanes<V: Lanes>(x: V) -> V {
    let magic = V::splat(ROUND_MAGIC);
    let sum = x.mul(V::splat(LOG2_E)).add(magic);
    let n = sum.sub(magic);
    let r = x.sub(n.mul(V::splat(LN2_HI))).sub(n.mul(V::splat(LN2_LO)));
    let mut p = V::splat(INV_FACTORIAL[13]);
    for k in (0..13).rev() {
        p = p.mul(r).add(V::splat(INV_FACTORIAL[k]));
    }
    p.mul(V::exp2_of_rounded(sum))
}

/// (sin a, cos a) for |a| ≤ PHASE_LIMIT: a = kπ/2 + r with |r| ≤ π/4 + ε,
/// the Taylor series of sin to r¹⁷ and of cos to r¹⁶ (next terms below
/// 10⁻¹⁷), then the quadrant k mod 4 swaps and negates them.
#[inline(always)]
fn sin_cos_lanes<V: Lanes>(a: V) -> (V, V) {
    let magic = V::splat(ROUND_MAGIC);
    let sum = a.mul(V::splat(TWO_OVER_PI)).add(magic);
    let k = sum.sub(magic);
    let r = a
        .sub(k.mul(V::splat(PIO2_1)))
        .sub(k.mul(V::splat(PIO2_2)))
        .sub(k.mul(V::splat(PIO2_3)));
    let r2 = r.mul(r);
    let sign = |k: usize| if k.is_multiple_of(2) { 1.0 } else { -1.0 };
    // sin r = r + r³ Σ_{k≥1} (−1)^k r^{2k−2}/(2k+1)!, to k = 8.
    let mut s = V::splat(INV_FACTORIAL[17]);
    for k in (1..8).rev() {
        s = s.mul(r2).add(V::splat(sign(k) * INV_FACTORIAL[2 * k + 1]));
    }
    let sin_r = r.add(r.mul(r2).mul(s));
    // cos r = 1 + r² Σ_{k≥1} (−1)^k r^{2k−2}/(2k)!, to k = 8.
    let mut c = V::splat(INV_FACTORIAL[16]);
    for k in (1..8).rev() {
        c = c.mul(r2).add(V::splat(sign(k) * INV_FACTORIAL[2 * k]));
    }
    let cos_r = V::splat(1.0).add(r2.mul(c));
    V::quadrant(sum, sin_r, cos_r)
}

/// The layer's one-way factor e^{iφ} = e^{−Im φ} (cos Re φ + i sin Re φ),
/// zero where the decay underflows to zero; lanes outside the polynomials'
/// range take the scalar solver's own expression.
#[inline(always)]
fn one_way<V: Lanes>(phase: Cv<V>) -> Cv<V> {
    let x = phase.im.neg();
    let zero = V::splat(0.0);
    // A lossless layer (the common case) decays by exactly 1 in every lane.
    let decay = if V::bits(x.eq(zero)) == ALL_LANES {
        V::splat(1.0)
    } else {
        exp_lanes(x)
    };
    let (sin, cos) = sin_cos_lanes(phase.re);
    let out = Cv {
        re: cos.mul(decay),
        im: sin.mul(decay),
    };
    let in_range =
        V::bits(x.ge(V::splat(EXP_NORMAL_MIN))) & V::bits(V::splat(PHASE_LIMIT).ge(phase.re.abs()));
    if in_range == ALL_LANES {
        return out;
    }
    let (mut re, mut im) = (out.re.to_array(), out.im.to_array());
    let (p_re, p_im) = (phase.re.to_array(), phase.im.to_array());
    for l in 0..LANES {
        if in_range & (1 << l) == 0 {
            let z = scalar_one_way(C64::new(p_re[l], p_im[l]));
            re[l] = z.re;
            im[l] = z.im;
        }
    }
    Cv {
        re: V::from_array(re),
        im: V::from_array(im),
    }
}

/// Every lane's bit of a mask.
const ALL_LANES: u32 = (1 << LANES) - 1;

/// The scalar solver's one-way factor, written as it writes it.
#[inline(never)]
fn scalar_one_way(phase: C64) -> C64 {
    let decay = (-phase.im).exp();
    if decay == 0.0 {
        C64::new(0.0, 0.0)
    } else {
        let (sin, cos) = phase.re.sin_cos();
        C64::new(cos * decay, sin * decay)
    }
}

/// Solves four (wavelength, angle) pairs of one stack. `indices[l]` holds
/// lane l's N + 2 indices (ambient, layers, substrate) at `wavelength_nm[l]`;
/// the preconditions are [`solve`]'s.
/// `medium(j)` gives medium j's n and n² in every lane (n² as `n * n`
/// computes it), `k0` is 2π over each lane's wavelength.
#[inline(always)]
fn solve_lanes<V: Lanes>(
    medium: impl Fn(usize) -> (Cv<V>, Cv<V>),
    k0: V,
    indices: [&[C64]; LANES],
    thicknesses_nm: &[f64],
    wavelength_nm: [f64; LANES],
    cos_theta0: [f64; LANES],
) -> [Response; LANES] {
    let last = thicknesses_nm.len() + 1;
    for lane in &indices {
        assert_eq!(lane.len(), last + 1, "indices: N + 2 per lane");
    }
    let zero = V::splat(0.0);
    let one = V::splat(1.0);
    // Lanes whose answer the scalar solver gives instead: grazing here,
    // near-critical layers below.
    let mut scalar = cos_theta0.map(|c| c.is_nan() || c <= 0.0);
    let cos = V::from_array(cos_theta0.map(|c| c.min(1.0)));
    let n0 = medium(0).0.re;
    let beta_sq = n0.mul(n0).mul(one.sub(cos).mul(one.add(cos)));

    let (n_sub, nsq_sub) = medium(last);
    let mut n_below = n_sub;
    let mut nsq_below = nsq_sub;
    let q_sub = sqrt_upper(nsq_below.sub_real(beta_sq));
    let mut q_below = q_sub;
    let (mut gamma_s, mut gamma_p) = (Cv::real(zero), Cv::real(zero));
    let (mut ts, mut tp) = (Cv::real(one), Cv::real(one));
    let mut near_critical = 0u32;

    for j in (0..last).rev() {
        let (n_above, nsq_above, q_above) = if j == 0 {
            (Cv::real(n0), Cv::real(n0.mul(n0)), Cv::real(n0.mul(cos)))
        } else {
            let (n, nsq) = medium(j);
            (n, nsq, sqrt_upper(nsq.sub_real(beta_sq)))
        };
        if j + 1 < last {
            let k0_d = k0.mul(V::splat(thicknesses_nm[j]));
            let one_way = one_way(q_below.scale(k0_d));
            let round_trip = one_way.mul(one_way);
            gamma_s = gamma_s.mul(round_trip);
            gamma_p = gamma_p.mul(round_trip);
            ts = ts.mul(one_way);
            tp = tp.mul(one_way);
        }
        if j > 0 {
            // The scalar solver's near-critical test: |q|⁴ < 10⁻⁸ |n²|².
            let q2 = q_above.norm_sqr();
            near_critical |= V::bits(q2.mul(q2).lt(V::splat(1e-8).mul(nsq_above.norm_sqr())));
        }

        let x = q_above.mul(gamma_s.one_plus());
        let y = q_below.mul(gamma_s.one_minus());
        let inv_s = x.add(y).inv();
        gamma_s = x.sub(y).mul(inv_s);
        ts = ts.mul(q_above.scale(V::splat(2.0)).mul(inv_s));

        let x = nsq_below.mul(q_above).mul(gamma_p.one_plus());
        let y = nsq_above.mul(q_below).mul(gamma_p.one_minus());
        let inv_p = x.add(y).inv();
        gamma_p = x.sub(y).mul(inv_p);
        tp = tp.mul(
            n_above
                .scale(V::splat(2.0))
                .mul(n_below)
                .mul(q_above)
                .mul(inv_p),
        );

        n_below = n_above;
        nsq_below = nsq_above;
        q_below = q_above;
    }

    // Power, as the scalar solver's `to_power`.
    let q0 = n0.mul(cos);
    let conj_q = Cv {
        re: q_sub.re,
        im: q_sub.im.neg(),
    };
    let p_flux = conj_q.mul(n_sub).mul(n_sub).re.div(n_sub.norm_sqr());
    let rs = gamma_s.norm_sqr().to_array();
    let rp = gamma_p.norm_sqr().to_array();
    let inv_q0 = one.div(q0);
    let t_s = ts.norm_sqr().mul(q_sub.re).mul(inv_q0).to_array();
    let t_p = tp.norm_sqr().mul(p_flux).mul(inv_q0).to_array();
    for (l, s) in scalar.iter_mut().enumerate() {
        *s |= near_critical & (1 << l) != 0;
    }
    let mut out = [Response::default(); LANES];
    for l in 0..LANES {
        out[l] = if scalar[l] {
            solve(indices[l], thicknesses_nm, wavelength_nm[l], cos_theta0[l])
        } else {
            Response {
                rs: rs[l],
                rp: rp[l],
                ts: t_s[l],
                tp: t_p[l],
            }
        };
    }
    out
}

/// The kernel's loop over groups of four output points. Point `i` of `out`
/// is wavelength `i / cos_theta0.len()` at angle `i % cos_theta0.len()`;
/// a last partial group repeats its final point in the unused lanes.
#[inline(always)]
fn batch_body<V: Lanes>(
    indices: &[C64],
    thicknesses_nm: &[f64],
    wavelengths_nm: &[f64],
    cos_theta0: &[f64],
    out: &mut [Response],
) {
    let media = thicknesses_nm.len() + 2;
    let n_angles = cos_theta0.len();
    let total = out.len();
    let mut start = 0;
    while start < total {
        let mut idx: [&[C64]; LANES] = [&[]; LANES];
        let mut wl = [0.0; LANES];
        let mut cos = [0.0; LANES];
        for l in 0..LANES {
            let i = (start + l).min(total - 1);
            let (w, a) = (i / n_angles, i % n_angles);
            idx[l] = &indices[w * media..(w + 1) * media];
            wl[l] = wavelengths_nm[w];
            cos[l] = cos_theta0[a];
        }
        let gather = |j: usize| {
            let n = Cv {
                re: V::from_array(idx.map(|n| n[j].re)),
                im: V::from_array(idx.map(|n| n[j].im)),
            };
            (n, n.mul(n))
        };
        let k0 = V::splat(std::f64::consts::TAU).div(V::from_array(wl));
        let res = solve_lanes::<V>(gather, k0, idx, thicknesses_nm, wl, cos);
        let end = (start + LANES).min(total);
        out[start..end].copy_from_slice(&res[..end - start]);
        start = end;
    }
}

/// A stack's indices at a list of wavelengths, laid out for the lanes:
/// per group of four consecutive wavelengths and per medium, n and n² of the
/// four lanes side by side, and 2π/λ of each lane. Built once per
/// [`StackGrid`](super::StackGrid), it turns each lane's loads into one
/// vector load and takes n², 2π/λ off the per-point work.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Spectrum {
    media: usize,
    wavelengths: usize,
    /// [group][medium][n.re, n.im, n².re, n².im][lane].
    lanes: Vec<[[f64; LANES]; 4]>,
    /// [group][lane].
    k0: Vec<[f64; LANES]>,
    wavelengths_nm: Vec<[f64; LANES]>,
}

impl Spectrum {
    /// `indices` wavelength-major, `media` per wavelength (as
    /// [`StackGrid`](super::StackGrid) stores them). A last partial group
    /// repeats its final wavelength.
    pub fn new(indices: &[C64], media: usize, wavelengths_nm: &[f64]) -> Spectrum {
        assert_eq!(indices.len(), media * wavelengths_nm.len());
        let groups = wavelengths_nm.len().div_ceil(LANES);
        let mut lanes = Vec::with_capacity(groups * media);
        let mut k0 = Vec::with_capacity(groups);
        let mut wl = Vec::with_capacity(groups);
        for g in 0..groups {
            let w = |l: usize| (g * LANES + l).min(wavelengths_nm.len() - 1);
            for j in 0..media {
                let mut m = [[0.0; LANES]; 4];
                for l in 0..LANES {
                    let n = indices[w(l) * media + j];
                    let nsq = n * n;
                    m[0][l] = n.re;
                    m[1][l] = n.im;
                    m[2][l] = nsq.re;
                    m[3][l] = nsq.im;
                }
                lanes.push(m);
            }
            let group_wl: [f64; LANES] = std::array::from_fn(|l| wavelengths_nm[w(l)]);
            k0.push(group_wl.map(|x| std::f64::consts::TAU / x));
            wl.push(group_wl);
        }
        Spectrum {
            media,
            wavelengths: wavelengths_nm.len(),
            lanes,
            k0,
            wavelengths_nm: wl,
        }
    }
}

/// Every wavelength of a [`Spectrum`] at one angle, four per vector.
#[inline(always)]
fn spectrum_body<V: Lanes>(
    spectrum: &Spectrum,
    indices: &[C64],
    thicknesses_nm: &[f64],
    cos_theta0: f64,
    out: &mut [Response],
) {
    let media = spectrum.media;
    let total = spectrum.wavelengths;
    for (g, (k0, wl)) in spectrum.k0.iter().zip(&spectrum.wavelengths_nm).enumerate() {
        let group = &spectrum.lanes[g * media..(g + 1) * media];
        let medium = |j: usize| {
            let m = &group[j];
            (
                Cv {
                    re: V::from_array(m[0]),
                    im: V::from_array(m[1]),
                },
                Cv {
                    re: V::from_array(m[2]),
                    im: V::from_array(m[3]),
                },
            )
        };
        let start = g * LANES;
        let idx: [&[C64]; LANES] = std::array::from_fn(|l| {
            let w = (start + l).min(total - 1);
            &indices[w * media..(w + 1) * media]
        });
        let res = solve_lanes::<V>(
            medium,
            V::from_array(*k0),
            idx,
            thicknesses_nm,
            *wl,
            [cos_theta0; LANES],
        );
        let end = (start + LANES).min(total);
        out[start..end].copy_from_slice(&res[..end - start]);
    }
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn spectrum_avx2(
    spectrum: &Spectrum,
    indices: &[C64],
    thicknesses_nm: &[f64],
    cos_theta0: f64,
    out: &mut [Response],
) {
    spectrum_body::<avx2::Avx2>(spectrum, indices, thicknesses_nm, cos_theta0, out)
}

fn spectrum_portable(
    spectrum: &Spectrum,
    indices: &[C64],
    thicknesses_nm: &[f64],
    cos_theta0: f64,
    out: &mut [Response],
) {
    spectrum_body::<Portable>(spectrum, indices, thicknesses_nm, cos_theta0, out)
}

/// R and T at every wavelength of `spectrum` at one angle, into `out` (one
/// per wavelength). `indices` are the same indices, wavelength-major (for
/// the lanes the scalar solver takes over); `thicknesses_nm` the N layers'.
///
/// # Panics
/// If the lengths disagree.
pub fn solve_spectrum_on(
    path: Path,
    spectrum: &Spectrum,
    indices: &[C64],
    thicknesses_nm: &[f64],
    cos_theta0: f64,
    out: &mut [Response],
) {
    assert_eq!(spectrum.media, thicknesses_nm.len() + 2, "media");
    assert_eq!(
        indices.len(),
        spectrum.media * spectrum.wavelengths,
        "indices"
    );
    assert_eq!(out.len(), spectrum.wavelengths, "out: one per wavelength");
    if out.is_empty() {
        return;
    }
    #[cfg(target_arch = "x86_64")]
    if path == Path::Best && avx2_available() {
        // SAFETY: the CPU has AVX2 (checked just above).
        return unsafe { spectrum_avx2(spectrum, indices, thicknesses_nm, cos_theta0, out) };
    }
    let _ = path;
    spectrum_portable(spectrum, indices, thicknesses_nm, cos_theta0, out)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn batch_avx2(
    indices: &[C64],
    thicknesses_nm: &[f64],
    wavelengths_nm: &[f64],
    cos_theta0: &[f64],
    out: &mut [Response],
) {
    batch_body::<avx2::Avx2>(indices, thicknesses_nm, wavelengths_nm, cos_theta0, out)
}

fn batch_portable(
    indices: &[C64],
    thicknesses_nm: &[f64],
    wavelengths_nm: &[f64],
    cos_theta0: &[f64],
    out: &mut [Response],
) {
    batch_body::<Portable>(indices, thicknesses_nm, wavelengths_nm, cos_theta0, out)
}

/// Which copy of the kernel runs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Path {
    /// AVX2 when the CPU has it (checked at run time), portable otherwise.
    Best,
    /// The portable copy, whatever the CPU (for tests and comparisons).
    Portable,
}

/// True when [`Path::Best`] runs the AVX2 copy on this CPU.
pub fn avx2_available() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        std::arch::is_x86_feature_detected!("avx2")
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}

/// [`solve_batch`](super::solver::solve_batch) on a chosen copy of the
/// kernel; the lengths must already agree (the caller checks them).
pub fn solve_batch_on(
    path: Path,
    indices: &[C64],
    thicknesses_nm: &[f64],
    wavelengths_nm: &[f64],
    cos_theta0: &[f64],
    out: &mut [Response],
) {
    if cos_theta0.is_empty() || out.is_empty() {
        return;
    }
    #[cfg(target_arch = "x86_64")]
    if path == Path::Best && avx2_available() {
        // SAFETY: the CPU has AVX2 (checked just above).
        return unsafe { batch_avx2(indices, thicknesses_nm, wavelengths_nm, cos_theta0, out) };
    }
    let _ = path;
    batch_portable(indices, thicknesses_nm, wavelengths_nm, cos_theta0, out)
}
