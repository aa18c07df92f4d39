//! The wavelength nodes of a spectral atlas: each texel holds the film's
//! R and T at these wavelengths, and a lookup at wavelength λ between
//! nodes λₖ and λₖ₊₁ reads node λₖ's block at thickness d·λₖ/λ and node
//! λₖ₊₁'s at d·λₖ₊₁/λ and interpolates linearly in λ.
//!
//! The varying layer's fringes are periodic in its optical path over the
//! wavelength, d/λ: read at the same d/λ, neighbouring nodes hold the same
//! fringe, and what is left to interpolate between them is the dispersion
//! of the materials and the phase of the layers that do not vary (none
//! for a free-standing film of constant index, whose response depends on
//! d/λ alone). The count of nodes is measured, not assumed: the film is
//! evaluated at probe points (thickness, cos θ) on the nodes and at every
//! midpoint between them, and the count grows (by the h² law of linear
//! interpolation) until every midpoint meets its share of the target.
//! Nodes are uniform in wavenumber 1/λ, so that the ratio of neighbouring
//! nodes, by which the blocks' thickness range extends beyond the table's,
//! is largest at the red end.
//!
//! At one wavelength the fringes of a free-standing film sharpen without
//! bound towards grazing incidence (their width in thickness goes as
//! cos θ): below the cos θ at which the thickness range holds more than
//! [`MAX_FRINGES`] fringe widths, the spectrum is *aliased* and the target
//! is not sought there, as for the colour of an rgb table.

use super::eval::Film;
use super::search::aliased_edge;
use crate::error::{Error, Result};
use crate::optics::Stack;

/// The most wavelength nodes a spectral atlas takes.
pub const MAX_WAVELENGTH_NODES: usize = 256;
/// The fewest: enough that neighbouring nodes are within 5 % of each
/// other over 360–830 nm, which bounds how far each block's thickness
/// range reaches beyond the table's.
pub const MIN_WAVELENGTH_NODES: usize = 17;
/// The most fringe widths the thickness range may hold at one wavelength
/// before the spectrum counts as aliased (a chart follows each with a few
/// texels).
pub const MAX_FRINGES: f64 = 96.0;

/// How wavelength nodes are spaced.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Spacing {
    /// Uniform in wavelength.
    Wavelength,
    /// Uniform in wavenumber 1/λ (what irid bakes).
    Wavenumber,
}

/// `count` nodes over `range` (nm), increasing.
pub fn nodes(range: (f64, f64), count: usize, spacing: Spacing) -> Vec<f64> {
    let (lo, hi) = range;
    if count < 2 || hi <= lo {
        return vec![lo];
    }
    let f = |k: usize| k as f64 / (count - 1) as f64;
    let mut v: Vec<f64> = match spacing {
        Spacing::Wavelength => (0..count).map(|k| lo + f(k) * (hi - lo)).collect(),
        Spacing::Wavenumber => (0..count)
            .map(|k| 1.0 / (1.0 / lo + f(k) * (1.0 / hi - 1.0 / lo)))
            .collect(),
    };
    // Exact ends, whatever the rounding of 1/(1/x).
    v[0] = lo;
    v[count - 1] = hi;
    v
}

/// The largest ratio of neighbouring nodes (1 for a single node): each
/// block is read at thicknesses up to this factor beyond the table's range.
pub fn largest_ratio(nodes_nm: &[f64]) -> f64 {
    nodes_nm.windows(2).map(|w| w[1] / w[0]).fold(1.0, f64::max)
}

/// The wavelength nodes chosen for a film.
#[derive(Clone, Debug, PartialEq)]
pub struct WavelengthAxis {
    /// Increasing wavelengths (nm).
    pub nodes_nm: Vec<f64>,
    /// The largest midpoint error at the probe points (absolute, R or T).
    pub measured: f64,
}

/// The probe's cos θ values: log-spaced from `floor` (1e-3 at the least)
/// to the range's top.
fn probe_cos(cos: (f64, f64), floor: f64) -> Vec<f64> {
    let (c0, c1) = (cos.0.max(floor), cos.1);
    if c1 <= c0 {
        return vec![c1];
    }
    let lo = c0.max(1e-3);
    let n = 48;
    let mut v: Vec<f64> = (0..n)
        .map(|k| lo * (c1 / lo).powf(k as f64 / (n - 1) as f64))
        .collect();
    v[n - 1] = c1;
    v
}

/// The probe's thicknesses: evenly over the range (the fringes, and where
/// they fall between nodes, change with thickness).
fn probe_thickness(thickness_nm: (f64, f64)) -> Vec<f64> {
    let (d0, d1) = thickness_nm;
    if d1 <= d0 {
        return vec![d0];
    }
    (1..=32).map(|k| d0 + (d1 - d0) * k as f64 / 32.0).collect()
}

