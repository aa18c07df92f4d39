//! What an export is measured by: random points over its domain with the
//! exact response at each, and the error of what a GPU computes there.

use rand::{Rng, SeedableRng};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use super::{ExportSpec, Film};
use crate::color::delta_e2000_rgb;
use crate::error::Result;

/// The random points of the default error measurement.
pub const DEFAULT_POINTS: usize = 20_000;
/// The seed of the measurement's PCG64 stream.
pub const POINTS_SEED: u64 = 15;

/// Error of what a GPU computes from the export against the exact solver,
/// at random points. `*_abs` arrays have six entries: R.r, R.g, R.b, T.r,
/// T.g, T.b; `*_delta_e00` two: reflectance and transmittance colour.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ExportError {
    /// Largest absolute error per channel.
    pub max_abs: [f64; 6],
    /// 99th percentile of the absolute error per channel.
    pub p99_abs: [f64; 6],
    /// Mean absolute error per channel.
    pub mean_abs: [f64; 6],
    /// Largest CIEDE2000, reflected and transmitted colour.
    pub max_delta_e00: [f64; 2],
    /// Mean CIEDE2000, reflected and transmitted colour.
    pub mean_delta_e00: [f64; 2],
    /// How many points were measured.
    pub points: usize,
    /// The PCG64 seed of the points.
    pub seed: u64,
    /// (thickness nm, cos θ) of the largest error over channels.
    pub worst_point: [f64; 2],
}

impl ExportError {
    /// The largest of `max_abs`.
    pub fn max_all(&self) -> f64 {
        self.max_abs.iter().fold(0.0, |a, &b| a.max(b))
    }
}

/// The random points (thickness nm, cos θ) at which an export is measured,
/// the same for both sides: `spec.points` points uniform over the domain
/// from a PCG64 stream seeded with [`POINTS_SEED`], drawn as f32 (what a
/// shader gets).
pub fn measurement_points(spec: &ExportSpec) -> Vec<[f32; 2]> {
    let mut rng = rand_pcg::Pcg64::seed_from_u64(POINTS_SEED);
    let mut draw = |(lo, hi): (f64, f64)| (lo + rng.random::<f64>() * (hi - lo)) as f32;
    (0..spec.points)
        .map(|_| [draw(spec.thickness_nm), draw(spec.cos_theta)])
        .collect()
}

/// Random points over the domain, drawn as f32 (what a shader receives),
/// with the exact response of one side of the film at each.
pub(super) struct Reference {
    points: Vec<[f32; 2]>,
    exact: Vec<[f64; 6]>,
}

impl Reference {
    /// `film` is the stack as seen from the side measured.
    pub(super) fn new(film: &Film, spec: &ExportSpec) -> Result<Reference> {
        let points = measurement_points(spec);
        let exact = film.exact_at(&points)?;
        Ok(Reference { points, exact })
    }

    /// The error of `sample` (what the GPU computes at a point) against the
    /// exact values.
    pub(super) fn measure(&self, sample: impl Fn(f32, f32) -> [f64; 6] + Sync) -> ExportError {
        let errors: Vec<([f64; 6], [f64; 2])> = self
            .points
            .par_iter()
            .zip(&self.exact)
            .map(|(p, exact)| {
                let got = sample(p[0], p[1]);
                let abs = std::array::from_fn(|k| (got[k] - exact[k]).abs());
                let de = [
                    delta_e2000_rgb([got[0], got[1], got[2]], [exact[0], exact[1], exact[2]]),
                    delta_e2000_rgb([got[3], got[4], got[5]], [exact[3], exact[4], exact[5]]),
                ];
                (abs, de)
            })
            .collect();
        let n = errors.len();
        let mut out = ExportError {
            max_abs: [0.0; 6],
            p99_abs: [0.0; 6],
            mean_abs: [0.0; 6],
            max_delta_e00: [0.0; 2],
            mean_delta_e00: [0.0; 2],
            points: n,
            seed: POINTS_SEED,
            worst_point: [0.0; 2],
        };
        for k in 0..6 {
            let mut e: Vec<f64> = errors.iter().map(|x| x.0[k]).collect();
            e.sort_by(f64::total_cmp);
            out.max_abs[k] = e[n - 1];
            out.p99_abs[k] = e[((n as f64 * 0.99).ceil() as usize).clamp(1, n) - 1];
            out.mean_abs[k] = e.iter().sum::<f64>() / n as f64;
        }
        for k in 0..2 {
            // NaN (a colour the Lab conversion cannot take) counts as worst.
            out.max_delta_e00[k] = errors.iter().map(|x| x.1[k]).fold(0.0, |a: f64, b| {
                if b.is_nan() {
                    f64::INFINITY
                } else {
                    a.max(b)
                }
            });
            out.mean_delta_e00[k] = errors.iter().map(|x| x.1[k]).sum::<f64>() / n as f64;
        }
        let worst = errors
            .iter()
            .map(|x| x.0.iter().fold(0.0f64, |a, &b| a.max(b)))
            .enumerate()
            .max_by(|a, b| a.1.total_cmp(&b.1))
            .map_or(0, |(k, _)| k);
        out.worst_point = [
            f64::from(self.points[worst][0]),
            f64::from(self.points[worst][1]),
        ];
        out
    }
}
