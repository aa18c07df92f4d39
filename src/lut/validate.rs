//! Validation: the table against direct evaluation by the solver at random
//! off-grid points, with the hard angles reported on their own.

use rand::{Rng, SeedableRng};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use super::bake::critical_cos;
use super::sample::{channel_names, Lut};
use super::Kind;
use crate::color::{delta_e2000_rgb, Sampling, SpectralIntegrator};
use crate::error::{Error, Result};
use crate::optics::{solve, StackGrid};

/// Error of a table against the solver. Arrays named `*_abs` have one
/// entry per channel (in `channels` order); `*_de2000` have two entries,
/// the reflectance colour and the transmittance colour.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ErrorStats {
    pub points: usize,
    pub seed: u64,
    pub channels: Vec<String>,
    pub max_abs: Vec<f64>,
    pub mean_abs: Vec<f64>,
    pub p99_abs: Vec<f64>,
    /// CIEDE2000 between the table's and the exact colour. For a spectral
    /// table the colour integrates the table's spectrum with the header's
    /// sampling; absent when its wavelength axis does not span that
    /// sampling's wavelengths.
    pub max_de2000: Option<[f64; 2]>,
    pub mean_de2000: Option<[f64; 2]>,
    /// Where the largest error (over channels) occurred: thickness (nm),
    /// cos θ, wavelength (nm; 0 for rgb tables).
    pub worst_point: [f64; 3],
    /// The same points split by where tables are hard, so a bad corner is
    /// not averaged away.
    pub regions: Vec<RegionStats>,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RegionStats {
    pub name: String,
    pub description: String,
    pub points: usize,
    /// Largest absolute error over all channels.
    pub max_abs: f64,
    /// Mean over points of the largest absolute error over channels.
    pub mean_abs: f64,
}

/// cos 80°: beyond it the response changes fastest with angle.
const GRAZING_COS: f64 = 0.173_648_177_666_930_4;
/// Half-width in cos θ of the band around the critical angle.
const CRITICAL_BAND: f64 = 0.02;

struct PointError {
    at: [f64; 3],
    cos_theta: f64,
    abs: [f64; 6],
    de: Option<[f64; 2]>,
}

/// The most validation points: the per-point errors are kept in memory, and
/// an absurd count aborted on allocation instead of failing.
pub const MAX_POINTS: usize = 100_000_000;

