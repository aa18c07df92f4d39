//! Fitting thicknesses to a measured spectrum: the measurement, the model
//! (the stack's unpolarized R and T with their exact thickness
//! derivatives) and the weighted residuals (model − measured)/σ.

use super::search::{Loss, Model};
use super::vary::Vary;
use crate::error::{Error, Result};
use crate::optics::gradient::solve_stack_grid_with_gradient;
use crate::optics::{Response, Stack, StackGrid, WAVELENGTH_RANGE_NM};

/// A measured spectrum: rows of (wavelength, angle) with R and/or T, and
/// optionally each row's standard deviation.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Measurement {
    /// Vacuum wavelength of each row, nm.
    pub wavelength_nm: Vec<f64>,
    /// Angle of incidence in the ambient of each row, degrees in [0, 90).
    pub angle_deg: Vec<f64>,
    /// Unpolarized reflectance per row, if measured.
    pub reflectance: Option<Vec<f64>>,
    /// Unpolarized transmittance (power into the substrate) per row, if measured.
    pub transmittance: Option<Vec<f64>>,
    /// The standard deviation of R and T in each row; `None`: unknown, every
    /// row weighs the same and σ_nm is scaled by the fit's own scatter.
    pub sigma: Option<Vec<f64>>,
}

/// The measured points grouped by angle, in the residuals' order: per
/// angle, per wavelength, R then T.
#[derive(Clone, Debug)]
pub(crate) struct Layout {
    groups: Vec<Group>,
    has_r: bool,
    has_t: bool,
    /// Each row's position among the groups' wavelengths (group, index).
    rows: Vec<(usize, usize)>,
}

#[derive(Clone, Debug)]
struct Group {
    cos_theta0: f64,
    wavelengths_nm: Vec<f64>,
    /// Where this group's values start in the predictions.
    offset: usize,
}

impl Measurement {
    /// Checks the measurement: equal lengths, wavelengths in range, angles
    /// in [0, 90), finite R and T, σ > 0, at least `parameters` + 1 values.
    /// `name` prefixes the argument names in errors (a file's path, or
    /// nothing for Python's keyword names).
    pub fn check(&self, name: &str, parameters: usize) -> Result<()> {
        let arg = |a: &str| {
            if name.is_empty() {
                a.to_string()
            } else {
                format!("{name}: {a}")
            }
        };
        let rows = self.wavelength_nm.len();
        if rows == 0 {
            return Err(Error::invalid(arg("wavelength_nm"), "no rows"));
        }
        let (lo, hi) = WAVELENGTH_RANGE_NM;
        for (i, w) in self.wavelength_nm.iter().enumerate() {
            if !(lo..=hi).contains(w) {
                return Err(Error::invalid(
                    arg("wavelength_nm"),
                    format!("row {}: {w} nm is outside {lo:e}–{hi:e} nm", i + 1),
                ));
            }
        }
        let columns: [(&str, Option<&Vec<f64>>); 4] = [
            ("angle_deg", Some(&self.angle_deg)),
            ("R", self.reflectance.as_ref()),
            ("T", self.transmittance.as_ref()),
            ("sigma", self.sigma.as_ref()),
        ];
        for (column, values) in columns {
            let Some(values) = values else { continue };
            if values.len() != rows {
                return Err(Error::invalid(
                    arg(column),
                    format!("{} values for {rows} wavelengths", values.len()),
                ));
            }
            let ok = |v: f64| match column {
                "angle_deg" => (0.0..90.0).contains(&v),
                "sigma" => v > 0.0 && v.is_finite(),
                _ => v.is_finite(),
            };
            if let Some(i) = values.iter().position(|&v| !ok(v)) {
                let want = match column {
                    "angle_deg" => "outside [0, 90) degrees",
                    "sigma" => "not a finite number > 0",
                    _ => "not a finite number",
                };
                return Err(Error::invalid(
                    arg(column),
                    format!("row {}: {} is {want}", i + 1, values[i]),
                ));
            }
        }
        if self.reflectance.is_none() && self.transmittance.is_none() {
            return Err(Error::invalid(arg("R"), "neither R nor T is given"));
        }
        let values =
            rows * (self.reflectance.is_some() as usize + self.transmittance.is_some() as usize);
        if values <= parameters {
            return Err(Error::invalid(
                arg("R"),
                format!("{values} measured values cannot fix {parameters} thicknesses and χ²"),
            ));
        }
        Ok(())
    }

