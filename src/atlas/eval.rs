//! Exact responses at the nodes of charts.

use rayon::prelude::*;

use super::chart::{Chart, Coords, Optical};
use crate::cancel::Cancel;
use crate::color::SpectralIntegrator;
use crate::error::{Error, Result};
use crate::optics::lanes::SpectralWeights;
use crate::optics::Stack;
use crate::sweep::{Kind, Prepared, Row};

/// |R| or |T| beyond which a gain film is taken to be at a lasing pole: a
/// hundredfold amplification is no film a renderer shows, and near a pole
/// the response is unbounded anyway.
pub const LASING_BOUND: f64 = 100.0;

/// Grid of the lasing check: thicknesses × cos θ.
const LASING_GRID: (usize, usize) = (257, 129);

/// One side of a film, with everything fixed for evaluating charts: exact
/// linear-RGB R and T at rows of constant cos θ (the baker's split-stack
/// sweep, one split per angle and wavelength) and at scattered points (the
/// batched solver, a whole spectrum per point).
pub struct Film {
    prep: Prepared,
    weights: SpectralWeights,
    /// The largest weight one wavelength has in any channel.
    largest_weight: f64,
    /// The colour of a flat spectrum 1 (what R + T adds up to for a
    /// lossless stack), when the stack is lossless.
    lossless_white: Option<[f64; 3]>,
    /// The side's optical thickness factor (see [`Optical`]).
    pub optical: Optical,
    /// A spectral film's wavelength nodes (else `None`: linear RGB).
    spectrum: Option<Spectrum>,
}

/// What a spectral film holds at each node: R and T at these wavelengths.
struct Spectrum {
    wavelengths_nm: Vec<f64>,
    /// cos θ below which the wavelength nodes do not follow the film's
    /// fringes (see [`super::spectrum`]).
    aliased_below: f64,
}

impl Film {
    /// The film `stack` (as seen from the side the light arrives on) with
    /// layer `layer` (from 1) varying, integrated by `integrator`.
    pub fn new(stack: &Stack, layer: usize, integrator: SpectralIntegrator) -> Result<Film> {
        let weights = integrator.rgb_lane_weights();
        let largest_weight = integrator
            .rgb_weights()
            .iter()
            .flat_map(|w| w.iter())
            .fold(0.0f64, |a, &b| a.max(b.abs()));
        let lossless =
            stack.layers.iter().all(|l| l.material.is_lossless()) && stack.substrate.is_lossless();
        let flat = vec![1.0; integrator.wavelengths_nm().len()];
        let lossless_white = lossless.then(|| integrator.rgb(&flat));
        let prep = Prepared::of(
            stack,
            layer,
            Kind::Rgb,
            integrator,
            (380.0, 780.0),
            Cancel::never(),
        )?;
        let optical = optical_of(&prep.stack, prep.layer, 550.0)?;
        Ok(Film {
            prep,
            weights,
            largest_weight,
            lossless_white,
            optical,
            spectrum: None,
        })
    }

    /// The film `stack` with layer `layer` varying, holding at each node
    /// its R and T at `wavelengths_nm` (increasing), whose linear
    /// interpolation follows the fringes down to cos θ `aliased_below`.
    pub fn spectral(
        stack: &Stack,
        layer: usize,
        wavelengths_nm: &[f64],
        aliased_below: f64,
    ) -> Result<Film> {
        let (lo, hi) = (wavelengths_nm[0], wavelengths_nm[wavelengths_nm.len() - 1]);
        // Its weights are never read: the nodes hold spectra.
        let integrator = SpectralIntegrator::new(crate::color::Sampling::Rgb3);
        let weights = integrator.rgb_lane_weights();
        let prep = Prepared::of(
            stack,
            layer,
            Kind::Spectral,
            integrator,
            (lo, hi),
            Cancel::never(),
        )?;
        let optical = optical_of(&prep.stack, prep.layer, 0.5 * (lo + hi))?;
        Ok(Film {
            prep,
            weights,
            largest_weight: 1.0,
            lossless_white: None,
            optical,
            spectrum: Some(Spectrum {
                wavelengths_nm: wavelengths_nm.to_vec(),
                aliased_below,
            }),
        })
    }

    /// Values per node: R.r, R.g, R.b, T.r, T.g, T.b for a colour film; R
    /// at every wavelength node, then T at every one, for a spectral film.
    pub fn channels(&self) -> usize {
        self.spectrum
            .as_ref()
            .map_or(6, |s| 2 * s.wavelengths_nm.len())
    }

    /// Whether the nodes hold spectra (see [`Self::channels`]).
    pub fn is_spectral(&self) -> bool {
        self.spectrum.is_some()
    }

