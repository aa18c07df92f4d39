//! Multiple scattering: energy compensation of the single-scattering GGX
//! lobe (docs/rough.md, "Multiple scattering").
//!
//! A single-scattering microfacet lobe loses the light that meets a second
//! microfacet before it leaves: at roughness 1 a white reflector keeps
//! about 0.6 of the light at grazing view, and a lossless rough interface
//! (reflection plus transmission) less than 0.9. The compensation here
//! follows Turquin ("Practical multiple scattering compensation for
//! microfacet models", 2019): the lost energy comes back as a scaling of the
//! single-scattering lobe, derived from the directional albedo of a white
//! lobe tabulated by deterministic quadrature (as Kulla and Conty,
//! "Revisiting physically based shading at Imageworks", 2017, tabulate it).
//!
//! The film version, with S = A_R F_eff + A_T T_eff the film's
//! single-scattering energy at the view and ρ the share of the light a
//! microfacet keeps (reflects or transmits rather than absorbs), scales both
//! F_eff and T_eff by
//!
//! ```text
//! k = 1 + ρ (1 − E_w) / E_w,   E_w = S / ρ,
//! ```
//!
//! E_w being the escape probability of a single scattering with the film's
//! own split between reflection and transmission but no absorption. A
//! lossless film (ρ = 1) then returns S k = 1: every bit of light leaves
//! the surface, as it does in the random walk of multiple scattering. On a
//! metal (no transmission), ρ = F_eff and E_w = A_R, and k is Turquin's
//! conductor form 1 + F (1 − E) / E with F the film's own F_eff.
//!
//! ρ has one definition, [`kept_share`]: at a microfacet, the film's R + T
//! (R alone on an opaque substrate, where what enters is absorbed); over a
//! lobe, its mean under the reflection lobe's weights (the rough table's
//! `kept`, the albedos' [`Albedos::kept`]), exactly 1 for a lossless film.
//! F_eff + T_eff is not it: the two average the film over different
//! microfacets (the ones whose reflection, resp. refraction, leaves).

use std::f64::consts::{FRAC_PI_2, FRAC_PI_4, PI};

use super::ggx;
use super::quadrature::Rule;

/// The single-scattering albedos of a GGX surface at one view angle and
/// roughness, without film: white (every microfacet reflects, resp.
/// refracts, everything) and with the bare interface's Fresnel.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Albedos {
    /// A_R: the white reflection lobe's directional albedo.
    pub reflect_white: f64,
    /// A_T: the white refraction lobe's (0 without transmission).
    pub transmit_white: f64,
    /// The bare interface's reflection, ∫ D_v F e_R (its F_eff times A_R;
    /// A_R for an opaque white reflector).
    pub reflect: f64,
    /// The bare interface's transmission, ∫ D_v (1 − F) e_T.
    pub transmit: f64,
    /// ρ over the reflection lobe: ∫ D_v e_R [`kept_share`] ÷ A_R (1 for a
    /// lossless interface or film, the film's F_eff when opaque).
    pub kept: f64,
}

impl Albedos {
    /// The bare interface's single-scattering energy E = reflect +
    /// transmit (for an opaque white reflector, A_R).
    pub fn energy(&self) -> f64 {
        self.reflect + self.transmit
    }
}

/// ρ, the share of the light a microfacet keeps (reflects, or transmits
/// into a substrate that lets it on) rather than absorbs: the film's
/// `reflectance` plus its `transmittance`, or the reflectance alone with
/// no transmittance (`None`: an opaque substrate absorbs what enters it).
/// The one definition every compensation uses: the renderer at its drawn
/// microfacet, the rough tables and albedos averaged over the reflection
/// lobe (it is linear, so the mean of ρ is ρ of the means).
#[inline]
pub fn kept_share(reflectance: f64, transmittance: Option<f64>) -> f64 {
    reflectance + transmittance.unwrap_or(0.0)
}

/// Deterministic quadrature of [`Albedos`]: `panels` panels of `points`
/// Gauss–Legendre points over each of the microfacet normal's two
/// coordinates.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct AlbedoQuadrature {
    /// Panels per coordinate.
    pub panels: usize,
    /// Gauss–Legendre points per panel.
    pub points: usize,
}

impl Default for AlbedoQuadrature {
    fn default() -> Self {
        AlbedoQuadrature {
            panels: 12,
            points: 8,
        }
    }
}

