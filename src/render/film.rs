//! The one interface through which the tracer shades thin films. Two
//! implementations: [`super::lut_film::LutFilm`] samples baked tables and
//! [`DirectFilm`] evaluates the transfer matrix at every hit (the reference),
//! so the two modes share every other line of the renderer.

use std::cell::RefCell;

use super::material::AngleTable;
use super::scene::Film;
use crate::color::{Sampling, SpectralIntegrator};
use crate::error::Result;
use crate::lut::FilmRgb;
use crate::optics::lanes::SpectralWeights;
use crate::optics::{Stack, StackGrid};
pub use crate::sweep::Side;

/// Reflectance and transmittance of a film, as linear-sRGB weights under D65.
pub trait FilmShading: Sync + Send {
    /// `cos_theta` is the cosine of the incidence angle in the medium the
    /// light arrives from; `thickness_nm` the varying layer's thickness.
    fn shade(&self, thickness_nm: f32, cos_theta: f32, side: Side) -> FilmRgb;
}

/// The reference: the full transfer-matrix solution at every wavelength of
/// a sampling strategy, integrated to colour, at every hit (the paper's method).
pub struct DirectFilm {
    weights: SpectralWeights,
    front: DirectSide,
    back: Option<DirectSide>,
}

/// One side's stack, with the indices at every wavelength precomputed.
struct DirectSide {
    grid: StackGrid,
    /// Which layer (0-based) the shading thickness replaces.
    layer: usize,
}

impl DirectSide {
    fn new(stack: &Stack, layer: usize, wavelengths_nm: &[f64]) -> Result<DirectSide> {
        Ok(DirectSide {
            grid: StackGrid::new(stack, wavelengths_nm)?,
            layer,
        })
    }
}

thread_local! {
    /// Per-thread scratch: the thicknesses with the shaded one put in.
    static THICKNESSES: RefCell<Vec<f64>> = const { RefCell::new(Vec::new()) };
}

impl DirectFilm {
    /// The direct shader for `film`: its stack's indices evaluated at every
    /// wavelength of `sampling` (and of the reversed stack too when the film
    /// has a back side), integrated under D65. Fails if a material cannot be
    /// evaluated at one of those wavelengths.
    pub fn new(film: &Film, sampling: Sampling) -> Result<DirectFilm> {
        let integrator = SpectralIntegrator::new(sampling);
        let wl = integrator.wavelengths_nm();
        let front = DirectSide::new(&film.stack, film.layer, wl)?;
        let back = if film.back_side {
            let reversed = film.stack.reversed();
            let layer = film.stack.layers.len() - 1 - film.layer;
            Some(DirectSide::new(&reversed, layer, wl)?)
        } else {
            None
        };
        Ok(DirectFilm {
            weights: integrator.rgb_lane_weights(),
            front,
            back,
        })
    }
}

impl FilmShading for DirectFilm {
    fn shade(&self, thickness_nm: f32, cos_theta: f32, side: Side) -> FilmRgb {
        let s = match side {
            Side::Back => self.back.as_ref().unwrap_or(&self.front),
            Side::Front => &self.front,
        };
        THICKNESSES.with_borrow_mut(|d| {
            d.clear();
            d.extend_from_slice(s.grid.thicknesses_nm());
            if let Some(x) = d.get_mut(s.layer) {
                *x = f64::from(thickness_nm);
            }
            // Every wavelength of the sampling in one batch, eight or four
            // per vector, integrated as it is solved.
            let sums = s
                .grid
                .weighted_spectrum(d, f64::from(cos_theta), &self.weights);
            FilmRgb {
                reflectance: sums.reflectance.map(|v| v as f32),
                transmittance: sums.transmittance.map(|v| v as f32),
            }
        })
    }
}

/// Reflectance of an uncoated surface (a zero-layer stack, e.g. air on gold)
/// over cos θ, integrated exactly: the colour of a bare metal.
pub fn bare_reflectance(stack: &Stack, nodes: usize) -> Result<AngleTable> {
    let integrator = SpectralIntegrator::new(Sampling::Exact);
    let film = Film {
        name: String::new(),
        stack: stack.clone(),
        layer: 0,
        thickness_range_nm: (0.0, 0.0),
        back_side: false,
    };
    let direct = DirectFilm::new(&film, integrator.sampling())?;
    Ok(AngleTable::from_fn(nodes, |cos| {
        direct.shade(0.0, cos as f32, Side::Front).reflectance
    }))
}