    /// A spectral film's cos θ below which its wavelength nodes do not
    /// follow its fringes.
    pub fn spectral_aliased_below(&self) -> Option<f64> {
        self.spectrum.as_ref().map(|s| s.aliased_below)
    }

    /// R and T (two values a node) of a spectral film along rows, each at
    /// one cos θ and one of its wavelength nodes (an index) with its own
    /// thickness nodes, row after row.
    pub fn spectral_rows(&self, rows: &[(f64, usize, Vec<f64>)]) -> Result<Vec<f64>> {
        let Some(spectrum) = &self.spectrum else {
            return Err(crate::error::Error::invalid(
                "film",
                "holds colours, not spectra",
            ));
        };
        let rows: Vec<Row> = rows
            .iter()
            .map(|(cos, k, t)| Row {
                cos: *cos,
                wavelength: *k,
                thickness_nm: t,
            })
            .collect();
        self.prep.eval_rows(&rows, &spectrum.wavelengths_nm)
    }

    /// The mean of a node's reflectance channels (its first half).
    pub fn brightness(&self, values: &[f64]) -> f64 {
        let half = &values[..values.len() / 2];
        half.iter().sum::<f64>() / half.len().max(1) as f64
    }

    /// Exact values ([`Self::channels`] per node) at the thickness nodes of
    /// each row (cos θ, thicknesses nm), row after row.
    pub fn rows_flat(&self, rows: &[(f64, Vec<f64>)]) -> Result<Vec<f64>> {
        let Some(spectrum) = &self.spectrum else {
            let rows: Vec<Row> = rows
                .iter()
                .map(|(cos, t)| Row {
                    cos: *cos,
                    wavelength: 0,
                    thickness_nm: t,
                })
                .collect();
            return self.prep.eval_rows(&rows, &[]);
        };
        let w = spectrum.wavelengths_nm.len();
        // One sweep per row and wavelength, wavelength fastest.
        let split: Vec<Row> = rows
            .iter()
            .flat_map(|(cos, t)| {
                (0..w).map(move |k| Row {
                    cos: *cos,
                    wavelength: k,
                    thickness_nm: t,
                })
            })
            .collect();
        let swept = self.prep.eval_rows(&split, &spectrum.wavelengths_nm)?;
        let ch = 2 * w;
        let nodes: usize = rows.iter().map(|r| r.1.len()).sum();
        let mut out = vec![0.0; nodes * ch];
        let (mut at, mut node) = (0, 0);
        for (_, t) in rows {
            let n = t.len();
            for k in 0..w {
                for i in 0..n {
                    let v = &swept[at + 2 * i..at + 2 * i + 2];
                    out[(node + i) * ch + k] = v[0];
                    out[(node + i) * ch + w + k] = v[1];
                }
                at += 2 * n;
            }
            node += n;
        }
        Ok(out)
    }

    /// The stack evaluated: a layerless stack gets a zero-thickness layer of
    /// the ambient medium.
    pub fn stack(&self) -> &Stack {
        &self.prep.stack
    }

    /// The varying layer, from 1.
    pub fn layer(&self) -> usize {
        self.prep.layer
    }

    /// Exact (R.r, R.g, R.b, T.r, T.g, T.b) at the thickness nodes of each
    /// row (cos θ, thicknesses nm), row after row.
    /// (A colour film.)
    pub fn rows(&self, rows: &[(f64, Vec<f64>)]) -> Result<Vec<[f64; 6]>> {
        Ok(sixes(&self.colour()?.rows_flat(rows)?))
    }

    /// This film when it holds colours, else an error.
    fn colour(&self) -> Result<&Film> {
        if self.is_spectral() {
            return Err(crate::error::Error::invalid(
                "film",
                "holds spectra, not six colour channels",
            ));
        }
        Ok(self)
    }

    /// Exact values at scattered (thickness nm, cos θ) points (with more
    /// points per nanometre where the film's fringes are narrower than the
    /// integration's step, as at the nodes of [`Self::rows`]).
    /// (A colour film.)
    pub fn points(&self, points: &[(f64, f64)]) -> Result<Vec<[f64; 6]>> {
        Ok(sixes(&self.colour()?.points_flat(points)?))
    }

