//! One (θ_v, roughness)'s weighting of the film's colour over μ = v·h.
//!
//! With h at angle β = arccos μ from v and azimuth ψ about v (ψ = 0 towards
//! the normal), dω_h = dμ dψ and dω_l = 4 μ dω_h, so
//!
//! ```text
//! ∫ D G2 F(v·h) / (4 cos θ_v) dl = ∫₀¹ F(μ) K(μ) dμ,
//! K(μ) = (2μ / cos θ_v) ∫₀^ψmax D(n·h) G2(v, l) dψ,
//! ```
//!
//! with n·h = cos θ_v cos β + sin θ_v sin β cos ψ and
//! n·l = cos θ_v cos 2β + sin θ_v sin 2β cos ψ; ψmax is where l reaches the
//! horizon (G2 = 0 beyond). K vanishes for β ≥ π/4 + θ_v/2 and its
//! azimuth range is whole for β ≤ π/4 − θ_v/2; both are kinks of K. D
//! makes K peak at β = θ_v (h = n) with a width of about α.
//!
//! The inner integral substitutes ψ = w tan τ, w the width of D's peak
//! along ψ, which turns the peak into a smooth bump; the outer one runs
//! over the μ grid's intervals in their own parameter s (so the cubic
//! interpolant of F is a polynomial on each), cut at K's kinks and at
//! θ_v ± α 2^k about the peak, each piece by Gauss–Legendre.

use std::f64::consts::{FRAC_PI_4, PI};

use super::ggx;
use super::mu_grid::{MuGrid, Segment};
use super::quadrature::{Quadrature, Rule};

/// cos θ_v below this is taken as this: the lobe's formulas divide by
/// cos θ_v, and F_eff is continuous at grazing view.
pub const MIN_COS_VIEW: f64 = 1e-6;

/// The weights that turn a film's smooth colour at the nodes of a
/// [`MuGrid`] into its F_eff for one view angle and roughness, and the
/// directional albedo of the white lobe (∫ D G2 / (4 cos θ_v) dl).
#[derive(Clone, Debug)]
pub struct Kernel {
    /// Index of the first node with a weight.
    first: usize,
    /// Weights of nodes `first..`, summing to 1.
    weights: Vec<f64>,
    albedo: f64,
}

/// The Gauss–Legendre rules of one [`Quadrature`], made once and shared by
/// its kernels.
pub(crate) struct Rules {
    pub(super) outer: Rule,
    pub(super) inner: Rule,
}

impl Rules {
    pub(crate) fn new(q: &Quadrature) -> Rules {
        Rules {
            outer: Rule::gauss_legendre(q.outer),
            inner: Rule::gauss_legendre(q.inner),
        }
    }
}

impl Kernel {
    /// The kernel of view cos θ_v = `cos_view` ∈ [0, 1] and `roughness`
    /// ∈ [0, 1] on `grid`. At roughness 0 it is the interpolation of the
    /// grid at μ = cos θ_v (a mirror).
    pub fn new(grid: &MuGrid, cos_view: f64, roughness: f64, quadrature: &Quadrature) -> Kernel {
        Kernel::with_rules(grid, cos_view, roughness, &Rules::new(quadrature))
    }

    pub(crate) fn with_rules(
        grid: &MuGrid,
        cos_view: f64,
        roughness: f64,
        rules: &Rules,
    ) -> Kernel {
        let cv = cos_view.clamp(MIN_COS_VIEW, 1.0);
        let alpha = ggx::alpha(roughness);
        if alpha == 0.0 {
            return Kernel::mirror(grid, cv);
        }
        let lobe = Lobe::new(cv, alpha);
        let mut raw = vec![0.0; grid.nodes().len()];
        for_each_panel(
            grid,
            lobe.beta_end.cos(),
            &lobe.cuts(),
            &mut |seg, k, s, _| {
                let density = |mu, sin_b, beta| lobe.density(mu, sin_b, beta, &rules.inner);
                self::panel(&lobe, &density, &rules.outer, seg, k, s, &mut raw);
            },
        );
        Kernel::from_raw(raw)
    }

