//! The cost of the exact thickness derivatives against the forward solve:
//! R and T of a 20-layer stack over 401 wavelengths × 3 angles (the
//! forward spectrum as `StackGrid::solve` gives it, on the widest lanes the
//! CPU has), and the same grid with the derivative of R and T (s, p) by
//! all 20 thicknesses (`optics::gradient::solve_stack_grid_with_gradient`).
//! Each is also timed as the fastest of several runs in one process, and
//! the ratio printed: docs/inverse.md quotes it. The same stack with two
//! incoherent layers (mixed) is timed through the lanes and point by point
//! on the scalar gradient, and that ratio printed too; and the coherent
//! grid with the n and k derivatives as well
//! (`solve_stack_grid_with_index_gradient`, scalar path) against the
//! thickness gradient and the forward solve.

// Not an API: criterion's macros generate undocumented public functions.
#![allow(missing_docs)]

use std::time::{Duration, Instant};

use criterion::{black_box, criterion_group, criterion_main, Criterion};

use irid::bench::inverse::gradient_stack;
use irid::optics::gradient::{
    solve_grid_point_with_gradient, solve_stack_grid_with_gradient,
    solve_stack_grid_with_index_gradient, Workspace,
};
use irid::optics::{Response, StackGrid};

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
    let stack = gradient_stack(20);
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
    let with_index = fastest(|| {
        black_box(solve_stack_grid_with_index_gradient(&grid, black_box(&d), &cos).expect("solve"));
    });
    println!(
        "20 layers, 401 wavelengths × 3 angles: with the 20 thickness, 20 n and 20 k \
         derivatives (scalar path) {with_index:?}: {:.2}× the thickness gradient (lanes), \
         {:.2}× the forward solve",
        with_index.as_secs_f64() / with_gradient.as_secs_f64(),
        with_index.as_secs_f64() / forward.as_secs_f64()
    );

    let mut mixed = stack.clone();
    for l in [5, 14] {
        mixed.layers[l].coherent = false;
        mixed.layers[l].thickness_nm = 2000.0;
    }
    let mixed_grid = StackGrid::new(&mixed, &wavelengths).expect("grid");
    let dm = mixed.thicknesses_nm();
    let scalar_mixed = || {
        let mut work = Workspace::default();
        for w in 0..wavelengths.len() {
            for &c in &cos {
                black_box(
                    solve_grid_point_with_gradient(&mixed_grid, w, &dm, c, &mut work)
                        .expect("solve"),
                );
            }
        }
    };
    let lanes_mixed = || {
        black_box(solve_stack_grid_with_gradient(&mixed_grid, black_box(&dm), &cos).expect("solve"))
    };
    let (scalar_time, lanes_time) = (
        fastest(scalar_mixed),
        fastest(|| {
            lanes_mixed();
        }),
    );
    println!(
        "20 layers (2 incoherent), 401 wavelengths × 3 angles, all 20 derivatives: \
         scalar {scalar_time:?}, lanes {lanes_time:?}: scalar/lanes {:.2}",
        scalar_time.as_secs_f64() / lanes_time.as_secs_f64()
    );

    let mut g = c.benchmark_group("gradient");
    g.bench_function(
        "mixed 20 layers, 401 wavelengths x 3 angles, gradient, scalar",
        |b| b.iter(scalar_mixed),
    );
    g.bench_function(
        "mixed 20 layers, 401 wavelengths x 3 angles, gradient, lanes",
        |b| b.iter(lanes_mixed),
    );
    g.bench_function("20 layers, 401 wavelengths x 3 angles, forward", |b| {
        b.iter(|| {
            grid.solve(black_box(&cos), &mut out);
            out[0].r()
        })
    });
    g.bench_function(
        "20 layers, 401 wavelengths x 3 angles, with gradient",
        |b| b.iter(|| solve_stack_grid_with_gradient(&grid, black_box(&d), &cos).expect("solve")),
    );
    g.finish();
}

criterion_group!(benches, gradient);
criterion_main!(benches);
