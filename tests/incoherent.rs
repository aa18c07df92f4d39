//! Stacks with incoherent (thick) layers: closed forms of a slab (lossless,
//! absorbing, with gain up to its lasing threshold), invariants over random
//! mixed stacks (energy, reciprocity, index-matched layers), the limits
//! (opaque and zero-thickness layers, grazing incidence, a layer at and
//! beyond its critical angle), and the batched loops against the point
//! solver. Byrnes' `tmm.inc_tmm` is the reference of
//! tools/crosscheck/crosscheck_incoherent.py and the Python tests.

// Not an API: a test crate has no public API to document.
#![allow(missing_docs)]

use num_complex::Complex64 as C64;
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64;

use irid::optics::lanes::{solve_batch_mixed_on, Path};
use irid::optics::{
    solve, solve_incoherent, Coherence, Layer, Material, Response, Stack, StackGrid,
};

fn c(n: f64, k: f64) -> C64 {
    C64::new(n, k)
}

fn cos_deg(angle_deg: f64) -> f64 {
    angle_deg.to_radians().cos()
}

/// |got − want| ≤ tol · max(|want|, 1) for each of Rs, Rp, Ts, Tp.
fn assert_responses(got: &Response, want: &Response, tol: f64, what: &str) {
    for (a, b) in [
        (got.rs, want.rs),
        (got.rp, want.rp),
        (got.ts, want.ts),
        (got.tp, want.tp),
    ] {
        assert!(
            (a - b).abs() <= tol * b.abs().max(1.0),
            "{what}: {got:?} vs {want:?}"
        );
    }
}

/// Layer `layer` (1-based) incoherent, the others coherent.
fn only(layer: usize, layers: usize) -> Coherence {
    Coherence::from_flags((1..=layers).map(|l| l != layer))
}

/// Fresnel power coefficients of one interface for s and p from medium a
/// (ambient side) into medium b, at the conserved β²: (R, T) with T the
/// flux ratio. Both media lossless and propagating.
fn interface(n_a: f64, n_b: f64, beta_sq: f64) -> [(f64, f64); 2] {
    let qa = (n_a * n_a - beta_sq).sqrt();
    let qb = (n_b * n_b - beta_sq).sqrt();
    let rs = (qa - qb) / (qa + qb);
    let rp = (n_b * n_b * qa - n_a * n_a * qb) / (n_b * n_b * qa + n_a * n_a * qb);
    [(rs * rs, 1.0 - rs * rs), (rp * rp, 1.0 - rp * rp)]
}

/// A slab of power transmission P per pass between two equal faces of
/// reflectance R1: the incoherent sum R1 + T1² R1 P² / (1 − R1² P²),
/// T1² P / (1 − R1² P²).
fn slab(r1: f64, t1: f64, pass: f64) -> (f64, f64) {
    let den = 1.0 - r1 * r1 * pass * pass;
    (r1 + t1 * t1 * r1 * pass * pass / den, t1 * t1 * pass / den)
}

fn slab_response(n: f64, pass: f64, beta_sq: f64) -> Response {
    let [(rs, ts), (rp, tp)] = interface(1.0, n, beta_sq);
    let (rs, ts) = slab(rs, ts, pass);
    let (rp, tp) = slab(rp, tp, pass);
    Response { rs, rp, ts, tp }
}

#[test]
fn a_lossless_sheet_adds_its_faces_in_power_at_any_thickness() {
    // Glass in air: R = 2 R1 / (1 + R1) per polarization, whatever the
    // thickness, zero included (unlike a coherent layer, which would vanish).
    for d in [0.0, 1.0, 550.0, 1e6, 1e12] {
        for angle in [0.0, 30.0, 56.3, 75.0, 89.0] {
            let cos = cos_deg(angle);
            let beta_sq = 1.0 - cos * cos;
            let want = slab_response(1.5, 1.0, beta_sq);
            let got = solve_incoherent(
                &[c(1.0, 0.0), c(1.5, 0.0), c(1.0, 0.0)],
                &[d],
                &only(1, 1),
                550.0,
                cos,
            )
            .unwrap();
            assert_responses(&got, &want, 1e-14, &format!("{d} nm at {angle}°"));
        }
    }
}

