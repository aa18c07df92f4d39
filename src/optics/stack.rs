//! A planar multilayer: a lossless ambient, finite layers from the top down,
//! and a semi-infinite substrate that may absorb.

use num_complex::Complex64 as C64;
use serde::{Deserialize, Serialize};

use super::incoherent::{solve_incoherent, Coherence, Diverged};
use super::lanes;
use super::material::Material;
use super::solver::Response;
use crate::error::{Error, Result};

/// The thickest layer accepted: a kilometre is no longer a film, and the bound
/// keeps k0 × thickness far from overflow at any accepted wavelength.
pub const MAX_THICKNESS_NM: f64 = 1e12;

/// Accepted vacuum wavelengths: 1 pm to 1 m, far beyond optics either way.
pub const WAVELENGTH_RANGE_NM: (f64, f64) = (1e-3, 1e9);

fn check_wavelength(wavelength_nm: f64) -> Result<()> {
    let (lo, hi) = WAVELENGTH_RANGE_NM;
    if (lo..=hi).contains(&wavelength_nm) {
        Ok(())
    } else {
        Err(Error::invalid(
            "wavelength",
            format!("{wavelength_nm} nm is outside {lo:e}–{hi:e} nm"),
        ))
    }
}

/// One film of a stack: a material and its physical thickness.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Layer {
    /// The film's complex index n + ik (k > 0 absorbs, k < 0 is gain).
    pub material: Material,
    /// Physical thickness in nanometres, 0 to [`MAX_THICKNESS_NM`].
    pub thickness_nm: f64,
    /// False for a layer thick against the light's coherence length (a
    /// glass sheet under a coating), whose inner reflections add in power
    /// ([`incoherent`](super::incoherent)). Left out of the serialized
    /// stack when true, so that a coherent stack's table headers and cache
    /// keys do not change.
    #[serde(default = "coherent_by_default", skip_serializing_if = "is_coherent")]
    pub coherent: bool,
}

fn coherent_by_default() -> bool {
    true
}

fn is_coherent(coherent: &bool) -> bool {
    *coherent
}

impl Layer {
    /// A coherent layer.
    pub fn new(material: Material, thickness_nm: f64) -> Layer {
        Layer {
            material,
            thickness_nm,
            coherent: true,
        }
    }
}

/// A planar multilayer seen from its ambient side: light arrives through the
/// `ambient` (lossless, semi-infinite), crosses the `layers` top down and
/// enters the semi-infinite `substrate`, which may absorb. Indices are
/// n + ik with k > 0 absorbing, fields vary as e^{-iωt}, and angles are
/// measured in the ambient from the normal. [`Stack::validate`] checks
/// these constraints; the stack file format is `docs/stack-format.md`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Stack {
    /// The medium the light comes from (air, water, glass): must be lossless.
    pub ambient: Material,
    /// The films from the ambient side down; may be empty (a bare interface).
    pub layers: Vec<Layer>,
    /// The medium below the last layer: may absorb (a metal), not amplify.
    pub substrate: Material,
}

impl Stack {
    /// Checks the physical constraints the solver relies on.
    pub fn validate(&self) -> Result<()> {
        let check = |field: String, m: &Material| {
            m.check().map_err(|e| Error::invalid(field, e.to_string()))
        };
        check("ambient".into(), &self.ambient)?;
        check("substrate".into(), &self.substrate)?;
        for (i, layer) in self.layers.iter().enumerate() {
            check(format!("layers[{}]", i + 1), &layer.material)?;
        }
        if !self.ambient.is_lossless() {
            return Err(Error::invalid(
                "ambient",
                format!("must be lossless (k = 0), got {}", self.ambient.name),
            ));
        }
        if self.substrate.has_gain() {
            return Err(Error::invalid(
                "substrate",
                format!(
                    "gain (k < 0) is only allowed in finite layers, got {}",
                    self.substrate.name
                ),
            ));
        }
        for (i, layer) in self.layers.iter().enumerate() {
            if !(0.0..=MAX_THICKNESS_NM).contains(&layer.thickness_nm) {
                return Err(Error::invalid(
                    format!("layers[{}].thickness_nm", i + 1),
                    if layer.thickness_nm.is_nan() {
                        "must be a number ≥ 0".to_string()
                    } else {
                        format!(
                            "must be finite, ≥ 0 and ≤ {MAX_THICKNESS_NM:e}, got {}",
                            layer.thickness_nm
                        )
                    },
                ));
            }
        }
        Ok(())
    }