impl AlbedoQuadrature {
    /// Twice the panels and points.
    pub fn finer(&self) -> AlbedoQuadrature {
        AlbedoQuadrature {
            panels: 2 * self.panels,
            points: 2 * self.points,
        }
    }
}

/// The albedos of view cos θ_v = `cos_view` and `roughness`, seen from a
/// medium whose far side has relative index `eta` = n_other / n_view
/// (`None`: opaque, reflection only).
///
/// Microfacet normals are parametrized by τ, with tan θ_h = α tan τ (GGX's
/// projected-area distribution is then uniform in sin² τ), and by their
/// azimuth φ from the view's plane; the visible-normal density
/// D_v = G1(v) max(0, v·h) D(h) / cos θ_v becomes the smooth weight of
/// [`visible_weight`]. A reflection leaves with G2(v, l) / G1(v), a
/// refraction likewise with |cos θ_l| (Walter et al. 2007; the shared
/// definition in docs/rough.md).
pub fn albedos(cos_view: f64, roughness: f64, eta: Option<f64>, q: &AlbedoQuadrature) -> Albedos {
    // Opaque: a white reflector.
    film_albedos(cos_view, roughness, eta, q, |mu, cos_t, eta| {
        if eta == 0.0 {
            return (1.0, 0.0);
        }
        let f = fresnel(mu, cos_t, eta);
        (f, 1.0 - f)
    })
}

/// [`albedos`] with a film's reflectance and transmittance per microfacet
/// in place of the bare Fresnel: `film(μ, cos θ_t, η)` returns (R, T) at a
/// microfacet seen at cos `μ` that refracts at cos θ_t (only called where
/// it refracts; past the critical angle R is 1). With `eta` `None` it is
/// called with cos θ_t = 0 and η = 0, and only R is used.
pub fn film_albedos(
    cos_view: f64,
    roughness: f64,
    eta: Option<f64>,
    q: &AlbedoQuadrature,
    film: impl Fn(f64, f64, f64) -> (f64, f64),
) -> Albedos {
    let cv = cos_view.clamp(super::kernel::MIN_COS_VIEW, 1.0);
    let alpha = ggx::alpha(roughness).max(1e-7);
    let a2 = alpha * alpha;
    let sv = ((1.0 - cv) * (1.0 + cv)).sqrt();
    let lambda_cos_v = ggx::lambda_cos(cv, a2);
    let g1_v = cv / (cv + lambda_cos_v);
    let view = View {
        cv,
        sv,
        a2,
        lambda_cos_v,
        g1_v,
    };
    let rule = Rule::gauss_legendre(q.points);
    let mut sum = [0.0f64; 5];
    // cos θ of the critical angle, where a microfacet stops refracting.
    let mu_c = eta
        .filter(|&e| e > 0.0 && e < 1.0)
        .map(|e| (1.0 - e * e).sqrt());
    let theta_v = cv.acos();
    // θ_h where a kink of the integrand enters or leaves the azimuths:
    // the critical angle and the reflection's horizon, at φ = 0 and π.
    let mut thetas = vec![FRAC_PI_4 + 0.5 * theta_v, FRAC_PI_4 - 0.5 * theta_v];
    if let Some(m) = mu_c {
        let tc = m.acos();
        thetas.extend([tc + theta_v, tc - theta_v, theta_v - tc]);
    }
    let mut tau_cuts: Vec<f64> = thetas
        .into_iter()
        .filter(|&t| t > 0.0 && t < FRAC_PI_2)
        .map(|t| (t.tan() / alpha).atan())
        .collect();
    // Past τ_full the view sees only part of the azimuths.
    if sv * alpha > 0.0 {
        tau_cuts.push((cv / (sv * alpha)).atan());
    }
    panels(&rule, (0.0, FRAC_PI_2), &tau_cuts, q.panels, |tau, w| {
        let (st, ct) = tau.sin_cos();
        // Azimuths where v·h > 0.
        let across = sv * alpha * st;
        let phi_max = if across <= cv * ct {
            PI
        } else {
            (-cv * ct / across).acos()
        };
        let norm = (ct * ct + a2 * st * st).sqrt();
        let (cos_h, sin_h) = (ct / norm, alpha * st / norm);
        // φ where μ = v·h crosses μ_c, and where the reflection sets.
        let cos_phi_at = |mu: f64| (mu - cv * cos_h) / (sv * sin_h);
        let mut phi_cuts = vec![cos_phi_at(cv / (2.0 * cos_h))];
        phi_cuts.extend(mu_c.map(cos_phi_at));
        let phi_cuts: Vec<f64> = phi_cuts
            .into_iter()
            .filter(|c| c.abs() < 1.0)
            .map(f64::acos)
            .collect();
        panels(&rule, (0.0, phi_max), &phi_cuts, q.panels, |phi, wy| {
            let (sp, cp) = phi.sin_cos();
            let weight = w * wy * visible_weight(st, ct, cp, cv, sv, alpha, lambda_cos_v);
            let h = [sin_h * cp, sin_h * sp, cos_h];
            let escapes = escapes(h, &view, eta, &film);
            for (s, e) in sum.iter_mut().zip(escapes) {
                *s += weight * e;
            }
        });
    });
    Albedos {
        reflect_white: sum[0],
        transmit_white: sum[1],
        reflect: sum[2],
        transmit: sum[3],
        kept: if sum[0] > 0.0 { sum[4] / sum[0] } else { 1.0 },
    }
}

