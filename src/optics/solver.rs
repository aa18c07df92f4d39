//! The transfer-matrix solution of a planar multilayer, written as the
//! reflection-coefficient recursion from the substrate up (Rouard/Parratt).
//!
//! Conventions (explained in docs/architecture.md): fields vary as
//! e^{-iωt}, a forward wave as e^{+i k0 q z}, the index is n + ik with k > 0
//! absorbing. Inside every medium we work with q = n cos θ = sqrt(n² − β²), β = n0 sin θ0 the
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
    /// s-polarized reflectance |r_s|², a power fraction.
    pub rs: f64,
    /// p-polarized reflectance |r_p|², a power fraction.
    pub rp: f64,
    /// s-polarized transmittance: the Poynting flux into the substrate,
    /// |t_s|² Re(q_sub) / q0. R + T + absorption = 1 for a passive stack.
    pub ts: f64,
    /// p-polarized transmittance: the Poynting flux into the substrate,
    /// |t_p|² Re(n_sub conj(cos θ_sub)) / (n0 cos θ0).
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

    /// False where a mixed solver found the sum over an incoherent gain
    /// layer's round trips divergent (it then gives +∞; see
    /// [`solve_mixed`](super::incoherent::solve_mixed)).
    #[inline]
    pub fn is_finite(&self) -> bool {
        self.rs.is_finite() && self.rp.is_finite() && self.ts.is_finite() && self.tp.is_finite()
    }
}

/// Complex amplitude coefficients of a whole stack, referenced to the top
/// interface (r) and to the bottom interface (t).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Amplitudes {
    /// s-polarized reflection coefficient at the top interface.
    pub rs: C64,
    /// p-polarized reflection coefficient at the top interface (Byrnes'
    /// sign convention).
    pub rp: C64,
    /// s-polarized transmission coefficient: the substrate's forward
    /// amplitude at the bottom interface over the incident one.
    pub ts: C64,
    /// p-polarized transmission coefficient, referenced like `ts`.
    pub tp: C64,
}

/// sqrt(z) on the branch Im ≥ 0 (Re > 0 when Im = 0).
///
/// Written out rather than `Complex::sqrt`, which goes through polar form
/// (atan2, sin, cos) and dominated the solver's time. The root is the
/// principal one, reflected when z lies below the real axis; a −0.0
/// imaginary part counts as above, so that a real negative z (an evanescent
/// wave) always gets +i|z|^½, the decaying branch.
#[inline]
pub(super) fn sqrt_upper(z: C64) -> C64 {
    let (x, y) = (z.re, z.im);
    let t = (0.5 * (z.norm_sqr().sqrt() + x.abs())).sqrt();
    if t == 0.0 {
        return C64::new(0.0, 0.0);
    }
    let u = 0.5 * y.abs() / t;
    // Principal root: (t, y/2t) for x ≥ 0, (|y|/2t, ±t) for x < 0.
    let (re, im) = if x >= 0.0 { (t, u) } else { (u, t) };
    if y < 0.0 {
        C64::new(-re, im)
    } else {
        C64::new(re, im)
    }
}

/// q = n cos θ = sqrt(n² − β²) on the branch Im q ≥ 0 (Re q > 0 when Im q = 0).
#[inline]
pub fn normal_index(n: C64, beta_sq: f64) -> C64 {
    sqrt_upper(n * n - beta_sq)
}

/// [`normal_index`] for light arriving from a lossless ambient of index
/// `n0` at cos θ0 `cos_theta0`: √((n² − n0²) + (n0 cos θ0)²), which is
/// √(n² − β²) but keeps (n0 cos θ0)² where it is below the rounding of n0²
/// (cos θ0 below about 1e-8). A medium of the ambient's own index then gets
/// q = n0 cos θ0 exactly, as the ambient itself, instead of 0: near
/// grazing incidence a free-standing film of zero thickness is the bare
/// ambient, not a perfect mirror over 0/0.
#[inline]
pub fn normal_index_at(n: C64, n0: f64, cos_theta0: f64) -> C64 {
    let q0 = n0 * cos_theta0;
    sqrt_upper((n * n - n0 * n0) + q0 * q0)
}

