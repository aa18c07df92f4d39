//! The exact sweep: a stack's response at many (thickness, cos θ
//! [, wavelength]) nodes of one varying layer, which the grid baker
//! (`lut`), the atlas search (`atlas`) and the rough tables (`rough`) all
//! evaluate through. It sits below them and imports none of them.
//!
//! The stack is split around the varying layer once per cos θ and
//! wavelength ([`crate::optics::twoport`]); along the thickness axis the
//! response is then Airy's sum in the layer's phase factor, which
//! `phases` advances by complex multiplication over evenly spaced runs of
//! nodes. `prepared` holds the stack and everything fixed for a sweep,
//! and evaluates grids (`grid`: axes as lists of segments, `axis`) or
//! the rows of atlas charts. The values agree with the solver to rounding
//! (tested to 1e-12), and a grid evaluated with a previous grid's values
//! at hand is the same bit for bit.
//!
//! Also here, because every layer above names them: what a table holds
//! ([`Kind`]), which side the light arrives from ([`Side`]), and the
//! domain a film can be evaluated over ([`check_film_domain`]).

pub(crate) mod axis;
pub(crate) mod grid;
mod phases;
mod prepared;
#[cfg(test)]
mod tests;

pub(crate) use axis::{share_intervals, uniform, Grading, Segment};
pub(crate) use grid::Grid;
#[cfg(test)]
pub(crate) use phases::{chunks, reuse_plan, Piece};
pub(crate) use prepared::{Prepared, Row};

use serde::{Deserialize, Serialize};

use crate::cancel::Cancel;
use crate::color::SpectralIntegrator;
use crate::error::{Error, Result};
use crate::optics::{Stack, MAX_THICKNESS_NM};

/// Checks what a table or an export covers: the stack itself, `layer`
/// within it, 0 ≤ min ≤ max ≤ [`MAX_THICKNESS_NM`] (the stack's own bound,
/// which also keeps an f32 thickness axis finite), and 0 ≤ cos θ min ≤ max
/// ≤ 1. Errors name the option: `layer`, `thickness` or `angles`.
pub fn check_film_domain(
    stack: &Stack,
    layer: usize,
    thickness_nm: (f64, f64),
    cos_theta: (f64, f64),
) -> Result<()> {
    stack.validate()?;
    let n = stack.layers.len();
    if n > 0 && !(1..=n).contains(&layer) {
        return Err(Error::invalid(
            "layer",
            format!("must be between 1 and {n} (the stack's layers), got {layer}"),
        ));
    }
    if n > 0 && !stack.layers[layer - 1].coherent {
        let coherent: Vec<String> = (1..=n)
            .filter(|&l| stack.layers[l - 1].coherent)
            .map(|l| l.to_string())
            .collect();
        return Err(Error::invalid(
            "layer",
            format!(
                "layer {layer} is incoherent (coherent = false): a table's thickness axis must be \
                 on a coherent layer ({})",
                if coherent.is_empty() {
                    "the stack has none".to_string()
                } else {
                    format!("coherent layers: {}", coherent.join(", "))
                }
            ),
        ));
    }
    let (t0, t1) = thickness_nm;
    if !(t0 >= 0.0 && t0 <= t1 && t1 <= MAX_THICKNESS_NM) {
        return Err(Error::invalid(
            "thickness",
            format!("need 0 ≤ min ≤ max ≤ {MAX_THICKNESS_NM:e} nm, got {t0}:{t1}"),
        ));
    }
    let (c0, c1) = cos_theta;
    if !(c0 >= 0.0 && c1 <= 1.0 && c0 <= c1) {
        return Err(Error::invalid(
            "angles",
            format!("cos θ range must satisfy 0 ≤ min ≤ max ≤ 1, got {c0}:{c1}"),
        ));
    }
    Ok(())
}

/// What a table holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Kind {
    /// Unpolarized R and T as linear sRGB under D65, over thickness × cos θ.
    Rgb,
    /// Unpolarized R and T over thickness × cos θ × wavelength.
    Spectral,
}