/// The largest error of the lookup's interpolation between `count` nodes
/// (at d/λ fixed, linear in λ) at their midpoints, in R or T, over the
/// probe points.
fn midpoint_error(
    stack: &Stack,
    layer: usize,
    range: (f64, f64),
    count: usize,
    spacing: Spacing,
    cos: &[f64],
    thickness: &[f64],
) -> Result<f64> {
    // Every node and the midpoint (in the spacing's variable) after it.
    let fine = nodes(range, 2 * count - 1, spacing);
    let film = Film::spectral(stack, layer, &fine, 0.0)?;
    let n = thickness.len();
    let scaled = |k: usize, to: usize| -> Vec<f64> {
        thickness.iter().map(|d| d * fine[k] / fine[to]).collect()
    };
    // Per cos θ and fine node: a midpoint's exact values at the probe
    // thicknesses; a node's at the thicknesses its two midpoints read it
    // at (towards the lower midpoint, then the upper).
    let mut rows = Vec::new();
    for &c in cos {
        for k in 0..fine.len() {
            let t = if k % 2 == 1 {
                thickness.to_vec()
            } else {
                let mut t = Vec::with_capacity(2 * n);
                if k > 0 {
                    t.extend(scaled(k, k - 1));
                }
                if k + 1 < fine.len() {
                    t.extend(scaled(k, k + 1));
                }
                t
            };
            rows.push((c, k, t));
        }
    }
    let values = film.spectral_rows(&rows)?;
    let mut start = Vec::with_capacity(rows.len());
    let mut at = 0;
    for r in &rows {
        start.push(at);
        at += 2 * r.2.len();
    }
    let per_cos = fine.len();
    let mut worst = 0.0f64;
    for j in 0..cos.len() {
        let row = |k: usize| &values[start[j * per_cos + k]..];
        for m in (1..fine.len()).step_by(2) {
            let f = (fine[m] - fine[m - 1]) / (fine[m + 1] - fine[m - 1]);
            // Node m − 1 read towards its upper midpoint: its second half,
            // unless it is the first node (one half only).
            let lower = if m == 1 { 0 } else { n };
            let (a, b, e) = (row(m - 1), row(m + 1), row(m));
            for i in 0..n {
                for o in 0..2 {
                    let (va, vb) = (a[2 * (lower + i) + o], b[2 * i + o]);
                    let got = va + f * (vb - va);
                    worst = worst.max((got - e[2 * i + o]).abs());
                }
            }
        }
    }
    Ok(worst)
}

/// Nodes along wavelength for the film `stack` (layer `layer` varying)
/// over `thickness_nm` × `cos` (from `floor` up) whose interpolation stays
/// within `share` (absolute, R and T) at the probe points (see the module
/// docs).
#[allow(clippy::too_many_arguments)]
pub fn choose(
    stack: &Stack,
    layer: usize,
    range: (f64, f64),
    thickness_nm: (f64, f64),
    cos: (f64, f64),
    floor: f64,
    share: f64,
    spacing: Spacing,
) -> Result<WavelengthAxis> {
    if !(share > 0.0 && share.is_finite()) {
        return Err(Error::invalid(
            "max-error",
            format!("a spectral atlas needs a finite error target, got a share of {share}"),
        ));
    }
    if range.1 <= range.0 {
        return Ok(WavelengthAxis {
            nodes_nm: vec![range.0],
            measured: 0.0,
        });
    }
    let cs = probe_cos(cos, floor);
    let ds = probe_thickness(thickness_nm);
    let mut count = MIN_WAVELENGTH_NODES;
    loop {
        let error = midpoint_error(stack, layer, range, count, spacing, &cs, &ds)?;
        if error <= share {
            return Ok(WavelengthAxis {
                nodes_nm: nodes(range, count, spacing),
                measured: error,
            });
        }
        if count >= MAX_WAVELENGTH_NODES {
            return Err(Error::invalid(
                "max-error",
                format!(
                    "{share:.1e} (the wavelength interpolation's share) is not reached with {MAX_WAVELENGTH_NODES} wavelength nodes over {}–{} nm: {error:.2e} at the probe points",
                    range.0, range.1
                ),
            ));
        }
        // The h² law, 5 % to spare.
        let wanted = ((count - 1) as f64 * (error / share).sqrt() * 1.05).ceil() as usize + 1;
        count = wanted.clamp(count + 1, MAX_WAVELENGTH_NODES);
    }
}

