//! One (θ_v, roughness, η)'s weighting of the film's transmittance over
//! μ = v·h: the refraction lobe beside the reflection one of
//! [`super::kernel`].
//!
//! A microfacet h seen at μ = v·h refracts (Snell about h, relative index
//! η = n_o / n_v) into l_t = −v/η + m h, m = μ/η − cos θ_t, cos θ_t =
//! √(η² − 1 + μ²)/η; past its critical angle (μ < μ_c = √(1 − η²), η < 1)
//! there is no l_t. In flux form (docs/rough.md), with h at angle β from v
//! and azimuth ψ about v as in the reflection kernel,
//!
//! ```text
//! A_T = ∫ D_v(h) [n·h > 0] [n·l_t < 0] G2(v, l_t) / G1(v) dh = ∫ K_T(μ) dμ,
//! K_T(μ) = (2μ / cos θ_v) ∫₀^π D(n·h) G2(v, l_t) [n·h > 0] [n·l_t < 0] dψ,
//! ```
//!
//! Λ(l_t) taken at |n·l_t|. With n·h = c, n·l_t = −cos θ_v/η + m c, so in
//! the versine ν = 1 − cos ψ both conditions are bounds: n·h > 0 for ν
//! below (1 − gap)/b (gap = 1 − cos(θ_v − β), b = sin θ_v sin β), and,
//! when m > 0 (η < 1), n·l_t < 0 for ν above a bound; when m ≤ 0 it holds
//! wherever n·h > 0.
//!
//! K_T's kinks in μ, where the outer integral is cut: its peak at β = θ_v;
//! μ = sin θ_v, where microfacets facing away (n·h ≤ 0, where D jumps from
//! α²/π to 0) enter the azimuth range at ψ = π, so that K_T falls like
//! √(sin θ_v − μ) below it; for η < 1 the critical μ_c, where K_T jumps
//! from 0 and grows like √(μ − μ_c), and tan β = cos θ_v / (1/η − sin θ_v),
//! where l_t at ψ = 0 reaches the horizon. The two square-root ends get a
//! panel in u, s = s_kink ± Δs u², on which K_T is smooth.

use std::f64::consts::PI;

use super::ggx;
use super::kernel::{for_each_panel, integrate, panel, Kernel, Lobe, Rules, MIN_COS_VIEW};
use super::mu_grid::{MuGrid, Segment};
use super::quadrature::{Quadrature, Rule};

/// Panel ends closer than this in μ to a square-root kink are at it.
const AT_KINK: f64 = 1e-12;

impl Kernel {
    /// The transmission kernel of view cos θ_v = `cos_view` ∈ [0, 1],
    /// `roughness` ∈ [0, 1] and relative index `eta` = n_o / n_v > 0 (the
    /// medium the light leaves into over the one it is seen from) on
    /// `grid`: its weights give T_eff from the film's transmittance at the
    /// grid's nodes, and its albedo is A_T, the white refraction lobe's.
    /// At roughness 0 it is the interpolation at μ = cos θ_v (albedo 1),
    /// or nothing (albedo 0) past the critical angle.
    pub fn transmission(
        grid: &MuGrid,
        cos_view: f64,
        roughness: f64,
        eta: f64,
        quadrature: &Quadrature,
    ) -> Kernel {
        Kernel::transmission_with_rules(grid, cos_view, roughness, eta, &Rules::new(quadrature))
    }

    pub(crate) fn transmission_with_rules(
        grid: &MuGrid,
        cos_view: f64,
        roughness: f64,
        eta: f64,
        rules: &Rules,
    ) -> Kernel {
        let cv = cos_view.clamp(MIN_COS_VIEW, 1.0);
        let alpha = ggx::alpha(roughness);
        let refraction = Refraction::new(Lobe::new(cv, alpha), eta);
        if alpha == 0.0 {
            return if cv > refraction.mu_critical {
                Kernel::mirror(grid, cv)
            } else {
                Kernel::from_raw(vec![0.0; grid.nodes().len()])
            };
        }
        let mut raw = vec![0.0; grid.nodes().len()];
        for_each_panel(
            grid,
            refraction.mu_critical,
            &refraction.cuts(),
            &mut |seg, k, s, mu| refraction.panel(rules, seg, k, s, mu, &mut raw),
        );
        Kernel::from_raw(raw)
    }
}

/// A GGX lobe seen at one view angle, refracting into relative index η.
struct Refraction {
    lobe: Lobe,
    eta: f64,
    /// Below this μ microfacets reflect totally (0 for η ≥ 1).
    mu_critical: f64,
    /// μ = sin θ_v, below which microfacets facing away cut the azimuth.
    mu_facing: f64,
}

impl Refraction {
    fn new(lobe: Lobe, eta: f64) -> Refraction {
        let mu_critical = if eta < 1.0 {
            ((1.0 - eta) * (1.0 + eta)).sqrt()
        } else {
            0.0
        };
        Refraction {
            mu_facing: lobe.sv,
            lobe,
            eta,
            mu_critical,
        }
    }

