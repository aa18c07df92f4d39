//! The batched solver (four points per vector, `optics::lanes`) against the
//! scalar one, over random stacks and the hard cases: thick absorbers,
//! evanescent gaps, grazing and critical angles, hundreds of layers, gain,
//! layers at their own critical angle, metal substrates, phases beyond the
//! polynomial's range. Every copy of the kernel runs: the AVX-512 and AVX2
//! ones (when the CPU has them) must equal the portable one bit for bit, and
//! all must equal the scalar solver to 1e-12.

use num_complex::Complex64 as C64;
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64;

use irid::optics::lanes::{avx2_available, avx512_available, best_copy, solve_batch_on, Path};
#[cfg(feature = "bench")]
use irid::optics::solve_batch;
use irid::optics::{solve, Response, Stack, StackGrid};

mod common;
use common::random_stack::{random_stack, Kind, KINDS};

fn c(n: f64, k: f64) -> C64 {
    C64::new(n, k)
}

/// One stack over a few wavelengths and angles, with indices that change
/// from one wavelength to the next (as dispersion makes them).
struct Case {
    what: String,
    /// Wavelength-major, N + 2 per wavelength.
    indices: Vec<C64>,
    thicknesses_nm: Vec<f64>,
    wavelengths_nm: Vec<f64>,
    cos_theta0: Vec<f64>,
}

const TOLERANCE: f64 = 1e-12;

fn differs(a: f64, b: f64) -> bool {
    let scale = a.abs().max(b.abs()).max(1.0);
    // NaN on either side counts as a difference unless both are NaN.
    !((a - b).abs() <= TOLERANCE * scale || (a.is_nan() && b.is_nan()))
}

fn same_bits(a: &Response, b: &Response) -> bool {
    [a.rs, a.rp, a.ts, a.tp]
        .iter()
        .zip([b.rs, b.rp, b.ts, b.tp])
        .all(|(x, y)| x.to_bits() == y.to_bits())
}

/// The widest copy's result `best` equals the portable one's bit for bit,
/// and both equal the scalar solver's `want` to [`TOLERANCE`].
fn assert_agrees(
    what: &str,
    best: &Response,
    portable: &Response,
    want: &Response,
    wl: f64,
    cos: f64,
) {
    assert!(
        same_bits(best, portable),
        "{what}: {} and portable differ at {wl} nm, cos {cos}: {best:?} vs {portable:?}",
        best_copy()
    );
    for (got, want, name) in [
        (best.rs, want.rs, "Rs"),
        (best.rp, want.rp, "Rp"),
        (best.ts, want.ts, "Ts"),
        (best.tp, want.tp, "Tp"),
    ] {
        assert!(
            !differs(got, want),
            "{what}: {name} at {wl} nm, cos {cos}: batched {got:e}, scalar {want:e} (Δ {:e})",
            got - want
        );
    }
}

/// Runs both copies of the kernel and the scalar solver; returns the
/// largest difference seen (for the report in a failure message).
fn check(case: &Case) {
    let media = case.thicknesses_nm.len() + 2;
    let points = case.wavelengths_nm.len() * case.cos_theta0.len();
    let run = |path: Path| {
        let mut out = vec![Response::default(); points];
        solve_batch_on(
            path,
            &case.indices,
            &case.thicknesses_nm,
            &case.wavelengths_nm,
            &case.cos_theta0,
            &mut out,
        );
        out
    };
    let (best, avx2, portable) = (run(Path::Best), run(Path::Avx2), run(Path::Portable));
    for (i, ((b, a2), p)) in best.iter().zip(&avx2).zip(&portable).enumerate() {
        assert!(
            same_bits(a2, p),
            "{}: AVX2 and portable differ at point {i}",
            case.what
        );
        let (w, a) = (i / case.cos_theta0.len(), i % case.cos_theta0.len());
        let n = &case.indices[w * media..(w + 1) * media];
        let wl = case.wavelengths_nm[w];
        let cos = case.cos_theta0[a];
        let want = solve(n, &case.thicknesses_nm, wl, cos);
        assert_agrees(&case.what, b, p, &want, wl, cos);
    }
}

