//! The spectrum of one point when no medium's index changes with
//! wavelength (a non-dispersive stack: constant n + ik in every layer, the
//! ambient and the substrate). At one angle every normal index q and every
//! interface's Fresnel coefficients are then the same at all wavelengths;
//! only the layers' phases k0 q d change. They are computed once per call,
//! and each wavelength costs one e^{iφ} per layer and, per interface and
//! polarization, the recursion
//!
//!   Γ ← (r + Γρ) / (1 + rΓρ),  t ← t · t_int · e^{iφ} / (1 + rΓρ),
//!
//! ρ = e^{2iφ} the layer's round trip. This is the general solver's
//! recursion divided through by the interface's own denominator
//! (x + y = (q_a + q_b)(1 + rΓρ) for s): the same quantities, with the
//! products that do not depend on wavelength taken out of the loop.
//!
//! Where that division would not be safe the caller's general kernel runs
//! instead: grazing incidence, a layer at or near its critical angle (the
//! scalar solver's field form), or a Fresnel coefficient that is not finite.

use num_complex::Complex64 as C64;

use super::arith::{phase_factor, Cv, Lanes};
use super::sink::Power;

/// Most media the interfaces are laid out for on the stack; deeper stacks
/// take the general kernel (they are dominated by their layers anyway).
pub(super) const MAX_MEDIA: usize = 66;

/// Most media of the small layout, which most stacks fit: the interfaces
/// are built afresh for every spectrum, and clearing and moving room for
/// [`MAX_MEDIA`] cost a few percent of a short stack's spectrum.
pub(super) const FEW_MEDIA: usize = 8;

/// One interface's coefficients, from the medium above into the one below.
#[derive(Clone, Copy, Debug, Default)]
struct Interface {
    rs: C64,
    rp: C64,
    /// 2q and d of the layer below the interface (q its normal index, d its
    /// thickness): the round trip's phase is (k0 d)(2q), which has the bits
    /// of twice the scalar solver's (k0 d) q, since doubling is exact.
    /// Unused for the bottom interface.
    two_q: C64,
    d: f64,
}

/// A non-dispersive stack at one angle: what stays the same at every
/// wavelength.
/// `M` is the room for media: [`FEW_MEDIA`] or [`MAX_MEDIA`].
pub(super) struct Interfaces<const M: usize> {
    /// Top-down; interface i lies between medium i and medium i + 1. The
    /// array has room for M media (one slot more than their interfaces).
    at: [Interface; M],
    count: usize,
    /// |Π t_s|² Re(q_sub) / q0: the s transmittance's constant factor.
    ts_scale: f64,
    /// |Π t_p|² Re(q̄_sub n_sub²) / (|n_sub|² q0), likewise for p.
    tp_scale: f64,
}

impl<const M: usize> Interfaces<M> {
    /// The interfaces of the stack with `indices` (N + 2: ambient, layers,
    /// substrate) and `thicknesses_nm` at incidence cos θ0, with the scalar
    /// solver's normal indices and branch; `None` where the general kernel
    /// must run instead.
    pub(super) fn new(indices: &[C64], thicknesses_nm: &[f64], cos_theta0: f64) -> Option<Self> {
        let media = indices.len();
        // Grazing (and NaN) incidence has its own closed form in the scalar solver.
        let grazing = cos_theta0.is_nan() || cos_theta0 <= 0.0;
        if grazing || media > M || media != thicknesses_nm.len() + 2 {
            return None;
        }
        let cos = cos_theta0.min(1.0);
        let n0 = indices[0].re;
        let beta_sq = n0 * n0 * ((1.0 - cos) * (1.0 + cos));
        let q0 = n0 * cos;
        let medium = |j: usize| -> (C64, C64, C64) {
            if j == 0 {
                let n = C64::new(n0, 0.0);
                (n, n * n, C64::new(q0, 0.0))
            } else {
                let n = indices[j];
                let nsq = n * n;
                (n, nsq, crate::optics::solver::normal_index(n, beta_sq))
            }
        };
        let mut at = [Interface::default(); M];
        let (mut ts_amp, mut tp_amp) = (C64::new(1.0, 0.0), C64::new(1.0, 0.0));
        let mut above = medium(0);
        for (i, slot) in at.iter_mut().enumerate().take(media - 1) {
            let below = medium(i + 1);
            let ((n_a, nsq_a, q_a), (n_b, nsq_b, q_b)) = (above, below);
            if i + 1 < media - 1 {
                // The scalar solver's near-critical test on the layer below.
                let q2 = q_b.norm_sqr();
                if q2 * q2 < 1e-8 * nsq_b.norm_sqr() {
                    return None;
                }
                slot.two_q = q_b * 2.0;
                slot.d = thicknesses_nm[i];
            }
            let s_den = (q_a + q_b).inv();
            slot.rs = (q_a - q_b) * s_den;
            ts_amp *= 2.0 * q_a * s_den;
            let (a, b) = (nsq_b * q_a, nsq_a * q_b);
            let p_den = (a + b).inv();
            slot.rp = (a - b) * p_den;
            tp_amp *= 2.0 * n_a * n_b * q_a * p_den;
            above = below;
        }
        let (n_sub, _, q_sub) = above;
        let p_flux = (q_sub.conj() * n_sub * n_sub).re / n_sub.norm_sqr();
        let out = Interfaces {
            at,
            count: media - 1,
            ts_scale: ts_amp.norm_sqr() * q_sub.re / q0,
            tp_scale: tp_amp.norm_sqr() * p_flux / q0,
        };
        let finite = |z: C64| z.re.is_finite() && z.im.is_finite();
        let all_finite = out.at[..out.count]
            .iter()
            .all(|f| finite(f.rs) && finite(f.rp) && finite(f.two_q) && f.d.is_finite())
            && out.ts_scale.is_finite()
            && out.tp_scale.is_finite();
        all_finite.then_some(out)
    }
}