/// Composite Gauss–Legendre over `range` cut at `cuts` (those inside it):
/// each piece gets its share of `count` panels (at least one); calls
/// `f(x, weight)` at every node.
fn panels(
    rule: &Rule,
    (lo, hi): (f64, f64),
    cuts: &[f64],
    count: usize,
    mut f: impl FnMut(f64, f64),
) {
    let mut ends: Vec<f64> = cuts.iter().copied().filter(|&c| c > lo && c < hi).collect();
    ends.push(hi);
    ends.sort_by(f64::total_cmp);
    let mut start = lo;
    for end in ends {
        if end <= start {
            continue;
        }
        let n = ((count as f64 * (end - start) / (hi - lo)).ceil() as usize).max(1);
        let width = (end - start) / n as f64;
        for p in 0..n {
            for (x, w) in rule.nodes.iter().zip(&rule.weights) {
                f(start + width * (p as f64 + x), w * width);
            }
        }
        start = end;
    }
}

/// D_v dω_h in the (τ, φ) parametrization of [`albedos`], over φ ∈ [0, π]
/// (the other half mirrors it): 2 (sin τ cos τ cos θ_v + sin θ_v α sin² τ
/// cos φ) / (π (cos θ_v + Λ(v) cos θ_v)).
#[inline]
fn visible_weight(st: f64, ct: f64, cp: f64, cv: f64, sv: f64, alpha: f64, lcv: f64) -> f64 {
    (2.0 * (st * ct * cv + sv * alpha * st * st * cp) / (PI * (cv + lcv))).max(0.0)
}

/// The view as [`escapes`] needs it: cos and sin θ_v, α², Λ(v) cos θ_v
/// and G1(v).
#[derive(Clone, Copy)]
struct View {
    cv: f64,
    sv: f64,
    a2: f64,
    lambda_cos_v: f64,
    g1_v: f64,
}