    /// The mirror's kernel: the interpolation of the grid at μ = `cv`, of
    /// albedo 1.
    pub(crate) fn mirror(grid: &MuGrid, cv: f64) -> Kernel {
        let (first, w) = grid.interpolation(cv);
        Kernel {
            first,
            weights: w.to_vec(),
            albedo: 1.0,
        }
    }

    /// Normalizes accumulated weights, keeping the span that has any (none
    /// when the lobe has no albedo at all: then F_eff is 0).
    pub(crate) fn from_raw(raw: Vec<f64>) -> Kernel {
        let albedo: f64 = raw.iter().sum();
        if albedo == 0.0 {
            return Kernel {
                first: 0,
                weights: Vec::new(),
                albedo,
            };
        }
        let first = raw.iter().position(|&w| w != 0.0).unwrap_or(0);
        let last = raw.iter().rposition(|&w| w != 0.0).unwrap_or(0);
        let weights = raw[first..=last].iter().map(|w| w / albedo).collect();
        Kernel {
            first,
            weights,
            albedo,
        }
    }

    /// The directional albedo of a white GGX lobe (single scattering) at
    /// this view angle and roughness: ∫ D G2 / (4 cos θ_v) dl, 1 for a
    /// mirror.
    pub fn albedo(&self) -> f64 {
        self.albedo
    }

    /// The index of the first grid node with a weight, and the weights
    /// from there on (they sum to 1).
    pub fn weights(&self) -> (usize, &[f64]) {
        (self.first, &self.weights)
    }

    /// F_eff of colours given at every node of the grid.
    ///
    /// # Panics
    /// If `values` is shorter than the grid the kernel was made on.
    pub fn apply(&self, values: &[[f64; 3]]) -> [f64; 3] {
        let mut sum = [0.0; 3];
        for (w, v) in self.weights.iter().zip(&values[self.first..]) {
            for c in 0..3 {
                sum[c] += w * v[c];
            }
        }
        sum
    }
}

/// What [`for_each_panel`] calls per panel.
pub(crate) type PanelVisit<'a> = dyn FnMut(&Segment, usize, (f64, f64), (f64, f64)) + 'a;

/// Calls `visit(segment, interval, (s_lo, s_hi), (μ_lo, μ_hi))` for every
/// panel of the outer integral over μ ∈ (`mu_end`, 1]: the grid's
/// intervals, cut at `cuts` (ascending μ) and at `mu_end`. The μ ends are
/// the exact cut, node or `mu_end` values, so a caller can tell a panel
/// that starts or ends at one of its own kinks.
pub(crate) fn for_each_panel(grid: &MuGrid, mu_end: f64, cuts: &[f64], visit: &mut PanelVisit) {
    for seg in grid.segments() {
        for k in 0..seg.intervals {
            let (m0, m1) = seg.interval_mu(k);
            if m1 <= mu_end {
                continue;
            }
            let n = seg.intervals as f64;
            let (mut s_lo, mut mu_lo) = if m0 < mu_end {
                (seg.s(mu_end), mu_end)
            } else {
                (k as f64 / n, m0)
            };
            let inside =
                cuts.partition_point(|&c| c <= m0.max(mu_end))..cuts.partition_point(|&c| c < m1);
            let ends = cuts[inside]
                .iter()
                .map(|&c| (seg.s(c), c))
                .chain(std::iter::once(((k + 1) as f64 / n, m1)));
            for (s_hi, mu_hi) in ends {
                if s_hi > s_lo {
                    visit(seg, k, (s_lo, s_hi), (mu_lo, mu_hi));
                }
                s_lo = s_hi;
                mu_lo = mu_hi;
            }
        }
    }
}

