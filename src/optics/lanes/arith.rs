//! Lane arithmetic for the batched solver: the lane type (a portable array
//! of four, or one AVX2 or AVX-512 register, all performing the same IEEE
//! operations), complex numbers held as their real parts and their imaginary
//! parts, and e^x, sin and cos by range reduction and polynomial.

use num_complex::Complex64 as C64;

/// The most lanes a lane type has (an AVX-512 register of f64); arrays that
/// pass lanes in and out have this length, of which a type uses its
/// [`Lanes::WIDTH`] first.
pub const MAX_LANES: usize = 8;

/// |phase| up to which sin and cos reduce the argument exactly: the
/// reduction multiplies the quadrant count by the first two 33-bit pieces
/// of π/2, exact while the count stays below 2^20 (phase ≈ 1.6 × 10⁶).
pub(super) const PHASE_LIMIT: f64 = 1e5;

/// exp(x) for x at or above this stays a normal number, built from 2^n.
pub(super) const EXP_NORMAL_MIN: f64 = -708.0;

/// 1.5 × 2^52: adding it rounds a float below 2^51 in magnitude to an
/// integer, which then sits in the low bits of the sum.
pub(super) const ROUND_MAGIC: f64 = 6_755_399_441_055_744.0;

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

/// 1/k! for k = 0..=13, the Taylor coefficients of e^x.
const INV_FACTORIAL: [f64; 14] = {
    let mut f = [1.0; 14];
    let mut k = 1;
    while k < 14 {
        f[k] = f[k - 1] / k as f64;
        k += 1;
    }
    f
};

/// f64 lanes and the operations the recursion needs. Every implementation
/// performs the same IEEE operations: [`Portable`] (an array of four, one
/// lane after the other) and, on x86-64, `Avx2` and `Avx512` (one register
/// of four or eight, in `x86`).
pub(super) trait Lanes: Copy {
    type Mask: Copy;
    /// How many f64 lanes: 4 or 8.
    const WIDTH: usize;
    /// The mask bits of all lanes.
    const ALL: u32 = (1 << Self::WIDTH) - 1;
    fn splat(x: f64) -> Self;
    /// Lanes from the first [`Self::WIDTH`] entries.
    fn from_array(a: [f64; MAX_LANES]) -> Self;
    /// The lanes in the first [`Self::WIDTH`] entries, zeros after.
    fn to_array(self) -> [f64; MAX_LANES];
    /// Lanes from the first [`Self::WIDTH`] values of `s`.
    ///
    /// # Panics
    /// If `s` is shorter.
    fn load(s: &[f64]) -> Self;
    fn add(self, o: Self) -> Self;
    fn sub(self, o: Self) -> Self;
    fn mul(self, o: Self) -> Self;
    fn div(self, o: Self) -> Self;
    /// self × b + c with one rounding.
    fn mul_add(self, b: Self, c: Self) -> Self;
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
pub(crate) struct Portable([f64; PORTABLE_LANES]);

const PORTABLE_LANES: usize = 4;

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
    fn test(self, o: Self, f: impl Fn(f64, f64) -> bool) -> [bool; PORTABLE_LANES] {
        std::array::from_fn(|i| f(self.0[i], o.0[i]))
    }

    /// The integer k that `sum` = x + ROUND_MAGIC holds in its low bits.
    #[inline(always)]
    fn rounded(sum: Self) -> [u64; PORTABLE_LANES] {
        sum.0
            .map(|v| v.to_bits().wrapping_sub(ROUND_MAGIC.to_bits()))
    }
}