#[test]
fn an_absorbing_sheet_keeps_p_per_pass() {
    // n = 1.5 + 1e-5 i, 1 mm: P = exp(−4π k d cos θ' ... ) from q. The faces'
    // Fresnel coefficients of an absorbing medium differ from the lossless
    // ones by O(k), so the closed form uses them exactly through the complex
    // q, and P = e^{−2 k0 Im(q) d}.
    let n = c(1.5, 1e-5);
    let wl = 600.0;
    let k0 = std::f64::consts::TAU / wl;
    for d in [1e3, 1e5, 1e6, 3e6] {
        for angle in [0.0, 45.0, 80.0] {
            let cos = cos_deg(angle);
            let beta_sq = 1.0 - cos * cos;
            let q = (n * n - beta_sq).sqrt();
            let pass = (-2.0 * k0 * q.im * d).exp();
            let q0 = cos;
            let mut want = Response::default();
            for (pol, (r, t)) in [0, 1].into_iter().zip([
                ((q0 - q) / (q0 + q), 2.0 * q0 / (q0 + q)),
                (
                    (n * n * q0 - q) / (n * n * q0 + q),
                    2.0 * n * q0 / (n * n * q0 + q),
                ),
            ]) {
                // Face up from inside: r' = −r; t' from the same pair.
                let t_up = if pol == 0 {
                    2.0 * q / (q0 + q)
                } else {
                    2.0 * n * q / (n * n * q0 + q)
                };
                let (rr, tt) = (r.norm_sqr(), (t * t_up).norm_sqr());
                let den = 1.0 - rr * rr * pass * pass;
                let big_r = rr + tt * rr * pass * pass / den;
                let big_t = tt * pass / den;
                if pol == 0 {
                    (want.rs, want.ts) = (big_r, big_t);
                } else {
                    (want.rp, want.tp) = (big_r, big_t);
                }
            }
            let got = solve_incoherent(&[c(1.0, 0.0), n, c(1.0, 0.0)], &[d], &only(1, 1), wl, cos)
                .unwrap();
            assert_responses(&got, &want, 1e-13, &format!("{d} nm at {angle}°"));
            assert!(got.r() + got.t() < 1.0, "it absorbs");
        }
    }
}

#[test]
fn an_opaque_layer_passes_nothing_and_reflects_its_top_face() {
    // e^{−2 k0 k d} underflows: T is exactly 0 and R is the face above it
    // (a coating on a millimetre of black glass).
    let idx = [c(1.0, 0.0), c(1.38, 0.0), c(1.5, 0.5), c(1.0, 0.0)];
    let top = [c(1.0, 0.0), c(1.38, 0.0), c(1.5, 0.5)];
    for angle in [0.0, 40.0, 85.0] {
        let got =
            solve_incoherent(&idx, &[100.0, 1e6], &only(2, 2), 550.0, cos_deg(angle)).unwrap();
        let want = solve(&top, &[100.0], 550.0, cos_deg(angle));
        assert_eq!((got.ts, got.tp), (0.0, 0.0));
        assert_responses(
            &got,
            &Response {
                ts: 0.0,
                tp: 0.0,
                ..want
            },
            1e-14,
            "opaque",
        );
    }
}

