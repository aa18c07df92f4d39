//! The thickness derivatives of R and T (optics::gradient) against central
//! finite differences of the forward solver (Richardson-extrapolated, so
//! the difference's own error is far below the tolerance), over random
//! coherent and mixed stacks and the hard cases: thick absorbers,
//! evanescent gaps, total internal reflection, grazing incidence, gain,
//! hundreds of layers and layers at their critical angle.

mod common;

use num_complex::Complex64 as C64;
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64;

use common::gradient::{gradient_parts, parts, stack_of};
use common::random_stack::{random_stack, KINDS};
use irid::optics::gradient::{
    solve_grid_with_gradient, solve_stack_grid_with_gradient_on, solve_with_gradient,
    ResponseGradient,
};
use irid::optics::lanes::Path;
use irid::optics::{solve_amplitudes, Stack, StackGrid};

/// The four derivatives by layer `layer`'s thickness, by a central
/// difference of step h and h/2 combined (Richardson): error O(h⁴).
fn finite_difference(stack: &Stack, layer: usize, wavelength_nm: f64, c: f64, h: f64) -> [f64; 4] {
    let at = |delta: f64| {
        let mut s = stack.clone();
        s.layers[layer].thickness_nm += delta;
        parts(&s.response(wavelength_nm, c).expect("forward solve"))
    };
    let central = |h: f64| {
        let (up, down) = (at(h), at(-h));
        [0, 1, 2, 3].map(|i| (up[i] - down[i]) / (2.0 * h))
    };
    let (coarse, fine) = (central(h), central(h / 2.0));
    [0, 1, 2, 3].map(|i| (4.0 * fine[i] - coarse[i]) / 3.0)
}

/// Checks every derivative of `stack` at one point against the finite
/// difference: within `rel` of the largest derivative of the same
/// quantity over the layers, or 1e-10 absolute.
fn check(stack: &Stack, wavelength_nm: f64, c: f64, rel: f64, what: &str) {
    let (response, gradient) = solve_with_gradient(stack, wavelength_nm, c).expect("gradient");
    let forward = stack.response(wavelength_nm, c).expect("forward");
    for (a, b) in parts(&response).iter().zip(parts(&forward)) {
        assert!(
            (a - b).abs() <= 1e-12 * b.abs().max(1.0),
            "{what}: response {a} vs {b}"
        );
    }
    let layers = stack.layers.len();
    let fd: Vec<[f64; 4]> = (0..layers)
        // R and T are analytic in d, so a zero-thickness layer is
        // differenced through negative thicknesses like any other.
        .map(|l| finite_difference(stack, l, wavelength_nm, c, 1e-2))
        .collect();
    for q in 0..4 {
        let scale = (0..layers).map(|l| fd[l][q].abs()).fold(0.0, f64::max);
        for (l, fd_l) in fd.iter().enumerate() {
            let got = gradient_parts(&gradient, l)[q];
            let want = fd_l[q];
            assert!(
                got.is_finite() && (got - want).abs() <= rel * scale + 1e-10,
                "{what}: layer {l}, quantity {q} (rs rp ts tp): {got} vs FD {want} (scale {scale})"
            );
        }
    }
}

#[test]
fn random_coherent_stacks() {
    let mut rng = Pcg64::seed_from_u64(38);
    for case in 0..120 {
        let kind = KINDS[case % KINDS.len()];
        let layers = rng.random_range(1..8);
        let (n, d) = random_stack(&mut rng, kind, layers, 400.0);
        let stack = stack_of(&n, &d);
        let wl = rng.random_range(350.0..850.0);
        let c: f64 = rng.random_range(0.05..1.0);
        check(&stack, wl, c, 1e-7, &format!("case {case} {kind:?}"));
    }
}

#[test]
fn random_mixed_stacks() {
    let mut rng = Pcg64::seed_from_u64(3838);
    let mut checked = 0;
    for case in 0..200 {
        let kind = KINDS[case % KINDS.len()];
        let layers = rng.random_range(2..8);
        let (n, mut d) = random_stack(&mut rng, kind, layers, 300.0);
        let mut stack = stack_of(&n, &d);
        for (l, layer) in stack.layers.iter_mut().enumerate() {
            if rng.random_bool(0.35) {
                layer.coherent = false;
                d[l] = rng.random_range(0.0..3000.0);
                layer.thickness_nm = d[l];
            }
        }
        let wl = rng.random_range(350.0..850.0);
        let c: f64 = rng.random_range(0.05..1.0);
        // A gain layer that lases has no answer either way.
        if stack.response(wl, c).is_err() {
            assert!(solve_with_gradient(&stack, wl, c).is_err());
            continue;
        }
        check(&stack, wl, c, 1e-7, &format!("case {case} {kind:?}"));
        checked += 1;
    }
    assert!(checked > 150, "only {checked} mixed stacks checked");
}

