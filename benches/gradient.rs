//! The cost of the exact thickness derivatives against the forward solve:
//! R and T of a 20-layer stack over 401 wavelengths × 3 angles (the
//! forward spectrum as `StackGrid::solve` gives it, on the widest lanes the
//! CPU has), and the same grid with the derivative of R and T (s, p) by
//! all 20 thicknesses (`optics::gradient::solve_stack_grid_with_gradient`).
//! Each is also timed as the fastest of several runs in one process, and
//! the ratio printed: docs/inverse.md quotes it.

// Not an API: criterion's macros generate undocumented public functions.
#![allow(missing_docs)]

use std::time::{Duration, Instant};

use criterion::{black_box, criterion_group, criterion_main, Criterion};

use irid::optics::gradient::solve_stack_grid_with_gradient;
use irid::optics::{Layer, Material, Response, Stack, StackGrid};

/// Air, 20 films alternating lossless (1.5) and absorbing (2.3 + 0.05i),
/// 100, 107, 114, ... nm, on a gold-like substrate: `benches/tmm.rs`'s stacks.
fn stack(layers: usize) -> Stack {
    Stack {
        ambient: Material::constant(1.0, 0.0),
        layers: (0..layers)
            .map(|i| {
                let m = if i % 2 == 0 {
                    Material::constant(1.5, 0.0)
                } else {
                    Material::constant(2.3, 0.05)
                };
                Layer::new(m, 100.0 + 7.0 * i as f64)
            })
            .collect(),
        substrate: Material::constant(0.27, 2.9),
    }
}

fn fastest(mut run: impl FnMut()) -> Duration {
    (0..30)
        .map(|_| {
            let start = Instant::now();
            run();
            start.elapsed()
        })
        .min()
        .expect("runs")
}

fn gradient(c: &mut Criterion) {
    let wavelengths: Vec<f64> = (0..401).map(|i| 400.0 + i as f64).collect();
    let cos: Vec<f64> = [0.0f64, 30.0, 60.0]
        .iter()
        .map(|a| a.to_radians().cos())
        .collect();
    let stack = stack(20);
    let grid = StackGrid::new(&stack, &wavelengths).expect("grid");
    let d = stack.thicknesses_nm();
    let mut out = vec![Response::default(); wavelengths.len() * cos.len()];

    let forward = fastest(|| grid.solve(black_box(&cos), &mut out));
    let with_gradient = fastest(|| {
        black_box(solve_stack_grid_with_gradient(&grid, black_box(&d), &cos).expect("solve"));
    });
    println!(
        "20 layers, 401 wavelengths × 3 angles: forward {forward:?}, with all 20 \
         derivatives {with_gradient:?}: {:.2}× the forward solve",
        with_gradient.as_secs_f64() / forward.as_secs_f64()
    );

    let mut g = c.benchmark_group("gradient");
    g.bench_function("20 layers, 401 wavelengths x 3 angles, forward", |b| {
        b.iter(|| {
            grid.solve(black_box(&cos), &mut out);
            out[0].r()
        })
    });
    g.bench_function("20 layers, 401 wavelengths x 3 angles, with gradient", |b| {
        b.iter(|| solve_stack_grid_with_gradient(&grid, black_box(&d), &cos).expect("solve"))
    });
    g.finish();
}

criterion_group!(benches, gradient);
criterion_main!(benches);