#[test]
fn gain_sums_up_to_the_lasing_threshold_and_is_refused_past_it() {
    // A gain sheet at normal incidence: R1 from n = 1.5, P = e^{2 k0 |k| d}
    // per pass. The sum converges while R1² P² < 1.
    let n = c(1.5, -1e-4);
    let wl = 500.0;
    let k0 = std::f64::consts::TAU / wl;
    let r1 = ((1.0 - n) / (1.0 + n)).norm_sqr(); // only to size the threshold
    let threshold = (1.0 / r1).ln() / (2.0 * k0 * 1e-4);
    for d in [0.5 * threshold, 0.99 * threshold] {
        let got =
            solve_incoherent(&[c(1.0, 0.0), n, c(1.0, 0.0)], &[d], &only(1, 1), wl, 1.0).unwrap();
        let q = n; // normal incidence, the forward (growing) branch: Re q > 0
        let pass = (-2.0 * k0 * q.im * d).exp();
        assert!(pass > 1.0);
        let r = (1.0 - q) / (1.0 + q);
        let tt = ((2.0 / (1.0 + q)) * (2.0 * q / (1.0 + q))).norm_sqr();
        let rr = r.norm_sqr();
        let den = 1.0 - rr * rr * pass * pass;
        let want_r = rr + tt * rr * pass * pass / den;
        let want_t = tt * pass / den;
        assert!(
            (got.rs - want_r).abs() <= 1e-12 * want_r,
            "{got:?} vs {want_r}"
        );
        assert!(
            (got.ts - want_t).abs() <= 1e-12 * want_t,
            "{got:?} vs {want_t}"
        );
        assert!(got.ts > 1.0, "it amplifies");
    }
    let err = solve_incoherent(
        &[c(1.0, 0.0), n, c(1.0, 0.0)],
        &[1.01 * threshold],
        &only(1, 1),
        wl,
        1.0,
    )
    .unwrap_err();
    assert_eq!(err.layer, 1);
    assert!(err.round_trip >= 1.0 && err.round_trip < 1.1, "{err:?}");
    // Overflowing gain is refused too, not returned as ∞ or NaN.
    let err = solve_incoherent(
        &[c(1.0, 0.0), c(1.5, -0.5), c(1.5, 0.0)],
        &[1e9],
        &only(1, 1),
        wl,
        1.0,
    )
    .unwrap_err();
    assert_eq!(err.layer, 1);
    // The stack-level call gives the one-line error naming the layer.
    let stack = Stack {
        ambient: Material::constant(1.0, 0.0),
        layers: vec![Layer {
            coherent: false,
            ..Layer::new(Material::constant(1.5, -1e-4), 1.01 * threshold)
        }],
        substrate: Material::constant(1.0, 0.0),
    };
    let message = stack.response(wl, 1.0).unwrap_err().to_string();
    assert!(
        message.starts_with("layers[1]: this incoherent layer lases at 500 nm, 0.0000°")
            && !message.contains('\n'),
        "{message}"
    );
}

#[test]
fn a_layer_beyond_its_critical_angle_is_opaque_and_continuous() {
    // From glass, an incoherent water layer between two coatings: its
    // critical angle is asin(1.33/1.5). Beyond it the layer carries no
    // propagating wave: R is that of the stack cut at its top face, T = 0.
    // Approaching it from below, T already falls to 0.
    let idx = [
        c(1.5, 0.0),
        c(1.38, 0.0),
        c(1.33, 0.0),
        c(1.38, 0.0),
        c(1.5, 0.0),
    ];
    let d = [120.0, 2e4, 120.0];
    let cut = [c(1.5, 0.0), c(1.38, 0.0), c(1.33, 0.0)];
    let crit = (1.33f64 / 1.5).asin().to_degrees();
    for angle in [crit + 1e-9, crit + 0.5, 70.0, 89.0] {
        let cos = cos_deg(angle);
        let got = solve_incoherent(&idx, &d, &only(2, 3), 500.0, cos).unwrap();
        let want = solve(&cut, &[120.0], 500.0, cos);
        assert_eq!((got.ts, got.tp), (0.0, 0.0), "{angle}");
        assert_responses(
            &got,
            &Response {
                ts: 0.0,
                tp: 0.0,
                ..want
            },
            1e-14,
            "beyond",
        );
        assert!((got.r() - 1.0).abs() < 1e-14, "total reflection: {got:?}");
    }
    // Continuity: T shrinks towards the critical angle from below.
    let mut last_t = 1.0;
    for delta in [1e-1, 1e-3, 1e-5, 1e-7] {
        let got = solve_incoherent(&idx, &d, &only(2, 3), 500.0, cos_deg(crit - delta)).unwrap();
        assert!(
            got.t() < last_t && got.r() + got.t() <= 1.0 + 1e-14,
            "{delta}: {got:?}"
        );
        last_t = got.t();
    }
    assert!(last_t < 1e-3, "{last_t}");
}