    /// The measured values and their σ in the residuals' order.
    pub(crate) fn values(&self, layout: &Layout) -> (Vec<f64>, Vec<f64>) {
        let width = layout.predictions();
        let (mut y, mut sigma) = (vec![0.0; width], vec![1.0; width]);
        for (row, &(g, i)) in layout.rows.iter().enumerate() {
            let at = layout.position(g, i);
            let s = self.sigma.as_ref().map_or(1.0, |s| s[row]);
            let mut k = at;
            if let Some(r) = &self.reflectance {
                y[k] = r[row];
                sigma[k] = s;
                k += 1;
            }
            if let Some(t) = &self.transmittance {
                y[k] = t[row];
                sigma[k] = s;
            }
        }
        (y, sigma)
    }
}

impl Layout {
    /// Groups the rows of a checked measurement by angle.
    pub fn new(m: &Measurement) -> Layout {
        let mut angles: Vec<f64> = m.angle_deg.clone();
        angles.sort_by(f64::total_cmp);
        angles.dedup();
        let mut per_angle: Vec<Vec<f64>> = vec![Vec::new(); angles.len()];
        let angle_of = |a: f64| angles.binary_search_by(|x| x.total_cmp(&a)).unwrap_or(0);
        for (&w, &a) in m.wavelength_nm.iter().zip(&m.angle_deg) {
            per_angle[angle_of(a)].push(w);
        }
        let channels = m.reflectance.is_some() as usize + m.transmittance.is_some() as usize;
        let mut offset = 0;
        let groups: Vec<Group> = angles
            .iter()
            .zip(per_angle)
            .map(|(&a, mut wavelengths_nm)| {
                wavelengths_nm.sort_by(f64::total_cmp);
                wavelengths_nm.dedup();
                let group = Group {
                    cos_theta0: a.to_radians().cos(),
                    offset,
                    wavelengths_nm,
                };
                offset += group.wavelengths_nm.len() * channels;
                group
            })
            .collect();
        let rows = m
            .wavelength_nm
            .iter()
            .zip(&m.angle_deg)
            .map(|(&w, &a)| {
                let g = angle_of(a);
                let i = groups[g]
                    .wavelengths_nm
                    .binary_search_by(|x| x.total_cmp(&w))
                    .unwrap_or(0);
                (g, i)
            })
            .collect();
        Layout {
            groups,
            has_r: m.reflectance.is_some(),
            has_t: m.transmittance.is_some(),
            rows,
        }
    }

    fn channels(&self) -> usize {
        self.has_r as usize + self.has_t as usize
    }

    /// The number of predicted values.
    pub fn predictions(&self) -> usize {
        self.groups
            .iter()
            .map(|g| g.wavelengths_nm.len() * self.channels())
            .sum()
    }

    fn position(&self, group: usize, index: usize) -> usize {
        self.groups[group].offset + index * self.channels()
    }

    /// Each row's predicted (R, T) from a prediction vector; `None` for a
    /// channel not measured.
    pub fn per_row(&self, p: &[f64]) -> Vec<(Option<f64>, Option<f64>)> {
        self.rows
            .iter()
            .map(|&(g, i)| {
                let at = self.position(g, i);
                let r = self.has_r.then(|| p[at]);
                let t = self.has_t.then(|| p[at + self.has_r as usize]);
                (r, t)
            })
            .collect()
    }
}

/// The stack's spectrum at the measured points as a function of the varied
/// thicknesses.
pub(crate) struct SpectrumModel {
    vary: Vary,
    base: Vec<f64>,
    layout: Layout,
    grids: Vec<StackGrid>,
    /// The largest Re n of each varied layer over the measured wavelengths.
    max_index: Vec<f64>,
    shortest_nm: f64,
}

impl SpectrumModel {
    /// The model of `stack` varied by `vary` at the points of `layout`.
    pub fn new(stack: &Stack, vary: &Vary, layout: Layout) -> Result<SpectrumModel> {
        let grids = layout
            .groups
            .iter()
            .map(|g| StackGrid::new(stack, &g.wavelengths_nm))
            .collect::<Result<Vec<_>>>()?;
        let media = stack.layers.len() + 2;
        let max_index = vary
            .layers
            .iter()
            .map(|&l| {
                grids
                    .iter()
                    .flat_map(|g| g.indices().chunks_exact(media).map(move |row| row[l].re))
                    .fold(1.0, f64::max)
            })
            .collect();
        let shortest_nm = layout
            .groups
            .iter()
            .flat_map(|g| g.wavelengths_nm.iter().copied())
            .fold(f64::INFINITY, f64::min);
        Ok(SpectrumModel {
            vary: vary.clone(),
            base: stack.thicknesses_nm(),
            layout,
            grids,
            max_index,
            shortest_nm,
        })
    }