/// A random stack of `layers` layers of up to `max_thickness_nm`, its
/// indices drifting by up to 2 % over `n_w` wavelengths.
fn random_case(
    rng: &mut Pcg64,
    kind: Kind,
    layers: usize,
    max_thickness_nm: f64,
    n_w: usize,
    n_a: usize,
) -> Case {
    let (base, thicknesses_nm) = random_stack(rng, kind, layers, max_thickness_nm);
    let n0 = base[0].re;
    let wavelengths_nm: Vec<f64> = (0..n_w).map(|_| rng.random_range(300.0..900.0)).collect();
    let mut indices = Vec::with_capacity(n_w * base.len());
    for _ in 0..n_w {
        for (m, n) in base.iter().enumerate() {
            let drift = 1.0 + rng.random_range(-0.02..0.02);
            // The ambient stays lossless; gain stays gain, loss stays loss.
            let k = if m == 0 { 0.0 } else { n.im * drift };
            indices.push(c(n.re * drift, k));
        }
    }
    let mut cos_theta0: Vec<f64> = (0..n_a).map(|_| rng.random_range(0.0..1.0)).collect();
    // Normal, grazing and near-grazing incidence, and every layer's own
    // critical angle (exactly, and just off it) where the ambient is denser.
    cos_theta0.extend([1.0, 0.0, 1e-9, 1e-4]);
    for n in &base[1..base.len() - 1] {
        if n.re < n0 {
            let cc = (1.0 - (n.re / n0).powi(2)).sqrt();
            cos_theta0.extend([cc, cc * (1.0 + 1e-7), cc * (1.0 - 1e-5)]);
        }
    }
    Case {
        what: format!("{kind:?}, {layers} layers"),
        indices,
        thicknesses_nm,
        wavelengths_nm,
        cos_theta0,
    }
}

#[test]
fn kernel_copies_are_reported() {
    // Which copy Path::Best runs on this machine, for the test log.
    println!(
        "AVX-512F: {}, AVX2: {}; Path::Best runs the {} copy",
        avx512_available(),
        avx2_available(),
        best_copy()
    );
    let expected = if avx512_available() {
        "AVX-512"
    } else if avx2_available() {
        "AVX2"
    } else {
        "portable"
    };
    assert_eq!(best_copy(), expected);
}

#[test]
fn random_stacks_batched_equal_scalar() {
    let mut rng = Pcg64::seed_from_u64(13);
    for round in 0..400 {
        let kind = KINDS[round % 4];
        let layers = rng.random_range(0..8);
        let n_w = rng.random_range(1..10);
        let n_a = rng.random_range(1..6);
        check(&random_case(&mut rng, kind, layers, 2000.0, n_w, n_a));
    }
}

#[test]
fn hundreds_of_layers() {
    let mut rng = Pcg64::seed_from_u64(14);
    for kind in KINDS {
        check(&random_case(&mut rng, kind, 300, 300.0, 5, 3));
    }
}

#[test]
fn thick_absorbers_and_huge_phases() {
    let mut rng = Pcg64::seed_from_u64(15);
    // Millimetre layers: decays that underflow (and must come out as exactly
    // zero, as in the scalar solver) and phases far beyond the polynomial
    // reduction's range, which fall back to the C library lane by lane.
    for kind in [Kind::Lossless, Kind::Passive, Kind::Metal, Kind::WithGain] {
        for _ in 0..20 {
            let layers = rng.random_range(1..5);
            check(&random_case(&mut rng, kind, layers, 2e6, 7, 3));
        }
    }
    // Mixed within one group of four: one lane with a tiny decay, one past
    // underflow, one with a phase of 10⁸, one ordinary.
    let case = Case {
        what: "mixed decays".into(),
        indices: [
            [c(1.0, 0.0), c(1.5, 1e-3), c(1.5, 0.0)],
            [c(1.0, 0.0), c(1.5, 0.9), c(1.5, 0.0)],
            [c(1.0, 0.0), c(1.5, 0.0), c(1.5, 0.0)],
            [c(1.0, 0.0), c(1.5, 1e-6), c(1.5, 0.0)],
        ]
        .concat(),
        thicknesses_nm: vec![4e7],
        wavelengths_nm: vec![500.0, 501.0, 502.0, 503.0],
        cos_theta0: vec![1.0],
    };
    check(&case);
}