#[test]
fn grazing_incidence_reflects_everything() {
    let idx = [c(1.0, 0.0), c(1.38, 0.0), c(1.52, 0.0), c(1.0, 0.0)];
    let got = solve_incoherent(&idx, &[100.0, 1e6], &only(2, 2), 550.0, 0.0).unwrap();
    assert_eq!(
        got,
        Response {
            rs: 1.0,
            rp: 1.0,
            ts: 0.0,
            tp: 0.0
        }
    );
    // Near grazing a sheet of glass in air keeps the closed form: the
    // substrate's q is taken as (n² − n0²) + q0², exact for n = n0.
    let cos = cos_deg(89.999999);
    let beta_sq = (1.0 - cos) * (1.0 + cos);
    let [(r1, _), _] = interface(1.0, 1.5, beta_sq);
    let got = solve_incoherent(
        &[c(1.0, 0.0), c(1.5, 0.0), c(1.0, 0.0)],
        &[1e6],
        &only(1, 1),
        550.0,
        cos,
    )
    .unwrap();
    // T = (1 − R1) / (1 + R1) with 1 − R1 = 4 q0 q / (q0 + q)² ≈ 6e-8.
    let q = (2.25 - beta_sq).sqrt();
    let t1 = 4.0 * cos * q / ((cos + q) * (cos + q));
    assert!((got.ts - t1 / (1.0 + r1)).abs() < 1e-15, "{got:?}");
}

/// A random mixed stack: (indices, thicknesses, coherence).
fn random_mixed(rng: &mut Pcg64, lossless: bool) -> (Vec<C64>, Vec<f64>, Coherence) {
    let layers = rng.random_range(1..8);
    let mut idx = vec![c(rng.random_range(1.0..1.6), 0.0)];
    let mut flags = Vec::new();
    let mut d = Vec::new();
    for _ in 0..layers {
        let incoherent = rng.random_bool(0.4);
        let k = if lossless || rng.random_bool(0.5) {
            0.0
        } else {
            rng.random_range(0.0..0.3)
        };
        idx.push(c(rng.random_range(1.0..2.6), k));
        d.push(if incoherent {
            rng.random_range(1e3..1e6)
        } else {
            rng.random_range(0.0..800.0)
        });
        flags.push(!incoherent);
    }
    idx.push(c(rng.random_range(1.0..2.0), 0.0));
    (idx, d, Coherence::from_flags(flags))
}

#[test]
fn lossless_mixed_stacks_conserve_energy() {
    let mut rng = Pcg64::seed_from_u64(27);
    for _ in 0..2000 {
        let (idx, d, coh) = random_mixed(&mut rng, true);
        let cos = rng.random_range(0.02..1.0);
        let r = solve_incoherent(&idx, &d, &coh, rng.random_range(380.0..780.0), cos).unwrap();
        for (rr, tt) in [(r.rs, r.ts), (r.rp, r.tp)] {
            assert!(
                (rr + tt - 1.0).abs() < 1e-12,
                "{idx:?} {d:?} {coh:?}: {r:?}"
            );
            assert!(rr >= 0.0 && tt >= 0.0);
        }
    }
}

