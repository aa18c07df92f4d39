//! Fits of synthetic measurements of hidden stacks.

use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64;

use super::*;
use crate::optics::{Layer, Material, Response, StackGrid};

fn constant(n: f64) -> Material {
    Material::constant(n, 0.0)
}

/// A stack of `thicknesses` alternating high and low index on glass.
fn hidden_stack(thicknesses: &[f64], indices: &[f64]) -> Stack {
    Stack {
        ambient: constant(1.0),
        layers: thicknesses
            .iter()
            .zip(indices)
            .map(|(&d, &n)| Layer::new(constant(n), d))
            .collect(),
        substrate: constant(1.52),
    }
}

/// One standard normal deviate (Box–Muller).
fn gaussian(rng: &mut Pcg64) -> f64 {
    let (u, v): (f64, f64) = (rng.random::<f64>().max(1e-300), rng.random());
    (-2.0 * u.ln()).sqrt() * (2.0 * std::f64::consts::PI * v).cos()
}

/// R of `stack` at `wavelengths` × `angles`, plus noise of σ `noise`.
fn measure(
    stack: &Stack,
    wavelengths: &[f64],
    angles: &[f64],
    noise: f64,
    rng: &mut Pcg64,
) -> Measurement {
    let grid = StackGrid::new(stack, wavelengths).unwrap();
    let mut m = Measurement {
        sigma: Some(Vec::new()),
        reflectance: Some(Vec::new()),
        ..Measurement::default()
    };
    let mut out = vec![Response::default(); wavelengths.len()];
    for &a in angles {
        grid.solve_spectrum(&stack.thicknesses_nm(), a.to_radians().cos(), &mut out);
        for (w, r) in wavelengths.iter().zip(&out) {
            m.wavelength_nm.push(*w);
            m.angle_deg.push(a);
            m.reflectance
                .as_mut()
                .unwrap()
                .push(r.r() + noise * gaussian(rng));
            m.sigma.as_mut().unwrap().push(noise);
        }
    }
    m
}

/// The target: hidden stacks of 1 to 6 layers, R with noise
/// σ = 1e-3, bounds ±50 % around the truth with the start at a random
/// point inside them: every thickness within 3 σ_nm of the truth, σ_nm ≤
/// 1 nm.
#[test]
fn recovers_hidden_stacks_of_one_to_six_layers() {
    let mut rng = Pcg64::seed_from_u64(38);
    let wavelengths: Vec<f64> = (0..201).map(|i| 380.0 + 2.0 * i as f64).collect();
    for layers in 1..=6 {
        for _ in 0..3 {
            let truth: Vec<f64> = (0..layers).map(|_| rng.random_range(40.0..300.0)).collect();
            let indices: Vec<f64> = (0..layers)
                .map(|i| {
                    if i % 2 == 0 {
                        rng.random_range(2.0..2.4)
                    } else {
                        rng.random_range(1.38..1.5)
                    }
                })
                .collect();
            let hidden = hidden_stack(&truth, &indices);
            let measured = measure(&hidden, &wavelengths, &[0.0, 45.0], 1e-3, &mut rng);
            let start: Vec<f64> = truth
                .iter()
                .map(|d| d * rng.random_range(0.6..1.4))
                .collect();
            let bounds: Vec<(f64, f64)> = truth.iter().map(|d| (0.5 * d, 1.5 * d)).collect();
            let guess = hidden_stack(&start, &indices);
            let all: Vec<usize> = (1..=layers).collect();
            let vary = Vary::new(&guess, &all, Some(&bounds), "vary", "bounds").unwrap();
            let fit = fit_spectrum(&guess, &vary, &measured).unwrap();
            for p in 0..layers {
                let (d, s) = (fit.thickness_nm[p], fit.sigma_nm[p]);
                assert!(
                    (d - truth[p]).abs() <= 3.0 * s && s <= 1.0,
                    "{layers} layers, layer {}: {d} ± {s} against {}\n{fit:?}\ntruth {truth:?}",
                    p + 1,
                    truth[p]
                );
            }
            let reduced = fit.chi2 / fit.degrees_of_freedom as f64;
            assert!((0.7..1.3).contains(&reduced), "χ²/dof {reduced}");
        }
    }
}

