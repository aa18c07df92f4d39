//! The transfer-matrix solution of a planar multilayer, written as the
//! reflection-coefficient recursion from the substrate up (Rouard/Parratt).
//!
//! Conventions (see `shared/design.md`): fields vary as e^{-iωt}, a forward
//! wave as e^{+i k0 q z}, the index is n + ik with k > 0 absorbing. Inside
//! every medium we work with q = n cos θ = sqrt(n² − β²), β = n0 sin θ0 the
//! conserved tangential index, on the branch Im q ≥ 0. On that branch the
//! round-trip factor e^{2i k0 q d} of every layer has modulus ≤ 1, so thick
//! absorbers and evanescent gaps underflow to zero instead of overflowing,
//! which is what breaks the plain product of 2×2 transfer matrices. For a
//! finite layer the branch does not change the answer (the layer's transfer
//! matrix is even in q), so gain layers take the same branch and stay bounded.

use num_complex::Complex64 as C64;

/// Power reflectance and transmittance for s and p polarization.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Response {
    pub rs: f64,
    pub rp: f64,
    pub ts: f64,
    pub tp: f64,
}

impl Response {
    /// Unpolarized reflectance.
    #[inline]
    pub fn r(&self) -> f64 {
        0.5 * (self.rs + self.rp)
    }

    /// Unpolarized transmittance (power flux into the substrate).
    #[inline]
    pub fn t(&self) -> f64 {
        0.5 * (self.ts + self.tp)
    }
}

/// Complex amplitude coefficients of a whole stack, referenced to the top
/// interface (r) and to the bottom interface (t).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Amplitudes {
    pub rs: C64,
    pub rp: C64,
    pub ts: C64,
    pub tp: C64,
}

/// q = n cos θ = sqrt(n² − β²) on the branch Im q ≥ 0 (Re q > 0 when Im q = 0).
///
/// The sign is fixed after the square root: the principal root returns
/// Im < 0 for gain media, and a −0.0 imaginary part of n² − β² would put an
/// evanescent wave on the growing branch.
#[inline]
pub fn normal_index(n: C64, beta_sq: f64) -> C64 {
    let q = (n * n - beta_sq).sqrt();
    if q.im < 0.0 || (q.im == 0.0 && q.re < 0.0) {
        -q
    } else {
        q
    }
}

/// Fresnel coefficients of one interface from medium `i` into medium `f`
/// (Byrnes' convention), given each side's index n and q.
#[derive(Clone, Copy, Debug)]
pub struct Fresnel {
    pub rs: C64,
    pub rp: C64,
    pub ts: C64,
    pub tp: C64,
}

#[inline]
pub fn fresnel(n_i: C64, q_i: C64, n_f: C64, q_f: C64) -> Fresnel {
    let s_den = (q_i + q_f).inv();
    let a = n_f * n_f * q_i;
    let b = n_i * n_i * q_f;
    let p_den = (a + b).inv();
    // t_p = 2 n_i n_f q_i / (n_f² q_i + n_i² q_f): the product n_i n_f is
    // kept whole so that t_ij t_ji keeps its sign when sub-stacks are combined.
    let ni_nf = n_i * n_f;
    Fresnel {
        rs: (q_i - q_f) * s_den,
        rp: (a - b) * p_den,
        ts: 2.0 * q_i * s_den,
        tp: 2.0 * ni_nf * q_i * p_den,
    }
}

/// At exact grazing incidence (cos θ0 = 0) no power enters the stack,
/// whatever the stack: every interface reflects with r = −1.
const GRAZING: Response = Response {
    rs: 1.0,
    rp: 1.0,
    ts: 0.0,
    tp: 0.0,
};

/// Solves one stack at one wavelength and one angle.
///
/// `indices` holds the ambient, the N layers from the top down, and the
/// substrate (N + 2 entries); `thicknesses_nm` the N layer thicknesses.
/// The ambient must be lossless (its imaginary part is ignored) and
/// `cos_theta0` in [0, 1]. Nothing is allocated.
#[inline]
pub fn solve(
    indices: &[C64],
    thicknesses_nm: &[f64],
    wavelength_nm: f64,
    cos_theta0: f64,
) -> Response {
    if cos_theta0 <= 0.0 {
        return GRAZING;
    }
    let amp = solve_amplitudes(indices, thicknesses_nm, wavelength_nm, cos_theta0);
    power(indices, cos_theta0, &amp)
}

/// Converts amplitude coefficients to power: R = |r|²; T from the Poynting
/// flux, Re(q_sub)/q0 for s and Re(n_sub conj(cos θ_sub))/(n0 cos θ0) for p.
#[inline]
pub fn power(indices: &[C64], cos_theta0: f64, amp: &Amplitudes) -> Response {
    let n0 = indices[0].re;
    let n_sub = indices[indices.len() - 1];
    let beta_sq = n0 * n0 * (1.0 - cos_theta0 * cos_theta0);
    let q_sub = normal_index(n_sub, beta_sq);
    let q0 = n0 * cos_theta0;
    let cos_sub = q_sub / n_sub;
    Response {
        rs: amp.rs.norm_sqr(),
        rp: amp.rp.norm_sqr(),
        ts: amp.ts.norm_sqr() * q_sub.re / q0,
        tp: amp.tp.norm_sqr() * (n_sub * cos_sub.conj()).re / q0,
    }
}

/// The complex r and t of the stack, both polarizations; see [`solve`].
pub fn solve_amplitudes(
    indices: &[C64],
    thicknesses_nm: &[f64],
    wavelength_nm: f64,
    cos_theta0: f64,
) -> Amplitudes {
    debug_assert_eq!(indices.len(), thicknesses_nm.len() + 2);
    let n0 = indices[0].re;
    let beta_sq = n0 * n0 * (1.0 - cos_theta0 * cos_theta0);
    let k0 = std::f64::consts::TAU / wavelength_nm;

    let last = indices.len() - 1;
    let mut n_below = indices[last];
    let mut q_below = normal_index(indices[last], beta_sq);
    // Reflection coefficients looking down into the medium below the
    // current interface, referenced to that interface.
    let mut gamma_s = C64::new(0.0, 0.0);
    let mut gamma_p = C64::new(0.0, 0.0);
    let mut ts = C64::new(1.0, 0.0);
    let mut tp = C64::new(1.0, 0.0);

    for j in (0..last).rev() {
        let n_above = if j == 0 {
            C64::new(n0, 0.0)
        } else {
            indices[j]
        };
        let q_above = normal_index(n_above, beta_sq);
        if j + 1 < last {
            // The medium below is a finite layer: carry Γ up through it.
            let one_way = (C64::new(0.0, k0 * thicknesses_nm[j]) * q_below).exp();
            let round_trip = one_way * one_way;
            gamma_s *= round_trip;
            gamma_p *= round_trip;
            ts *= one_way;
            tp *= one_way;
        }
        let f = fresnel(n_above, q_above, n_below, q_below);
        let ds = (1.0 + f.rs * gamma_s).inv();
        let dp = (1.0 + f.rp * gamma_p).inv();
        gamma_s = (f.rs + gamma_s) * ds;
        gamma_p = (f.rp + gamma_p) * dp;
        ts *= f.ts * ds;
        tp *= f.tp * dp;
        n_below = n_above;
        q_below = q_above;
    }
    Amplitudes {
        rs: gamma_s,
        rp: gamma_p,
        ts,
        tp,
    }
}
