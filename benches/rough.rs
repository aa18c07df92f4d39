//! Rough films: the F_eff grid engine (`irid::rough::rough_reflectance`)
//! on the soap film over 0–1000 nm, one kernel on its own, and a colour
//! fit's evaluation (F_eff at four angles) with and without the
//! transmission kernel's work.

// Not an API: criterion's macros generate undocumented public functions.
#![allow(missing_docs)]

use criterion::{black_box, criterion_group, criterion_main, Criterion};
use irid::color::{Sampling, SpectralIntegrator};
use irid::optics::{Layer, Material, Stack};
use irid::rough::{
    rough_colors, rough_reflectance, rough_reflectance_colors, Kernel, MuGrid, Quadrature,
};

fn soap() -> Stack {
    Stack {
        ambient: Material::constant(1.0, 0.0),
        layers: vec![Layer::new(Material::constant(1.33, 0.0), 500.0)],
        substrate: Material::constant(1.0, 0.0),
    }
}

fn linspace(lo: f64, hi: f64, n: usize) -> Vec<f64> {
    (0..n)
        .map(|i| lo + (hi - lo) * i as f64 / (n - 1) as f64)
        .collect()
}

fn kernels(c: &mut Criterion) {
    let q = Quadrature::default();
    let grid = MuGrid::new(q.mu_intervals, None);
    let mut g = c.benchmark_group("rough kernel");
    for (cos, r) in [(0.9, 0.05), (0.7, 0.3), (0.2, 0.8)] {
        g.bench_function(format!("cos {cos} roughness {r}"), |b| {
            b.iter(|| Kernel::new(&grid, black_box(cos), black_box(r), &q))
        });
    }
    g.finish();
}

/// The whole engine on the soap film, 0–1000 nm, exact 1 nm colour: the
/// smooth sweep on the μ grid plus a kernel per (cos θ, roughness) and
/// the weighting, on every core.
fn grids(c: &mut Criterion) {
    let stack = soap();
    let integrator = SpectralIntegrator::new(Sampling::Exact);
    let q = Quadrature::default();
    let mut g = c.benchmark_group("rough grid soap 0-1000 nm");
    g.sample_size(10);
    for (nt, nc, nr) in [(257, 33, 9), (1025, 65, 17)] {
        let thickness = linspace(0.0, 1000.0, nt);
        let cos = linspace(0.0, 1.0, nc);
        let roughness = linspace(0.0, 1.0, nr);
        g.bench_function(format!("{nt}x{nc}x{nr}"), |b| {
            b.iter(|| {
                rough_reflectance(&stack, 1, &integrator, &thickness, &cos, &roughness, &q).unwrap()
            })
        });
    }
    g.finish();
}

/// What a rough colour fit evaluates per point: F_eff of a film on glass
/// at four angles, roughness 0.4, exact colour; `rough_colors` also gives
/// T_eff and the compensated outputs, `rough_reflectance_colors` F_eff
/// alone, bit for bit the same.
fn fit_colours(c: &mut Criterion) {
    let stack = Stack {
        ambient: Material::constant(1.0, 0.0),
        layers: vec![Layer::new(Material::constant(1.38, 0.0), 300.0)],
        substrate: Material::constant(1.52, 0.0),
    };
    let integrator = SpectralIntegrator::new(Sampling::Exact);
    let angles = [0.0, 30.0, 50.0, 70.0];
    let mut g = c.benchmark_group("rough colours 4 angles");
    g.bench_function("with transmission (rough_colors)", |b| {
        b.iter(|| rough_colors(&stack, &integrator, black_box(&angles), 0.4).unwrap())
    });
    g.bench_function("reflection only (rough_reflectance_colors)", |b| {
        b.iter(|| rough_reflectance_colors(&stack, &integrator, black_box(&angles), 0.4).unwrap())
    });
    g.finish();
}

criterion_group!(benches, kernels, grids, fit_colours);
criterion_main!(benches);