/// Fresnel coefficients of one interface from medium `i` into medium `f`
/// (Byrnes' convention), given each side's index n and q.
#[derive(Clone, Copy, Debug)]
pub struct Fresnel {
    /// s reflection: (q_i − q_f) / (q_i + q_f).
    pub rs: C64,
    /// p reflection: (n_f² q_i − n_i² q_f) / (n_f² q_i + n_i² q_f).
    pub rp: C64,
    /// s transmission: 2 q_i / (q_i + q_f).
    pub ts: C64,
    /// p transmission: 2 n_i n_f q_i / (n_f² q_i + n_i² q_f).
    pub tp: C64,
}

/// The [`Fresnel`] coefficients from medium i (index `n_i`, normal index
/// `q_i` = n_i cos θ_i) into medium f; the q are those of
/// [`normal_index`], on the branch Im q ≥ 0. Where a denominator vanishes
/// the coefficients are not finite.
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

/// At exact grazing incidence (cos θ0 = 0) no power enters the stack:
/// every interface reflects with r = −1. The one exception is a stack with no
/// interface at all (every medium equal to the ambient), which transmits.
#[inline(never)]
pub(super) fn grazing(indices: &[C64]) -> Response {
    let n0 = C64::new(indices[0].re, 0.0);
    if indices[1..].iter().all(|&n| n == n0) {
        Response {
            rs: 0.0,
            rp: 0.0,
            ts: 1.0,
            tp: 1.0,
        }
    } else {
        Response {
            rs: 1.0,
            rp: 1.0,
            ts: 0.0,
            tp: 0.0,
        }
    }
}

/// Solves one stack at one wavelength and one angle.
///
/// `indices` holds the ambient, the N layers from the top down, and the
/// substrate (N + 2 entries); `thicknesses_nm` the N layer thicknesses.
/// The ambient must be lossless (its imaginary part is ignored), the
/// substrate without gain (its power flux is taken on the decaying branch),
/// every
/// index finite, nonzero and below 10¹⁰⁰ in modulus (materials are held to
/// [`MAX_INDEX`](super::material::MAX_INDEX)), and `cos_theta0` in [0, 1]
/// (larger values are taken as 1). Nothing is allocated.
#[inline]
pub fn solve(
    indices: &[C64],
    thicknesses_nm: &[f64],
    wavelength_nm: f64,
    cos_theta0: f64,
) -> Response {
    if cos_theta0 <= 0.0 {
        return grazing(indices);
    }
    let cos_theta0 = cos_theta0.min(1.0);
    let (amp, q_sub) = recurse(indices, thicknesses_nm, wavelength_nm, cos_theta0);
    to_power(indices, cos_theta0, &amp, q_sub)
}

/// Converts amplitude coefficients to power: R = |r|²; T from the Poynting
/// flux, Re(q_sub)/q0 for s and Re(n_sub conj(cos θ_sub))/(n0 cos θ0) for p.
#[inline]
pub fn power(indices: &[C64], cos_theta0: f64, amp: &Amplitudes) -> Response {
    let n0 = indices[0].re;
    let beta_sq = n0 * n0 * sin_sq(cos_theta0);
    let q_sub = normal_index(indices[indices.len() - 1], beta_sq);
    to_power(indices, cos_theta0, amp, q_sub)
}

#[inline]
fn to_power(indices: &[C64], cos_theta0: f64, amp: &Amplitudes, q_sub: C64) -> Response {
    let q0 = indices[0].re * cos_theta0;
    let n_sub = indices[indices.len() - 1];
    // Re(n conj(q/n)) = Re(q̄ n / n̄) = Re(q̄ n²) / |n|².
    let p_flux = (q_sub.conj() * n_sub * n_sub).re / n_sub.norm_sqr();
    Response {
        rs: amp.rs.norm_sqr(),
        rp: amp.rp.norm_sqr(),
        ts: amp.ts.norm_sqr() * q_sub.re / q0,
        tp: amp.tp.norm_sqr() * p_flux / q0,
    }
}