impl std::str::FromStr for Kind {
    type Err = Error;
    fn from_str(s: &str) -> Result<Kind> {
        match s {
            "rgb" => Ok(Kind::Rgb),
            "spectral" => Ok(Kind::Spectral),
            _ => Err(Error::invalid(
                format!("kind '{s}'"),
                "expected rgb or spectral",
            )),
        }
    }
}

impl Kind {
    /// Values per node: R and T of each of three colour channels, or R and
    /// T at one wavelength.
    pub(crate) fn channels(self) -> usize {
        match self {
            Kind::Rgb => 6,
            Kind::Spectral => 2,
        }
    }
}

impl std::fmt::Display for Kind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Kind::Rgb => "rgb",
            Kind::Spectral => "spectral",
        })
    }
}

/// Which side of the film the light arrives from.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(into = "u32", try_from = "u32")]
pub enum Side {
    /// From the ambient: the stack as written.
    #[default]
    Front,
    /// From the substrate (inside a coated gem): the reversed stack, whose
    /// denser incidence medium gives total internal reflection.
    Back,
}

impl Side {
    /// 0 for [`Side::Front`], 1 for [`Side::Back`]: how a chart, the
    /// shaders' uniform array and film.json number the side.
    pub fn index(self) -> u32 {
        match self {
            Side::Front => 0,
            Side::Back => 1,
        }
    }
}

impl From<Side> for u32 {
    fn from(side: Side) -> u32 {
        side.index()
    }
}

impl TryFrom<u32> for Side {
    type Error = String;
    fn try_from(index: u32) -> std::result::Result<Side, String> {
        match index {
            0 => Ok(Side::Front),
            1 => Ok(Side::Back),
            _ => Err(format!("side {index}, expected 0 or 1")),
        }
    }
}

/// Exact linear-RGB reflectance and transmittance (`[R; 3]` then `[T; 3]`)
/// of `stack` with its `layer` (from 1) at every thickness × cos θ node,
/// row-major with one row per cos θ node, integrated by `integrator`: the
/// baker's sweep (the stack split once per wavelength and angle) on nodes
/// the caller chose, as the GPU export lays out its own. Stops with
/// [`Error::Cancelled`] once `cancel` is set (it looks before each cos θ).
pub(crate) fn rgb_at_nodes(
    stack: &Stack,
    layer: usize,
    integrator: SpectralIntegrator,
    thickness_nm: &[f64],
    cos_theta: &[f64],
    cancel: &Cancel,
) -> Result<Vec<[f64; 6]>> {
    let prep = Prepared::of(stack, layer, Kind::Rgb, integrator, (380.0, 780.0), cancel)?;
    let grid = Grid::rgb_of_nodes(thickness_nm, cos_theta);
    let values = prep.eval(&grid, None, &|_| {}, cancel)?;
    Ok(values
        .chunks_exact(6)
        .map(|v| [v[0], v[1], v[2], v[3], v[4], v[5]])
        .collect())
}

/// The substrate's critical cos θ (where its normal index has a square-root
/// branch point), when it is lossless and optically thinner than the
/// ambient, at 550 nm for rgb tables or mid-range for spectral ones.
pub(crate) fn critical_cos(stack: &Stack, kind: Kind, wavelength_nm: (f64, f64)) -> Option<f64> {
    let reference_nm = match kind {
        Kind::Rgb => 550.0,
        Kind::Spectral => 0.5 * (wavelength_nm.0 + wavelength_nm.1),
    };
    match (
        stack.ambient.index_at(reference_nm),
        stack.substrate.index_at(reference_nm),
    ) {
        (Ok(n0), Ok(ns)) if ns.im == 0.0 && ns.re < n0.re => {
            Some((1.0 - (ns.re / n0.re).powi(2)).sqrt())
        }
        _ => None,
    }
}
