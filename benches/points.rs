//! R and T at arbitrary points, each its own wavelength, angle and
//! thickness, as a spectral renderer asks for them (irid.mitsuba's solver
//! path): 4096 random points (cos θ in [0, 1], 360–830 nm, 250–350 nm of the
//! film) of three stacks, time per point via throughput, four ways:
//! - `indices + solve per point`: each point's materials evaluated and the
//!   scalar solver called, as the Python package did point by point;
//! - `indices only`: the materials' evaluation alone, the part no kernel
//!   speeds up;
//! - `Stack::solve_points` on the portable and AVX2 copies of the lane
//!   kernel, and on the widest the CPU has.

// Not an API: criterion's macros generate undocumented public functions.
#![allow(missing_docs)]

use std::path::Path as FsPath;

use criterion::{black_box, criterion_group, criterion_main, Criterion, Throughput};
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64;

use irid::optics::lanes::{avx2_available, best_copy, Path};
use irid::optics::{solve, LayerThickness, PointSolver, Response, Stack};

const POINTS: usize = 4096;

fn stacks() -> Vec<(&'static str, Stack)> {
    let luts = FsPath::new(env!("CARGO_MANIFEST_DIR")).join("luts");
    let film_on_copper = Stack::from_toml_str(
        "ambient = { n = 1.0 }\nsubstrate = { material = \"copper\" }\n\
         [[layers]]\nmaterial = \"TiO2\"\nthickness_nm = 300.0\n",
        &luts,
        "bench",
    )
    .unwrap();
    vec![
        ("TiO2 on copper", film_on_copper),
        (
            "soap-film",
            Stack::load(&luts.join("soap-film.toml")).unwrap(),
        ),
        (
            "two-layer",
            Stack::load(&luts.join("two-layer.toml")).unwrap(),
        ),
    ]
}

fn points(c: &mut Criterion) {
    let mut rng = Pcg64::seed_from_u64(7);
    let wl: Vec<f64> = (0..POINTS)
        .map(|_| rng.random_range(360.0..830.0))
        .collect();
    let cos: Vec<f64> = (0..POINTS).map(|_| rng.random_range(0.0..1.0)).collect();
    let thickness: Vec<f64> = (0..POINTS)
        .map(|_| rng.random_range(250.0..350.0))
        .collect();
    let varying = Some(LayerThickness {
        layer: 0,
        thickness_nm: &thickness,
    });
    let mut out = vec![Response::default(); POINTS];
    let mut g = c.benchmark_group("points");
    g.throughput(Throughput::Elements(POINTS as u64));
    for (name, stack) in stacks() {
        g.bench_function(format!("{name}, indices + solve per point"), |b| {
            let mut n = Vec::new();
            let mut d = stack.thicknesses_nm();
            b.iter(|| {
                for i in 0..POINTS {
                    stack.indices_at(wl[i], &mut n).unwrap();
                    d[0] = thickness[i];
                    out[i] = solve(&n, &d, wl[i], cos[i]);
                }
                out[POINTS - 1].r()
            })
        });
        g.bench_function(format!("{name}, indices only"), |b| {
            let mut n = Vec::new();
            b.iter(|| {
                let mut sum = 0.0;
                for &w in &wl {
                    stack.indices_at(black_box(w), &mut n).unwrap();
                    sum += n[1].re;
                }
                sum
            })
        });
        let mut copies = vec![("portable", Path::Portable)];
        if avx2_available() {
            copies.push(("AVX2", Path::Avx2));
        }
        if best_copy() != copies[copies.len() - 1].0 {
            copies.push((best_copy(), Path::Best));
        }
        for (copy, path) in copies {
            let solver = PointSolver::new(&stack).unwrap();
            g.bench_function(format!("{name}, solve_points {copy}"), |b| {
                b.iter(|| {
                    solver
                        .solve_on(path, varying, black_box(&wl), &cos, &mut out)
                        .unwrap();
                    out[POINTS - 1].r()
                })
            });
        }
    }
    g.finish();
}

criterion_group!(benches, points);
criterion_main!(benches);