fn c64(re: f64, im: f64) -> C64 {
    C64::new(re, im)
}

#[test]
fn thick_absorbers() {
    // A coherent absorbing layer so thick that its round trip underflows:
    // nothing below it matters, and its own derivative is that of a half-space (0).
    let n = [
        c64(1.0, 0.0),
        c64(1.4, 0.0),
        c64(2.0, 1.0),
        c64(1.6, 0.0),
        c64(1.5, 0.0),
    ];
    for d2 in [5e3, 1e6] {
        let stack = stack_of(&n, &[120.0, d2, 80.0]);
        let (_, g) = solve_with_gradient(&stack, 500.0, 0.8).unwrap();
        // e^{-2 k0 Im(q) d}: 1e-55 through 5 µm, exactly 0 (underflow) through 1 mm.
        let bound = if d2 > 1e4 { 0.0 } else { 1e-50 };
        for l in [1, 2] {
            let g = gradient_parts(&g, l);
            assert!(
                g.iter().all(|x| x.abs() <= bound),
                "layer {l} below the absorber: {g:?}"
            );
        }
        check(&stack, 500.0, 0.8, 1e-7, "thick absorber");
    }
    // A thinner absorber lets some light through: every derivative counts.
    let stack = stack_of(&n, &[120.0, 60.0, 80.0]);
    check(&stack, 500.0, 0.8, 1e-7, "thin absorber");
}

#[test]
fn evanescent_gap_and_total_internal_reflection() {
    // Glass, an air gap, glass: frustrated total internal reflection at 60°.
    let n = [c64(1.5, 0.0), c64(1.0, 0.0), c64(1.5, 0.0), c64(1.5, 0.0)];
    let c = 60f64.to_radians().cos();
    for gap in [50.0, 300.0, 3000.0] {
        check(
            &stack_of(&n, &[gap, 200.0]),
            600.0,
            c,
            1e-7,
            "evanescent gap",
        );
    }
    // Total internal reflection at the substrate, films above it.
    let n = [c64(1.6, 0.0), c64(2.1, 0.0), c64(1.45, 0.0), c64(1.0, 0.0)];
    check(&stack_of(&n, &[90.0, 140.0]), 550.0, 0.3, 1e-7, "TIR");
    // With an absorbing film, R < 1 under TIR.
    let n = [c64(1.6, 0.0), c64(2.1, 0.3), c64(1.45, 0.0), c64(1.0, 0.0)];
    check(&stack_of(&n, &[90.0, 140.0]), 550.0, 0.3, 1e-7, "lossy TIR");
}

#[test]
fn grazing_incidence() {
    let n = [c64(1.0, 0.0), c64(1.5, 0.0), c64(2.0, 0.1), c64(1.5, 0.0)];
    for c in [1e-2, 1e-4, 1e-7] {
        check(&stack_of(&n, &[150.0, 80.0]), 500.0, c, 1e-7, "grazing");
    }
    // At exactly grazing incidence nothing depends on the thicknesses.
    let (r, g) = solve_with_gradient(&stack_of(&n, &[150.0, 80.0]), 500.0, 0.0).unwrap();
    assert_eq!(r.r(), 1.0);
    assert_eq!(g, ResponseGradient::zeros(2));
}

#[test]
fn gain_layers() {
    let n = [
        c64(1.0, 0.0),
        c64(1.8, -0.05),
        c64(1.3, 0.0),
        c64(2.2, -0.02),
        c64(1.5, 0.0),
    ];
    for wl in [400.0, 550.0, 700.0] {
        check(&stack_of(&n, &[300.0, 120.0, 500.0]), wl, 0.9, 1e-7, "gain");
    }
}