/// One panel of the outer integral, the parameter range `s` of interval `k`
/// of `seg`: adds w K(μ) dμ (K from `density(μ, sin β, β)`) times the interpolation weights of each point
/// to `raw`. Gauss–Legendre in τ = atan((β − θ_v)/α), in which K's peak at
/// β = θ_v is a smooth bump; beside a kink, in s, in which the
/// interpolated F is a polynomial while it has a square root in τ.
pub(super) fn panel(
    lobe: &Lobe,
    density: &dyn Fn(f64, f64, f64) -> f64,
    rule: &Rule,
    seg: &Segment,
    k: usize,
    (s_lo, s_hi): (f64, f64),
    raw: &mut [f64],
) {
    let mut add = |s: f64, weight: f64| {
        let (first, cardinal) = seg.stencil(k, s);
        for (i, l) in cardinal.iter().enumerate() {
            raw[first + i] += weight * l;
        }
    };
    if (s_lo == 0.0 && seg.kink_at_start()) || (s_hi == 1.0 && seg.kink_at_end()) {
        let span = s_hi - s_lo;
        for (x, w) in rule.nodes.iter().zip(&rule.weights) {
            let s = s_lo + span * x;
            let mu = seg.mu(s);
            let sin_b = ((1.0 - mu) * (1.0 + mu)).max(0.0).sqrt();
            add(
                s,
                w * span * seg.dmu_ds(s) * density(mu, sin_b, sin_b.atan2(mu)),
            );
        }
        return;
    }
    let tau = |s: f64| ((seg.mu(s).clamp(-1.0, 1.0).acos() - lobe.theta_v) / lobe.alpha).atan();
    // β falls as s rises.
    let (tau_a, tau_b) = (tau(s_hi), tau(s_lo));
    let span = tau_b - tau_a;
    for (x, w) in rule.nodes.iter().zip(&rule.weights) {
        let t = (tau_a + span * x).tan();
        let beta = lobe.theta_v + lobe.alpha * t;
        let (sin_b, mu) = beta.sin_cos();
        let dbeta = lobe.alpha * (1.0 + t * t);
        add(
            seg.s(mu),
            w * span * dbeta * sin_b * density(mu, sin_b, beta),
        );
    }
}

/// A GGX lobe seen at one view angle, with what its density K(μ) needs.
pub(super) struct Lobe {
    pub(super) cv: f64,
    pub(super) sv: f64,
    pub(super) theta_v: f64,
    pub(super) alpha: f64,
    pub(super) alpha2: f64,
    /// Λ(v) cos θ_v.
    pub(super) lambda_cos_v: f64,
    /// Past this β = arccos μ, l is below the horizon for every azimuth.
    beta_end: f64,
    /// How far from the horizon, in cos θ_l, G2 has its nearest
    /// singularity: G2 changes on this scale as l sets (about cos θ_v at
    /// grazing view, α otherwise).
    pub(super) horizon_scale: f64,
}

impl Lobe {
    pub(super) fn new(cv: f64, alpha: f64) -> Lobe {
        let alpha2 = alpha * alpha;
        let theta_v = cv.acos();
        let lambda_cos_v = ggx::lambda_cos(cv, alpha2);
        Lobe {
            cv,
            sv: (1.0 - cv * cv).max(0.0).sqrt(),
            theta_v,
            alpha,
            alpha2,
            lambda_cos_v,
            beta_end: FRAC_PI_4 + 0.5 * theta_v,
            // G2's denominator vanishes near cos θ_l = −cv α / (cv + 2 Λ_v cv),
            // and √(cos² θ_l + α² sin² θ_l) branches at about ±iα.
            horizon_scale: (cv * alpha / (cv + 2.0 * lambda_cos_v)).min(alpha),
        }
    }

    /// μ where the outer integral is cut, ascending: K's peak and kinks,
    /// and a geometric sequence about the peak.
    fn cuts(&self) -> Vec<f64> {
        let mut betas = vec![self.theta_v, FRAC_PI_4 - 0.5 * self.theta_v];
        let mut offset = self.alpha / 8.0;
        while offset < PI {
            betas.push(self.theta_v + offset);
            betas.push(self.theta_v - offset);
            offset *= 2.0;
        }
        let mut cuts: Vec<f64> = betas
            .into_iter()
            .filter(|&b| b > 0.0 && b < self.beta_end)
            .map(f64::cos)
            .collect();
        cuts.sort_by(f64::total_cmp);
        cuts.dedup();
        cuts
    }