#[test]
fn passive_mixed_stacks_are_reciprocal_in_transmission() {
    // T from the ambient equals T from the substrate at the same β, as for
    // coherent stacks (each group is reciprocal, and the incoherent sums
    // share their denominators).
    let mut rng = Pcg64::seed_from_u64(2027);
    for _ in 0..1000 {
        let (idx, d, coh) = random_mixed(&mut rng, false);
        let (n0, n_sub) = (idx[0].re, idx[idx.len() - 1].re);
        let cos = rng.random_range(0.05..1.0);
        let beta_sq = n0 * n0 * (1.0 - cos * cos);
        if beta_sq >= n_sub * n_sub {
            continue;
        }
        let cos_back = (1.0 - beta_sq / (n_sub * n_sub)).sqrt();
        let rev: Vec<C64> = idx.iter().rev().copied().collect();
        let d_rev: Vec<f64> = d.iter().rev().copied().collect();
        let wl = rng.random_range(380.0..780.0);
        let there = solve_incoherent(&idx, &d, &coh, wl, cos).unwrap();
        let back = solve_incoherent(&rev, &d_rev, &coh.reversed(d.len()), wl, cos_back).unwrap();
        for (a, b) in [(there.ts, back.ts), (there.tp, back.tp)] {
            assert!((a - b).abs() < 1e-12, "{idx:?} {d:?} {coh:?}: {a} vs {b}");
        }
    }
}

#[test]
fn an_index_matched_incoherent_layer_is_invisible() {
    // A lossless incoherent layer of the substrate's index adds no
    // interface: the stack answers as its coherent part on that substrate.
    let mut rng = Pcg64::seed_from_u64(7);
    for _ in 0..500 {
        let (mut idx, mut d, _) = random_mixed(&mut rng, false);
        let n_sub = idx[idx.len() - 1];
        let coherent = solve(&idx, &d, 500.0, 0.6);
        idx.insert(idx.len() - 1, n_sub);
        d.push(rng.random_range(0.0..1e7));
        let layers = d.len();
        let got = solve_incoherent(&idx, &d, &only(layers, layers), 500.0, 0.6).unwrap();
        assert_responses(&got, &coherent, 1e-13, "index-matched");
    }
}

#[test]
fn every_layer_coherent_is_the_coherent_solver_bit_for_bit() {
    let mut rng = Pcg64::seed_from_u64(11);
    for _ in 0..200 {
        let (idx, d, _) = random_mixed(&mut rng, false);
        for cos in [1.0, 0.5, 0.0] {
            let got = solve_incoherent(&idx, &d, &Coherence::coherent(), 480.0, cos).unwrap();
            assert_eq!(got, solve(&idx, &d, 480.0, cos));
        }
    }
}

#[test]
fn the_batched_loops_agree_with_the_point_solver() {
    let mut rng = Pcg64::seed_from_u64(99);
    let wavelengths: Vec<f64> = (0..13).map(|i| 380.0 + 31.0 * f64::from(i)).collect();
    let cosines = [1.0, 0.9, 0.31, 0.02, 0.0];
    for _ in 0..40 {
        let (idx, d, coh) = random_mixed(&mut rng, false);
        let media = idx.len();
        // A dispersive stack: every wavelength its own indices.
        let indices: Vec<C64> = wavelengths
            .iter()
            .flat_map(|&w| {
                idx.iter()
                    .map(move |n| n * (1.0 + 1e-4 * (w - 500.0) / 100.0))
            })
            .collect();
        let grid = StackGrid::from_indices(indices.clone(), d.clone(), &wavelengths)
            .with_coherence(coh.clone());
        let point = |i: usize, cos: f64| {
            solve_incoherent(
                &indices[i * media..(i + 1) * media],
                &d,
                &coh,
                wavelengths[i],
                cos,
            )
            .unwrap()
        };
        let mut out = vec![Response::default(); wavelengths.len() * cosines.len()];
        grid.solve(&cosines, &mut out);
        for path in [Path::Best, Path::Avx2, Path::Portable] {
            let mut other = vec![Response::default(); out.len()];
            solve_batch_mixed_on(path, &indices, &d, &coh, &wavelengths, &cosines, &mut other);
            assert_eq!(other, out, "{path:?}");
        }
        let mut spectrum = vec![Response::default(); wavelengths.len()];
        for (a, &cos) in cosines.iter().enumerate() {
            grid.solve_spectrum(&d, cos, &mut spectrum);
            for (i, got) in spectrum.iter().enumerate() {
                // Every copy of a loop gives the same bits; the point solver,
                // compiled apart, may round a last digit differently.
                let want = point(i, cos);
                assert_responses(got, &want, 1e-14, &format!("spectrum at {i}, cos {cos}"));
                let grid_point = &out[i * cosines.len() + a];
                assert_responses(grid_point, &want, 1e-14, &format!("grid at {i}, cos {cos}"));
            }
        }
    }
}