    /// Writes the indices of ambient, layers and substrate at one wavelength
    /// into `out` (cleared first), N + 2 entries.
    pub fn indices_at(&self, wavelength_nm: f64, out: &mut Vec<C64>) -> Result<()> {
        check_wavelength(wavelength_nm)?;
        out.clear();
        let ambient = self.ambient.index_at(wavelength_nm)?;
        out.push(C64::new(ambient.re, 0.0));
        for layer in &self.layers {
            out.push(layer.material.index_at(wavelength_nm)?);
        }
        out.push(self.substrate.index_at(wavelength_nm)?);
        Ok(())
    }

    /// The N layer thicknesses in nm, top (ambient side) down: the
    /// `thicknesses_nm` argument of [`solve`](super::solver::solve).
    pub fn thicknesses_nm(&self) -> Vec<f64> {
        self.layers.iter().map(|l| l.thickness_nm).collect()
    }

    /// Which layers are incoherent, as the mixed solvers take it.
    pub fn coherence(&self) -> Coherence {
        Coherence::from_flags(self.layers.iter().map(|l| l.coherent))
    }

    /// True when every layer is coherent.
    pub fn is_coherent(&self) -> bool {
        self.layers.iter().all(|l| l.coherent)
    }

    /// The same stack seen from the substrate side: the substrate becomes
    /// the ambient (it must then be lossless) and the layers are reversed.
    pub fn reversed(&self) -> Stack {
        Stack {
            ambient: self.substrate.clone(),
            layers: self.layers.iter().rev().cloned().collect(),
            substrate: self.ambient.clone(),
        }
    }

    /// Convenience: R and T at one wavelength and incidence angle
    /// (allocates; the hot paths call [`solve`](super::solver::solve) with reused buffers).
    /// Fails, naming the layer, where an incoherent gain layer lases.
    pub fn response(&self, wavelength_nm: f64, cos_theta0: f64) -> Result<Response> {
        let mut n = Vec::with_capacity(self.layers.len() + 2);
        self.indices_at(wavelength_nm, &mut n)?;
        solve_incoherent(
            &n,
            &self.thicknesses_nm(),
            &self.coherence(),
            wavelength_nm,
            cos_theta0,
        )
        .map_err(|d| d.error(wavelength_nm, cos_theta0))
    }
}

/// A stack's indices evaluated once over a list of wavelengths, ready for
/// [`solve_batch`](super::solver::solve_batch): the per-stack work (dispersion formulas, table
/// look-ups, validation) done once, so that sweeping angles and thicknesses
/// allocates nothing and evaluates no material.
#[derive(Clone, Debug, PartialEq)]
pub struct StackGrid {
    wavelengths_nm: Vec<f64>,
    /// Wavelength-major: the N + 2 indices of wavelength i at [i(N+2), (i+1)(N+2)).
    indices: Vec<C64>,
    thicknesses_nm: Vec<f64>,
    /// Which layers are incoherent.
    coherence: Coherence,
    /// The same indices laid out for the four-lane solver.
    spectrum: lanes::Spectrum,
}

impl StackGrid {
    /// Validates the stack and evaluates every medium at every wavelength;
    /// fails (naming the material) if a wavelength lies outside a table.
    pub fn new(stack: &Stack, wavelengths_nm: &[f64]) -> Result<StackGrid> {
        stack.validate()?;
        let media = stack.layers.len() + 2;
        let mut indices = Vec::with_capacity(media * wavelengths_nm.len());
        let mut row = Vec::with_capacity(media);
        for &wl in wavelengths_nm {
            stack.indices_at(wl, &mut row)?;
            indices.extend_from_slice(&row);
        }
        Ok(StackGrid {
            spectrum: lanes::Spectrum::new(&indices, media, wavelengths_nm),
            wavelengths_nm: wavelengths_nm.to_vec(),
            indices,
            thicknesses_nm: stack.thicknesses_nm(),
            coherence: stack.coherence(),
        })
    }