/// sin² θ from cos θ without the cancellation of 1 − cos² near normal incidence.
#[inline]
pub(super) fn sin_sq(cos_theta: f64) -> f64 {
    (1.0 - cos_theta) * (1.0 + cos_theta)
}

/// The complex r and t of the stack, both polarizations; see [`solve`].
pub fn solve_amplitudes(
    indices: &[C64],
    thicknesses_nm: &[f64],
    wavelength_nm: f64,
    cos_theta0: f64,
) -> Amplitudes {
    recurse(indices, thicknesses_nm, wavelength_nm, cos_theta0).0
}

/// The recursion proper; also returns q of the substrate for the power flux.
///
/// At each interface, with Γ the reflection coefficient of everything below
/// referred to that interface and r, t the interface's own coefficients,
/// Γ' = (r + Γ)/(1 + rΓ) and the transmitted amplitude gains t/(1 + rΓ).
/// Writing r = (a − b)/(a + b) and t = c/(a + b) turns both into one shared
/// complex reciprocal: with x = a(1 + Γ) and y = b(1 − Γ), Γ' = (x − y)/(x + y)
/// and t/(1 + rΓ) = c/(x + y). For s, a = q_above, b = q_below, c = 2a; for
/// p, a = n_b² q_a, b = n_a² q_b, c = 2 n_a n_b q_a. Grouping by (1 ± Γ)
/// rather than by (a ± b) matters when |a| ≪ |b| and Γ = 1: then a + b and
/// a − b round to ±b and D = 2a would come out as 0.
///
/// A layer at (or near) its own critical angle, q → 0, is where the two
/// waves of the Γ description merge: its interfaces reflect with r → ±1 and
/// Γ loses digits as ε/|q| (0/0 at q = 0 exactly). Such layers, and runs of
/// them, are crossed in field form instead; see [`NearCritical`].
#[inline(always)]
fn recurse(
    indices: &[C64],
    thicknesses_nm: &[f64],
    wavelength_nm: f64,
    cos_theta0: f64,
) -> (Amplitudes, C64) {
    let n0 = indices[0].re;
    let top = [
        C64::new(n0, 0.0),
        C64::new(n0 * n0, 0.0),
        C64::new(n0 * cos_theta0, 0.0),
    ];
    let beta_sq = n0 * n0 * sin_sq(cos_theta0);
    let q_sub = normal_index(indices[indices.len() - 1], beta_sq);
    let amp = recurse_beta(indices, thicknesses_nm, wavelength_nm, beta_sq, top, q_sub);
    (amp, q_sub)
}

/// r and t of a stack whose top medium may absorb or gain, given the
/// conserved β² = (n sin θ)² instead of an angle: what a sub-stack below (or
/// above) a buried layer sees, the top medium being that layer's. Every q,
/// the top medium's included, is on the branch Im q ≥ 0. r is referenced to
/// the top interface, t (the ratio of forward amplitudes) to the bottom one.
/// A top medium with q = 0 exactly (lossless, at its critical angle) has no
/// forward wave to refer r and t to; the result is then not finite.
pub fn solve_amplitudes_beta(
    indices: &[C64],
    thicknesses_nm: &[f64],
    wavelength_nm: f64,
    beta_sq: f64,
) -> Amplitudes {
    let n_top = indices[0];
    let nsq_top = n_top * n_top;
    let top = [n_top, nsq_top, sqrt_upper(nsq_top - beta_sq)];
    let q_bottom = normal_index(indices[indices.len() - 1], beta_sq);
    recurse_beta(
        indices,
        thicknesses_nm,
        wavelength_nm,
        beta_sq,
        top,
        q_bottom,
    )
}

