//! Solver speed: unpolarized R and T of stacks of 1, 2, 10 and 100 layers at
//! one wavelength and angle (both polarizations), and the batched entry point.
//! The stacks are the ones `tools/time_tmm.py` times in Python `tmm`.

use criterion::{black_box, criterion_group, criterion_main, Criterion};
use num_complex::Complex64 as C64;

use irid::optics::solve;

/// Ambient air, `layers` alternating lossless/absorbing films, a gold-like
/// substrate: the same stacks as `tools/time_tmm.py`.
fn bench_stack(layers: usize) -> (Vec<C64>, Vec<f64>) {
    let mut n = vec![C64::new(1.0, 0.0)];
    let mut d = Vec::new();
    for i in 0..layers {
        n.push(if i % 2 == 0 {
            C64::new(1.5, 0.0)
        } else {
            C64::new(2.3, 0.05)
        });
        d.push(100.0 + 7.0 * i as f64);
    }
    n.push(C64::new(0.27, 2.9));
    (n, d)
}

fn single(c: &mut Criterion) {
    let mut g = c.benchmark_group("solve");
    for layers in [1usize, 2, 10, 100] {
        let (n, d) = bench_stack(layers);
        g.bench_function(format!("{layers} layers"), |b| {
            b.iter(|| {
                let r = solve(
                    black_box(&n),
                    black_box(&d),
                    black_box(550.0),
                    black_box(0.8),
                );
                (r.r(), r.t())
            })
        });
    }
    g.finish();
}

criterion_group!(benches, single);
criterion_main!(benches);
