//! Refractive-index models: a material's complex index as a function of
//! vacuum wavelength. k > 0 absorbs, k < 0 is gain.

use num_complex::Complex64 as C64;
use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};

/// A tabulated index, linearly interpolated in wavelength.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct IndexTable {
    /// Where the data came from (a built-in's citation, or the CSV path).
    pub source: String,
    /// Strictly increasing.
    pub wavelength_nm: Vec<f64>,
    pub n: Vec<f64>,
    pub k: Vec<f64>,
}

/// A dispersion model.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Dispersion {
    /// The same n + ik at every wavelength.
    Constant {
        n: f64,
        k: f64,
    },
    /// n(λ) = A + B/λ² + C/λ⁴ with λ in micrometres; k = 0.
    Cauchy {
        a: f64,
        b: f64,
        c: f64,
    },
    /// n²(λ) = 1 + Σ Bᵢ λ² / (λ² − Cᵢ) with λ and √Cᵢ in micrometres; k = 0.
    Sellmeier {
        b: Vec<f64>,
        c: Vec<f64>,
    },
    Table(IndexTable),
}

/// A named material: its dispersion and a label used in messages and headers.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Material {
    pub name: String,
    pub dispersion: Dispersion,
}

impl Material {
    pub fn constant(n: f64, k: f64) -> Self {
        Material {
            name: if k == 0.0 {
                format!("n={n}")
            } else {
                format!("n={n}{k:+}i")
            },
            dispersion: Dispersion::Constant { n, k },
        }
    }

    /// The complex index at a vacuum wavelength, or an error naming the
    /// material when the wavelength lies outside a table's range.
    pub fn index_at(&self, wavelength_nm: f64) -> Result<C64> {
        let um = wavelength_nm * 1e-3;
        match &self.dispersion {
            Dispersion::Constant { n, k } => Ok(C64::new(*n, *k)),
            Dispersion::Cauchy { a, b, c } => {
                let l2 = um * um;
                Ok(C64::new(a + b / l2 + c / (l2 * l2), 0.0))
            }
            Dispersion::Sellmeier { b, c } => {
                let l2 = um * um;
                let n2 = 1.0 + b.iter().zip(c).map(|(b, c)| b * l2 / (l2 - c)).sum::<f64>();
                if n2 <= 0.0 {
                    return Err(Error::invalid(
                        format!("material {}", self.name),
                        format!("Sellmeier n² = {n2} ≤ 0 at {wavelength_nm} nm (near a pole)"),
                    ));
                }
                Ok(C64::new(n2.sqrt(), 0.0))
            }
            Dispersion::Table(t) => t.index_at(wavelength_nm).ok_or_else(|| {
                Error::invalid(
                    format!("material {}", self.name),
                    format!(
                        "wavelength {wavelength_nm} nm is outside its table ({}–{} nm)",
                        t.wavelength_nm[0],
                        t.wavelength_nm[t.wavelength_nm.len() - 1]
                    ),
                )
            }),
        }
    }

    /// The wavelength range over which the material is defined.
    pub fn range_nm(&self) -> (f64, f64) {
        match &self.dispersion {
            Dispersion::Table(t) => (
                t.wavelength_nm[0],
                t.wavelength_nm[t.wavelength_nm.len() - 1],
            ),
            _ => (0.0, f64::INFINITY),
        }
    }

    /// True when the index has no imaginary part anywhere.
    pub fn is_lossless(&self) -> bool {
        match &self.dispersion {
            Dispersion::Constant { k, .. } => *k == 0.0,
            Dispersion::Cauchy { .. } | Dispersion::Sellmeier { .. } => true,
            Dispersion::Table(t) => t.k.iter().all(|&k| k == 0.0),
        }
    }

    /// True when some wavelength has k < 0.
    pub fn has_gain(&self) -> bool {
        match &self.dispersion {
            Dispersion::Constant { k, .. } => *k < 0.0,
            Dispersion::Cauchy { .. } | Dispersion::Sellmeier { .. } => false,
            Dispersion::Table(t) => t.k.iter().any(|&k| k < 0.0),
        }
    }
}

impl IndexTable {
    /// Linear interpolation; `None` outside the tabulated range.
    pub fn index_at(&self, wavelength_nm: f64) -> Option<C64> {
        let w = &self.wavelength_nm;
        if !(wavelength_nm >= w[0] && wavelength_nm <= w[w.len() - 1]) {
            return None;
        }
        let hi = w
            .partition_point(|&x| x < wavelength_nm)
            .clamp(1, w.len() - 1);
        let lo = hi - 1;
        let t = (wavelength_nm - w[lo]) / (w[hi] - w[lo]);
        Some(C64::new(
            self.n[lo] + t * (self.n[hi] - self.n[lo]),
            self.k[lo] + t * (self.k[hi] - self.k[lo]),
        ))
    }
}
