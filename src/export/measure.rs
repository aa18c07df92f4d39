//! What an export is measured by: random points over its domain, and the
//! figures of what a GPU computes there against the exact response.

use super::ExportSpec;
use rand::{Rng, SeedableRng};

/// The random points of the default error measurement.
pub const DEFAULT_POINTS: usize = 20_000;
/// The seed of the measurement's PCG64 stream.
pub const POINTS_SEED: u64 = 15;

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