/// Compares the table with the solver at `points` random points spread
/// uniformly over the table's domain (thickness, cos θ and, for spectral
/// tables, wavelength), drawn from a PCG64 stream seeded with `seed`.
pub fn validate(lut: &Lut, points: usize, seed: u64) -> Result<ErrorStats> {
    if !(1..=MAX_POINTS).contains(&points) {
        return Err(Error::invalid(
            "points",
            format!("must be between 1 and {MAX_POINTS}, got {points}"),
        ));
    }
    let h = lut.header();
    let stack = &h.stack;
    let kind = h.kind;
    let range = |k: usize| {
        let n = &h.axes[k].nodes;
        (n[0], n[n.len() - 1])
    };
    let (t_range, c_range) = (range(0), range(1));
    let w_range = if kind == Kind::Spectral {
        range(2)
    } else {
        (0.0, 0.0)
    };
    let sampling: Sampling = h.color.sampling.parse()?;
    let integrator = SpectralIntegrator::with_white(sampling, h.color.white);
    let wavelengths = integrator.wavelengths_nm();
    let color_covered = match kind {
        Kind::Rgb => true,
        Kind::Spectral => wavelengths
            .iter()
            .all(|&w| w >= w_range.0 && w <= w_range.1),
    };
    let color_grid = StackGrid::new(stack, if color_covered { wavelengths } else { &[] })?;

    let mut rng = rand_pcg::Pcg64::seed_from_u64(seed);
    let mut draw = |(lo, hi): (f64, f64)| (lo + rng.random::<f64>() * (hi - lo)) as f32;
    let samples: Vec<[f32; 3]> = (0..points)
        .map(|_| [draw(t_range), draw(c_range), draw(w_range)])
        .collect();

    let layer = h.layer;
    let base_thicknesses = stack.thicknesses_nm();
    let n_channels = channel_names(kind).len();
    let errors: Vec<PointError> = samples
        .par_iter()
        .map_init(
            || {
                (
                    base_thicknesses.clone(),
                    vec![0.0; wavelengths.len()],
                    vec![0.0; wavelengths.len()],
                    Vec::new(),
                )
            },
            |(thick, spec_r, spec_t, idx), &[t, c, w]| -> Result<PointError> {
                if layer > 0 {
                    thick[layer - 1] = f64::from(t);
                }
                let cos = f64::from(c);
                let mut color = |table_r: &[f64; 3], table_t: &[f64; 3]| {
                    for (k, (wl, n)) in color_grid.iter().enumerate() {
                        let resp = solve(n, thick, wl, cos);
                        spec_r[k] = resp.r();
                        spec_t[k] = resp.t();
                    }
                    let (r, t) = (integrator.rgb(spec_r), integrator.rgb(spec_t));
                    (
                        r,
                        t,
                        [delta_e2000_rgb(*table_r, r), delta_e2000_rgb(*table_t, t)],
                    )
                };
                let mut abs = [0.0; 6];
                let de = match kind {
                    Kind::Rgb => {
                        let s = lut.sample_rgb(t, c);
                        let table_r = s.reflectance.map(f64::from);
                        let table_t = s.transmittance.map(f64::from);
                        let (r, tr, de) = color(&table_r, &table_t);
                        for k in 0..3 {
                            abs[k] = (table_r[k] - r[k]).abs();
                            abs[3 + k] = (table_t[k] - tr[k]).abs();
                        }
                        Some(de)
                    }
                    Kind::Spectral => {
                        stack.indices_at(f64::from(w), idx)?;
                        let resp = solve(idx, thick, f64::from(w), cos);
                        let (r, tr) = lut.sample_spectral(t, c, w);
                        abs[0] = (f64::from(r) - resp.r()).abs();
                        abs[1] = (f64::from(tr) - resp.t()).abs();
                        if color_covered {
                            let mut table_r = vec![0.0; wavelengths.len()];
                            let mut table_t = vec![0.0; wavelengths.len()];
                            for (k, &wl) in wavelengths.iter().enumerate() {
                                let (r, t) = lut.sample_spectral(t, c, wl as f32);
                                table_r[k] = f64::from(r);
                                table_t[k] = f64::from(t);
                            }
                            let rgb_r = integrator.rgb(&table_r);
                            let rgb_t = integrator.rgb(&table_t);
                            Some(color(&rgb_r, &rgb_t).2)
                        } else {
                            None
                        }
                    }
                };
                Ok(PointError {
                    at: [f64::from(t), cos, f64::from(w)],
                    cos_theta: cos,
                    abs,
                    de,
                })
            },
        )
        .collect::<Result<_>>()?;

    let mut stats = ErrorStats {
        points,
        seed,
        channels: channel_names(kind).iter().map(|s| s.to_string()).collect(),
        max_abs: Vec::new(),
        mean_abs: Vec::new(),
        p99_abs: Vec::new(),
        max_de2000: None,
        mean_de2000: None,
        regions: Vec::new(),
        worst_point: [0.0; 3],
    };
    for ch in 0..n_channels {
        let mut e: Vec<f64> = errors.iter().map(|p| p.abs[ch]).collect();
        e.sort_by(f64::total_cmp);
        stats.max_abs.push(e[e.len() - 1]);
        stats.mean_abs.push(e.iter().sum::<f64>() / e.len() as f64);
        let p99 = ((0.99 * e.len() as f64).ceil() as usize).clamp(1, e.len()) - 1;
        stats.p99_abs.push(e[p99]);
    }
    if errors.iter().all(|p| p.de.is_some()) {
        let des: Vec<[f64; 2]> = errors.iter().filter_map(|p| p.de).collect();
        let mut max = [0.0f64; 2];
        let mut sum = [0.0f64; 2];
        for d in &des {
            for k in 0..2 {
                max[k] = max[k].max(d[k]);
                sum[k] += d[k];
            }
        }
        stats.max_de2000 = Some(max);
        stats.mean_de2000 = Some(sum.map(|s| s / des.len() as f64));
    }

    let worst = |p: &PointError| max_or_nan(&p.abs[..n_channels]);
    if let Some(p) = errors.iter().max_by(|a, b| worst(a).total_cmp(&worst(b))) {
        stats.worst_point = p.at;
    }
    let critical = critical_cos(stack, kind, w_range)
        .filter(|&cc| cc >= c_range.0 - CRITICAL_BAND && cc <= c_range.1 + CRITICAL_BAND);
    let mut region = |name: &str, description: String, inside: &dyn Fn(f64) -> bool| {
        let chosen: Vec<f64> = errors
            .iter()
            .filter(|p| inside(p.cos_theta))
            .map(worst)
            .collect();
        if !chosen.is_empty() {
            stats.regions.push(RegionStats {
                name: name.into(),
                description,
                points: chosen.len(),
                max_abs: chosen.iter().fold(0.0, |a: f64, &b| a.max(b)),
                mean_abs: chosen.iter().sum::<f64>() / chosen.len() as f64,
            });
        }
    };
    region(
        "grazing",
        "incidence beyond 80° (cos θ < 0.1736)".into(),
        &|c| c < GRAZING_COS,
    );
    if let Some(cc) = critical {
        region(
            "critical",
            format!(
                "within ±{CRITICAL_BAND} in cos θ of the substrate's critical angle (cos θc = {cc:.6})"
            ),
            &|c| (c - cc).abs() < CRITICAL_BAND,
        );
    }
    region("other", "every remaining point".into(), &|c| {
        c >= GRAZING_COS && critical.is_none_or(|cc| (c - cc).abs() >= CRITICAL_BAND)
    });
    Ok(stats)
}

impl Lut {
    /// Records validation figures in the header (written with the table).
    pub fn set_validation(&mut self, stats: ErrorStats) {
        self.header_mut().error.validation = Some(stats);
    }
}

/// The largest of `values` (0 for none), or NaN if any is NaN: `f64::max`
/// alone drops a NaN, which would let a broken point pass as the best.
pub(crate) fn max_or_nan(values: &[f64]) -> f64 {
    values.iter().fold(0.0f64, |a, &b| {
        if a.is_nan() || b.is_nan() {
            f64::NAN
        } else {
            a.max(b)
        }
    })
}

#[cfg(test)]
mod tests {
    use super::max_or_nan;

    #[test]
    fn a_nan_error_is_never_the_smallest() {
        assert_eq!(max_or_nan(&[1e-4, 3e-4, 2e-4]), 3e-4);
        assert_eq!(max_or_nan(&[]), 0.0);
        assert!(max_or_nan(&[1e-4, f64::NAN, 2e-4]).is_nan());
        assert!(max_or_nan(&[f64::NAN, 2e-4]).is_nan());
    }
}
