use num_complex::Complex64 as C64;

use super::super::solver::{solve_amplitudes, Amplitudes};
use super::*;

fn c(re: f64, im: f64) -> C64 {
    C64::new(re, im)
}

/// The taped recursion is the solver's recursion: the same amplitudes, in
/// Γ form bit for bit, and across near-critical layers (whose matrix
/// products it groups differently) to rounding.
#[test]
fn taped_recursion_is_the_solver() {
    let cases: [(&[C64], &[f64], f64); 3] = [
        (
            &[c(1.0, 0.0), c(1.4, 0.0), c(2.0, 0.5), c(1.5, 0.0)],
            &[100.0, 50.0],
            0.7,
        ),
        (
            &[
                c(1.5, 0.0),
                c(1.2, 0.0),
                c(1.9, 0.0),
                c(1.2, 1e-5),
                c(1.5, 0.1),
            ],
            &[200.0, 100.0, 250.0],
            0.6,
        ),
        (&[c(1.0, 0.0), c(1.5, -0.05), c(1.0, 0.0)], &[300.0], 1.0),
    ];
    for (indices, thicknesses, cos) in cases {
        let n0 = indices[0].re;
        let beta_sq = n0 * n0 * sin_sq(cos);
        let top = [c(n0, 0.0), c(n0 * n0, 0.0), c(n0 * cos, 0.0)];
        let q_sub = normal_index(indices[indices.len() - 1], beta_sq);
        let mut tape = Vec::new();
        let mut out = vec![AmplitudeGradient::default(); thicknesses.len()];
        let mut by_index = vec![AmplitudeGradient::default(); indices.len()];
        let got: Amplitudes = recurse_media_gradient(
            indices.len(),
            |j| indices[j],
            |j| thicknesses[j],
            550.0,
            beta_sq,
            top,
            q_sub,
            &mut tape,
            (&mut out, &mut by_index),
        );
        let want = solve_amplitudes(indices, thicknesses, 550.0, cos);
        for (g, w) in [
            (got.rs, want.rs),
            (got.rp, want.rp),
            (got.ts, want.ts),
            (got.tp, want.tp),
        ] {
            assert!((g - w).norm() <= 1e-14 * w.norm().max(1.0), "{g} vs {w}");
        }
    }
}
