//! Refractive-index models: a material's complex index as a function of
//! vacuum wavelength. k > 0 absorbs, k < 0 is gain.

use std::path::Path;

use num_complex::Complex64 as C64;
use serde::{Deserialize, Serialize};

use crate::error::{short_number, Error, Result};

/// A tabulated index, linearly interpolated in wavelength.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct IndexTable {
    /// Where the data came from (a built-in's citation, or the CSV path).
    pub source: String,
    /// Strictly increasing.
    pub wavelength_nm: Vec<f64>,
    /// Real part of the index at each wavelength (0 ≤ n ≤ [`MAX_INDEX`]),
    /// same length as `wavelength_nm`.
    pub n: Vec<f64>,
    /// Extinction coefficient at each wavelength, same length as
    /// `wavelength_nm`: k > 0 absorbs, k < 0 is gain, |k| ≤ [`MAX_INDEX`].
    pub k: Vec<f64>,
}

/// A dispersion model.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Dispersion {
    /// The same n + ik at every wavelength.
    Constant {
        /// Real part of the index (0 ≤ n ≤ [`MAX_INDEX`]).
        n: f64,
        /// Extinction coefficient: k > 0 absorbs, k < 0 is gain.
        k: f64,
    },
    /// n(λ) = A + B/λ² + C/λ⁴ with λ in micrometres; k = 0.
    Cauchy {
        /// The constant term A (dimensionless).
        a: f64,
        /// B, in µm².
        b: f64,
        /// C, in µm⁴.
        c: f64,
    },
    /// n²(λ) = A + Σ Bᵢ λ² / (λ² − Cᵢ) with λ in micrometres and Cᵢ in µm²;
    /// k = 0. A is 1 in the classic form; some fits (the built-in air's
    /// rewriting of Ciddor's formula) carry a constant of their own.
    Sellmeier {
        #[serde(default = "one")]
        /// The constant term A (defaults to 1 when absent from a file).
        a: f64,
        /// The oscillator strengths Bᵢ (dimensionless), one per term.
        b: Vec<f64>,
        /// The resonance terms Cᵢ in µm² (squared resonance wavelengths),
        /// as many as `b`.
        c: Vec<f64>,
    },
    /// Tabulated n and k, linearly interpolated in wavelength; an error
    /// outside the table's range.
    Table(IndexTable),
}

/// A named material: its dispersion and a label used in messages and headers.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Material {
    /// The label that names the material in error messages and table
    /// headers: a built-in's name, the `name` given in a stack file, or one
    /// derived from the index form (e.g. the Cauchy coefficients or the
    /// table's path).
    pub name: String,
    /// How the complex index n + ik varies with vacuum wavelength.
    pub dispersion: Dispersion,
}

fn one() -> f64 {
    1.0
}

/// Largest |n| or |k| accepted: far beyond any material (metals in the far
/// infrared reach about 100), and small enough that the solver's n² and
/// |n|² stay far inside the range of f64.
pub const MAX_INDEX: f64 = 1e6;

/// Smallest |n + ik| accepted. The solver squares indices and divides by
/// them (n², n⁴ in the p-polarized admittances): below about 1e-9 those
/// underflow or lose the digits that separate s from p, and n = 1e-320
/// gave NaN. 1e-6, the mirror of [`MAX_INDEX`], keeps every product far
/// inside f64 and is far below any material (silver's n is about 0.05).
pub const MIN_INDEX: f64 = 1e-6;

/// Whether a complex index lies in the range the solver computes exactly.
fn index_in_range(n: f64, k: f64) -> bool {
    (0.0..=MAX_INDEX).contains(&n) && k.abs() <= MAX_INDEX && n.hypot(k) >= MIN_INDEX
}

impl Material {
    /// A wavelength-independent index; see [`Material::check`] for the
    /// values it accepts.
    pub fn constant(n: f64, k: f64) -> Self {
        Material {
            name: if k == 0.0 {
                format!("n={}", short_number(n))
            } else {
                let sign = if k.is_sign_negative() { "" } else { "+" };
                format!("n={}{sign}{}i", short_number(n), short_number(k))
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
                let n = a + b / l2 + c / (l2 * l2);
                if !(MIN_INDEX..=MAX_INDEX).contains(&n) {
                    return Err(Error::invalid(
                        format!("material {}", self.name),
                        format!(
                            "Cauchy n = {n:e} at {wavelength_nm} nm is outside {MIN_INDEX:e}–{MAX_INDEX:e}"
                        ),
                    ));
                }
                Ok(C64::new(n, 0.0))
            }
            Dispersion::Sellmeier { a, b, c } => {
                let l2 = um * um;
                let n2 = a + b.iter().zip(c).map(|(b, c)| b * l2 / (l2 - c)).sum::<f64>();
                if !(MIN_INDEX * MIN_INDEX..=MAX_INDEX * MAX_INDEX).contains(&n2) {
                    return Err(Error::invalid(
                        format!("material {}", self.name),
                        format!(
                            "Sellmeier n² = {n2:e} at {wavelength_nm} nm (near a pole) puts n outside {MIN_INDEX:e}–{MAX_INDEX:e}"
                        ),
                    ));
                }
                Ok(C64::new(n2.sqrt(), 0.0))
            }
            Dispersion::Table(t) => {
                let index = t.index_at(wavelength_nm).ok_or_else(|| {
                    Error::invalid(
                        format!("material {}", self.name),
                        format!(
                            "wavelength {wavelength_nm} nm is outside its table ({}–{} nm)",
                            self.range_nm().0,
                            self.range_nm().1
                        ),
                    )
                })?;
                // Rows are checked, but between two rows whose k differ in
                // sign the interpolated index can pass near zero.
                if !index_in_range(index.re, index.im) {
                    return Err(Error::invalid(
                        format!("material {}", self.name),
                        format!(
                            "interpolated index {:e}{:+e}i at {wavelength_nm} nm is below {MIN_INDEX:e} in magnitude",
                            index.re, index.im
                        ),
                    ));
                }
                Ok(index)
            }
        }
    }