/// The cos θ below which, at some wavelength of `range`, the film's
/// fringes along thickness are narrower than [`MAX_FRINGES`] of them fill
/// the thickness range and change R by more than `visible` (0 when
/// nowhere).
pub fn fringe_floor(
    film: &Film,
    range: (f64, f64),
    thickness_nm: (f64, f64),
    cos: (f64, f64),
    visible: f64,
) -> Result<f64> {
    let (d0, d1) = thickness_nm;
    let (c0, c1) = cos;
    if d1 <= d0 {
        return Ok(0.0);
    }
    let layer = &film.stack().layers[film.layer() - 1].material;
    let wavelengths = nodes(range, 9, Spacing::Wavenumber);
    let thicknesses: Vec<f64> = (0..5)
        .map(|k| d1 / f64::from(1 << k))
        .filter(|&d| d >= d0 && d > 0.0)
        .collect();
    let aliased = |c: f64| -> Result<bool> {
        for &lambda in &wavelengths {
            let n = layer.index_at(lambda)?.re.max(1e-6);
            let rate = 4.0 * std::f64::consts::PI * n * film.optical.s(c) / lambda;
            for &d in &thicknesses {
                let (y, visibility) = film.fringe(lambda, c, d)?;
                if y.is_nan() || y <= 0.0 || visibility < visible || rate <= 0.0 {
                    continue;
                }
                let width = 2.0 * (1.0 - y).abs() / y.sqrt() / rate;
                if (d1 - d0) / width > MAX_FRINGES {
                    return Ok(true);
                }
            }
        }
        Ok(false)
    };
    aliased_edge((c0, c1), &aliased)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::optics::{Layer, Material};

    fn soap() -> Stack {
        Stack {
            ambient: Material::constant(1.0, 0.0),
            layers: vec![Layer::new(Material::constant(1.33, 0.0), 500.0)],
            substrate: Material::constant(1.0, 0.0),
        }
    }

    #[test]
    fn nodes_span_the_range_in_order() {
        for spacing in [Spacing::Wavelength, Spacing::Wavenumber] {
            let n = nodes((360.0, 830.0), 17, spacing);
            assert_eq!((n[0], n[16]), (360.0, 830.0));
            assert!(n.windows(2).all(|w| w[1] > w[0]));
        }
        // Uniform in 1/λ: the steps grow as λ².
        let n = nodes((400.0, 800.0), 3, Spacing::Wavenumber);
        assert!((n[1] - 1.0 / (0.5 * (1.0 / 400.0 + 1.0 / 800.0))).abs() < 1e-9);
    }

    /// Read at the same d/λ, a free-standing film of constant index is
    /// the same at every wavelength: the fewest nodes meet any share. A
    /// dispersive layer between two others takes more, and each count
    /// meets the share at the probe points it claims.
    #[test]
    fn nodes_follow_what_d_over_lambda_leaves() {
        let pick = |stack: &Stack, share: f64| {
            choose(
                stack,
                1,
                (360.0, 830.0),
                (0.0, 1000.0),
                (0.0, 1.0),
                0.2,
                share,
                Spacing::Wavenumber,
            )
            .unwrap()
        };
        let free = pick(&soap(), 1e-4);
        assert_eq!(free.nodes_nm.len(), MIN_WAVELENGTH_NODES);
        assert!(free.measured < 1e-9, "{}", free.measured);
        let mut coated = soap();
        coated.layers[0].material = Material {
            name: "cauchy".into(),
            dispersion: crate::optics::Dispersion::Cauchy {
                a: 1.45,
                b: 0.02,
                c: 0.0,
            },
        };
        coated.substrate = Material::constant(1.52, 0.0);
        coated
            .layers
            .push(Layer::new(Material::constant(2.1, 0.0), 300.0));
        let coated = pick(&coated, 3e-3);
        assert!(coated.nodes_nm.len() > MIN_WAVELENGTH_NODES);
        assert!(coated.measured <= 3e-3);
    }

    /// A free-standing film's fringes narrow towards grazing incidence:
    /// the floor is above grazing, and a thinner range has a lower one.
    #[test]
    fn fringe_floor_rises_with_thickness() {
        let film = Film::spectral(&soap(), 1, &[360.0, 830.0], 0.0).unwrap();
        let floor =
            |d1: f64| fringe_floor(&film, (360.0, 830.0), (0.0, d1), (0.0, 1.0), 1e-2).unwrap();
        let (thick, thin) = (floor(1000.0), floor(100.0));
        assert!(thick > 1e-3 && thick < 0.2, "{thick}");
        assert!(thin < thick, "{thin} {thick}");
    }
}