/// One step of the recursion up through an interface, for one polarization:
/// Γ ← (r + g)/(1 + r g) with g = Γρ; returns 1/|1 + r g|², the factor
/// |t|² picks up. The denominator is formed as 1 + (rΓ)ρ: rΓ does not wait
/// for ρ, so once ρ is known g and the denominator are one product each,
/// side by side (and rΓ is a constant on the bottom layer).
#[inline(always)]
fn step<V: Lanes>(gamma: &mut Cv<V>, r: Cv<V>, rho: Cv<V>) -> V {
    let g = gamma.mul(rho);
    let den = r.mul(*gamma).mul(rho).one_plus();
    let inv_norm = V::splat(1.0).div(den.norm_sqr_fused());
    let inv = Cv {
        re: den.re.mul(inv_norm),
        im: den.im.neg().mul(inv_norm),
    };
    *gamma = r.add(g).mul(inv);
    inv_norm
}

/// [`step`] through the top interface, where only |Γ|² is wanted: it is
/// |r + g|² / |1 + r g|², without forming Γ. Returns it and 1/|1 + r g|².
#[inline(always)]
fn top_step<V: Lanes>(gamma: Cv<V>, r: Cv<V>, rho: Cv<V>) -> (V, V) {
    top_step_with(gamma, r, r.mul(gamma), rho)
}

/// [`top_step`] with rΓ given (a constant when Γ is the bottom interface's).
#[inline(always)]
fn top_step_with<V: Lanes>(gamma: Cv<V>, r: Cv<V>, r_gamma: Cv<V>, rho: Cv<V>) -> (V, V) {
    let g = gamma.mul(rho);
    let den = r_gamma.mul(rho).one_plus();
    let inv_norm = V::splat(1.0).div(den.norm_sqr_fused());
    (r.add(g).norm_sqr_fused().mul(inv_norm), inv_norm)
}

/// R and T of one wavelength per lane (2π/λ in `k0`) of the stack `f`
/// describes.
#[inline(always)]
pub(super) fn solve_lanes<V: Lanes, const M: usize>(f: &Interfaces<M>, k0: V) -> Power<V> {
    // `Cv::splat`, not a closure: a closure is compiled without the kernel
    // copy's target features, and the intrinsics in it would not be inlined.
    let splat = Cv::<V>::splat;
    let bottom = &f.at[f.count - 1];
    let (mut gamma_s, mut gamma_p) = (splat(bottom.rs), splat(bottom.rp));
    // With no layer, R is the single interface's.
    let (mut rs, mut rp) = (gamma_s.norm_sqr(), gamma_p.norm_sqr());
    // |t|² without its constant factor: Π |e^{iφ}|² / |1 + rΓρ|².
    let (mut ts_norm, mut tp_norm) = (V::splat(1.0), V::splat(1.0));
    for i in (0..f.count - 1).rev() {
        let face = &f.at[i];
        // The round trip e^{2iφ} straight from 2φ, and |e^{iφ}|² as its
        // modulus: one complex product fewer on the chain of dependent
        // operations than squaring e^{iφ}.
        let (rho, decay) = phase_factor(splat(face.two_q).scale(k0.mul(V::splat(face.d))));
        let (r_s, r_p) = (splat(face.rs), splat(face.rp));
        let (inv_s, inv_p) = if i > 0 {
            (step(&mut gamma_s, r_s, rho), step(&mut gamma_p, r_p, rho))
        } else {
            let (top_s, inv_s) = top_step(gamma_s, r_s, rho);
            let (top_p, inv_p) = top_step(gamma_p, r_p, rho);
            (rs, rp) = (top_s, top_p);
            (inv_s, inv_p)
        };
        ts_norm = ts_norm.mul(decay).mul(inv_s);
        tp_norm = tp_norm.mul(decay).mul(inv_p);
    }
    Power {
        rs,
        rp,
        ts: ts_norm.mul(V::splat(f.ts_scale)),
        tp: tp_norm.mul(V::splat(f.tp_scale)),
    }
}

