//! Fitting: layer thicknesses from a measured spectrum (weighted least
//! squares, [`fit_spectrum`], and over many spectra at once,
//! [`SpectrumFitter::fit_many`]) or from colours seen at given angles
//! ([`fit_color`]).
//!
//! Above [`optics`](crate::optics) and [`color`](crate::color), whose exact
//! thickness derivatives it uses; below the command line (`irid fit`) and
//! the Python package (`irid.fit`, `irid.fit_color`), which are thin shells
//! over it. The model, its uncertainty, the global search and the colour
//! fit are described in docs/inverse.md.

mod color;
mod csv;
mod linalg;
mod lm;
mod search;
mod spectrum;
mod stack_file;
mod vary;

pub use color::{
    check_target, fit_color, ColorAlternative, ColorFit, ColorTarget, AMBIGUITY_DE2000,
};
pub use csv::{parse_spectrum_csv, read_spectrum_csv};
pub use lm::{minimize, Minimum, Options, Residuals};
pub use spectrum::Measurement;
pub use stack_file::with_thicknesses;
pub use vary::Vary;

use rayon::prelude::*;
use serde::Serialize;

use crate::error::Result;
use crate::optics::Stack;
use search::{Library, Model};
use spectrum::{Layout, SpectrumModel, WeightedResiduals};

/// The most points the coarse scan evaluates (the full grid when it is
/// smaller).
pub const SCAN_BUDGET: usize = 4096;

/// The fitted thicknesses of one spectrum.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SpectrumFit {
    /// The varied layers, 1-based from the top.
    pub layers: Vec<usize>,
    /// Each varied layer's fitted thickness, nm.
    pub thickness_nm: Vec<f64>,
    /// Each one's standard deviation, nm: √diag((JᵀWJ)⁻¹) at the optimum,
    /// scaled by χ²/(values − thicknesses) when the measurement gives no σ;
    /// infinite for a thickness the data do not constrain.
    pub sigma_nm: Vec<f64>,
    /// Σ ((model − measured)/σ)² at the optimum (σ = 1 when not given).
    pub chi2: f64,
    /// Measured values minus fitted thicknesses: χ²'s degrees of freedom.
    pub degrees_of_freedom: usize,
    /// Root mean square of model − measured over every fitted value.
    pub rms_residual: f64,
    /// model − measured R per row (when R was measured).
    pub residual_r: Option<Vec<f64>>,
    /// model − measured T per row (when T was measured).
    pub residual_t: Option<Vec<f64>>,
    /// Other minima the data cannot tell from the best: χ² within
    /// [`Self::threshold`] of it, thicknesses more than 3 σ_nm away.
    pub alternatives: Vec<Alternative>,
    /// The χ² difference below which two minima are not told apart: the
    /// 95 % quantile of χ² with as many degrees of freedom as thicknesses,
    /// times the reduced χ² when that exceeds 1 (or when σ is unknown).
    pub threshold: f64,
}

/// A minimum other than the best.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Alternative {
    /// Its thicknesses, nm, in the order of [`SpectrumFit::layers`].
    pub thickness_nm: Vec<f64>,
    /// Its χ².
    pub chi2: f64,
}

impl SpectrumFit {
    /// True when another minimum fits as well within the noise.
    pub fn is_ambiguous(&self) -> bool {
        !self.alternatives.is_empty()
    }
}

/// Fits the thicknesses of `vary`'s layers of `stack` to `measured`.
pub fn fit_spectrum(stack: &Stack, vary: &Vary, measured: &Measurement) -> Result<SpectrumFit> {
    measured.check("", vary.layers.len())?;
    let fitter = SpectrumFitter::new(stack, vary, measured)?;
    fitter.fit(measured)
}

/// A fit set up once for many measurements on the same points (a
/// hyperspectral cube): the scan's model spectra are computed once.
pub struct SpectrumFitter {
    vary: Vary,
    model: SpectrumModel,
    library: Library,
}

impl SpectrumFitter {
    /// Prepares fits of `vary` on `stack` at the points (wavelengths,
    /// angles, measured channels) of `layout_of`, a checked measurement.
    pub fn new(stack: &Stack, vary: &Vary, layout_of: &Measurement) -> Result<SpectrumFitter> {
        stack.validate()?;
        let model = SpectrumModel::new(stack, vary, Layout::new(layout_of))?;
        let library = Library::new(&model, &vary.bounds_nm, &vary.start(stack), SCAN_BUDGET)?;
        Ok(SpectrumFitter {
            vary: vary.clone(),
            model,
            library,
        })
    }