/// The recursion for a given β², the top medium given as (n, n², q) and the
/// bottom medium's q as `q_sub` (as [`solve_amplitudes_beta`] and
/// [`normal_index`] compute them): a caller that solves several sub-stacks
/// sharing media, as the two-port split does, computes each medium's q once.
#[inline(always)]
pub(super) fn recurse_beta(
    indices: &[C64],
    thicknesses_nm: &[f64],
    wavelength_nm: f64,
    beta_sq: f64,
    top: [C64; 3],
    q_sub: C64,
) -> Amplitudes {
    debug_assert_eq!(indices.len(), thicknesses_nm.len() + 2);
    recurse_media(
        indices.len(),
        |j| indices[j],
        |j| thicknesses_nm[j],
        wavelength_nm,
        beta_sq,
        top,
        q_sub,
    )
}

/// [`recurse_beta`] over `media` media read through `index(j)` (medium j
/// from the top, 0 to `media` − 1) and `thickness(j)` (the thickness of
/// medium j + 1, a finite layer): the same recursion over a view of a
/// stack, such as a run of its media read bottom up, without copying it.
#[inline(always)]
pub(super) fn recurse_media(
    media: usize,
    index: impl Fn(usize) -> C64,
    thickness: impl Fn(usize) -> f64,
    wavelength_nm: f64,
    beta_sq: f64,
    top: [C64; 3],
    q_sub: C64,
) -> Amplitudes {
    let k0 = std::f64::consts::TAU / wavelength_nm;

    let last = media - 1;
    let mut n_below = index(last);
    let mut nsq_below = n_below * n_below;
    let mut q_below = q_sub;
    let zero = C64::new(0.0, 0.0);
    let one = C64::new(1.0, 0.0);
    let (mut gamma_s, mut gamma_p, mut ts, mut tp) = (zero, zero, one, one);
    // Some while the medium below is a near-critical layer.
    let mut fields: Option<NearCritical> = None;

    for j in (0..last).rev() {
        let (n_above, nsq_above, q_above) = if j == 0 {
            (top[0], top[1], top[2])
        } else {
            let n = index(j);
            let nsq = n * n;
            (n, nsq, sqrt_upper(nsq - beta_sq))
        };
        if j + 1 < last {
            // The medium below is a finite layer: carry the state up through it.
            let d = thickness(j);
            if let Some(f) = &mut fields {
                let scale = f.cross_layer(k0 * d, nsq_below, q_below);
                ts *= scale;
                tp *= scale;
            } else {
                let one_way = one_way(k0 * d * q_below);
                let round_trip = one_way * one_way;
                gamma_s *= round_trip;
                gamma_p *= round_trip;
                ts *= one_way;
                tp *= one_way;
            }
        }
        let above_near_critical = j > 0 && near_critical(q_above, nsq_above);
        match (fields, above_near_critical) {
            (None, false) => {
                let x = q_above * (one + gamma_s);
                let y = q_below * (one - gamma_s);
                let inv_s = (x + y).inv();
                gamma_s = (x - y) * inv_s;
                ts *= 2.0 * q_above * inv_s;

                let x = nsq_below * q_above * (one + gamma_p);
                let y = nsq_above * q_below * (one - gamma_p);
                let inv_p = (x + y).inv();
                gamma_p = (x - y) * inv_p;
                tp *= 2.0 * n_above * n_below * q_above * inv_p;
            }
            (None, true) => {
                fields = Some(NearCritical::from_gamma(
                    gamma_s,
                    gamma_p,
                    q_below,
                    q_below / nsq_below,
                ));
                tp *= n_above / n_below;
            }
            (Some(_), true) => tp *= n_above / n_below,
            (Some(f), false) => {
                let (g_s, t_s) = f.s.to_gamma(q_above);
                let (g_p, t_p) = f.p.to_gamma(q_above / nsq_above);
                gamma_s = g_s;
                gamma_p = g_p;
                ts *= t_s;
                tp *= t_p * n_above / n_below;
                fields = None;
            }
        }
        n_below = n_above;
        nsq_below = nsq_above;
        q_below = q_above;
    }
    Amplitudes {
        rs: gamma_s,
        rp: gamma_p,
        ts,
        tp,
    }
}

