//! The sweep against the solver and the integrator: its phase recurrence,
//! its colour weights, and its values on caller-chosen nodes.

use crate::cancel::Cancel;
use num_complex::Complex64 as C64;

use super::grid::AxisGrid;
use super::phases::{chunks, phases};
use super::prepared::rgb_weights;
use super::{rgb_at_nodes, uniform};
use crate::color::SpectralIntegrator;
use crate::optics::twoport::{Scratch, VaryingLayer};
use crate::optics::{Layer, Stack};

/// The incremental phase of `phases` and the batched responses against an
/// exact exponential and `response` per node, on an absorbing and a gain
/// layer at a steep angle.
#[test]
fn sweep_matches_exact_phase() {
    for (n, k) in [(1.5, 0.15), (1.5, -0.05), (1.33, 0.0)] {
        let idx = [C64::new(1.0, 0.0), C64::new(n, k), C64::new(0.2, 3.0)];
        let mut scratch = Scratch::default();
        let v = VaryingLayer::new(&idx, &[0.0], 1, 420.0, 0.3, &mut scratch);
        // Equal spacings that join into one run, and unequal ones.
        let mut segments: Vec<_> = (0..3)
            .map(|k| uniform(2000.0 * k as f64 / 3.0, 2000.0 * (k + 1) as f64 / 3.0, 700))
            .collect();
        segments.push(uniform(2000.0, 2003.0, 5));
        segments.push(uniform(2003.0, 2100.0, 131));
        let axis = AxisGrid::new(&segments);
        let mut worst = 0.0f64;
        let n = axis.nodes.len();
        // `phases` runs each chunk on to whole vectors.
        let (mut re, mut im) = (vec![0.0; n + 7], vec![0.0; n + 7]);
        phases(&v, &axis.nodes, &chunks(&axis), &mut re, &mut im);
        let (re, im) = (&re[..n], &im[..n]);
        for (j, &d) in axis.nodes.iter().enumerate() {
            let want = v.phase(d);
            worst = worst.max((C64::new(re[j], im[j]) - want).norm() / (1.0 + want.norm()));
        }
        let (mut r, mut t) = (vec![0.0; n], vec![0.0; n]);
        v.responses(re, im, &mut r, &mut t);
        for j in 0..n {
            let want = v.response(v.phase(axis.nodes[j]));
            for (g, w) in [(r[j], want.r()), (t[j], want.t())] {
                worst = worst.max((g - w).abs() / (1.0 + w.abs()));
            }
        }
        // The fused pass adds exactly what the separate one gives.
        let weights = [0.3, -0.7, 1.1];
        let start: Vec<f64> = (0..6 * n).map(|i| i as f64 * 1e-3).collect();
        let mut acc = start.clone();
        v.accumulate_responses(re, im, weights, &mut acc);
        for (k, (a, s)) in acc.chunks_exact(n).zip(start.chunks_exact(n)).enumerate() {
            let values = if k < 3 { &r } else { &t };
            for j in 0..n {
                let want = weights[k % 3].mul_add(values[j], s[j]);
                assert_eq!(a[j].to_bits(), want.to_bits(), "channel {k} node {j}");
            }
        }
        assert!(worst < 1e-12, "n = {n}{k:+}i: {worst:e}");
    }
}

/// The weights the bake accumulates are the integrator's colour of a
/// unit impulse at each wavelength, bit for bit (its dot product adds
/// only zeros to the one weight), so folding the integration into the
/// bake gives what integrating each spectrum would.
#[test]
fn rgb_weights_are_the_color_of_an_impulse() {
    use crate::color::Sampling;
    for sampling in [
        Sampling::Exact,
        Sampling::Rgb3,
        Sampling::Uniform(9),
        Sampling::Uniform(16),
        Sampling::Uniform(81),
    ] {
        let integrator = SpectralIntegrator::new(sampling);
        let weights = rgb_weights(&integrator);
        let mut impulse = vec![0.0; integrator.wavelengths_nm().len()];
        assert_eq!(weights.len(), impulse.len());
        for (i, w) in weights.iter().enumerate() {
            impulse[i] = 1.0;
            let want = integrator.rgb(&impulse);
            impulse[i] = 0.0;
            assert_eq!(
                w.map(f64::to_bits),
                want.map(f64::to_bits),
                "{sampling} {i}"
            );
        }
    }
}