    /// A grid of indices the caller already has: `indices` wavelength-major,
    /// N + 2 per wavelength (ambient, layers, substrate), for the N layers of
    /// `thicknesses_nm`. The caller has checked the physics ([`Stack::validate`]'s
    /// constraints on each row); this only lays the indices out.
    ///
    /// # Panics
    /// If `indices` does not hold N + 2 values per wavelength.
    pub fn from_indices(
        indices: Vec<C64>,
        thicknesses_nm: Vec<f64>,
        wavelengths_nm: &[f64],
    ) -> StackGrid {
        let media = thicknesses_nm.len() + 2;
        assert_eq!(
            indices.len(),
            media * wavelengths_nm.len(),
            "indices: N + 2 per wavelength"
        );
        StackGrid {
            spectrum: lanes::Spectrum::new(&indices, media, wavelengths_nm),
            wavelengths_nm: wavelengths_nm.to_vec(),
            indices,
            thicknesses_nm,
            coherence: Coherence::coherent(),
        }
    }

    /// The same grid with the layers `coherence` names incoherent (every
    /// layer is coherent in a grid made by [`StackGrid::from_indices`]).
    ///
    /// # Panics
    /// If `coherence` names a layer the grid does not have.
    pub fn with_coherence(mut self, coherence: Coherence) -> StackGrid {
        assert!(
            coherence
                .incoherent_layers()
                .iter()
                .all(|&l| (1..=self.thicknesses_nm.len()).contains(&l)),
            "coherence: a layer the grid does not have"
        );
        self.coherence = coherence;
        self
    }

    /// Which layers are incoherent.
    pub fn coherence(&self) -> &Coherence {
        &self.coherence
    }

    /// True when every medium has the same index at every wavelength.
    pub fn is_non_dispersive(&self) -> bool {
        self.spectrum.is_non_dispersive()
    }

    /// The vacuum wavelengths in nm the indices were evaluated at, in the
    /// order given to [`StackGrid::new`].
    pub fn wavelengths_nm(&self) -> &[f64] {
        &self.wavelengths_nm
    }

    /// The stack's N layer thicknesses in nm, top down, as they were
    /// when the grid was built.
    pub fn thicknesses_nm(&self) -> &[f64] {
        &self.thicknesses_nm
    }

    /// All indices, wavelength-major (N + 2 per wavelength).
    pub fn indices(&self) -> &[C64] {
        &self.indices
    }

    /// The N + 2 indices at the `i`-th wavelength.
    pub fn indices_at(&self, i: usize) -> &[C64] {
        let media = self.thicknesses_nm.len() + 2;
        &self.indices[i * media..(i + 1) * media]
    }