    /// Exact values ([`Self::channels`] per point) at scattered (thickness
    /// nm, cos θ) points.
    pub fn points_flat(&self, points: &[(f64, f64)]) -> Result<Vec<f64>> {
        if self.is_spectral() {
            let rows: Vec<(f64, Vec<f64>)> = points.iter().map(|&(d, c)| (c, vec![d])).collect();
            return self.rows_flat(&rows);
        }
        let grid = &self.prep.stack_grid;
        let layer = self.prep.layer;
        points
            .par_iter()
            .map_init(
                || grid.thicknesses_nm().to_vec(),
                |thick, &(d, c)| {
                    thick[layer - 1] = d;
                    let sums = match &self.prep.refined {
                        Some(r) => r
                            .criterion
                            .weighted_spectrum(grid, &self.weights, thick, c)?,
                        None => grid.weighted_spectrum(thick, c, &self.weights),
                    };
                    let (r, t) = (sums.reflectance, sums.transmittance);
                    Ok([r[0], r[1], r[2], t[0], t[1], t[2]])
                },
            )
            .collect::<Result<Vec<[f64; 6]>>>()
            .map(|v| v.concat())
    }

    /// For a gain film, fails when `thickness_nm` × `cos` reaches (or
    /// crosses) a lasing pole: |R| or |T| beyond [`LASING_BOUND`], or not
    /// finite, on a grid over the domain. Checked before a size search,
    /// which would otherwise chase the pole's growing fringes to the size
    /// limit and name the wrong cause.
    pub fn check_lasing(&self, thickness_nm: (f64, f64), cos: (f64, f64)) -> Result<()> {
        let stack = self.stack();
        let gain = stack.layers.iter().any(|l| l.material.has_gain()) || stack.substrate.has_gain();
        if !gain {
            return Ok(());
        }
        let at =
            |(lo, hi): (f64, f64), k: usize, n: usize| lo + (hi - lo) * k as f64 / (n - 1) as f64;
        let (nt, nc) = LASING_GRID;
        let points: Vec<(f64, f64)> = (0..nc)
            .flat_map(|j| (0..nt).map(move |i| (i, j)))
            .map(|(i, j)| (at(thickness_nm, i, nt), at(cos, j, nc)))
            .collect();
        let values = self.points_flat(&points)?;
        let ch = self.channels();
        match values
            .chunks_exact(ch)
            .position(|v| v.iter().any(|x| !x.is_finite() || x.abs() > LASING_BOUND))
        {
            None => Ok(()),
            Some(k) => Err(Error::invalid(
                "gain film",
                format!(
                    "R or T exceeds {LASING_BOUND} or is not finite at thickness {:.3} nm, cos θ {:.6}: the range reaches a lasing pole; narrow --thickness or --angles",
                    points[k].0, points[k].1
                ),
            )),
        }
    }

    /// Where the colour integration of [`Self::rows`] and [`Self::points`]
    /// takes more points per nanometre (`None` for samplings never
    /// refined).
    pub fn refinement(&self) -> Option<&crate::color::refine::Refinement> {
        self.prep.refined.as_ref().map(|r| &r.criterion)
    }

    /// Exact values at every node of `chart` laid out as `width` × `height`
    /// nodes (its rectangle's size is ignored), row-major.
    /// (A colour film.)
    pub fn chart(&self, chart: &Chart, width: usize, height: usize) -> Result<Vec<[f64; 6]>> {
        Ok(sixes(&self.colour()?.chart_flat(chart, width, height)?))
    }

    /// [`Self::chart`] with [`Self::channels`] values per node.
    pub fn chart_flat(&self, chart: &Chart, width: usize, height: usize) -> Result<Vec<f64>> {
        let mut sized = *chart;
        sized.rect.width = width;
        sized.rect.height = height;
        match chart.coords {
            Coords::Band { .. } => {
                let rows: Vec<(f64, Vec<f64>)> = (0..height)
                    .map(|j| {
                        let c = sized.node(0, j).1;
                        (c, (0..width).map(|i| sized.node(i, j).0).collect())
                    })
                    .collect();
                self.rows_flat(&rows)
            }
            Coords::Corner { .. } => {
                let points: Vec<(f64, f64)> = (0..height)
                    .flat_map(|j| (0..width).map(move |i| (i, j)))
                    .map(|(i, j)| sized.node(i, j))
                    .collect();
                self.points_flat(&points)
            }
        }
    }
}

/// Six values at a time.
fn sixes(flat: &[f64]) -> Vec<[f64; 6]> {
    flat.chunks_exact(6)
        .map(|v| [v[0], v[1], v[2], v[3], v[4], v[5]])
        .collect()
}

/// The optical thickness factor of `layer` (from 1) of `stack` with real
/// indices at `reference_nm`.
pub(crate) fn optical_of(stack: &Stack, layer: usize, reference_nm: f64) -> Result<Optical> {
    let n0 = stack.ambient.index_at(reference_nm)?.re;
    let nj = stack.layers[layer - 1].material.index_at(reference_nm)?.re;
    Ok(Optical::new(n0, nj))
}