    /// K(μ) (see the module's doc) at μ = cos β, given sin β and β.
    fn density(&self, mu: f64, sin_b: f64, beta: f64, inner: &Rule) -> f64 {
        let (cv, sv, a2) = (self.cv, self.sv, self.alpha2);
        let scale = 2.0 * mu / cv;
        // 1 − n·h at ψ = 0, i.e. 1 − cos(θ_v − β), without cancellation.
        let half = 0.5 * (self.theta_v - beta);
        let gap = 2.0 * half.sin() * half.sin();
        let b = sin_b * sv;
        if b < 1e-300 {
            // h on a cone about the normal (or v along it): no azimuth
            // dependence.
            let c = 1.0 - gap;
            let cos_l = 2.0 * mu * c - cv;
            let g = ggx::g2(cv, self.lambda_cos_v, cos_l, a2);
            return scale * PI * ggx::ndf(c, gap * (1.0 + c), a2) * g;
        }
        // n·l = A + B cos ψ; n·l > 0 ⟺ cos ψ > κ.
        let (big_a, big_b) = (cv * (1.0 - 2.0 * sin_b * sin_b), sv * 2.0 * sin_b * mu);
        let kappa = -big_a / big_b;
        if kappa >= 1.0 {
            return 0.0;
        }
        let psi_max = if kappa <= -1.0 { PI } else { kappa.acos() };
        // D's denominator near ψ = 0 is about α² + 2 gap + b ψ².
        let width = ((a2 + 2.0 * gap) / b).sqrt();
        let tau_max = (psi_max / width).atan();
        let integrand = |x: f64| {
            let t = x.tan();
            let psi = width * t;
            let h = (0.5 * psi).sin();
            let versine = 2.0 * h * h;
            let one_minus_c = gap + b * versine;
            let c = 1.0 - one_minus_c;
            let cos_l = big_a + big_b * (1.0 - versine);
            let g = ggx::g2(cv, self.lambda_cos_v, cos_l, a2);
            width * (1.0 + t * t) * ggx::ndf(c, one_minus_c * (1.0 + c), a2) * g
        };
        let sum = match self.horizon_split(psi_max, big_a, big_b) {
            // G2's layer at the horizon gets a panel of its own.
            Some(psi_split) => {
                let tau_split = (psi_split / width).atan();
                integrate(inner, (0.0, tau_split), &integrand)
                    + integrate(inner, (tau_split, tau_max), &integrand)
            }
            None => integrate(inner, (0.0, tau_max), &integrand),
        };
        scale * sum
    }

    /// Where to cut the azimuth integral so that G2's layer near the
    /// horizon (see [`Lobe::horizon_scale`]) has a panel of its own: four
    /// times its width in ψ before ψmax, if that is well inside the range.
    fn horizon_split(&self, psi_max: f64, big_a: f64, big_b: f64) -> Option<f64> {
        let sigma = self.horizon_scale;
        let reach = if psi_max < PI {
            // n·l falls through 0 at ψmax at the rate B sin ψmax.
            sigma / (big_b * psi_max.sin())
        } else {
            // n·l bottoms out at A − B ≥ 0 at ψ = π, quadratically.
            (2.0 * (sigma + big_a - big_b) / big_b).sqrt()
        };
        let split = psi_max - 4.0 * reach;
        (split > 0.5 * psi_max).then_some(split)
    }
}

/// ∫ f over `range` by `rule`.
#[inline]
pub(super) fn integrate(rule: &Rule, (lo, hi): (f64, f64), f: &dyn Fn(f64) -> f64) -> f64 {
    let span = hi - lo;
    span * rule
        .nodes
        .iter()
        .zip(&rule.weights)
        .map(|(x, w)| w * f(lo + span * x))
        .sum::<f64>()
}