/// For microfacet normal `h` (macro frame, view in the x–z plane): the
/// escape weights of its reflection and refraction, white and with the
/// bare interface's Fresnel (or the film's R, T), and what the microfacet
/// keeps under the reflection's escape: [e_R, e_T, F e_R, (1 − F) e_T,
/// ρ e_R].
#[inline]
fn escapes(
    h: [f64; 3],
    view: &View,
    eta: Option<f64>,
    film: &impl Fn(f64, f64, f64) -> (f64, f64),
) -> [f64; 5] {
    let View {
        cv,
        sv,
        a2,
        lambda_cos_v,
        g1_v,
    } = *view;
    let mu = (sv * h[0] + cv * h[2]).max(0.0);
    let cos_l = 2.0 * mu * h[2] - cv;
    let e_r = ggx::g2(cv, lambda_cos_v, cos_l, a2) / g1_v;
    let Some(eta) = eta else {
        let r = film(mu, 0.0, 0.0).0;
        return [e_r, 0.0, r * e_r, 0.0, kept_share(r, None) * e_r];
    };
    let sin2_t = (1.0 - mu * mu) / (eta * eta);
    if sin2_t >= 1.0 {
        // Total internal reflection at this microfacet.
        return [e_r, 0.0, e_r, 0.0, kept_share(1.0, Some(0.0)) * e_r];
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    let (r, t) = film(mu, cos_t, eta);
    // t = −v/η + (μ/η − cos θ_t) h; its z, negated, is |cos θ_l|.
    let cos_lt = -(-cv / eta + (mu / eta - cos_t) * h[2]);
    let e_t = ggx::g2(cv, lambda_cos_v, cos_lt, a2) / g1_v;
    [e_r, e_t, r * e_r, t * e_t, kept_share(r, Some(t)) * e_r]
}

/// Unpolarized Fresnel reflectance at incidence cos `mu`, refraction cos
/// `cos_t`, relative index `eta`.
#[inline]
pub fn fresnel(mu: f64, cos_t: f64, eta: f64) -> f64 {
    let rs = (mu - eta * cos_t) / (mu + eta * cos_t);
    let rp = (eta * mu - cos_t) / (eta * mu + cos_t);
    0.5 * (rs * rs + rp * rp)
}

/// The albedo integrated over view directions with cos-weight, 2 ∫ E(μ) μ dμ
/// (Kulla and Conty's E_avg), by Gauss–Legendre on `points` points in μ².
pub fn average(points: usize, mut albedo: impl FnMut(f64) -> f64) -> f64 {
    // 2 ∫ E(μ) μ dμ = ∫ E(√s) ds with s = μ².
    let rule = Rule::gauss_legendre(points);
    rule.nodes
        .iter()
        .zip(&rule.weights)
        .map(|(s, w)| w * albedo(s.sqrt()))
        .sum()
}

/// A film's single-scattering outputs at one view angle and roughness
/// (docs/rough.md): its lobe-averaged reflectance and transmittance and
/// the white lobes' albedos.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SingleScattering {
    /// F_eff, per channel.
    pub reflectance: [f64; 3],
    /// T_eff, per channel (0 for an opaque substrate).
    pub transmittance: [f64; 3],
    /// A_R.
    pub reflect_albedo: f64,
    /// A_T (0 for an opaque substrate).
    pub transmit_albedo: f64,
}

/// The compensated outputs of a film at `roughness`: F_eff and T_eff of
/// `ss` scaled by Turquin's k ([`compensation`]), its microfacets keeping
/// `kept` per channel ([`kept_share`] over the reflection lobe: a rough
/// table's `kept`, or F_eff on an opaque substrate). A host draws the
/// white lobes (albedos A_R, A_T) times these. Roughness 0 scatters once:
/// `ss`'s own.
pub fn compensate(roughness: f64, ss: &SingleScattering, kept: [f64; 3]) -> ([f64; 3], [f64; 3]) {
    if roughness == 0.0 {
        return (ss.reflectance, ss.transmittance);
    }
    let k = compensation(ss, kept);
    (
        std::array::from_fn(|c| ss.reflectance[c] * k[c]),
        std::array::from_fn(|c| ss.transmittance[c] * k[c]),
    )
}

/// Turquin's scale k of a film's single-scattering lobe (see the module's
/// doc) per channel, its microfacets keeping `keep` (ρ, [`kept_share`]
/// over the reflection lobe; clamped to [S, 1]).
pub fn compensation(ss: &SingleScattering, keep: [f64; 3]) -> [f64; 3] {
    std::array::from_fn(|c| {
        let (f, t) = (ss.reflectance[c], ss.transmittance[c]);
        let energy = ss.reflect_albedo * f + ss.transmit_albedo * t;
        // Nothing lost (a film with gain can give more than it gets): no
        // compensation, and no clamp to an empty range.
        if energy <= 1e-12 || energy >= 1.0 {
            return 1.0;
        }
        let keep = keep[c].clamp(energy, 1.0);
        // 1 + ρ (1 − E_w) / E_w with E_w = S / ρ.
        1.0 + keep * (keep - energy) / energy
    })
}

/// Catmull–Rom interpolation of a table on evenly spaced nodes over
/// [0, 1] in two coordinates.
#[derive(Clone, Debug)]
struct Grid2 {
    n0: usize,
    n1: usize,
    values: Vec<f64>,
}

impl Grid2 {
    fn from_fn(n0: usize, n1: usize, mut f: impl FnMut(f64, f64) -> f64) -> Grid2 {
        let mut values = Vec::with_capacity(n0 * n1);
        for i in 0..n0 {
            for j in 0..n1 {
                values.push(f(i as f64 / (n0 - 1) as f64, j as f64 / (n1 - 1) as f64));
            }
        }
        Grid2 { n0, n1, values }
    }