/// A stack of one layer (the common soap film or single coating) in lanes,
/// its constants splat once per spectrum instead of once per vector: what
/// [`solve_lanes`] computes for it, with the same operations, but for rΓ,
/// which does not depend on the wavelength and is made here.
pub(super) struct OneLayer<V> {
    two_q: Cv<V>,
    d: V,
    /// The bottom interface's coefficients (Γ below the layer), s and p.
    gamma: [Cv<V>; 2],
    /// The top interface's.
    r: [Cv<V>; 2],
    /// r Γ for each polarization.
    r_gamma: [Cv<V>; 2],
    t_scale: [V; 2],
}

impl<V: Lanes> OneLayer<V> {
    /// `None` unless `f` has exactly one layer.
    #[inline(always)]
    pub(super) fn new<const M: usize>(f: &Interfaces<M>) -> Option<Self> {
        if f.count != 2 {
            return None;
        }
        let splat = Cv::<V>::splat;
        let (top, bottom) = (&f.at[0], &f.at[1]);
        let gamma = [splat(bottom.rs), splat(bottom.rp)];
        let r = [splat(top.rs), splat(top.rp)];
        Some(OneLayer {
            two_q: splat(top.two_q),
            d: V::splat(top.d),
            gamma,
            r,
            r_gamma: [r[0].mul(gamma[0]), r[1].mul(gamma[1])],
            t_scale: [V::splat(f.ts_scale), V::splat(f.tp_scale)],
        })
    }

    /// [`solve_lanes`] for this stack: the bits it gives.
    #[inline(always)]
    pub(super) fn solve(&self, k0: V) -> Power<V> {
        let (rho, decay) = phase_factor(self.two_q.scale(k0.mul(self.d)));
        let (rs, inv_s) = top_step_with(self.gamma[0], self.r[0], self.r_gamma[0], rho);
        let (rp, inv_p) = top_step_with(self.gamma[1], self.r[1], self.r_gamma[1], rho);
        // solve_lanes starts |t|² at 1 and multiplies by the decay: 1 × x
        // is x exactly.
        Power {
            rs,
            rp,
            ts: decay.mul(inv_s).mul(self.t_scale[0]),
            tp: decay.mul(inv_p).mul(self.t_scale[1]),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::arith::Portable;
    use super::*;
    use rand::{Rng, SeedableRng};

    /// The one-layer path gives the general constant path's bits, on
    /// lossless, absorbing, gain and metal-backed layers at random angles.
    #[test]
    fn one_layer_gives_the_bits_of_solve_lanes() {
        let mut rng = rand_pcg::Pcg64::seed_from_u64(5);
        let mut checked = 0;
        for _ in 0..2000 {
            let n = |rng: &mut rand_pcg::Pcg64| {
                C64::new(rng.random_range(1.0..3.0), rng.random_range(-0.05..0.5))
            };
            let ambient = C64::new(rng.random_range(1.0..1.6), 0.0);
            let substrate = if rng.random_bool(0.2) {
                C64::new(0.2, 3.4)
            } else {
                n(&mut rng)
            };
            let indices = [ambient, n(&mut rng), substrate];
            let d = [rng.random_range(0.0..2000.0)];
            let cos = rng.random_range(0.01..1.0);
            let Some(f) = Interfaces::<FEW_MEDIA>::new(&indices, &d, cos) else {
                continue;
            };
            let one = OneLayer::<Portable>::new(&f).unwrap();
            let k0 = Portable::from_array(std::array::from_fn(|l| {
                std::f64::consts::TAU / (360.0 + 61.0 * l as f64)
            }));
            let (a, b) = (one.solve(k0), solve_lanes::<Portable, FEW_MEDIA>(&f, k0));
            for (x, y) in [(a.rs, b.rs), (a.rp, b.rp), (a.ts, b.ts), (a.tp, b.tp)] {
                let bits = |v: Portable| v.to_array().map(f64::to_bits);
                assert_eq!(bits(x), bits(y), "{indices:?} {d:?} cos {cos}");
            }
            checked += 1;
        }
        assert!(checked > 1500, "{checked}");
    }
}