    /// Checks the model's parameters: finite numbers, 0 ≤ n ≤ [`MAX_INDEX`],
    /// |k| ≤ [`MAX_INDEX`], |n + ik| ≥ [`MIN_INDEX`] (the solver divides by
    /// n²), Sellmeier
    /// lists of equal length.
    pub fn check(&self) -> Result<()> {
        let bad = |why: String| Err(Error::invalid(format!("material {}", self.name), why));
        let index_ok = index_in_range;
        match &self.dispersion {
            Dispersion::Constant { n, k } => {
                if !index_ok(*n, *k) {
                    return bad(format!(
                        "index {n:e}{k:+e}i must have 0 ≤ n ≤ {MAX_INDEX:e}, |k| ≤ {MAX_INDEX:e} and |n + ik| ≥ {MIN_INDEX:e}"
                    ));
                }
            }
            Dispersion::Cauchy { a, b, c } => {
                if ![a, b, c].iter().all(|v| v.is_finite()) {
                    return bad("Cauchy coefficients must be finite".into());
                }
            }
            Dispersion::Sellmeier { a, b, c } => {
                if b.is_empty() || b.len() != c.len() {
                    return bad(format!(
                        "Sellmeier needs as many b as c terms, at least one (got {} and {})",
                        b.len(),
                        c.len()
                    ));
                }
                if !(a.is_finite() && b.iter().chain(c).all(|v| v.is_finite())) {
                    return bad("Sellmeier coefficients must be finite".into());
                }
            }
            Dispersion::Table(t) => {
                t.check()?;
                if let Some(i) = (0..t.n.len()).find(|&i| !index_ok(t.n[i], t.k[i])) {
                    return bad(format!(
                        "table row {} ({} nm): index {:e}{:+e}i must have 0 ≤ n ≤ {MAX_INDEX:e}, |k| ≤ {MAX_INDEX:e} and |n + ik| ≥ {MIN_INDEX:e}",
                        i + 1,
                        t.wavelength_nm[i],
                        t.n[i],
                        t.k[i]
                    ));
                }
            }
        }
        Ok(())
    }

