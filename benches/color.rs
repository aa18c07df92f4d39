//! Spectral integration: a sampled spectrum to linear sRGB (a dot product per
//! channel against precomputed weights).

// Not an API: criterion's macros generate undocumented public functions.
#![allow(missing_docs)]

use criterion::{black_box, criterion_group, criterion_main, Criterion};
use irid::color::{Sampling, SpectralIntegrator};

fn integrate(c: &mut Criterion) {
    for sampling in [
        Sampling::Exact,
        Sampling::Uniform(401),
        Sampling::Uniform(41),
    ] {
        let integ = SpectralIntegrator::new(sampling);
        let spectrum: Vec<f64> = integ
            .wavelengths_nm()
            .iter()
            .map(|l| 0.5 + 0.5 * (l / 37.0).sin())
            .collect();
        let name = format!("rgb {sampling} ({} samples)", spectrum.len());
        c.bench_function(&name, |b| b.iter(|| integ.rgb(black_box(&spectrum))));
    }
}

criterion_group!(benches, integrate);
criterion_main!(benches);