/// Colours of hidden films (one and two layers) at three angles: the fit
/// reaches ΔE00 ≤ 0.5 at every angle, where an exact solution exists.
#[test]
fn colour_fit_reaches_reachable_targets() {
    use crate::color::{stack_colors, Sampling, SpectralIntegrator, White};
    let mut rng = Pcg64::seed_from_u64(2);
    let integrator = SpectralIntegrator::new(Sampling::Exact);
    let angles = [0.0, 35.0, 65.0];
    for layers in 1..=2 {
        for _ in 0..3 {
            let truth: Vec<f64> = (0..layers).map(|_| rng.random_range(60.0..500.0)).collect();
            let indices = [1.9, 1.4];
            let hidden = hidden_stack(&truth, &indices[..layers]);
            let colors = stack_colors(&hidden, &integrator, &angles).unwrap();
            let targets: Vec<ColorTarget> = colors
                .iter()
                .map(|c| ColorTarget {
                    angle_deg: c.angle_deg,
                    rgb: c.reflectance_rgb,
                })
                .collect();
            let start: Vec<f64> = truth
                .iter()
                .map(|d| d * rng.random_range(0.7..1.3))
                .collect();
            let bounds: Vec<(f64, f64)> = truth.iter().map(|d| (0.5 * d, 1.5 * d)).collect();
            let guess = hidden_stack(&start, &indices[..layers]);
            let all: Vec<usize> = (1..=layers).collect();
            let vary = Vary::new(&guess, &all, Some(&bounds), "vary", "bounds").unwrap();
            let fit = fit_color(&guess, &vary, &targets, White::D65, None).unwrap();
            assert!(
                fit.delta_e2000.iter().all(|de| *de <= 0.5),
                "{fit:?} truth {truth:?}"
            );
        }
    }
}

/// A colour brighter than white in one channel only, or negative
/// everywhere, is no passive film's; a film's own colour is.
#[test]
fn unreachable_colours_are_refused() {
    let guess = hidden_stack(&[300.0], &[1.33]);
    let vary = Vary::new(&guess, &[1], None, "vary", "bounds").unwrap();
    for rgb in [
        [1.5, 0.0, 0.0],
        [-0.1, -0.1, -0.1],
        [1.01, 1.01, 1.01],
        [f64::NAN, 0.0, 0.0],
    ] {
        let target = [ColorTarget {
            angle_deg: 0.0,
            rgb,
        }];
        let e = fit_color(&guess, &vary, &target, crate::color::White::D65, None).unwrap_err();
        assert!(e.to_string().starts_with("target_rgb[0]: "), "{e}");
    }
    let grey = [ColorTarget {
        angle_deg: 10.0,
        rgb: [0.99, 0.99, 0.99],
    }];
    assert!(fit_color(&guess, &vary, &grey, crate::color::White::D65, None).is_ok());
}

/// A 2.0-index film on glass: at normal incidence its first order (92 nm)
/// and its third (near 358 nm) reflect colours about 1 ΔE apart, so one
/// angle cannot tell them apart and the fit says so; at 0°, 45° and 70°
/// their colours differ by tens of ΔE and the fit is unique, at the truth.
#[test]
fn colour_fit_says_when_one_angle_cannot_tell_orders_apart() {
    use crate::color::{stack_colors, Sampling, SpectralIntegrator, White};
    let integrator = SpectralIntegrator::new(Sampling::Exact);
    let truth = [92.0];
    let hidden = hidden_stack(&truth, &[2.0]);
    let guess = hidden_stack(&[200.0], &[2.0]);
    let vary = Vary::new(&guess, &[1], Some(&[(60.0, 420.0)]), "vary", "bounds").unwrap();
    let targets_at = |angles: &[f64]| -> Vec<ColorTarget> {
        stack_colors(&hidden, &integrator, angles)
            .unwrap()
            .iter()
            .map(|c| ColorTarget {
                angle_deg: c.angle_deg,
                rgb: c.reflectance_rgb,
            })
            .collect()
    };

    let one = fit_color(&guess, &vary, &targets_at(&[0.0]), White::D65, None).unwrap();
    assert!((one.thickness_nm[0] - 92.0).abs() < 0.5, "{one:?}");
    assert!(one.is_ambiguous(), "{one:?}");
    assert_eq!(one.tolerance_de2000, AMBIGUITY_DE2000);
    let third = &one.alternatives[0];
    assert!((third.thickness_nm[0] - 358.0).abs() < 10.0, "{one:?}");
    assert!(third.delta_e2000[0] <= one.delta_e2000[0] + AMBIGUITY_DE2000);

    let three = fit_color(
        &guess,
        &vary,
        &targets_at(&[0.0, 45.0, 70.0]),
        White::D65,
        None,
    )
    .unwrap();
    assert!((three.thickness_nm[0] - 92.0).abs() < 0.5, "{three:?}");
    assert!(!three.is_ambiguous(), "{three:?}");
}
