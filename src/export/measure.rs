//! What an export is measured by: random points over its domain, and the
//! figures of what a GPU computes there against the exact response.

use rand::{Rng, SeedableRng};
use serde::{Deserialize, Serialize};

use super::ExportSpec;

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