#[test]
fn hundreds_of_layers() {
    let mut rng = Pcg64::seed_from_u64(300);
    let (n, d) = random_stack(&mut rng, KINDS[1], 300, 150.0);
    let stack = stack_of(&n, &d);
    let (_, g) = solve_with_gradient(&stack, 600.0, 0.7).unwrap();
    // Every derivative finite; a sample of layers against the difference.
    assert!(g
        .rs
        .iter()
        .chain(&g.rp)
        .chain(&g.ts)
        .chain(&g.tp)
        .all(|x| x.is_finite()));
    // A lossless quarter-wave mirror of 200 layers, where light reaches every layer.
    let mut n = vec![c64(1.0, 0.0)];
    let mut d = vec![];
    for i in 0..200 {
        let (ni, di) = if i % 2 == 0 {
            (2.3, 60.0)
        } else {
            (1.38, 100.0)
        };
        n.push(c64(ni, 0.0));
        d.push(di + rng.random_range(-5.0..5.0));
    }
    n.push(c64(1.52, 0.0));
    check(&stack_of(&n, &d), 700.0, 0.9, 1e-7, "200 layers");
}

#[test]
fn near_critical_layers() {
    // Glass ambient at sin θ0 = 0.8: β = 1.2, so a layer of index 1.2 sits
    // at its critical angle (q = 0) and is crossed in field form.
    let c = 0.6;
    for (k, d) in [(0.0, 300.0), (1e-5, 300.0), (1e-6, 1e7), (0.0, 0.0)] {
        let n = [
            c64(1.5, 0.0),
            c64(2.0, 0.0),
            c64(1.2, k),
            c64(1.7, 0.0),
            c64(1.5, 0.0),
        ];
        check(
            &stack_of(&n, &[80.0, d, 150.0]),
            550.0,
            c,
            1e-7,
            "near-critical",
        );
        // A run of two near-critical layers, and one at the bottom of the stack.
        let n = [
            c64(1.5, 0.0),
            c64(1.2, 0.0),
            c64(1.2, k),
            c64(1.9, 0.0),
            c64(1.2, 0.0),
            c64(1.5, 0.1),
        ];
        check(
            &stack_of(&n, &[200.0, d, 100.0, 250.0]),
            550.0,
            c,
            1e-7,
            "near-critical run",
        );
    }
}

/// The grid (the lanes for coherent stacks, each copy of the kernel, the
/// scalar gradient for the points they leave) against the scalar gradient
/// point by point, and a coherent grid's amplitudes against
/// `solve_amplitudes`, over random stacks of every kind, with grazing and
/// near-critical points among them, and for a mixed stack (no amplitudes).
#[test]
fn grid_matches_points() {
    let mut rng = Pcg64::seed_from_u64(401);
    let mut stacks: Vec<Stack> = (0..24)
        .map(|case| {
            let layers = rng.random_range(0..12);
            let (n, d) = random_stack(&mut rng, KINDS[case % KINDS.len()], layers, 300.0);
            stack_of(&n, &d)
        })
        .collect();
    // Glass at sin θ0 = 0.8 (cos 0.6) puts the 1.2 layer at its critical angle.
    stacks.push(stack_of(
        &[
            c64(1.5, 0.0),
            c64(2.0, 0.0),
            c64(1.2, 0.0),
            c64(1.7, 0.01),
            c64(1.5, 0.0),
        ],
        &[80.0, 300.0, 150.0],
    ));
    let mut mixed = stack_of(
        &[c64(1.0, 0.0), c64(1.45, 0.0), c64(2.1, 0.2), c64(1.5, 0.0)],
        &[130.0, 2000.0],
    );
    mixed.layers[1].coherent = false;
    stacks.push(mixed);
    let wavelengths: Vec<f64> = (0..11).map(|i| 400.0 + 37.0 * i as f64).collect();
    let cosines = [1.0, 0.6, 0.1, 1e-6, 0.0];
    for (case, stack) in stacks.iter().enumerate() {
        let grid = StackGrid::new(stack, &wavelengths).unwrap();
        assert_eq!(
            solve_grid_with_gradient(stack, &wavelengths, &cosines).unwrap(),
            solve_stack_grid_with_gradient_on(Path::Best, &grid, &stack.thicknesses_nm(), &cosines)
                .unwrap()
        );
        for path in [Path::Best, Path::Avx2, Path::Portable] {
            let got =
                solve_stack_grid_with_gradient_on(path, &grid, &stack.thicknesses_nm(), &cosines)
                    .unwrap();
            assert_eq!(
                (got.layers, got.wavelengths, got.angles),
                (stack.layers.len(), 11, 5)
            );
            let coherent = stack.is_coherent();
            assert_eq!(got.amplitudes.len(), if coherent { 55 } else { 0 });
            for (w, &wl) in wavelengths.iter().enumerate() {
                for (a, &c) in cosines.iter().enumerate() {
                    let (r, g) = solve_with_gradient(stack, wl, c).unwrap();
                    let close =
                        |x: f64, y: f64, scale: f64| (x - y).abs() <= 1e-12 * scale.max(1.0);
                    if coherent {
                        let want =
                            solve_amplitudes(grid.indices_at(w), &stack.thicknesses_nm(), wl, c);
                        let have = got.amplitudes[w * 5 + a];
                        let pairs = [
                            (have.rs, want.rs),
                            (have.rp, want.rp),
                            (have.ts, want.ts),
                            (have.tp, want.tp),
                        ];
                        assert!(
                            pairs
                                .iter()
                                .all(|(x, y)| (x - y).norm() <= 1e-12 * y.norm().max(1.0)),
                            "case {case} {path:?} amplitudes at ({w}, {a}): {have:?} vs {want:?}"
                        );
                    }
                    let resp = got.response[w * 5 + a];
                    assert!(
                        parts(&resp)
                            .iter()
                            .zip(parts(&r))
                            .all(|(x, y)| close(*x, y, y.abs())),
                        "case {case} {path:?}: {resp:?} vs {r:?}"
                    );
                    for l in 0..stack.layers.len() {
                        let i = got.at(l, w, a);
                        let lanes = [got.d_rs[i], got.d_rp[i], got.d_ts[i], got.d_tp[i]];
                        let scalar = gradient_parts(&g, l);
                        for q in 0..4 {
                            let scale = (0..stack.layers.len())
                                .map(|m| gradient_parts(&g, m)[q].abs())
                                .fold(0.0, f64::max);
                            assert!(
                                close(lanes[q], scalar[q], scale * 1e3),
                                "case {case} {path:?} layer {l} at ({w}, {a}), quantity {q}: {} vs {}",
                                lanes[q],
                                scalar[q]
                            );
                        }
                    }
                }
            }
        }
    }
}