    /// The fit of one measurement on this fitter's points (same rows as
    /// the measurement it was made with; values and σ may differ).
    pub fn fit(&self, measured: &Measurement) -> Result<SpectrumFit> {
        let (y, sigma) = measured.values(self.model.layout());
        let loss = WeightedResiduals { measured: y, sigma };
        let found = search::search(&self.model, &loss, &self.library, &self.vary.bounds_nm)?;
        self.report(measured, &loss, &found.minima)
    }

    /// [`Self::fit`] over many measurements, in parallel on rayon's
    /// current pool.
    pub fn fit_many(&self, measured: &[Measurement]) -> Result<Vec<SpectrumFit>> {
        measured.par_iter().map(|m| self.fit(m)).collect()
    }

    fn report(
        &self,
        measured: &Measurement,
        loss: &WeightedResiduals,
        minima: &[Minimum],
    ) -> Result<SpectrumFit> {
        let best = &minima[0];
        let k = self.vary.layers.len();
        let values = loss.measured.len();
        let dof = values - k;
        let reduced = best.chi2 / dof.max(1) as f64;
        let scale = if measured.sigma.is_some() {
            reduced.max(1.0)
        } else {
            reduced
        };
        let cov_scale = if measured.sigma.is_some() {
            1.0
        } else {
            reduced
        };
        let sigma_nm: Vec<f64> = (0..k)
            .map(|p| match &best.covariance {
                Some(c) => (c[p * k + p] * cov_scale).max(0.0).sqrt(),
                None => f64::INFINITY,
            })
            .collect();
        let threshold = chi2_quantile_95(k) * scale;
        let alternatives = minima[1..]
            .iter()
            .filter(|m| m.chi2 - best.chi2 <= threshold)
            .filter(|m| {
                m.x.iter()
                    .zip(&best.x)
                    .zip(&sigma_nm)
                    .any(|((a, b), s)| (a - b).abs() > 3.0 * s.max(1e-3))
            })
            .map(|m| Alternative {
                thickness_nm: m.x.clone(),
                chi2: m.chi2,
            })
            .collect();
        let mut p = vec![0.0; self.model.predictions()];
        self.model.predict(&best.x, &mut p)?;
        let rows = self.model.layout().per_row(&p);
        let residual_r = measured.reflectance.as_ref().map(|r| {
            rows.iter()
                .zip(r)
                .map(|((m, _), y)| m.unwrap_or(0.0) - y)
                .collect::<Vec<_>>()
        });
        let residual_t = measured.transmittance.as_ref().map(|t| {
            rows.iter()
                .zip(t)
                .map(|((_, m), y)| m.unwrap_or(0.0) - y)
                .collect::<Vec<_>>()
        });
        let (sum, count) = [&residual_r, &residual_t]
            .into_iter()
            .flatten()
            .flatten()
            .fold((0.0, 0usize), |(s, c), v| (s + v * v, c + 1));
        Ok(SpectrumFit {
            layers: self.vary.layers.clone(),
            thickness_nm: best.x.clone(),
            sigma_nm,
            chi2: best.chi2,
            degrees_of_freedom: dof,
            rms_residual: (sum / count.max(1) as f64).sqrt(),
            residual_r,
            residual_t,
            alternatives,
            threshold,
        })
    }
}

/// The 95 % quantile of the χ² distribution with `k` degrees of freedom:
/// tabulated to 10 (Abramowitz & Stegun, table 26.8), Wilson–Hilferty's
/// approximation beyond (within 0.1 % there).
fn chi2_quantile_95(k: usize) -> f64 {
    const TABLE: [f64; 10] = [
        3.841, 5.991, 7.815, 9.488, 11.070, 12.592, 14.067, 15.507, 16.919, 18.307,
    ];
    if (1..=10).contains(&k) {
        return TABLE[k - 1];
    }
    const Z95: f64 = 1.644_853_626_951_472_2;
    let k = k as f64;
    let a = 2.0 / (9.0 * k);
    k * (1.0 - a + Z95 * a.sqrt()).powi(3)
}

#[cfg(test)]
mod tests;