#[test]
fn evanescent_gaps() {
    // Frustrated total internal reflection: glass / air gap / glass beyond
    // the critical angle, gaps from nothing to far past the decay length.
    let glass = c(1.5, 0.0);
    let air = c(1.0, 0.0);
    for gap in [0.0, 1.0, 50.0, 200.0, 1000.0, 1e5, 1e7] {
        let case = Case {
            what: format!("gap {gap} nm"),
            indices: [glass, air, glass, glass, air, c(0.2, 3.0)].to_vec(),
            thicknesses_nm: vec![gap],
            wavelengths_nm: vec![450.0, 650.0],
            cos_theta0: vec![0.9, 0.6, 0.5, 0.3, 0.1, 0.0],
        };
        check(&case);
    }
}

#[test]
fn gain_on_gold_and_near_critical_runs() {
    // A gain film on gold, and runs of layers at their critical angle
    // (taken by the scalar field form, lane by lane).
    let mut case = Case {
        what: "gain on gold".into(),
        indices: vec![c(1.0, 0.0), c(1.6, -0.08), c(0.27, 2.9)],
        thicknesses_nm: vec![350.0],
        wavelengths_nm: vec![620.0],
        cos_theta0: (0..=40).map(|i| f64::from(i) / 40.0).collect(),
    };
    check(&case);
    let n0 = 1.7;
    let cc = (1.0 - (1.2f64 / n0).powi(2)).sqrt();
    case = Case {
        what: "near-critical run".into(),
        indices: vec![
            c(n0, 0.0),
            c(1.2, 0.0),
            c(1.2, 0.0),
            c(1.2, 1e-9),
            c(1.45, 0.0),
            c(1.2, 0.0),
            c(1.5, 0.0),
        ],
        thicknesses_nm: vec![80.0, 0.0, 300.0, 120.0, 5.0],
        wavelengths_nm: vec![550.0],
        cos_theta0: vec![
            cc,
            cc + 1e-12,
            cc - 1e-9,
            0.9,
            cc * (1.0 + 1e-3),
            0.2,
            cc,
            0.7,
        ],
    };
    check(&case);
}

#[test]
fn batch_lengths_that_are_not_multiples_of_four() {
    let mut rng = Pcg64::seed_from_u64(16);
    for n_w in 1..9 {
        for n_a in 1..4 {
            let mut case = random_case(&mut rng, Kind::Passive, 2, 500.0, n_w, n_a);
            case.cos_theta0.truncate(n_a);
            check(&case);
        }
    }
}

#[cfg(feature = "bench")]
#[test]
fn stack_grid_solves_through_the_batch() {
    // The public path (StackGrid::solve → solve_batch) on a dispersive stack.
    let stack: Stack = irid::bench::stacks::find("soap").unwrap().unwrap().stack;
    let wl: Vec<f64> = (380..=780).step_by(7).map(f64::from).collect();
    let grid = StackGrid::new(&stack, &wl).unwrap();
    let cos: Vec<f64> = (0..=9).map(|i| f64::from(i) / 9.0).collect();
    let mut out = vec![Response::default(); wl.len() * cos.len()];
    grid.solve(&cos, &mut out);
    let mut direct = vec![Response::default(); out.len()];
    solve_batch(
        grid.indices(),
        grid.thicknesses_nm(),
        grid.wavelengths_nm(),
        &cos,
        &mut direct,
    );
    assert_eq!(out, direct);
    for (i, (w, n)) in grid.iter().enumerate() {
        for (a, &c) in cos.iter().enumerate() {
            let want = solve(n, grid.thicknesses_nm(), w, c);
            let got = out[i * cos.len() + a];
            assert!(!differs(got.r(), want.r()) && !differs(got.t(), want.t()));
        }
    }
}

