//! A planar multilayer: a lossless ambient, finite layers from the top down,
//! and a semi-infinite substrate that may absorb.

use num_complex::Complex64 as C64;
use serde::{Deserialize, Serialize};

use super::material::Material;
use super::solver::{self, Response};
use crate::error::{Error, Result};

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Layer {
    pub material: Material,
    pub thickness_nm: f64,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Stack {
    pub ambient: Material,
    pub layers: Vec<Layer>,
    pub substrate: Material,
}

impl Stack {
    /// Checks the physical constraints the solver relies on.
    pub fn validate(&self) -> Result<()> {
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
            if !(layer.thickness_nm.is_finite() && layer.thickness_nm >= 0.0) {
                return Err(Error::invalid(
                    format!("layers[{}].thickness_nm", i + 1),
                    format!("must be finite and ≥ 0, got {}", layer.thickness_nm),
                ));
            }
        }
        Ok(())
    }

    /// Writes the indices of ambient, layers and substrate at one wavelength
    /// into `out` (cleared first), N + 2 entries.
    pub fn indices_at(&self, wavelength_nm: f64, out: &mut Vec<C64>) -> Result<()> {
        out.clear();
        let ambient = self.ambient.index_at(wavelength_nm)?;
        out.push(C64::new(ambient.re, 0.0));
        for layer in &self.layers {
            out.push(layer.material.index_at(wavelength_nm)?);
        }
        out.push(self.substrate.index_at(wavelength_nm)?);
        Ok(())
    }

    pub fn thicknesses_nm(&self) -> Vec<f64> {
        self.layers.iter().map(|l| l.thickness_nm).collect()
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
    /// (allocates; the hot paths call [`solver::solve`] with reused buffers).
    pub fn response(&self, wavelength_nm: f64, cos_theta0: f64) -> Result<Response> {
        let mut n = Vec::with_capacity(self.layers.len() + 2);
        self.indices_at(wavelength_nm, &mut n)?;
        Ok(solver::solve(
            &n,
            &self.thicknesses_nm(),
            wavelength_nm,
            cos_theta0,
        ))
    }
}