/// A free-standing film of thickness 0 is no film: the sweep gives R = 0
/// and T = the colour of a flat spectrum at every angle, including cos θ
/// 1e-9, where its interfaces reflect all but 5e-9 of the light and (n0
/// cos θ)² is below the rounding of n0² (it once gave 0/0 there).
#[test]
fn a_film_of_no_thickness_is_no_film_at_grazing_incidence() {
    let stack = Stack {
        ambient: crate::optics::Material::constant(1.0, 0.0),
        layers: vec![Layer::new(
            crate::optics::Material::constant(1.33, 0.0),
            0.0,
        )],
        substrate: crate::optics::Material::constant(1.0, 0.0),
    };
    let integrator = SpectralIntegrator::new(crate::color::Sampling::Exact);
    let white = integrator.rgb(&vec![1.0; integrator.wavelengths_nm().len()]);
    let cos = [1e-9, 1e-7, 1e-3, 0.5, 1.0];
    let values = rgb_at_nodes(&stack, 1, integrator, &[0.0], &cos, Cancel::never()).unwrap();
    for (v, c) in values.iter().zip(cos) {
        for k in 0..3 {
            assert!(v[k].abs() < 1e-5, "cos θ {c}: R {v:?}");
            assert!((v[3 + k] - white[k]).abs() < 1e-5, "cos θ {c}: T {v:?}");
        }
    }
}

/// `rgb_at_nodes` (the sweep on caller-chosen nodes, as the GPU export uses
/// it) against the solver and the integrator node by node, on a
/// square-root thickness axis, an evenly spaced one and an uneven cos θ
/// axis, for a two-layer stack with an absorbing film on gold.
#[test]
fn sweep_on_given_nodes_matches_the_solver() {
    let stack = Stack {
        ambient: crate::optics::Material::constant(1.0, 0.0),
        layers: vec![
            Layer::new(crate::optics::Material::constant(1.5, 0.15), 300.0),
            Layer::new(crate::optics::library::builtin("TiO2").unwrap(), 80.0),
        ],
        substrate: crate::optics::library::builtin("gold").unwrap(),
    };
    let integrator = SpectralIntegrator::new(crate::color::Sampling::Exact);
    let cos: Vec<f64> = (0..7)
        .map(|i| (f64::from(i) / 6.0).powf(0.7).max(0.01))
        .collect();
    let sqrt_axis: Vec<f64> = (0..150)
        .map(|i| 500.0 * (f64::from(i) / 149.0).powi(2))
        .collect();
    let even_axis: Vec<f64> = (0..150).map(|i| 500.0 * f64::from(i) / 149.0).collect();
    let grid = crate::optics::StackGrid::new(&stack, integrator.wavelengths_nm()).unwrap();
    // Near grazing incidence some nodes integrate more finely (see
    // crate::color::refine), at the wavelengths of their level.
    let refinement = crate::color::refine::Refinement::new(&stack, Some(1), &integrator).unwrap();
    let mut refined = 0;
    for axis in [&sqrt_axis, &even_axis, &vec![250.0]] {
        let values =
            rgb_at_nodes(&stack, 1, integrator.clone(), axis, &cos, Cancel::never()).unwrap();
        assert_eq!(values.len(), axis.len() * cos.len());
        let mut worst = 0.0f64;
        for (c_index, &c) in cos.iter().enumerate() {
            for (t_index, &t) in axis.iter().enumerate().step_by(7) {
                let mut thick = grid.thicknesses_nm().to_vec();
                thick[0] = t;
                let m = refinement.sub_steps(t, c);
                refined += usize::from(m > 1);
                let (grid, integrator) = if m > 1 {
                    let level = refinement.level(m).unwrap();
                    (&level.grid, &level.integrator)
                } else {
                    (&grid, &integrator)
                };
                let mut spectrum =
                    vec![crate::optics::Response::default(); grid.wavelengths_nm().len()];
                grid.solve_spectrum(&thick, c, &mut spectrum);
                let r: Vec<f64> = spectrum.iter().map(|x| x.r()).collect();
                let tr: Vec<f64> = spectrum.iter().map(|x| x.t()).collect();
                let (want_r, want_t) = (integrator.rgb(&r), integrator.rgb(&tr));
                let got = values[c_index * axis.len() + t_index];
                for k in 0..3 {
                    worst = worst.max((got[k] - want_r[k]).abs());
                    worst = worst.max((got[3 + k] - want_t[k]).abs());
                }
            }
        }
        assert!(worst < 1e-12, "{} nodes: worst {worst:e}", axis.len());
    }
    assert!(refined > 0, "no node at cos θ 0.01 integrated more finely");
}