#[cfg(feature = "bench")]
#[test]
fn spectrum_path_equals_scalar_on_both_copies() {
    // StackGrid::solve_spectrum (indices laid out per lane group once) on
    // dispersive and hard stacks, thicknesses varied per call as the
    // validation and the direct film vary them.
    let mut rng = Pcg64::seed_from_u64(17);
    for name in [
        "soap",
        "absorbing",
        "gain-on-gold",
        "two-layer",
        "mirror-front",
        "mirror-back",
    ] {
        let b = irid::bench::stacks::find(name).unwrap().unwrap();
        for n_w in [1usize, 3, 4, 41, 471] {
            let wl: Vec<f64> = (0..n_w)
                .map(|i| 360.0 + 470.0 * i as f64 / n_w.max(2) as f64)
                .collect();
            let grid = StackGrid::new(&b.stack, &wl).unwrap();
            let mut thick = grid.thicknesses_nm().to_vec();
            for _ in 0..6 {
                let layer = rng.random_range(0..thick.len());
                thick[layer] = rng.random_range(0.0..3000.0);
                let cos = match rng.random_range(0..4) {
                    0 => 0.0,
                    1 => 1.0,
                    _ => rng.random_range(0.0..1.0),
                };
                let mut best = vec![Response::default(); n_w];
                let mut portable = vec![Response::default(); n_w];
                grid.solve_spectrum(&thick, cos, &mut best);
                grid.solve_spectrum_on(Path::Portable, &thick, cos, &mut portable);
                let mut avx2 = vec![Response::default(); n_w];
                grid.solve_spectrum_on(Path::Avx2, &thick, cos, &mut avx2);
                for (a2, p) in avx2.iter().zip(&portable) {
                    assert!(same_bits(a2, p), "{name}: AVX2 vs portable");
                }
                for (k, ((b_, p), (w, n))) in
                    best.iter().zip(&portable).zip(grid.iter()).enumerate()
                {
                    assert!(same_bits(b_, p), "{name} {k}: best copy vs portable");
                    let want = solve(n, &thick, w, cos);
                    for (got, want) in [
                        (b_.rs, want.rs),
                        (b_.rp, want.rp),
                        (b_.ts, want.ts),
                        (b_.tp, want.tp),
                    ] {
                        assert!(
                            !differs(got, want),
                            "{name} at {w} nm, cos {cos}: {got:e} vs {want:e}"
                        );
                    }
                }
            }
        }
    }
}

/// A stack whose every medium has one index at all wavelengths, which
/// `StackGrid::solve_spectrum` solves with its interfaces computed once per
/// angle (`lanes::constant`).
fn non_dispersive(n0: f64, layers: &[(C64, f64)], substrate: C64) -> Stack {
    use irid::optics::{Layer, Material};
    Stack {
        ambient: Material::constant(n0, 0.0),
        layers: layers
            .iter()
            .map(|&(n, d)| Layer::new(Material::constant(n.re, n.im), d))
            .collect(),
        substrate: Material::constant(substrate.re, substrate.im),
    }
}

/// `solve_spectrum` on both copies of the kernel against the scalar solver,
/// over `wavelengths` and every angle of `cosines`.
fn check_spectrum(what: &str, stack: &Stack, wavelengths: &[f64], cosines: &[f64]) {
    let grid = StackGrid::new(stack, wavelengths).unwrap();
    let thick = grid.thicknesses_nm().to_vec();
    for &cos in cosines {
        let mut best = vec![Response::default(); wavelengths.len()];
        let mut portable = vec![Response::default(); wavelengths.len()];
        grid.solve_spectrum(&thick, cos, &mut best);
        grid.solve_spectrum_on(Path::Portable, &thick, cos, &mut portable);
        let mut avx2 = vec![Response::default(); wavelengths.len()];
        grid.solve_spectrum_on(Path::Avx2, &thick, cos, &mut avx2);
        for (a2, p) in avx2.iter().zip(&portable) {
            assert!(same_bits(a2, p), "{what}: AVX2 vs portable at cos {cos}");
        }
        for ((b, p), (w, n)) in best.iter().zip(&portable).zip(grid.iter()) {
            assert_agrees(what, b, p, &solve(n, &thick, w, cos), w, cos);
        }
    }
}

#[test]
fn non_dispersive_stacks_equal_scalar() {
    // Random constant-index stacks of every kind, at random, normal, grazing
    // and every layer's own critical angle; 1 to 471 wavelengths, so that
    // partial groups of four occur.
    let mut rng = Pcg64::seed_from_u64(18);
    for round in 0..300 {
        let kind = KINDS[round % 4];
        let layers = rng.random_range(0..8);
        let case = random_case(&mut rng, kind, layers, 2000.0, 1, 4);
        let media = case.thicknesses_nm.len() + 2;
        let n = &case.indices[..media];
        let body: Vec<(C64, f64)> = n[1..media - 1]
            .iter()
            .copied()
            .zip(case.thicknesses_nm.iter().copied())
            .collect();
        let stack = non_dispersive(n[0].re, &body, n[media - 1]);
        let n_w = [1, 3, 4, 5, 41, 471][round % 6];
        let wl: Vec<f64> = (0..n_w)
            .map(|i| 360.0 + 470.0 * i as f64 / n_w.max(2) as f64)
            .collect();
        check_spectrum(&case.what, &stack, &wl, &case.cos_theta0);
    }
}