impl Film {
    /// The varying layer's sharpest fringe at one wavelength, cos θ and
    /// thickness: its round trip's amplitude and how much R changes across
    /// it (see [`crate::optics::twoport::VaryingLayer::fringe`]).
    pub fn fringe(&self, wavelength_nm: f64, c: f64, thickness_nm: f64) -> Result<(f64, f64)> {
        let stack = &self.prep.stack;
        let mut indices = Vec::new();
        stack.indices_at(wavelength_nm, &mut indices)?;
        let split = crate::optics::twoport::VaryingLayer::new(
            &indices,
            &stack.thicknesses_nm(),
            self.prep.layer,
            wavelength_nm,
            c,
            &mut Default::default(),
        );
        Ok(split.fringe(thickness_nm))
    }

    /// The largest weight one wavelength has in any colour channel: how much
    /// a change of R at one wavelength can move the colour.
    pub fn largest_weight(&self) -> f64 {
        self.largest_weight
    }

    /// For a lossless stack (no layer or substrate absorbs or amplifies),
    /// R + T: the colour of a flat spectrum, the same at every thickness and
    /// angle.
    pub fn lossless_white(&self) -> Option<[f64; 3]> {
        self.lossless_white
    }

    /// The wavelengths the colour integrates over, or a spectral film's
    /// wavelength nodes.
    pub fn wavelengths_nm(&self) -> &[f64] {
        match &self.spectrum {
            Some(s) => &s.wavelengths_nm,
            None => self.prep.stack_grid.wavelengths_nm(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::color::{Sampling, White};
    use crate::optics::{Layer, Material};

    fn soap() -> Stack {
        Stack {
            ambient: Material::constant(1.0, 0.0),
            layers: vec![Layer::new(Material::constant(1.33, 0.0), 500.0)],
            substrate: Material::constant(1.0, 0.0),
        }
    }

    fn film(stack: &Stack) -> Film {
        let integrator = SpectralIntegrator::with_white(Sampling::Uniform(41), White::D65);
        Film::new(stack, 1, integrator).unwrap()
    }

    /// Rows with unevenly spaced nodes (each phase an exact exponential)
    /// agree with the batched solver point by point.
    #[test]
    fn rows_match_points() {
        let mut stack = soap();
        stack.substrate = Material::constant(1.52, 0.0);
        stack
            .layers
            .push(Layer::new(Material::constant(2.1, 0.02), 80.0));
        let f = film(&stack);
        let rows: Vec<(f64, Vec<f64>)> = [0.02, 0.4, 1.0]
            .iter()
            .map(|&c| {
                (
                    c,
                    (0..37).map(|i| 3.7 * f64::from(i) * f64::from(i)).collect(),
                )
            })
            .collect();
        let got = f.rows(&rows).unwrap();
        let points: Vec<(f64, f64)> = rows
            .iter()
            .flat_map(|(c, t)| t.iter().map(move |&d| (d, *c)))
            .collect();
        let want = f.points(&points).unwrap();
        for (g, w) in got.iter().zip(&want) {
            for k in 0..6 {
                assert!((g[k] - w[k]).abs() < 1e-12, "{g:?} {w:?}");
            }
        }
    }

    /// A free-standing film's fringes sharpen without bound towards grazing
    /// incidence and stay visible; behind total internal reflection in a
    /// lossless stack they cannot show in R.
    #[test]
    fn fringes_sharpen_at_grazing_and_vanish_behind_total_reflection() {
        let f = film(&soap());
        let (y_grazing, vis_grazing) = f.fringe(500.0, 1e-3, 300.0).unwrap();
        let (y_normal, _) = f.fringe(500.0, 1.0, 300.0).unwrap();
        assert!(y_grazing > 0.99 && y_normal < 0.1, "{y_grazing} {y_normal}");
        assert!(vis_grazing > 0.5);
        let mut glass = soap();
        glass.ambient = Material::constant(1.5, 0.0);
        glass.layers[0].material = Material::constant(2.0, 0.0);
        let (y, visibility) = film(&glass).fringe(500.0, 0.3, 300.0).unwrap();
        assert!(y > 0.0 && visibility < 1e-9, "{y} {visibility}");
        // An absorbing layer's round trip fades with its thickness.
        let mut absorbing = soap();
        absorbing.layers[0].material = Material::constant(1.5, 0.15);
        let a = film(&absorbing);
        let (thin, _) = a.fringe(500.0, 1e-3, 10.0).unwrap();
        let (thick, _) = a.fringe(500.0, 1e-3, 500.0).unwrap();
        assert!(thick < 0.1 * thin, "{thin} {thick}");
    }
}