    fn at(&self, x0: f64, x1: f64) -> f64 {
        let (i, w0) = stencil(x0, self.n0);
        let (j, w1) = stencil(x1, self.n1);
        let mut sum = 0.0;
        for (a, wa) in w0.iter().enumerate() {
            let row = (i + a).saturating_sub(1).min(self.n0 - 1);
            for (b, wb) in w1.iter().enumerate() {
                let col = (j + b).saturating_sub(1).min(self.n1 - 1);
                sum += wa * wb * self.values[row * self.n1 + col];
            }
        }
        sum
    }
}

/// The Catmull–Rom stencil of x ∈ [0, 1] on n evenly spaced nodes: the
/// index of its second node (the first is one below, clamped) and the four
/// weights. At the ends the missing node is extrapolated linearly.
fn stencil(x: f64, n: usize) -> (usize, [f64; 4]) {
    let s = x.clamp(0.0, 1.0) * (n - 1) as f64;
    let i = (s.floor() as usize).min(n - 2);
    let t = s - i as f64;
    let (t2, t3) = (t * t, t * t * t);
    let mut w = [
        -0.5 * t3 + t2 - 0.5 * t,
        1.5 * t3 - 2.5 * t2 + 1.0,
        -1.5 * t3 + 2.0 * t2 + 0.5 * t,
        0.5 * t3 - 0.5 * t2,
    ];
    // Node −1 = 2 node 0 − node 1; node n = 2 node n−1 − node n−2.
    if i == 0 {
        w[1] += 2.0 * w[0];
        w[2] -= w[0];
        w[0] = 0.0;
    }
    if i + 2 >= n {
        w[2] += 2.0 * w[3];
        w[1] -= w[3];
        w[3] = 0.0;
    }
    (i, w)
}

/// The white-lobe tables of one interface (one η, or opaque) over view
/// cos θ and roughness, for a host that compensates without the film's own
/// single scattering (as the renderer does, with the bare interface's E).
/// The nodes are even in √cos θ_v (the albedos steepen towards grazing
/// view) and in roughness, Catmull–Rom interpolated.
#[derive(Clone, Debug)]
pub struct EnergyTable {
    eta: Option<f64>,
    reflect_white: Grid2,
    energy: Grid2,
}

impl EnergyTable {
    /// Nodes per coordinate that keep the interpolation within 1e-3.
    pub const DEFAULT_NODES: usize = 49;

    /// The tables for relative index `eta` = n_other / n_view (`None`:
    /// opaque), `nodes` per coordinate (at least 4), by [`albedos`].
    pub fn new(eta: Option<f64>, nodes: usize, q: &AlbedoQuadrature) -> EnergyTable {
        let nodes = nodes.max(4);
        let mut cache = vec![None; nodes * nodes];
        let mut at = |x: f64, r: f64| -> Albedos {
            let i = (x * (nodes - 1) as f64).round() as usize;
            let j = (r * (nodes - 1) as f64).round() as usize;
            *cache[i * nodes + j].get_or_insert_with(|| albedos(x * x, r, eta, q))
        };
        let reflect_white = Grid2::from_fn(nodes, nodes, |x, r| at(x, r).reflect_white);
        let energy = Grid2::from_fn(nodes, nodes, |x, r| at(x, r).energy());
        EnergyTable {
            eta,
            reflect_white,
            energy,
        }
    }

    /// The relative index the table is for.
    pub fn eta(&self) -> Option<f64> {
        self.eta
    }

    /// E_R: the white reflection lobe's albedo (A_R).
    pub fn reflect_white(&self, cos_view: f64, roughness: f64) -> f64 {
        self.reflect_white.at(cos_view.max(0.0).sqrt(), roughness)
    }

    /// E: the bare interface's single-scattering energy (reflection plus
    /// transmission with its Fresnel; E_R when opaque).
    pub fn energy(&self, cos_view: f64, roughness: f64) -> f64 {
        self.energy.at(cos_view.max(0.0).sqrt(), roughness)
    }

    /// E_avg: [`Self::energy`] averaged over views with cos-weight.
    pub fn energy_average(&self, roughness: f64) -> f64 {
        average(32, |mu| self.energy(mu, roughness))
    }
}

#[cfg(test)]
#[path = "energy_tests.rs"]
mod tests;