#[test]
fn non_dispersive_hard_cases() {
    let wl: Vec<f64> = (0..37).map(|i| 380.0 + 11.0 * f64::from(i)).collect();
    let cosines: Vec<f64> = (0..=50).map(|i| f64::from(i) / 50.0).collect();
    let glass = c(1.5, 0.0);
    let air = c(1.0, 0.0);
    // Evanescent gaps: glass / air / glass beyond the critical angle.
    for gap in [0.0, 1.0, 200.0, 1e5, 1e7] {
        let s = non_dispersive(1.5, &[(air, gap)], glass);
        check_spectrum(&format!("gap {gap} nm"), &s, &wl, &cosines);
    }
    // Thick absorbers (decays that underflow) and phases beyond the
    // polynomial's range.
    for (k, d) in [(1e-3, 4e7), (0.9, 4e7), (0.0, 4e7), (1e-6, 1e6)] {
        let s = non_dispersive(1.0, &[(c(1.5, k), d)], glass);
        check_spectrum(&format!("k {k}, {d} nm"), &s, &wl, &cosines);
    }
    // Gain on gold, a metal substrate, and a dense ambient over a run of
    // layers at their critical angle (taken by the general kernel).
    let gold = c(0.27, 2.9);
    check_spectrum(
        "gain on gold",
        &non_dispersive(1.0, &[(c(1.6, -0.08), 350.0)], gold),
        &wl,
        &cosines,
    );
    let n0 = 1.7;
    let cc = (1.0 - (1.2f64 / n0).powi(2)).sqrt();
    check_spectrum(
        "near-critical run",
        &non_dispersive(
            n0,
            &[
                (c(1.2, 0.0), 80.0),
                (c(1.2, 0.0), 30.0),
                (c(2.0, 0.1), 60.0),
            ],
            c(1.45, 0.0),
        ),
        &wl,
        &[cc, cc * (1.0 + 1e-7), cc * (1.0 - 1e-5), 0.5],
    );
    // Sixty layers (the most media the non-dispersive kernel lays out is
    // 66), a lossless quarter-wave mirror.
    let mirror: Vec<(C64, f64)> = (0..60)
        .map(|i| {
            if i % 2 == 0 {
                (c(2.4, 0.0), 57.3)
            } else {
                (c(1.46, 0.0), 94.2)
            }
        })
        .collect();
    check_spectrum(
        "60-layer mirror",
        &non_dispersive(1.0, &mirror, glass),
        &wl,
        &cosines,
    );
}

#[test]
fn a_grid_from_raw_indices_is_the_grid_of_the_stack() {
    // StackGrid::from_indices (the Python package's path: indices given as
    // arrays) lays out exactly what StackGrid::new does for the same stack.
    let glass = c(1.52, 0.0);
    let stack = non_dispersive(1.0, &[(c(2.1, 0.02), 140.0), (c(1.38, 0.0), 90.0)], glass);
    let wl: Vec<f64> = (0..23).map(|i| 400.0 + 15.0 * f64::from(i)).collect();
    let grid = StackGrid::new(&stack, &wl).unwrap();
    let raw = StackGrid::from_indices(grid.indices().to_vec(), grid.thicknesses_nm().to_vec(), &wl);
    assert_eq!(raw, grid);
    check_spectrum("from raw indices", &stack, &wl, &[1.0, 0.6, 0.2]);
}

