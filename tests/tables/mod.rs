//! Helpers shared by the table tests (tests/lut.rs, tests/lut_spectral.rs).

use std::path::{Path, PathBuf};

use irid::color::Sampling;
use irid::lut::{BakeSpec, Resolution};
use irid::optics::Stack;

pub fn luts_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("luts")
}

/// A spec small enough for a test: 31 wavelengths instead of 471.
pub fn quick_spec(stack: Stack, thickness_nm: (f64, f64), max_error: f64) -> BakeSpec {
    let mut spec = BakeSpec::new(stack);
    spec.thickness_nm = thickness_nm;
    spec.sampling = Sampling::Uniform(31);
    spec.resolution = Resolution::MaxError(max_error);
    spec
}

pub fn worst(values: &[f64]) -> f64 {
    values.iter().cloned().fold(0.0, f64::max)
}

/// The largest error of a validation where the table's target applies:
/// above an atlas table's aliased strip, everywhere for a grid.
pub fn worst_targeted(stats: &irid::lut::Validation) -> f64 {
    match stats.regions.iter().find(|r| r.name == "resolved") {
        Some(r) => r.max_abs,
        None => worst(&stats.figures.max_abs),
    }
}
