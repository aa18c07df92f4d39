//! Fitting: one 3-layer fit to a 401-wavelength spectrum (the issue's
//! target is under 50 ms), and the batched fit's spectra per second (the
//! scan shared, spectra in parallel on rayon's pool).

// Not an API: criterion's macros generate undocumented public functions.
#![allow(missing_docs)]

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use irid::fit::{fit_spectrum, Measurement, SpectrumFitter, Vary};
use irid::optics::{Layer, Material, Response, Stack, StackGrid};

fn stack(thicknesses: &[f64]) -> Stack {
    let indices = [2.3, 1.45, 2.1];
    Stack {
        ambient: Material::constant(1.0, 0.0),
        layers: thicknesses
            .iter()
            .zip(indices)
            .map(|(&d, n)| Layer::new(Material::constant(n, 0.0), d))
            .collect(),
        substrate: Material::constant(1.52, 0.0),
    }
}

/// R at normal incidence, 380–780 nm every 1 nm, with a deterministic
/// ripple of 1e-3 standing for noise.
fn measure(truth: &[f64], seed: f64) -> Measurement {
    let wavelengths: Vec<f64> = (0..401).map(|i| 380.0 + i as f64).collect();
    let grid = StackGrid::new(&stack(truth), &wavelengths).unwrap();
    let mut out = vec![Response::default(); wavelengths.len()];
    grid.solve_spectrum(truth, 1.0, &mut out);
    Measurement {
        angle_deg: vec![0.0; wavelengths.len()],
        reflectance: Some(
            out.iter()
                .enumerate()
                .map(|(i, r)| r.r() + 1e-3 * (i as f64 * 1.3 + seed).sin())
                .collect(),
        ),
        sigma: Some(vec![1e-3; wavelengths.len()]),
        wavelength_nm: wavelengths,
        transmittance: None,
    }
}

fn fits(c: &mut Criterion) {
    let truth = [95.0, 160.0, 70.0];
    let start = stack(&[110.0, 140.0, 80.0]);
    let bounds: Vec<(f64, f64)> = truth.iter().map(|d| (0.5 * d, 1.5 * d)).collect();
    let vary = Vary::new(&start, &[1, 2, 3], Some(&bounds), "vary", "bounds").unwrap();
    let measured = measure(&truth, 0.0);
    let mut group = c.benchmark_group("fit");
    group.sample_size(10);
    group.bench_function("3 layers, 401 wavelengths, one spectrum", |b| {
        b.iter(|| fit_spectrum(&start, &vary, &measured).unwrap())
    });
    let batch: Vec<Measurement> = (0..64)
        .map(|i| {
            let t: Vec<f64> = truth.iter().map(|d| d * (1.0 + 0.002 * i as f64)).collect();
            measure(&t, i as f64)
        })
        .collect();
    let fitter = SpectrumFitter::new(&start, &vary, &batch[0]).unwrap();
    group.throughput(Throughput::Elements(batch.len() as u64));
    group.bench_function("3 layers, 401 wavelengths, batch of 64 spectra", |b| {
        b.iter(|| fitter.fit_many(&batch).unwrap())
    });
    group.finish();
}

criterion_group!(benches, fits);
criterion_main!(benches);