    /// μ where the outer integral is cut, ascending, inside (μ_c, 1): K_T's
    /// peak and kinks, and a geometric sequence about the peak.
    fn cuts(&self) -> Vec<f64> {
        let l = &self.lobe;
        let mut cuts = vec![l.cv, self.mu_facing];
        if self.eta < 1.0 {
            // tan β = cos θ_v / (1/η − sin θ_v): l_t at ψ = 0 on the horizon.
            let (x, y) = (1.0 / self.eta - l.sv, l.cv);
            cuts.push(x / x.hypot(y));
        }
        let mut offset = l.alpha / 8.0;
        while offset < PI {
            for beta in [l.theta_v + offset, l.theta_v - offset] {
                if beta > 0.0 && beta < 0.5 * PI {
                    cuts.push(beta.cos());
                }
            }
            offset *= 2.0;
        }
        cuts.retain(|&c| c > self.mu_critical && c < 1.0);
        cuts.sort_by(f64::total_cmp);
        cuts.dedup();
        cuts
    }

    /// One panel of the outer integral (see [`panel`]), in u at K_T's
    /// square-root kinks.
    fn panel(
        &self,
        rules: &Rules,
        seg: &Segment,
        k: usize,
        (s_lo, s_hi): (f64, f64),
        (mu_lo, mu_hi): (f64, f64),
        raw: &mut [f64],
    ) {
        let density = |mu, sin_b, beta| self.density(mu, sin_b, beta, &rules.inner);
        let from = if self.mu_critical > 0.0 && (mu_lo - self.mu_critical).abs() <= AT_KINK {
            Some((s_lo, s_hi - s_lo))
        } else if (mu_hi - self.mu_facing).abs() <= AT_KINK {
            Some((s_hi, s_lo - s_hi))
        } else {
            None
        };
        let Some((s_kink, ds)) = from else {
            panel(
                &self.lobe,
                &density,
                &rules.outer,
                seg,
                k,
                (s_lo, s_hi),
                raw,
            );
            return;
        };
        let rule: &Rule = &rules.outer;
        for (x, w) in rule.nodes.iter().zip(&rule.weights) {
            let s = s_kink + ds * x * x;
            let mu = seg.mu(s);
            let sin_b = ((1.0 - mu) * (1.0 + mu)).max(0.0).sqrt();
            // |ds/du| = 2 |Δs| u.
            let weight =
                w * 2.0 * ds.abs() * x * seg.dmu_ds(s) * density(mu, sin_b, sin_b.atan2(mu));
            let (first, cardinal) = seg.stencil(k, s);
            for (i, l) in cardinal.iter().enumerate() {
                raw[first + i] += weight * l;
            }
        }
    }

    /// K_T(μ) (see the module's doc) at μ = cos β, given sin β and β.
    fn density(&self, mu: f64, sin_b: f64, beta: f64, inner: &Rule) -> f64 {
        let l = &self.lobe;
        let (cv, a2, eta) = (l.cv, l.alpha2, self.eta);
        let cos_t2 = (eta - 1.0) * (eta + 1.0) + mu * mu;
        if cos_t2 <= 0.0 {
            return 0.0;
        }
        let m = (mu - cos_t2.sqrt()) / eta;
        // n·l_t of a microfacet at n·h = c.
        let exit = |c: f64| m * c - cv / eta;
        let g2 = |c: f64| ggx::g2(cv, l.lambda_cos_v, -exit(c), a2);
        let scale = 2.0 * mu / cv;
        let half = 0.5 * (l.theta_v - beta);
        let gap = 2.0 * half.sin() * half.sin();
        let b = sin_b * l.sv;
        if b < 1e-300 {
            let c = 1.0 - gap;
            if c <= 0.0 || exit(c) >= 0.0 {
                return 0.0;
            }
            return scale * PI * ggx::ndf(c, gap * (1.0 + c), a2) * g2(c);
        }
        let nu_facing = (1.0 - gap) / b;
        // n·l_t = exit(1 − gap) − m b ν.
        let nu_exit = if m > 0.0 {
            exit(1.0 - gap) / (m * b)
        } else {
            f64::NEG_INFINITY
        };
        let (nu_lo, nu_hi) = (nu_exit.max(0.0), nu_facing.min(2.0));
        if nu_lo >= nu_hi {
            return 0.0;
        }
        let psi = |nu: f64| 2.0 * (0.5 * nu).sqrt().min(1.0).asin();
        let (psi_lo, psi_hi) = (psi(nu_lo), psi(nu_hi));
        let width = ((a2 + 2.0 * gap) / b).sqrt();
        let integrand = |x: f64| {
            let t = x.tan();
            let h = (0.5 * width * t).sin();
            let one_minus_c = gap + b * 2.0 * h * h;
            let c = 1.0 - one_minus_c;
            width * (1.0 + t * t) * ggx::ndf(c, one_minus_c * (1.0 + c), a2) * g2(c)
        };
        let tau = |psi: f64| (psi / width).atan();
        let (tau_lo, tau_hi) = (tau(psi_lo), tau(psi_hi));
        // G2's layer where l_t sets (η < 1) gets a panel of its own: up to
        // where n·l_t is four layer widths below the horizon.
        let split = (m > 0.0)
            .then(|| (exit(1.0 - gap) + 4.0 * l.horizon_scale) / (m * b))
            .filter(|&nu| nu > nu_lo && nu < nu_hi)
            .map(psi)
            .filter(|&p| p < 0.5 * (psi_lo + psi_hi));
        let sum = match split {
            Some(p) => {
                integrate(inner, (tau_lo, tau(p)), &integrand)
                    + integrate(inner, (tau(p), tau_hi), &integrand)
            }
            None => integrate(inner, (tau_lo, tau_hi), &integrand),
        };
        scale * sum
    }
}