    /// The wavelength range over which the material is defined.
    pub fn range_nm(&self) -> (f64, f64) {
        match &self.dispersion {
            Dispersion::Table(t) => (
                t.wavelength_nm.first().copied().unwrap_or(f64::NAN),
                t.wavelength_nm.last().copied().unwrap_or(f64::NAN),
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
    /// A table from columns, checked: at least two rows, equal lengths,
    /// finite values, strictly increasing positive wavelengths.
    pub fn new(
        source: impl Into<String>,
        wavelength_nm: Vec<f64>,
        n: Vec<f64>,
        k: Vec<f64>,
    ) -> Result<Self> {
        let table = IndexTable {
            source: source.into(),
            wavelength_nm,
            n,
            k,
        };
        table.check()?;
        Ok(table)
    }

    /// The checks of [`IndexTable::new`], for a table built or read otherwise
    /// (a stack embedded in a file header, say).
    pub fn check(&self) -> Result<()> {
        let (source, wavelength_nm, n, k) = (&self.source, &self.wavelength_nm, &self.n, &self.k);
        let bad = |why: String| Err(Error::invalid(format!("table {source}"), why));
        if wavelength_nm.len() != n.len() || n.len() != k.len() {
            return bad("columns of unequal length".into());
        }
        if wavelength_nm.len() < 2 {
            return bad(format!(
                "needs at least 2 rows, got {}",
                wavelength_nm.len()
            ));
        }
        if let Some(i) = wavelength_nm
            .iter()
            .position(|w| !(w.is_finite() && *w > 0.0))
        {
            return bad(format!(
                "row {}: wavelength {} is not positive",
                i + 1,
                wavelength_nm[i]
            ));
        }
        if let Some(i) = wavelength_nm.windows(2).position(|w| w[1] <= w[0]) {
            return bad(format!(
                "row {}: wavelengths must increase strictly ({} after {})",
                i + 2,
                wavelength_nm[i + 1],
                wavelength_nm[i]
            ));
        }
        Ok(())
    }

    /// Reads a CSV in the layout refractiveindex.info exports: wavelength in
    /// micrometres, then n, then k (optional, 0 when absent), separated by
    /// commas or white space. Lines that do not start with a number (headers,
    /// `#` comments) are skipped, except that a header whose second column is
    /// `k` starts a block of (wavelength, k) rows: the site's export of a
    /// material with both n and k puts them in two such blocks. Two blocks
    /// on different wavelength grids are merged on the union of both grids,
    /// each interpolated linearly, over the range they share.
    pub fn load_csv(path: &Path) -> Result<Self> {
        let text = crate::limits::read_text(path)?;
        Self::parse_csv(&text, &path.display().to_string())
    }

    /// [`IndexTable::load_csv`] on text already read; `origin` names it in errors.
    pub fn parse_csv(text: &str, origin: &str) -> Result<Self> {
        let bad =
            |line: usize, why: String| Err(Error::malformed(origin, format!("line {line}: {why}")));
        // (wavelength µm, n, k) rows, and (wavelength µm, k) rows of a k block.
        let mut nk: Vec<(f64, f64, f64)> = Vec::new();
        let mut k_block: Vec<(f64, f64)> = Vec::new();
        let mut in_k_block = false;
        for (i, raw) in text.lines().enumerate() {
            let line = raw.trim();
            let fields: Vec<&str> = line
                .split(|c: char| c == ',' || c == ';' || c.is_whitespace())
                .filter(|f| !f.is_empty())
                .collect();
            let starts_numeric = fields.first().is_some_and(|f| {
                f.starts_with(|c: char| c.is_ascii_digit() || c == '.' || c == '-' || c == '+')
            });
            if !starts_numeric {
                if fields.len() >= 2 && !line.starts_with('#') {
                    in_k_block = fields[1].eq_ignore_ascii_case("k");
                }
                continue;
            }
            let mut values = Vec::with_capacity(3);
            for f in &fields {
                match f.parse::<f64>() {
                    Ok(v) if v.is_finite() => values.push(v),
                    _ => return bad(i + 1, format!("'{f}' is not a finite number")),
                }
            }
            match (in_k_block, values.len()) {
                (true, 2) => k_block.push((values[0], values[1])),
                (false, 2) => nk.push((values[0], values[1], 0.0)),
                (false, 3) => nk.push((values[0], values[1], values[2])),
                (_, count) => {
                    return bad(
                        i + 1,
                        format!(
                            "expected {} columns, got {count}",
                            if in_k_block {
                                "2 (wavelength, k)"
                            } else {
                                "2 or 3 (wavelength µm, n[, k])"
                            }
                        ),
                    )
                }
            }
        }
        let to_nm = |um: f64| um * 1e3;
        let table = if k_block.is_empty() {
            Self::new(
                origin,
                nk.iter().map(|r| to_nm(r.0)).collect(),
                nk.iter().map(|r| r.1).collect(),
                nk.iter().map(|r| r.2).collect(),
            )
        } else {
            let n_only = Self::new(
                origin,
                nk.iter().map(|r| to_nm(r.0)).collect(),
                nk.iter().map(|r| r.1).collect(),
                vec![0.0; nk.len()],
            )?;
            let k_only = Self::new(
                origin,
                k_block.iter().map(|r| to_nm(r.0)).collect(),
                k_block.iter().map(|r| r.1).collect(),
                vec![0.0; k_block.len()],
            )?;
            merge_n_k(origin, &n_only, &k_only)
        }
        .map_err(|e| Error::malformed(origin, e.to_string()))?;
        Ok(table)
    }

    /// Linear interpolation; `None` outside the tabulated range.
    pub fn index_at(&self, wavelength_nm: f64) -> Option<C64> {
        let w = &self.wavelength_nm;
        // A table deserialized from a file may be empty: no panic, just None.
        if w.len() < 2
            || self.n.len() != w.len()
            || self.k.len() != w.len()
            || !(wavelength_nm >= w[0] && wavelength_nm <= w[w.len() - 1])
        {
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

/// Joins an n table and a k table (both in their `n` column) on the union of
/// their wavelength grids, over the range both cover.
fn merge_n_k(origin: &str, n: &IndexTable, k: &IndexTable) -> Result<IndexTable> {
    let lo = n.wavelength_nm[0].max(k.wavelength_nm[0]);
    let hi =
        n.wavelength_nm[n.wavelength_nm.len() - 1].min(k.wavelength_nm[k.wavelength_nm.len() - 1]);
    let mut grid: Vec<f64> = n
        .wavelength_nm
        .iter()
        .chain(&k.wavelength_nm)
        .copied()
        .filter(|w| (lo..=hi).contains(w))
        .collect();
    grid.sort_by(f64::total_cmp);
    grid.dedup();
    let column = |t: &IndexTable| -> Vec<f64> {
        grid.iter()
            .filter_map(|&w| t.index_at(w))
            .map(|z| z.re)
            .collect()
    };
    let (n_col, k_col) = (column(n), column(k));
    IndexTable::new(origin, grid.clone(), n_col, k_col)
}
