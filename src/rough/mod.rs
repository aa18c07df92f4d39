//! Rough films: a thin-film stack under a GGX microfacet surface, and its
//! reflectance pre-integrated over the lobe (docs/rough.md).
//!
//! The definition, used everywhere in irid: GGX (Trowbridge–Reitz) with
//! α = roughness², the height-correlated Smith masking-shadowing
//! G2 = 1 / (1 + Λ(v) + Λ(l)), single scattering. The pre-integrated film
//! reflectance at view angle θ_v is
//!
//! ```text
//! F_eff(d, θ_v, r) = ∫ D G2 F(v·h) / (4 |n·v|) dl  ÷  ∫ D G2 / (4 |n·v|) dl
//! ```
//!
//! with F the film's unpolarized reflectance at incidence cos = v·h,
//! integrated to colour as every other irid colour. A lobe of colour F_eff
//! has the film's directional albedo exactly.
//!
//! F depends on the light direction only through μ = v·h, so F_eff is a
//! one-dimensional weighting of the smooth film colour,
//! F_eff = ∫ F(μ) K(μ; θ_v, α) dμ ÷ ∫ K dμ. A [`Kernel`] holds that weighting
//! for one (θ_v, roughness) as weights on the nodes of a [`MuGrid`] (the
//! film's colour is interpolated between them), computed once by
//! deterministic quadrature ([`Quadrature`]); colour integration is linear,
//! so the same weights apply to RGB colours. [`rough_reflectance`] fills F_eff
//! over a whole thickness × cos θ × roughness grid: the film's smooth colour
//! on the μ nodes from the baker's split-stack sweep, times a kernel per
//! (cos θ, roughness). [`rough_colors`] is `irid color --roughness`.
//!
//! The transmittance is the same construction with the refraction lobe's
//! kernel K_T(μ; θ_v, α, η) ([`Kernel::transmission`], Walter et al.
//! 2007's microfacet refraction in flux form): T_eff and its white lobe's
//! albedo A_T, from either side of the film ([`rough_response`],
//! [`rough_colors_from`]; the substrate side is the reversed stack).

pub mod energy;
mod engine;
pub mod ggx;
mod kernel;
mod mu_grid;
mod quadrature;
pub mod slices;
#[cfg(test)]
mod tests;
#[cfg(test)]
mod tests_transmission;
mod transmission;

pub use engine::{
    relative_index, rough_colors, rough_colors_cancellable, rough_colors_from,
    rough_colors_from_cancellable, rough_reflectance, rough_reflectance_colors, rough_response,
    seen_from, RoughColor, RoughTable, ETA_WAVELENGTH_NM,
};
pub use kernel::Kernel;
pub use mu_grid::MuGrid;
pub use quadrature::Quadrature;

use crate::error::{Error, Result};

/// Checks a roughness: finite and in [0, 1] (`what` names it in the error).
pub fn check_roughness(what: &str, roughness: f64) -> Result<()> {
    if (0.0..=1.0).contains(&roughness) {
        Ok(())
    } else {
        Err(Error::invalid(
            what,
            format!("must be in [0, 1], got {roughness}"),
        ))
    }
}

/// Refuses a rough table over a smooth atlas that does not seek its target
/// over `band`, a dispersive critical band (cos θ lo, hi; see
/// [`crate::atlas::search::CRITICAL_BAND_TEXELS`]): the table's smallest
/// roughness is that atlas, texel for texel, and F_eff at small roughness
/// has the band's features too, so no slice count or chart size meets a
/// target there (the mirror seen from its glass side searched 230 s before
/// failing).
pub fn refuse_unsought_band(band: Option<(f64, f64)>) -> Result<()> {
    match band {
        None => Ok(()),
        Some((lo, hi)) => Err(Error::invalid(
            "rough",
            format!(
                "the smooth atlas does not seek its target over cos θ {lo:.4}–{hi:.4}, where the critical angle moves with the wavelength (docs/limits.md), and a rough table's smallest roughness is that atlas: a looser --max-error may let the band be sought"
            ),
        )),
    }
}