    pub fn layout(&self) -> &Layout {
        &self.layout
    }

    /// Ok unless an incoherent gain layer lases somewhere at `x`.
    fn check_finite(&self, x: &[f64], p: &[f64]) -> Result<()> {
        if p.iter().all(|v| v.is_finite()) {
            return Ok(());
        }
        let mut t = Vec::new();
        self.vary.fill(&self.base, x, &mut t);
        for (grid, group) in self.grids.iter().zip(&self.layout.groups) {
            for i in 0..group.wavelengths_nm.len() {
                if let Some(d) = grid.diverged(i, &t, group.cos_theta0) {
                    return Err(d.error(group.wavelengths_nm[i], group.cos_theta0));
                }
            }
        }
        Err(Error::invalid(
            "fit",
            "the model is not finite at the varied thicknesses",
        ))
    }

    fn store(&self, at: usize, response: &Response, out: &mut [f64]) {
        let mut k = at;
        if self.layout.has_r {
            out[k] = response.r();
            k += 1;
        }
        if self.layout.has_t {
            out[k] = response.t();
        }
    }
}

impl Model for SpectrumModel {
    fn predictions(&self) -> usize {
        self.layout.predictions()
    }

    fn predict(&self, x: &[f64], out: &mut [f64]) -> Result<()> {
        let mut t = Vec::with_capacity(self.base.len());
        self.vary.fill(&self.base, x, &mut t);
        let channels = self.layout.channels();
        let mut responses = Vec::new();
        for (grid, group) in self.grids.iter().zip(&self.layout.groups) {
            responses.resize(group.wavelengths_nm.len(), Response::default());
            grid.solve_spectrum(&t, group.cos_theta0, &mut responses);
            for (i, response) in responses.iter().enumerate() {
                self.store(group.offset + i * channels, response, out);
            }
        }
        self.check_finite(x, out)
    }

    fn predict_with_jacobian(
        &self,
        x: &[f64],
        out: &mut [f64],
        jacobian: &mut [f64],
    ) -> Result<()> {
        let mut t = Vec::with_capacity(self.base.len());
        self.vary.fill(&self.base, x, &mut t);
        let width = self.predictions();
        let channels = self.layout.channels();
        for (grid, group) in self.grids.iter().zip(&self.layout.groups) {
            let g = solve_stack_grid_with_gradient(grid, &t, &[group.cos_theta0])?;
            for (i, response) in g.response.iter().enumerate() {
                let at = group.offset + i * channels;
                self.store(at, response, out);
                for (p, &layer) in self.vary.layers.iter().enumerate() {
                    let d = (layer - 1) * g.wavelengths + i;
                    let column = &mut jacobian[p * width..(p + 1) * width];
                    let mut k = at;
                    if self.layout.has_r {
                        column[k] = 0.5 * (g.d_rs[d] + g.d_rp[d]);
                        k += 1;
                    }
                    if self.layout.has_t {
                        column[k] = 0.5 * (g.d_ts[d] + g.d_tp[d]);
                    }
                }
            }
        }
        self.check_finite(x, out)
    }

    fn scan_steps(&self) -> Vec<f64> {
        // A layer's R repeats every λ/(2 n cos θ) of thickness: a quarter of
        // the shortest such period (normal incidence, the largest n).
        self.max_index
            .iter()
            .map(|n| self.shortest_nm / (8.0 * n))
            .collect()
    }
}

/// (model − measured)/σ.
pub(crate) struct WeightedResiduals {
    pub measured: Vec<f64>,
    pub sigma: Vec<f64>,
}

impl Loss for WeightedResiduals {
    fn residual_count(&self) -> usize {
        self.measured.len()
    }

    fn residuals(&self, p: &[f64], r: &mut [f64]) {
        for i in 0..r.len() {
            r[i] = (p[i] - self.measured[i]) / self.sigma[i];
        }
    }

    fn chain(&self, p: &[f64], dp: &[f64], r: &mut [f64], jacobian: &mut [f64]) {
        self.residuals(p, r);
        let m = r.len();
        for (column, dcolumn) in jacobian.chunks_exact_mut(m).zip(dp.chunks_exact(m)) {
            for i in 0..m {
                column[i] = dcolumn[i] / self.sigma[i];
            }
        }
    }
}