/// A layer's one-way factor e^{iφ} = e^{−Im φ} (cos Re φ + i sin Re φ).
/// Past e^{−745} nothing comes back up through the layer: the factor is
/// exactly zero, and skipping the trigonometry also avoids sin(huge) there.
#[inline]
pub(super) fn one_way(phase: C64) -> C64 {
    let decay = (-phase.im).exp();
    if decay == 0.0 {
        C64::new(0.0, 0.0)
    } else {
        let (sin, cos) = phase.re.sin_cos();
        C64::new(cos * decay, sin * decay)
    }
}

/// |q|² < 10⁻⁴ |n|²: within this the Γ recursion would lose more than
/// about two digits to the merging of the layer's two waves.
#[inline]
pub(super) fn near_critical(q: C64, nsq: C64) -> bool {
    let q2 = q.norm_sqr();
    q2 * q2 < 1e-8 * nsq.norm_sqr()
}

/// The tangential fields (u, v) at the bottom of a run of near-critical
/// layers, in units of the forward amplitude of the ordinary medium below
/// the run. For s, u = E_t and v = H_t with admittance η = q; for p, by
/// duality, u = H_t and v = E_t with η = q/n² (and amplitudes n·E).
/// Both obey the same layer matrix
/// [u, v]_top = [[cos δ, −i sin δ/η], [−i η sin δ, cos δ]] [u, v]_bottom,
/// δ = k0 q d, which is even in q and has no trouble at q = 0.
#[derive(Clone, Copy)]
struct NearCritical {
    s: Fields,
    p: Fields,
}

#[derive(Clone, Copy)]
struct Fields {
    u: C64,
    v: C64,
}

impl Fields {
    /// Leaves the run into an ordinary medium of admittance η: returns Γ
    /// there and the amplitude ratio (below the run / above it).
    /// Γ = (ηu − v)/(ηu + v), and u = B⁺(1 + Γ) gives B_below/B_above = 2η/(ηu + v).
    #[inline]
    fn to_gamma(self, eta: C64) -> (C64, C64) {
        let inv = (eta * self.u + self.v).inv();
        ((eta * self.u - self.v) * inv, 2.0 * eta * inv)
    }
}

impl NearCritical {
    #[inline]
    fn from_gamma(gamma_s: C64, gamma_p: C64, eta_s: C64, eta_p: C64) -> Self {
        let one = C64::new(1.0, 0.0);
        NearCritical {
            s: Fields {
                u: one + gamma_s,
                v: eta_s * (one - gamma_s),
            },
            p: Fields {
                u: one + gamma_p,
                v: eta_p * (one - gamma_p),
            },
        }
    }

    /// Applies one layer's matrix (k0 d, and the layer's n², q) to both
    /// polarizations. Thick lossy layers would overflow cos and sin, so when
    /// Im δ is large everything is multiplied by e^{iδ} (|e^{iδ}| < 1); the
    /// returned factor is what the transmitted amplitude must be multiplied
    /// by to undo that (1 otherwise).
    #[inline(never)]
    fn cross_layer(&mut self, k0_d: f64, nsq: C64, q: C64) -> C64 {
        let i = C64::new(0.0, 1.0);
        let one = C64::new(1.0, 0.0);
        let delta = k0_d * q;
        let (cos_d, sin_d, sinc_d, scale) = if delta.im > 30.0 {
            let e = (i * delta).exp();
            let e2 = e * e;
            let sin_d = i * (one - e2) * 0.5;
            (0.5 * (one + e2), sin_d, sin_d / delta, e)
        } else {
            let sinc_d = if delta.norm_sqr() < 1e-6 {
                let d2 = delta * delta;
                one - d2 / 6.0 + d2 * d2 / 120.0
            } else {
                delta.sin() / delta
            };
            (delta.cos(), delta.sin(), sinc_d, one)
        };
        // sin δ / η: k0 d sinc δ for s (η = q), n² k0 d sinc δ for p (η = q/n²).
        let sin_over_q = k0_d * sinc_d;
        for (f, eta, sin_over_eta) in [
            (&mut self.s, q, sin_over_q),
            (&mut self.p, q / nsq, sin_over_q * nsq),
        ] {
            let (u, v) = (f.u, f.v);
            f.u = cos_d * u - i * sin_over_eta * v;
            f.v = -i * eta * sin_d * u + cos_d * v;
        }
        scale
    }
}