#[test]
fn lasing_is_an_error() {
    let mut stack = stack_of(&[c64(1.0, 0.0), c64(1.5, -0.05), c64(1.0, 0.0)], &[1e5]);
    stack.layers[0].coherent = false;
    let err = solve_with_gradient(&stack, 500.0, 1.0)
        .unwrap_err()
        .to_string();
    assert!(err.contains("layers[1]") && err.contains("lases"), "{err}");
}

mod color {
    use super::*;
    use irid::color::gradient::{
        color_with_gradient, colors_with_gradient, delta_e00_with_gradient,
    };
    use irid::color::{delta_e2000_rgb, stack_colors, Sampling, SpectralIntegrator, White};

    fn film(coherent_sheet: bool) -> Stack {
        let n = [
            c64(1.0, 0.0),
            c64(1.38, 0.0),
            c64(2.3, 0.05),
            c64(1.5, 0.0),
            c64(1.52, 0.0),
        ];
        let mut stack = stack_of(&n, &[110.0, 260.0, 1500.0]);
        stack.layers[2].coherent = coherent_sheet;
        stack
    }

    /// The colour and its derivatives against stack_colors and its finite
    /// difference, for a coherent film and one on an incoherent sheet,
    /// under both whites.
    #[test]
    fn color_derivatives_match_finite_differences() {
        for (coherent, white) in [(true, White::D65), (false, White::E)] {
            let stack = film(coherent);
            let integrator = SpectralIntegrator::with_white(Sampling::Exact, white);
            let angles = [0.0, 35.0, 70.0];
            let got = colors_with_gradient(&stack, &integrator, &angles).unwrap();
            let want = stack_colors(&stack, &integrator, &angles).unwrap();
            // The same sum; the batched solver's lanes agree with the
            // scalar recursion to an ulp or so.
            let close = |x: [f64; 3], y: [f64; 3]| (0..3).all(|c| (x[c] - y[c]).abs() <= 1e-13);
            for (a, (g, w)) in got.iter().zip(&want).enumerate() {
                assert!(close(g.reflectance_rgb, w.reflectance_rgb), "angle {a}");
                assert!(close(g.transmittance_rgb, w.transmittance_rgb), "angle {a}");
                assert!(close(g.reflectance_xyz, w.reflectance_xyz), "angle {a}");
                assert!(close(g.transmittance_xyz, w.transmittance_xyz), "angle {a}");
            }
            let single = color_with_gradient(&stack, angles[1].to_radians().cos(), white).unwrap();
            assert_eq!(single, got[1]);
            for l in 0..stack.layers.len() {
                let colors = |delta: f64| {
                    let mut s = stack.clone();
                    s.layers[l].thickness_nm += delta;
                    stack_colors(&s, &integrator, &angles).unwrap()
                };
                let h = 1e-2;
                let [up, down, up2, down2] = [h, -h, h / 2.0, -h / 2.0].map(colors);
                for a in 0..angles.len() {
                    for ch in 0..3 {
                        let fd = |f: fn(&irid::color::FilmColor) -> [f64; 3]| {
                            let coarse = (f(&up[a])[ch] - f(&down[a])[ch]) / (2.0 * h);
                            let fine = (f(&up2[a])[ch] - f(&down2[a])[ch]) / h;
                            (4.0 * fine - coarse) / 3.0
                        };
                        let (fr, ft) = (fd(|c| c.reflectance_rgb), fd(|c| c.transmittance_rgb));
                        let (gr, gt) = (
                            got[a].d_reflectance_rgb[l][ch],
                            got[a].d_transmittance_rgb[l][ch],
                        );
                        assert!(
                            (gr - fr).abs() <= 1e-7 * fr.abs() + 1e-10,
                            "R {l} {a} {ch}: {gr} vs {fr}"
                        );
                        assert!(
                            (gt - ft).abs() <= 1e-7 * ft.abs() + 1e-10,
                            "T {l} {a} {ch}: {gt} vs {ft}"
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn delta_e00_derivative_matches_finite_differences() {
        let mut rng = Pcg64::seed_from_u64(2000);
        for case in 0..500 {
            let rgb: [f64; 3] = std::array::from_fn(|_| rng.random_range(0.0..1.0));
            let target: [f64; 3] = std::array::from_fn(|_| rng.random_range(0.0..1.0));
            let (de, grad) = delta_e00_with_gradient(rgb, target);
            let want = delta_e2000_rgb(rgb, target);
            assert!(
                (de - want).abs() <= 1e-9 * want.max(1.0),
                "case {case}: {de} vs {want}"
            );
            for c in 0..3 {
                let at = |h: f64| {
                    let mut x = rgb;
                    x[c] += h;
                    delta_e2000_rgb(x, target)
                };
                let h = 1e-5;
                let coarse = (at(h) - at(-h)) / (2.0 * h);
                let fine = (at(h / 2.0) - at(-h / 2.0)) / h;
                let fd = (4.0 * fine - coarse) / 3.0;
                // The hue's branch cuts (mean hue across 0/360) make ΔE00
                // kinked on a measure-zero set; a draw on one is skipped.
                let kink =
                    ((at(h) - at(0.0)) / h - (at(0.0) - at(-h)) / h).abs() > 1e-2 * fd.abs() + 1e-3;
                if !kink {
                    assert!(
                        (grad[c] - fd).abs() <= 1e-6 * fd.abs().max(1.0),
                        "case {case}, channel {c}: {} vs {fd}",
                        grad[c]
                    );
                }
            }
        }
        // At the target itself ΔE00 is 0 and its (sub)gradient 0.
        let (de, grad) = delta_e00_with_gradient([0.3, 0.4, 0.5], [0.3, 0.4, 0.5]);
        assert_eq!((de, grad), (0.0, [0.0; 3]));
    }
}

/// Every point of a mixed stack's grid (the lanes, each copy of the kernel,
/// and the scalar gradient for the points they leave) against the scalar
/// gradient point by point: random mixed stacks, a thick absorbing
/// incoherent layer, total internal reflection at an incoherent gap (opaque)
/// and in an absorbing one (evanescent), gain below the lasing threshold.
#[test]
fn mixed_grid_matches_points() {
    let mut rng = Pcg64::seed_from_u64(3839);
    let mut stacks: Vec<Stack> = Vec::new();
    for case in 0..40 {
        let layers = rng.random_range(1..9);
        let (n, _) = random_stack(&mut rng, KINDS[case % KINDS.len()], layers, 300.0);
        let d: Vec<f64> = (0..layers).map(|_| rng.random_range(0.0..300.0)).collect();
        let mut stack = stack_of(&n, &d);
        let first = rng.random_range(0..layers);
        for (l, layer) in stack.layers.iter_mut().enumerate() {
            if l == first || rng.random_bool(0.3) {
                layer.coherent = false;
                layer.thickness_nm = rng.random_range(0.0..3000.0);
            }
        }
        stacks.push(stack);
    }
    let incoherent = |mut stack: Stack, which: &[usize]| {
        for &l in which {
            stack.layers[l].coherent = false;
        }
        stack
    };
    let thick_absorber = stack_of(
        &[
            c64(1.0, 0.0),
            c64(1.45, 0.0),
            c64(2.0, 0.3),
            c64(1.6, 0.0),
            c64(1.5, 0.0),
        ],
        &[120.0, 5e4, 90.0],
    );
    stacks.push(incoherent(thick_absorber, &[1]));
    // From glass at sin θ0 = 0.8: the 1.0 gap is lossless beyond its
    // critical angle (opaque), the 1.1 + 1e-3i one evanescent and absorbing.
    let tir = stack_of(
        &[
            c64(1.5, 0.0),
            c64(1.7, 0.0),
            c64(1.0, 0.0),
            c64(1.3, 0.0),
            c64(1.5, 0.0),
        ],
        &[140.0, 600.0, 90.0],
    );
    stacks.push(incoherent(tir, &[1]));
    let evanescent = stack_of(
        &[
            c64(1.5, 0.0),
            c64(1.7, 0.0),
            c64(1.1, 1e-3),
            c64(1.3, 0.0),
            c64(1.5, 0.0),
        ],
        &[140.0, 400.0, 90.0],
    );
    stacks.push(incoherent(evanescent, &[1]));
    let gain = stack_of(
        &[
            c64(1.0, 0.0),
            c64(1.8, -0.01),
            c64(1.5, -5e-4),
            c64(2.2, 0.0),
            c64(1.5, 0.0),
        ],
        &[120.0, 2000.0, 80.0],
    );
    stacks.push(incoherent(gain, &[1]));
    let wavelengths: Vec<f64> = (0..11).map(|i| 400.0 + 37.0 * i as f64).collect();
    let cosines = [1.0, 0.6, 0.3, 1e-6, 0.0];
    let mut checked = 0;
    for (case, stack) in stacks.iter().enumerate() {
        let grid = StackGrid::new(stack, &wavelengths).unwrap();
        let d = stack.thicknesses_nm();
        let Ok(best) = solve_stack_grid_with_gradient_on(Path::Best, &grid, &d, &cosines) else {
            // A gain layer that lases somewhere: the points say so too.
            assert!(wavelengths.iter().any(|&wl| cosines
                .iter()
                .any(|&c| solve_with_gradient(stack, wl, c).is_err())));
            continue;
        };
        for path in [Path::Best, Path::Avx2, Path::Portable] {
            let got = solve_stack_grid_with_gradient_on(path, &grid, &d, &cosines).unwrap();
            assert_eq!(got, best, "case {case} {path:?} against the widest lanes");
            assert!(got.amplitudes.is_empty());
            for (w, &wl) in wavelengths.iter().enumerate() {
                for (a, &c) in cosines.iter().enumerate() {
                    let (r, g) = solve_with_gradient(stack, wl, c).unwrap();
                    let close =
                        |x: f64, y: f64, scale: f64| (x - y).abs() <= 1e-12 * scale.max(1.0);
                    let resp = got.response[w * 5 + a];
                    assert!(
                        parts(&resp)
                            .iter()
                            .zip(parts(&r))
                            .all(|(x, y)| close(*x, y, y.abs())),
                        "case {case} {path:?}: {resp:?} vs {r:?}"
                    );
                    for l in 0..stack.layers.len() {
                        let i = got.at(l, w, a);
                        let lanes = [got.d_rs[i], got.d_rp[i], got.d_ts[i], got.d_tp[i]];
                        let scalar = gradient_parts(&g, l);
                        for q in 0..4 {
                            let scale = (0..stack.layers.len())
                                .map(|m| gradient_parts(&g, m)[q].abs())
                                .fold(0.0, f64::max);
                            assert!(
                                close(lanes[q], scalar[q], scale * 1e3),
                                "case {case} {path:?} layer {l} at ({w}, {a}), quantity {q}: {} vs {}",
                                lanes[q],
                                scalar[q]
                            );
                        }
                    }
                }
            }
        }
        checked += 1;
    }
    assert!(checked >= 35, "only {checked} mixed grids checked");
}