#[test]
fn a_lasing_point_of_a_grid_is_named() {
    let stack = Stack {
        ambient: Material::constant(1.0, 0.0),
        layers: vec![
            Layer::new(Material::constant(1.38, 0.0), 100.0),
            Layer {
                coherent: false,
                ..Layer::new(Material::constant(1.5, -1e-3), 7.5e4)
            },
        ],
        substrate: Material::constant(0.2, 3.4),
    };
    // Short wavelengths gain more per nanometre: with the metal below and
    // the coated face above (R' ρ ≈ 0.015), 400 nm lases (P² ≈ 111 per
    // round trip), 700 nm does not (P² ≈ 15).
    let grid = StackGrid::new(&stack, &[700.0, 400.0]).unwrap();
    let cos = [1.0, 0.9];
    let mut out = vec![Response::default(); 4];
    grid.solve(&cos, &mut out);
    assert!(out[0].is_finite() && out[1].is_finite());
    assert!(!out[2].is_finite() && out[2].rs == f64::INFINITY);
    let message = grid.check_solved(&cos, &out).unwrap_err().to_string();
    assert!(
        message.starts_with("layers[2]: this incoherent layer lases at 400 nm, 0.0000°"),
        "{message}"
    );
    assert!(StackGrid::new(&stack, &[700.0])
        .unwrap()
        .diverged(0, &[100.0, 7.5e4], 1.0)
        .is_none());
}

#[test]
fn the_bakers_split_agrees_with_the_solver() {
    // The split around a coherent layer (its group's two-port and the
    // incoherent sums around it), at thicknesses of that layer, against
    // the point solver: random mixed stacks, absorbing and dense-ambient
    // ones (layers beyond their critical angle, opaque layers below), and
    // a weakly amplifying incoherent layer.
    use irid::optics::solve_mixed;
    use irid::optics::twoport::{Scratch, VaryingLayer};
    let mut rng = Pcg64::seed_from_u64(4242);
    let mut scratch = Scratch::default();
    let mut checked = 0;
    for case in 0..400 {
        let (mut idx, d, coh) = random_mixed(&mut rng, false);
        if case % 4 == 0 {
            idx[0] = c(1.5, 0.0);
        }
        if case % 7 == 0 {
            if let Some(&m) = coh.incoherent_layers().first() {
                idx[m] = c(1.52, -2e-6);
            }
        }
        let Some(layer) = (1..=d.len()).find(|&l| coh.is_layer_coherent(l)) else {
            continue;
        };
        for &wl in &[400.0, 633.0] {
            for &cos in &[1.0, 0.7, 0.3, 0.05] {
                let v = VaryingLayer::new_mixed(&idx, &d, &coh, layer, wl, cos, &mut scratch);
                for &t in &[0.0, 37.0, 250.0, 1234.0] {
                    let mut dd = d.clone();
                    dd[layer - 1] = t;
                    let want = solve_mixed(&idx, &dd, &coh, wl, cos);
                    if v.is_degenerate() || !want.is_finite() {
                        continue;
                    }
                    let got = v.response(v.phase(t));
                    assert_responses(
                        &got,
                        &want,
                        1e-11,
                        &format!("{idx:?} {dd:?} {coh:?} layer {layer} at {wl} nm, cos {cos}"),
                    );
                    checked += 1;
                }
            }
        }
    }
    assert!(checked > 5000, "{checked}");
}