/// `StackGrid::weighted_spectrum` folds the spectrum into the colour as it
/// solves it; it must give the bits of integrating the stored spectrum, on
/// every copy of the kernel, dispersive or not, whatever the wavelength
/// count's remainder mod the lane width.
#[test]
fn weighted_spectrum_is_the_integrated_stored_spectrum() {
    use irid::color::{Sampling, SpectralIntegrator};
    use irid::optics::{Layer, Material};
    let dispersive = Stack {
        ambient: Material::constant(1.0, 0.0),
        layers: vec![Layer::new(
            irid::optics::library::builtin("TiO2").unwrap(),
            300.0,
        )],
        substrate: irid::optics::library::builtin("fused-silica").unwrap(),
    };
    let stacks = [
        (
            "soap",
            non_dispersive(1.0, &[(c(1.33, 0.0), 500.0)], c(1.0, 0.0)),
        ),
        (
            "absorbing pair on glass",
            non_dispersive(
                1.0,
                &[(c(2.0, 0.3), 120.0), (c(1.38, 0.0), 90.0)],
                c(1.52, 0.0),
            ),
        ),
        ("TiO2 on fused silica (dispersive)", dispersive),
    ];
    let mut rng = Pcg64::seed_from_u64(19);
    for sampling in [
        Sampling::Exact,
        Sampling::Rgb3,
        Sampling::Uniform(2),
        Sampling::Uniform(5),
        Sampling::Uniform(6),
        Sampling::Uniform(7),
        Sampling::Uniform(41),
    ] {
        let integ = SpectralIntegrator::new(sampling);
        let weights = integ.rgb_lane_weights();
        for (name, stack) in &stacks {
            let grid = StackGrid::new(stack, integ.wavelengths_nm()).unwrap();
            let mut thick = grid.thicknesses_nm().to_vec();
            for _ in 0..8 {
                thick[0] = rng.random_range(0.0..2000.0);
                let cos = rng.random_range(0.0..=1.0);
                let mut spectrum = vec![Response::default(); grid.wavelengths_nm().len()];
                for path in [Path::Best, Path::Avx2, Path::Portable] {
                    grid.solve_spectrum_on(path, &thick, cos, &mut spectrum);
                    let r: Vec<f64> = spectrum.iter().map(Response::r).collect();
                    let t: Vec<f64> = spectrum.iter().map(Response::t).collect();
                    let got = grid.weighted_spectrum_on(path, &thick, cos, &weights);
                    let bits = |v: [f64; 3]| v.map(f64::to_bits);
                    assert_eq!(
                        (bits(got.reflectance), bits(got.transmittance)),
                        (bits(integ.rgb(&r)), bits(integ.rgb(&t))),
                        "{name}, {sampling:?}, {path:?}, d {}, cos {cos}",
                        thick[0]
                    );
                }
            }
        }
    }
}

/// The lanes' exponential for scattered phases (the baker's exact phase at
/// each chunk's start): every copy gives the same bits, all within a few
/// ulps of the C library's e^{iφ}, over lossless, decaying and growing
/// phases, beyond the polynomials' range, and where the decay underflows.
#[test]
fn one_way_many_matches_the_library() {
    use irid::optics::lanes::{one_way_many, MAX_LANES};
    let mut rng = Pcg64::seed_from_u64(17);
    let mut phases: Vec<C64> = (0..4000)
        .map(|i| {
            let re = rng.random_range(-3000.0..3000.0);
            let im = match i % 4 {
                0 => 0.0,
                1 => rng.random_range(0.0..50.0),
                2 => rng.random_range(-5.0..0.0),
                _ => rng.random_range(-1.0..1.0) * 1e-3,
            };
            c(re, im)
        })
        .collect();
    // Past the polynomials' range, an underflowing decay, and zero.
    phases.extend([c(2e5, 0.0), c(-7e6, 0.3), c(10.0, 800.0), c(0.0, 0.0)]);
    phases.resize(phases.len().next_multiple_of(MAX_LANES), c(1.0, 0.0));
    let mut worst = 0.0f64;
    for group in phases.chunks_exact(MAX_LANES) {
        let group: [C64; MAX_LANES] = group.try_into().unwrap();
        let portable = one_way_many(Path::Portable, &group);
        for path in [Path::Best, Path::Avx2] {
            let got = one_way_many(path, &group);
            for (g, p) in got.iter().zip(&portable) {
                assert_eq!(
                    [g.re.to_bits(), g.im.to_bits()],
                    [p.re.to_bits(), p.im.to_bits()]
                );
            }
        }
        for (z, phi) in portable.iter().zip(&group) {
            let want = (C64::new(0.0, 1.0) * phi).exp();
            worst = worst.max((z - want).norm() / want.norm().max(1e-300));
        }
    }
    // About 3e-16 here: an ulp or two.
    assert!(worst < 2e-15, "worst relative difference {worst:e}");
}