/// One stack over many wavelengths and angles: R and T at every
/// (wavelength, cos θ0) pair, written wavelength-major into `out`
/// (`out[i * cos_theta0.len() + j]` for wavelength i, angle j).
///
/// `indices` holds, for each wavelength in turn, that wavelength's N + 2
/// indices (ambient, layers, substrate), as [`StackGrid`](super::StackGrid)
/// stores them. Nothing is allocated; the materials were evaluated once by
/// whoever filled `indices`. Points are solved eight or four at a time (the
/// widest vectors the CPU has), agreeing with [`solve`] point by point to about 10⁻¹⁵; see
/// [`lanes`](super::lanes).
///
/// # Panics
/// If the slice lengths disagree.
pub fn solve_batch(
    indices: &[C64],
    thicknesses_nm: &[f64],
    wavelengths_nm: &[f64],
    cos_theta0: &[f64],
    out: &mut [Response],
) {
    let media = thicknesses_nm.len() + 2;
    assert_eq!(
        indices.len(),
        media * wavelengths_nm.len(),
        "indices: N + 2 per wavelength"
    );
    assert_eq!(
        out.len(),
        wavelengths_nm.len() * cos_theta0.len(),
        "out: wavelengths × angles"
    );
    super::lanes::solve_batch_on(
        super::lanes::Path::Best,
        indices,
        thicknesses_nm,
        wavelengths_nm,
        cos_theta0,
        out,
    );
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn square_root_branch() {
        let c = C64::new;
        // Against the principal root, reflected into the upper half plane.
        for z in [
            c(2.0, 0.0),
            c(2.0, 3.0),
            c(2.0, -3.0),
            c(-2.0, 3.0),
            c(-2.0, -3.0),
            c(-5.0, 1e-300),
            c(1e-12, -1e-14),
        ] {
            let p = z.sqrt();
            let want = if p.im < 0.0 || (p.im == 0.0 && p.re < 0.0) {
                -p
            } else {
                p
            };
            let got = sqrt_upper(z);
            assert!(
                (got - want).norm() <= 1e-15 * want.norm(),
                "{z}: {got} vs {want}"
            );
            assert!((got * got - z).norm() <= 1e-15 * z.norm(), "{z}");
        }
        // An evanescent wave whose n² − β² carries a −0.0 imaginary part
        // must still decay: +i, never −i.
        assert_eq!(sqrt_upper(c(-4.0, -0.0)), c(0.0, 2.0));
        assert_eq!(sqrt_upper(c(-4.0, 0.0)), c(0.0, 2.0));
        assert_eq!(sqrt_upper(c(0.0, 0.0)), c(0.0, 0.0));
        assert_eq!(sqrt_upper(c(4.0, -0.0)), c(2.0, 0.0));
        // Gain (k < 0): Im q ≥ 0 puts Re q < 0, which is fine inside a finite layer.
        let q = normal_index(c(1.5, -0.1), 0.5);
        assert!(q.im > 0.0 && q.re < 0.0, "{q}");
    }

    #[test]
    fn batch_shapes_and_grazing() {
        let n = [C64::new(1.0, 0.0), C64::new(1.4, 0.0), C64::new(1.5, 0.0)];
        let d = [100.0];
        let mut out = [Response::default(); 6];
        let n2: Vec<C64> = n.iter().chain(&n).copied().collect();
        solve_batch(&n2, &d, &[500.0, 600.0], &[1.0, 0.5, 0.0], &mut out);
        assert_eq!(out[2], out[5]);
        assert_eq!(out[2].r(), 1.0);
        // The batch runs four points per vector: the scalar solver's answer
        // to within an ulp or a few (tests/batched.rs holds it to 1e-12).
        let one = solve(&n, &d, 600.0, 0.5);
        for (got, want) in [
            (out[4].rs, one.rs),
            (out[4].rp, one.rp),
            (out[4].ts, one.ts),
            (out[4].tp, one.tp),
        ] {
            assert!((got - want).abs() <= 1e-15, "{got} vs {want}");
        }
    }
}
