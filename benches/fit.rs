//! Fitting: one 3-layer fit to a 401-wavelength spectrum (the issue's
//! target is under 50 ms), and the batched fit's spectra per second (the
//! scan shared, spectra in parallel on rayon's pool).

// Not an API: criterion's macros generate undocumented public functions.
#![allow(missing_docs)]

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use irid::bench::inverse::{fit_measurement, fit_stack};
use irid::fit::{fit_spectrum, Measurement, SpectrumFitter, Vary};

fn fits(c: &mut Criterion) {
    let truth = [95.0, 160.0, 70.0];
    let start = fit_stack(&[110.0, 140.0, 80.0]);
    let bounds: Vec<(f64, f64)> = truth.iter().map(|d| (0.5 * d, 1.5 * d)).collect();
    let vary = Vary::new(&start, &[1, 2, 3], Some(&bounds), "vary", "bounds").unwrap();
    let measured = fit_measurement(&truth, 0.0).unwrap();
    let mut group = c.benchmark_group("fit");
    group.sample_size(10);
    group.bench_function("3 layers, 401 wavelengths, one spectrum", |b| {
        b.iter(|| fit_spectrum(&start, &vary, &measured).unwrap())
    });
    let batch: Vec<Measurement> = (0..64)
        .map(|i| {
            let t: Vec<f64> = truth.iter().map(|d| d * (1.0 + 0.002 * i as f64)).collect();
            fit_measurement(&t, i as f64).unwrap()
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