impl Lanes for Portable {
    type Mask = [bool; PORTABLE_LANES];
    const WIDTH: usize = PORTABLE_LANES;
    #[inline(always)]
    fn splat(x: f64) -> Self {
        Portable([x; PORTABLE_LANES])
    }
    #[inline(always)]
    fn from_array(a: [f64; MAX_LANES]) -> Self {
        Portable(std::array::from_fn(|i| a[i]))
    }
    #[inline(always)]
    fn to_array(self) -> [f64; MAX_LANES] {
        let mut a = [0.0; MAX_LANES];
        a[..PORTABLE_LANES].copy_from_slice(&self.0);
        a
    }
    #[inline(always)]
    fn load(s: &[f64]) -> Self {
        let mut a = [0.0; PORTABLE_LANES];
        a.copy_from_slice(&s[..PORTABLE_LANES]);
        Portable(a)
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
    fn mul_add(self, b: Self, c: Self) -> Self {
        Portable(std::array::from_fn(|i| self.0[i].mul_add(b.0[i], c.0[i])))
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
        let mut r = [0.0; PORTABLE_LANES];
        for i in 0..PORTABLE_LANES {
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
        let mut sin = [0.0; PORTABLE_LANES];
        let mut cos = [0.0; PORTABLE_LANES];
        for i in 0..PORTABLE_LANES {
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

/// Complex numbers in lanes, real and imaginary parts apart. The operations
/// follow num_complex's formulas (including 0 − x where it writes that,
/// which differs from −x in the sign of a zero), but for the product and
/// [`Cv::norm_sqr_fused`], which fuse a sum into a product.
#[derive(Clone, Copy, Debug)]
pub(super) struct Cv<V> {
    pub(super) re: V,
    pub(super) im: V,
}

impl<V: Lanes> Cv<V> {
    /// `z` in every lane.
    #[inline(always)]
    pub(super) fn splat(z: C64) -> Self {
        Cv {
            re: V::splat(z.re),
            im: V::splat(z.im),
        }
    }

    #[inline(always)]
    pub(super) fn real(re: V) -> Self {
        Cv {
            re,
            im: V::splat(0.0),
        }
    }

    #[inline(always)]
    pub(super) fn add(self, o: Self) -> Self {
        Cv {
            re: self.re.add(o.re),
            im: self.im.add(o.im),
        }
    }

    #[inline(always)]
    pub(super) fn sub(self, o: Self) -> Self {
        Cv {
            re: self.re.sub(o.re),
            im: self.im.sub(o.im),
        }
    }

    /// The complex product with each part's sum fused to its first
    /// product (two roundings instead of three): four operations instead of
    /// six, and a shorter chain.
    #[inline(always)]
    pub(super) fn mul(self, o: Self) -> Self {
        Cv {
            re: self.re.mul_add(o.re, self.im.mul(o.im).neg()),
            im: self.re.mul_add(o.im, self.im.mul(o.re)),
        }
    }

    /// A real factor times a complex number (`f64 * C64`).
    #[inline(always)]
    pub(super) fn scale(self, k: V) -> Self {
        Cv {
            re: k.mul(self.re),
            im: k.mul(self.im),
        }
    }

    /// `C64 - f64`.
    #[inline(always)]
    pub(super) fn sub_real(self, x: V) -> Self {
        Cv {
            re: self.re.sub(x),
            im: self.im,
        }
    }

    /// |z|² as num_complex forms it (the near-critical tests compare it
    /// with the scalar solver's thresholds).
    #[inline(always)]
    pub(super) fn norm_sqr(self) -> V {
        self.re.mul(self.re).add(self.im.mul(self.im))
    }

    /// |z|² with the sum fused to the first square.
    #[inline(always)]
    pub(super) fn norm_sqr_fused(self) -> V {
        self.re.mul_add(self.re, self.im.mul(self.im))
    }

    /// 1/z with one division (num_complex divides twice; the results
    /// differ by at most an ulp).
    #[inline(always)]
    pub(super) fn inv(self) -> Self {
        let r = V::splat(1.0).div(self.norm_sqr());
        Cv {
            re: self.re.mul(r),
            im: self.im.neg().mul(r),
        }
    }

    /// `one + self` with `one` = 1 + 0i.
    #[inline(always)]
    pub(super) fn one_plus(self) -> Self {
        Cv {
            re: V::splat(1.0).add(self.re),
            im: V::splat(0.0).add(self.im),
        }
    }

    /// `one - self`.
    #[inline(always)]
    pub(super) fn one_minus(self) -> Self {
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
pub(super) fn sqrt_upper<V: Lanes>(z: Cv<V>) -> Cv<V> {
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
/// r¹³ (the next term is below 5 × 10⁻¹⁸) in fused multiply-adds, times 2^n
/// built in the exponent bits.
#[inline(always)]
fn exp_lanes<V: Lanes>(x: V) -> V {
    let magic = V::splat(ROUND_MAGIC);
    let sum = x.mul(V::splat(LOG2_E)).add(magic);
    let n = sum.sub(magic);
    let r = x.sub(n.mul(V::splat(LN2_HI))).sub(n.mul(V::splat(LN2_LO)));
    let mut p = V::splat(INV_FACTORIAL[13]);
    for k in (0..13).rev() {
        p = p.mul_add(r, V::splat(INV_FACTORIAL[k]));
    }
    p.mul(V::exp2_of_rounded(sum))
}

/// e^x in every lane: [`exp_lanes`] where x is in [EXP_NORMAL_MIN, 0], the
/// C library's e^x in the other lanes (a growth, or a decay past the normal
/// range), lane by lane.
#[inline(always)]
pub(super) fn exp_any<V: Lanes>(x: V) -> V {
    let in_range = V::bits(x.ge(V::splat(EXP_NORMAL_MIN))) & V::bits(V::splat(0.0).ge(x));
    let e = exp_lanes(x);
    if in_range == V::ALL {
        return e;
    }
    let (mut e, x) = (e.to_array(), x.to_array());
    for l in 0..V::WIDTH {
        if in_range & (1 << l) == 0 {
            e[l] = x[l].exp();
        }
    }
    V::from_array(e)
}

/// Minimax coefficients of sin r = r + r³ (S1 + r² S2 + … + r¹⁰ S6) on
/// |r| ≤ π/4, error below 2⁻⁵⁸: fdlibm's `k_sin.c` (Sun Microsystems, 1993),
/// S1 first, by their bits as fdlibm lists them (decimal -1.666…6632e-1,
/// 8.333…2249e-3, -1.984…5795e-4, 2.755…0701e-6, -2.505…4069e-8,
/// 1.589…1550e-10).
const SIN_MINIMAX: [f64; 6] = [
    f64::from_bits(0xBFC5_5555_5555_5549),
    f64::from_bits(0x3F81_1111_1110_F8A6),
    f64::from_bits(0xBF2A_01A0_19C1_61D5),
    f64::from_bits(0x3EC7_1DE3_57B1_FE7D),
    f64::from_bits(0xBE5A_E5E6_8A2B_9CEB),
    f64::from_bits(0x3DE5_D93A_5ACF_D57C),
];

/// Likewise cos r = 1 − r²/2 + r⁴ (C1 + r² C2 + … + r¹⁰ C6): fdlibm's
/// `k_cos.c`, C1 first (4.166…6602e-2, -1.388…7411e-3, 2.480…7673e-5,
/// -2.755…9066e-7, 2.087…8175e-9, -1.135…8819e-11).
const COS_MINIMAX: [f64; 6] = [
    f64::from_bits(0x3FA5_5555_5555_554C),
    f64::from_bits(0xBF56_C16C_16C1_5177),
    f64::from_bits(0x3EFA_01A0_19CB_1590),
    f64::from_bits(0xBE92_7E4F_809C_52AD),
    f64::from_bits(0x3E21_EE9E_BDB4_B1C4),
    f64::from_bits(0xBDA8_FAE9_BE88_38D4),
];

/// (sin a, cos a) for |a| ≤ PHASE_LIMIT: a = kπ/2 + r with |r| ≤ π/4 + ε
/// (the first two products k·π/2 are exact, so fusing them changes
/// nothing but the operation count), then minimax polynomials in r² in
/// fused multiply-adds, and the quadrant k mod 4 swaps and negates them.
#[inline(always)]
fn sin_cos_lanes<V: Lanes>(a: V) -> (V, V) {
    let magic = V::splat(ROUND_MAGIC);
    let sum = a.mul(V::splat(TWO_OVER_PI)).add(magic);
    let k = sum.sub(magic);
    let neg_k = k.neg();
    let r = neg_k.mul_add(
        V::splat(PIO2_3),
        neg_k.mul_add(V::splat(PIO2_2), neg_k.mul_add(V::splat(PIO2_1), a)),
    );
    let r2 = r.mul(r);
    let mut s = V::splat(SIN_MINIMAX[5]);
    for &coef in SIN_MINIMAX[..5].iter().rev() {
        s = s.mul_add(r2, V::splat(coef));
    }
    let sin_r = r.mul(r2).mul_add(s, r);
    let mut c = V::splat(COS_MINIMAX[5]);
    for &coef in COS_MINIMAX[..5].iter().rev() {
        c = c.mul_add(r2, V::splat(coef));
    }
    let cos_r = r2.mul_add(c.mul_add(r2, V::splat(-0.5)), V::splat(1.0));
    V::quadrant(sum, sin_r, cos_r)
}

/// The layer's one-way factor e^{iφ} = e^{−Im φ} (cos Re φ + i sin Re φ),
/// zero where the decay underflows to zero; lanes outside the polynomials'
/// range take the scalar solver's own expression.
#[inline(always)]
pub(super) fn one_way<V: Lanes>(phase: Cv<V>) -> Cv<V> {
    phase_factor(phase).0
}

/// [`one_way`] and its modulus e^{−Im φ}, which the polynomial gives on the
/// way (and the C library's e^x in the lanes the scalar solver takes).
#[inline(always)]
pub(super) fn phase_factor<V: Lanes>(phase: Cv<V>) -> (Cv<V>, V) {
    let x = phase.im.neg();
    let zero = V::splat(0.0);
    // A lossless layer (the common case) decays by exactly 1 in every lane.
    let decay = if V::bits(x.eq(zero)) == V::ALL {
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
    if in_range == V::ALL {
        return (out, decay);
    }
    let (mut re, mut im) = (out.re.to_array(), out.im.to_array());
    let mut modulus = decay.to_array();
    let (p_re, p_im) = (phase.re.to_array(), phase.im.to_array());
    for l in 0..V::WIDTH {
        if in_range & (1 << l) == 0 {
            let z = scalar_one_way(C64::new(p_re[l], p_im[l]));
            re[l] = z.re;
            im[l] = z.im;
            modulus[l] = (-p_im[l]).exp();
        }
    }
    let out = Cv {
        re: V::from_array(re),
        im: V::from_array(im),
    };
    (out, V::from_array(modulus))
}

/// The scalar solver's one-way factor, kept out of line: lanes need it only
/// past the polynomials' range.
#[inline(never)]
fn scalar_one_way(phase: C64) -> C64 {
    crate::optics::solver::one_way(phase)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The polynomial coefficients' bits are fdlibm's decimal constants.
    #[test]
    fn minimax_bits_are_fdlibms_decimals() {
        let sin = [
            "-1.66666666666666324348e-01",
            "8.33333333332248946124e-03",
            "-1.98412698298579493134e-04",
            "2.75573137070700676789e-06",
            "-2.50507602534068634195e-08",
            "1.58969099521155010221e-10",
        ];
        let cos = [
            "4.16666666666666019037e-02",
            "-1.38888888888741095749e-03",
            "2.48015872894767294178e-05",
            "-2.75573143513906633035e-07",
            "2.08757232129817482790e-09",
            "-1.13596475577881948265e-11",
        ];
        for (bits, text) in SIN_MINIMAX
            .iter()
            .zip(sin)
            .chain(COS_MINIMAX.iter().zip(cos))
        {
            assert_eq!(*bits, text.parse::<f64>().unwrap(), "{text}");
        }
    }

    /// sin and cos over many periods, within an ulp or two of the library.
    #[test]
    fn sin_cos_match_the_library() {
        let mut worst = 0.0f64;
        for i in 0..200_000 {
            let a = (i as f64 - 100_000.0) * 0.4999;
            let (s, c) = sin_cos_lanes(Portable::splat(a));
            worst = worst
                .max((s.0[0] - a.sin()).abs())
                .max((c.0[0] - a.cos()).abs());
        }
        assert!(worst < 4e-16, "{worst:e}");
    }
}