    /// Each wavelength with its N + 2 indices, in order.
    pub fn iter(&self) -> impl Iterator<Item = (f64, &[C64])> + '_ {
        let media = self.thicknesses_nm.len() + 2;
        self.wavelengths_nm
            .iter()
            .copied()
            .zip(self.indices.chunks_exact(media))
    }

    /// R and T at every wavelength at one angle, with the N layer
    /// thicknesses given (e.g. the stack's own with one varied), into `out`
    /// (one per wavelength): the spectrum of one point, the batched solver's
    /// fastest entry (indices and 2π/λ are laid out once, in [`StackGrid::new`]).
    /// Allocates nothing.
    ///
    /// # Panics
    /// If `thicknesses_nm` or `out` has the wrong length.
    pub fn solve_spectrum(&self, thicknesses_nm: &[f64], cos_theta0: f64, out: &mut [Response]) {
        self.solve_spectrum_on(lanes::Path::Best, thicknesses_nm, cos_theta0, out);
    }

    /// [`StackGrid::solve_spectrum`] on a chosen copy of the kernel.
    pub fn solve_spectrum_on(
        &self,
        path: lanes::Path,
        thicknesses_nm: &[f64],
        cos_theta0: f64,
        out: &mut [Response],
    ) {
        lanes::solve_spectrum_on(
            path,
            &self.spectrum,
            &self.indices,
            thicknesses_nm,
            &self.coherence,
            cos_theta0,
            out,
        );
    }

    /// [`StackGrid::solve_spectrum`] folded into three weighted sums of R and
    /// of T (a colour) as it is solved: the same sums as integrating the
    /// stored spectrum with the same weights, without storing it.
    ///
    /// # Panics
    /// If `thicknesses_nm` has the wrong length or `weights` does not have one
    /// weight per wavelength.
    pub fn weighted_spectrum(
        &self,
        thicknesses_nm: &[f64],
        cos_theta0: f64,
        weights: &lanes::SpectralWeights,
    ) -> lanes::WeightedPower {
        self.weighted_spectrum_on(lanes::Path::Best, thicknesses_nm, cos_theta0, weights)
    }

    /// [`StackGrid::weighted_spectrum`] on a chosen copy of the kernel.
    pub fn weighted_spectrum_on(
        &self,
        path: lanes::Path,
        thicknesses_nm: &[f64],
        cos_theta0: f64,
        weights: &lanes::SpectralWeights,
    ) -> lanes::WeightedPower {
        lanes::weighted_spectrum_on(
            path,
            &self.spectrum,
            &self.indices,
            thicknesses_nm,
            &self.coherence,
            cos_theta0,
            weights,
        )
    }

    /// R and T at every (wavelength, cos θ0) pair, wavelength-major, into
    /// `out` (length wavelengths × angles). Allocates nothing. Where an
    /// incoherent gain layer lases, R and T are +∞
    /// ([`solve_mixed`](super::incoherent::solve_mixed); find such points
    /// with [`Self::check_solved`]).
    ///
    /// # Panics
    /// If `out` has the wrong length.
    pub fn solve(&self, cos_theta0: &[f64], out: &mut [Response]) {
        assert_eq!(
            out.len(),
            self.wavelengths_nm.len() * cos_theta0.len(),
            "out: wavelengths × angles"
        );
        lanes::solve_batch_mixed_on(
            lanes::Path::Best,
            &self.indices,
            &self.thicknesses_nm,
            &self.coherence,
            &self.wavelengths_nm,
            cos_theta0,
            out,
        );
    }

    /// The lasing layer at the `i`-th wavelength and `cos_theta0` with
    /// `thicknesses_nm`, where an incoherent gain layer's round trips have
    /// no finite sum (a point [`Self::solve`] gives as +∞); `None` elsewhere.
    /// [`Diverged::error`] turns it into the one-line error.
    pub fn diverged(&self, i: usize, thicknesses_nm: &[f64], cos_theta0: f64) -> Option<Diverged> {
        solve_incoherent(
            self.indices_at(i),
            thicknesses_nm,
            &self.coherence,
            self.wavelengths_nm[i],
            cos_theta0,
        )
        .err()
    }

    /// Ok unless a point of `out`, as [`Self::solve`] gave it for
    /// `cos_theta0` with the grid's own thicknesses, is one where an
    /// incoherent gain layer lases: then the first such point's one-line
    /// error ([`Diverged::error`]).
    pub fn check_solved(&self, cos_theta0: &[f64], out: &[Response]) -> Result<()> {
        let Some(i) = out.iter().position(|r| !r.is_finite()) else {
            return Ok(());
        };
        let (w, a) = (i / cos_theta0.len(), i % cos_theta0.len());
        match self.diverged(w, &self.thicknesses_nm, cos_theta0[a]) {
            Some(d) => Err(d.error(self.wavelengths_nm[w], cos_theta0[a])),
            None => Ok(()),
        }
    }
}
