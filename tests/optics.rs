//! The solver against closed forms, invariants over thousands of random
//! stacks, an independent characteristic-matrix computation, and the hard
//! cases of issue 2 (thick absorbers, frustrated TIR, deep mirrors, grazing
//! incidence, gain, 1000 layers).

// Not an API: a test crate has no public API to document.
#![allow(missing_docs)]

use num_complex::Complex64 as C64;
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64;

use irid::optics::{solve, solve_batch, Response, Stack, StackGrid};

fn c(n: f64, k: f64) -> C64 {
    C64::new(n, k)
}

fn cos_deg(angle_deg: f64) -> f64 {
    angle_deg.to_radians().cos()
}

fn assert_close(got: f64, want: f64, tol: f64, what: &str) {
    assert!(
        (got - want).abs() <= tol,
        "{what}: got {got:e}, want {want:e}, |d| = {:e} > {tol:e}",
        (got - want).abs()
    );
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

fn assert_finite(r: &Response, what: &str) {
    assert!(
        [r.rs, r.rp, r.ts, r.tp].iter().all(|v| v.is_finite()),
        "{what}: {r:?}"
    );
}

/// An independent path: the characteristic (admittance) matrix of each layer
/// multiplied out, as in Macleod's "Thin-Film Optical Filters", with tilted
/// admittances η_s = q and η_p = n²/q. It overflows for thick absorbers and
/// evanescent gaps, so tests use it only where the growth e^{Σ Im δ} is
/// modest.
fn matrix_method(
    indices: &[C64],
    thicknesses_nm: &[f64],
    wavelength_nm: f64,
    cos_theta0: f64,
) -> Response {
    let n0 = indices[0].re;
    let beta_sq = n0 * n0 * (1.0 - cos_theta0 * cos_theta0);
    let k0 = std::f64::consts::TAU / wavelength_nm;
    let q = |n: C64| {
        let r = (n * n - beta_sq).sqrt();
        if r.im < 0.0 || (r.im == 0.0 && r.re < 0.0) {
            -r
        } else {
            r
        }
    };
    let q0 = c(n0 * cos_theta0, 0.0);
    let sub = indices[indices.len() - 1];
    let mut out = [0.0; 4];
    for (pol, slot) in [(0, 0), (1, 1)] {
        let eta = |n: C64, qn: C64| if pol == 0 { qn } else { n * n / qn };
        let eta0 = eta(c(n0, 0.0), q0);
        let eta_sub = eta(sub, q(sub));
        // [B, C] = Π M_j · [1, η_sub]
        let mut m = [[c(1.0, 0.0), c(0.0, 0.0)], [c(0.0, 0.0), c(1.0, 0.0)]];
        for (j, &d) in thicknesses_nm.iter().enumerate() {
            let n = indices[j + 1];
            let qj = q(n);
            let e = eta(n, qj);
            let delta = k0 * qj * d;
            let (cs, sn) = (delta.cos(), delta.sin());
            let i = c(0.0, 1.0);
            let l = [[cs, -i * sn / e], [-i * e * sn, cs]];
            m = [
                [
                    m[0][0] * l[0][0] + m[0][1] * l[1][0],
                    m[0][0] * l[0][1] + m[0][1] * l[1][1],
                ],
                [
                    m[1][0] * l[0][0] + m[1][1] * l[1][0],
                    m[1][0] * l[0][1] + m[1][1] * l[1][1],
                ],
            ];
        }
        let b = m[0][0] + m[0][1] * eta_sub;
        let cc = m[1][0] + m[1][1] * eta_sub;
        let den = eta0 * b + cc;
        out[slot] = ((eta0 * b - cc) / den).norm_sqr();
        out[slot + 2] = 4.0 * eta0.re * eta_sub.re / den.norm_sqr();
    }
    Response {
        rs: out[0],
        rp: out[1],
        ts: out[2],
        tp: out[3],
    }
}

/// A random stack: ambient, layers and substrate indices and thicknesses.
struct Random {
    indices: Vec<C64>,
    thicknesses_nm: Vec<f64>,
}

#[derive(Clone, Copy)]
enum Kind {
    Lossless,
    Passive,
    WithGain,
}

fn random_stack(
    rng: &mut Pcg64,
    layers: std::ops::Range<usize>,
    kind: Kind,
    max_thickness_nm: f64,
) -> Random {
    let layers = rng.random_range(layers);
    let mut indices = vec![c(rng.random_range(1.0..2.0), 0.0)];
    let mut thicknesses_nm = Vec::with_capacity(layers);
    let k = |rng: &mut Pcg64| match kind {
        Kind::Lossless => 0.0,
        Kind::Passive => {
            if rng.random_bool(0.5) {
                0.0
            } else {
                rng.random_range(0.0..1.0)
            }
        }
        Kind::WithGain => rng.random_range(-0.05..0.5),
    };
    for _ in 0..layers {
        let kk = k(rng);
        indices.push(c(rng.random_range(1.0..3.0), kk));
        thicknesses_nm.push(rng.random_range(0.0..max_thickness_nm));
    }
    let sub = match kind {
        Kind::Lossless => c(rng.random_range(1.0..2.5), 0.0),
        _ => {
            if rng.random_bool(0.5) {
                c(rng.random_range(1.0..2.5), rng.random_range(0.0..0.5))
            } else {
                c(rng.random_range(0.05..2.0), rng.random_range(1.0..8.0))
            }
        }
    };
    indices.push(sub);
    Random {
        indices,
        thicknesses_nm,
    }
}

fn solve_both(s: &Random, wl: f64, cos: f64) -> Response {
    solve(&s.indices, &s.thicknesses_nm, wl, cos)
}

// ---------------------------------------------------------------- closed forms

#[test]
fn single_interface_matches_fresnel() {
    for &(n1, n2) in &[(1.0, 1.5), (1.5, 1.0), (1.0, 2.4), (1.33, 1.0)] {
        for angle in [0.0, 10.0, 30.0, 40.0, 41.0, 60.0, 80.0] {
            let (ci, si) = (cos_deg(angle), angle.to_radians().sin());
            let st = n1 * si / n2;
            if st >= 1.0 {
                continue;
            }
            let ct = (1.0 - st * st).sqrt();
            let rs = (n1 * ci - n2 * ct) / (n1 * ci + n2 * ct);
            let rp = (n2 * ci - n1 * ct) / (n2 * ci + n1 * ct);
            let r = solve(&[c(n1, 0.0), c(n2, 0.0)], &[], 550.0, ci);
            let what = format!("{n1}->{n2} at {angle}");
            assert_close(r.rs, rs * rs, 4e-15, &what);
            assert_close(r.rp, rp * rp, 4e-15, &what);
            assert_close(r.ts, 1.0 - rs * rs, 4e-15, &what);
            assert_close(r.tp, 1.0 - rp * rp, 4e-15, &what);
        }
    }
}

#[test]
fn absorbing_interface_matches_complex_fresnel() {
    // Air on gold-like metal: r_s = (cos θ − q)/(cos θ + q), q = sqrt(n² − sin² θ).
    let n = c(0.43, 2.455);
    for angle in [0.0, 45.0, 75.0] {
        let ci = cos_deg(angle);
        let q = (n * n - (1.0 - ci * ci)).sqrt();
        let rs = (ci - q) / (ci + q);
        let rp = (n * n * ci - q) / (n * n * ci + q);
        let r = solve(&[c(1.0, 0.0), n], &[], 550.0, ci);
        assert_close(r.rs, rs.norm_sqr(), 1e-15, "Rs");
        assert_close(r.rp, rp.norm_sqr(), 1e-15, "Rp");
        // No absorption before the substrate: all that is not reflected enters.
        assert_close(r.ts, 1.0 - r.rs, 1e-14, "Ts");
        assert_close(r.tp, 1.0 - r.rp, 1e-14, "Tp");
    }
}

#[test]
fn brewster_angle_has_no_p_reflection() {
    for &(n1, n2) in &[(1.0f64, 1.5f64), (1.0, 2.4), (1.5, 1.0)] {
        let theta_b = (n2 / n1).atan();
        let r = solve(&[c(n1, 0.0), c(n2, 0.0)], &[], 500.0, theta_b.cos());
        assert!(r.rp < 1e-30, "Rp at Brewster {n1}->{n2}: {}", r.rp);
        assert!(r.rs > 0.01);
    }
}

#[test]
fn quarter_wave_antireflection_coating() {
    let ns: f64 = 1.52;
    let nc = ns.sqrt();
    let wl = 550.0;
    let r = solve(
        &[c(1.0, 0.0), c(nc, 0.0), c(ns, 0.0)],
        &[wl / (4.0 * nc)],
        wl,
        1.0,
    );
    assert!(r.r() < 1e-30, "R = {}", r.r());
    assert_close(r.t(), 1.0, 1e-15, "T");
    // Away from its design wavelength it does reflect.
    let off = solve(
        &[c(1.0, 0.0), c(nc, 0.0), c(ns, 0.0)],
        &[wl / (4.0 * nc)],
        400.0,
        1.0,
    );
    assert!(off.r() > 1e-4);
}

/// (HL)^N quarter-wave mirror at its design wavelength, normal incidence:
/// each quarter-wave layer maps admittance Y to n²/Y, so the stack on the
/// substrate looks like Y = (n_H/n_L)^{2N} n_s and R = ((n0 − Y)/(n0 + Y))².
fn bragg(pairs: usize, n_h: f64, n_l: f64, n_s: f64) -> (Vec<C64>, Vec<f64>, f64, f64) {
    let wl = 600.0;
    let mut n = vec![c(1.0, 0.0)];
    let mut d = vec![];
    for _ in 0..pairs {
        n.extend([c(n_h, 0.0), c(n_l, 0.0)]);
        d.extend([wl / (4.0 * n_h), wl / (4.0 * n_l)]);
    }
    n.push(c(n_s, 0.0));
    let y = (n_h / n_l).powi(2 * pairs as i32) * n_s;
    let r = ((1.0 - y) / (1.0 + y)).powi(2);
    let t = 4.0 * y / (1.0 + y).powi(2);
    (n, d, r, t)
}

#[test]
fn quarter_wave_bragg_mirror_matches_closed_form() {
    for pairs in [1, 2, 5, 10] {
        let (n, d, r, t) = bragg(pairs, 2.35, 1.46, 1.52);
        let got = solve(&n, &d, 600.0, 1.0);
        assert_close(got.r(), r, 1e-13, &format!("{pairs} pairs R"));
        assert!(
            (got.t() - t).abs() <= 1e-12 * t,
            "{pairs} pairs T {} vs {t}",
            got.t()
        );
    }
}

#[test]
fn total_internal_reflection_reflects_everything() {
    for angle in [42.0, 50.0, 70.0, 89.0] {
        let r = solve(&[c(1.5, 0.0), c(1.0, 0.0)], &[], 600.0, cos_deg(angle));
        // |r| = |q0 − i g| / |q0 + i g| = 1, to rounding.
        assert_close(r.rs, 1.0, 1e-15, "Rs");
        assert_close(r.rp, 1.0, 1e-15, "Rp");
        assert_eq!((r.ts, r.tp), (0.0, 0.0));
        // Also through lossless layers above the interface.
        let r = solve(
            &[c(1.5, 0.0), c(1.8, 0.0), c(1.2, 0.0), c(1.0, 0.0)],
            &[120.0, 333.0],
            600.0,
            cos_deg(angle),
        );
        assert_close(r.rs, 1.0, 1e-14, "Rs");
        assert_close(r.rp, 1.0, 1e-14, "Rp");
        assert_eq!((r.ts, r.tp), (0.0, 0.0));
    }
}

#[test]
fn zero_thickness_and_index_matched_layers_are_invisible() {
    let mut rng = Pcg64::seed_from_u64(1);
    for _ in 0..500 {
        let s = random_stack(&mut rng, 0..6, Kind::WithGain, 800.0);
        let wl = rng.random_range(350.0..800.0);
        let cos = rng.random_range(0.05..1.0);
        let base = solve_both(&s, wl, cos);
        let at = rng.random_range(1..s.indices.len());
        // A zero-thickness layer of any index, inserted anywhere.
        let mut n = s.indices.clone();
        let mut d = s.thicknesses_nm.clone();
        n.insert(
            at,
            c(rng.random_range(1.0..3.0), rng.random_range(0.0..2.0)),
        );
        d.insert(at - 1, 0.0);
        let zero = solve(&n, &d, wl, cos);
        // A layer of the same index as the medium below it, of any thickness.
        let mut n = s.indices.clone();
        let mut d = s.thicknesses_nm.clone();
        n.insert(at, s.indices[at]);
        let below = if at < s.indices.len() - 1 {
            s.thicknesses_nm[at - 1]
        } else {
            0.0
        };
        let extra: f64 = rng.random_range(0.0..300.0);
        if at < s.indices.len() - 1 {
            // Splitting a layer in two leaves it unchanged.
            d[at - 1] = below - extra.min(below);
            d.insert(at - 1, extra.min(below));
        } else {
            // Above the substrate: a layer of substrate material moves the
            // point where T is measured down by its thickness, which only a
            // lossy substrate notices.
            let lossless = s.indices[at].im == 0.0;
            d.insert(at - 1, if lossless { extra } else { 0.0 });
        }
        let matched = solve(&n, &d, wl, cos);
        for (got, what) in [(zero, "zero-thickness"), (matched, "index-matched")] {
            assert_responses(&got, &base, 1e-12, what);
        }
    }
}

#[test]
fn normal_incidence_has_no_polarization() {
    let mut rng = Pcg64::seed_from_u64(2);
    for _ in 0..500 {
        let s = random_stack(&mut rng, 0..8, Kind::WithGain, 600.0);
        let r = solve_both(&s, 500.0, 1.0);
        assert!((r.rs - r.rp).abs() <= 1e-13 * r.rs.max(1.0), "{r:?}");
        assert!((r.ts - r.tp).abs() <= 1e-13 * r.ts.max(1.0), "{r:?}");
    }
}

// ---------------------------------------------------------------- invariants

#[test]
fn lossless_stacks_conserve_energy() {
    let mut rng = Pcg64::seed_from_u64(3);
    for i in 0..5000 {
        let s = random_stack(&mut rng, 0..20, Kind::Lossless, 1000.0);
        let wl = rng.random_range(300.0..900.0);
        let cos = rng.random_range(0.0..1.0);
        let r = solve_both(&s, wl, cos);
        assert_finite(&r, "lossless");
        assert!((r.rs + r.ts - 1.0).abs() <= 1e-12, "stack {i} s: {r:?}");
        assert!((r.rp + r.tp - 1.0).abs() <= 1e-12, "stack {i} p: {r:?}");
    }
}

#[test]
fn passive_stacks_absorb_nonnegatively() {
    let mut rng = Pcg64::seed_from_u64(4);
    for i in 0..5000 {
        let s = random_stack(&mut rng, 0..20, Kind::Passive, 1000.0);
        let wl = rng.random_range(300.0..900.0);
        let cos = rng.random_range(0.0..1.0);
        let r = solve_both(&s, wl, cos);
        assert_finite(&r, "passive");
        for (rr, tt) in [(r.rs, r.ts), (r.rp, r.tp)] {
            assert!(
                rr >= 0.0 && tt >= 0.0 && rr <= 1.0 + 1e-12,
                "stack {i}: {r:?}"
            );
            assert!(1.0 - rr - tt >= -1e-12, "stack {i}: A < 0: {r:?}");
        }
    }
}

#[test]
fn transmission_is_reciprocal() {
    // T from the ambient side at θ0 equals T from the substrate side at the
    // matching angle (n0 sin θ0 = ns sin θs), absorbing layers included.
    let mut rng = Pcg64::seed_from_u64(5);
    let mut checked = 0;
    for i in 0..4000 {
        let mut s = random_stack(&mut rng, 0..12, Kind::Passive, 800.0);
        let last = s.indices.len() - 1;
        s.indices[last] = c(rng.random_range(1.0..2.5), 0.0);
        let (n0, ns) = (s.indices[0].re, s.indices[last].re);
        let cos0: f64 = rng.random_range(0.05..1.0);
        let sin_s = n0 * (1.0 - cos0 * cos0).sqrt() / ns;
        if sin_s >= 0.999 {
            continue;
        }
        let cos_s = (1.0 - sin_s * sin_s).sqrt();
        let wl = rng.random_range(350.0..850.0);
        let forward = solve_both(&s, wl, cos0);
        let mut rev_n = s.indices.clone();
        rev_n.reverse();
        let mut rev_d = s.thicknesses_nm.clone();
        rev_d.reverse();
        let backward = solve(&rev_n, &rev_d, wl, cos_s);
        assert!(
            (forward.ts - backward.ts).abs() <= 1e-12,
            "stack {i} s: {forward:?} vs {backward:?}"
        );
        assert!(
            (forward.tp - backward.tp).abs() <= 1e-12,
            "stack {i} p: {forward:?} vs {backward:?}"
        );
        checked += 1;
    }
    assert!(checked > 3000);
}

#[test]
fn agrees_with_the_characteristic_matrix_method() {
    // Moderate stacks, where the plain matrix product is still accurate.
    let mut rng = Pcg64::seed_from_u64(6);
    for i in 0..3000 {
        let kind = [Kind::Lossless, Kind::Passive, Kind::WithGain][i % 3];
        let mut s = random_stack(&mut rng, 0..10, kind, 300.0);
        for n in &mut s.indices[1..] {
            n.im = n.im.clamp(-0.05, 0.3);
        }
        let wl = rng.random_range(350.0..850.0);
        let cos = rng.random_range(0.2..1.0);
        let got = solve_both(&s, wl, cos);
        let want = matrix_method(&s.indices, &s.thicknesses_nm, wl, cos);
        assert_responses(&got, &want, 1e-10, &format!("stack {i}"));
    }
}

// ---------------------------------------------------------------- hard cases

#[test]
fn millimetre_absorber_is_its_top_interface() {
    // 1 mm of n = 2 + 0.5i: e^{-2 k0 Im q d} ≈ e^{-11000}, nothing comes back
    // from below, so R is the air/absorber Fresnel reflectance and T is 0.
    let n = c(2.0, 0.5);
    for angle in [0.0, 45.0, 85.0] {
        let ci = cos_deg(angle);
        let r = solve(&[c(1.0, 0.0), n, c(1.5, 0.0)], &[1e6], 550.0, ci);
        assert_finite(&r, "1 mm absorber");
        let top = solve(&[c(1.0, 0.0), n], &[], 550.0, ci);
        assert_close(r.rs, top.rs, 1e-15, "Rs");
        assert_close(r.rp, top.rp, 1e-15, "Rp");
        assert_eq!((r.ts, r.tp), (0.0, 0.0));
    }
}

#[test]
fn frustrated_total_internal_reflection() {
    // Glass / air gap / glass at 60°, beyond the 41.8° critical angle. In the
    // gap q = i g, g = sqrt(β² − 1), and the wave decays as e^{-κd} with
    // κ = k0 g. For a gap of microns the multiple-reflection term
    // r01 r12 e^{-2κd} is below double precision, leaving
    // T_s = 16 q0² g² / (q0² + g²)² e^{-2κd} and
    // T_p = 16 n⁴ q0² g² / (q0² + n⁴ g²)² e^{-2κd}; compared through logs,
    // T being about 1e-164 for the 20 µm gap.
    let (ng, wl, angle) = (1.5, 550.0, 60.0);
    let ci = cos_deg(angle);
    let q0 = ng * ci;
    let beta_sq = ng * ng * (1.0 - ci) * (1.0 + ci);
    let g = (beta_sq - 1.0).sqrt();
    let kappa = std::f64::consts::TAU / wl * g;
    let n4 = ng.powi(4);
    let n = [c(ng, 0.0), c(1.0, 0.0), c(ng, 0.0)];
    for gap_nm in [2_000.0, 5_000.0, 20_000.0] {
        let r = solve(&n, &[gap_nm], wl, ci);
        assert_finite(&r, "FTIR");
        let ln_ts =
            (16.0 * q0 * q0 * g * g / (q0 * q0 + g * g).powi(2)).ln() - 2.0 * kappa * gap_nm;
        let ln_tp = (16.0 * n4 * q0 * q0 * g * g / (q0 * q0 + n4 * g * g).powi(2)).ln()
            - 2.0 * kappa * gap_nm;
        assert!(
            (r.ts.ln() - ln_ts).abs() <= 1e-12 * ln_ts.abs(),
            "{gap_nm} nm: ln Ts {} vs {ln_ts}",
            r.ts.ln()
        );
        assert!(
            (r.tp.ln() - ln_tp).abs() <= 1e-12 * ln_tp.abs(),
            "{gap_nm} nm: ln Tp {} vs {ln_tp}",
            r.tp.ln()
        );
        assert_close(r.rs + r.ts, 1.0, 1e-15, "Rs + Ts");
        assert_close(r.rp + r.tp, 1.0, 1e-15, "Rp + Tp");
    }
    // A thin gap tunnels a lot, and the matrix method agrees.
    for gap_nm in [50.0, 200.0] {
        let r = solve(&n, &[gap_nm], wl, ci);
        let m = matrix_method(&n, &[gap_nm], wl, ci);
        assert!(r.ts > 0.01);
        assert_close(r.ts, m.ts, 1e-12, "thin gap Ts");
        assert_close(r.tp, m.tp, 1e-12, "thin gap Tp");
    }
}

#[test]
fn hundred_pair_mirror() {
    // TiO2/SiO2-like (2.35/1.46) quarter waves: R rounds to 1, yet T ≈ 4/Y
    // ≈ 1e-41 must still come out right, since |t|² is computed directly.
    let (n, d, r, t) = bragg(100, 2.35, 1.46, 1.52);
    let got = solve(&n, &d, 600.0, 1.0);
    assert_finite(&got, "100 pairs");
    assert_close(got.r(), r, 1e-15, "R");
    assert!((got.t() - t).abs() <= 1e-10 * t, "T {} vs {t}", got.t());
    // Oblique and off-design: still lossless, still conserving energy.
    for (wl, angle) in [(600.0, 30.0), (450.0, 0.0), (700.0, 70.0)] {
        let r = solve(&n, &d, wl, cos_deg(angle));
        assert_finite(&r, "100 pairs");
        assert!(
            (r.rs + r.ts - 1.0).abs() < 1e-12 && (r.rp + r.tp - 1.0).abs() < 1e-12,
            "{r:?}"
        );
    }
}

#[test]
fn grazing_incidence() {
    let ci = cos_deg(89.999);
    // One interface: Fresnel's closed form, R → 1 as cos θ → 0.
    let (n1, n2) = (1.0, 1.5);
    let st = (1.0 - ci * ci).sqrt() / n2;
    let ct = (1.0 - st * st).sqrt();
    let rs = (n1 * ci - n2 * ct) / (n1 * ci + n2 * ct);
    let rp = (n2 * ci - n1 * ct) / (n2 * ci + n1 * ct);
    let r = solve(&[c(n1, 0.0), c(n2, 0.0)], &[], 550.0, ci);
    assert_close(r.rs, rs * rs, 1e-14, "Rs");
    assert_close(r.rp, rp * rp, 1e-14, "Rp");
    assert!(r.ts > 0.0 && r.ts < 1e-3);
    // Random stacks at 89.999°: finite, lossless ones conserve energy.
    let mut rng = Pcg64::seed_from_u64(7);
    for _ in 0..1000 {
        let s = random_stack(&mut rng, 0..10, Kind::Lossless, 1000.0);
        let r = solve_both(&s, 550.0, ci);
        assert!(
            (r.rs + r.ts - 1.0).abs() <= 1e-12 && (r.rp + r.tp - 1.0).abs() <= 1e-12,
            "{r:?}"
        );
        let s = random_stack(&mut rng, 0..10, Kind::WithGain, 1000.0);
        assert_finite(&solve_both(&s, 550.0, ci), "gain at grazing");
    }
    // Exactly grazing: everything reflects, unless there is no interface at all.
    assert_eq!(solve(&[c(1.0, 0.0), c(1.5, 0.1)], &[], 550.0, 0.0).r(), 1.0);
    assert_eq!(
        solve(&[c(1.0, 0.0), c(1.0, 0.0)], &[10.0; 0], 550.0, 0.0).t(),
        1.0
    );
}

#[test]
fn gain_film_on_gold() {
    let stack = Stack::load(std::path::Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/luts/gain-on-gold.toml"
    )))
    .unwrap();
    let wavelengths: Vec<f64> = (0..=40).map(|i| 380.0 + 10.0 * i as f64).collect();
    let grid = StackGrid::new(&stack, &wavelengths).unwrap();
    let cos: Vec<f64> = [0.0, 30.0, 60.0, 85.0].map(cos_deg).to_vec();
    let mut out = vec![Response::default(); wavelengths.len() * cos.len()];
    grid.solve(&cos, &mut out);
    let mut amplifies = false;
    for (i, r) in out.iter().enumerate() {
        assert_finite(r, "gain on gold");
        let (wl, ci) = (wavelengths[i / cos.len()], cos[i % cos.len()]);
        let n = grid.indices_at(i / cos.len());
        let m = matrix_method(n, grid.thicknesses_nm(), wl, ci);
        assert_responses(r, &m, 1e-11, &format!("{wl} nm"));
        amplifies |= r.r() > 1.0;
    }
    assert!(
        amplifies,
        "the gain film should reflect more than it receives somewhere"
    );
}

#[test]
fn thousand_random_layers() {
    let mut rng = Pcg64::seed_from_u64(8);
    for kind in [Kind::Lossless, Kind::Passive, Kind::WithGain] {
        for _ in 0..5 {
            let mut s = random_stack(&mut rng, 1000..1001, kind, 200.0);
            for n in &mut s.indices[1..] {
                n.im = n.im.clamp(-0.01, 0.02);
            }
            let wl = rng.random_range(400.0..800.0);
            let cos = rng.random_range(0.3..1.0);
            let r = solve_both(&s, wl, cos);
            assert_finite(&r, "1000 layers");
            match kind {
                Kind::Lossless => {
                    assert!(
                        (r.rs + r.ts - 1.0).abs() <= 1e-12 && (r.rp + r.tp - 1.0).abs() <= 1e-12,
                        "{r:?}"
                    )
                }
                Kind::Passive => assert!(1.0 - r.r() - r.t() >= -1e-12, "{r:?}"),
                Kind::WithGain => {}
            }
            // The plain matrix product stays accurate here (thin layers,
            // little loss or gain, propagating waves): an independent answer.
            let m = matrix_method(&s.indices, &s.thicknesses_nm, wl, cos);
            assert_responses(&r, &m, 1e-9, "1000 layers");
        }
    }
    // Strong absorbers and evanescent layers among 1000: the matrix method
    // overflows here; the recursion stays finite, passive and lossless-exact.
    for _ in 0..20 {
        let s = random_stack(&mut rng, 1000..1001, Kind::Passive, 2000.0);
        let r = solve_both(&s, 500.0, 0.1);
        assert_finite(&r, "1000 hard layers");
        assert!(r.rs <= 1.0 + 1e-15 && r.rp <= 1.0 + 1e-15, "{r:?}");
        assert!(1.0 - r.r() - r.t() >= -1e-12, "{r:?}");
    }
}

#[test]
fn batch_equals_one_at_a_time() {
    let stack = Stack::load(std::path::Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/luts/two-layer.toml"
    )))
    .unwrap();
    let wavelengths: Vec<f64> = (0..50).map(|i| 380.0 + 8.0 * i as f64).collect();
    let cos: Vec<f64> = (0..17).map(|i| i as f64 / 16.0).collect();
    let grid = StackGrid::new(&stack, &wavelengths).unwrap();
    let mut out = vec![Response::default(); wavelengths.len() * cos.len()];
    solve_batch(
        grid.indices(),
        grid.thicknesses_nm(),
        &wavelengths,
        &cos,
        &mut out,
    );
    // Four points per vector: the one-at-a-time answer to within a few ulps
    // (tests/batched.rs holds the lanes to the scalar solver over hard cases).
    for (i, &wl) in wavelengths.iter().enumerate() {
        for (j, &cj) in cos.iter().enumerate() {
            assert_responses(
                &out[i * cos.len() + j],
                &stack.response(wl, cj).unwrap(),
                1e-14,
                &format!("{wl} nm, cos {cj}"),
            );
        }
    }
}

#[test]
fn wavelength_outside_a_table_names_the_material() {
    let stack = Stack::load(std::path::Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/luts/two-layer.toml"
    )))
    .unwrap();
    let err = StackGrid::new(&stack, &[500.0, 2500.0])
        .unwrap_err()
        .to_string();
    assert!(err.contains("gold") && err.contains("2500"), "{err}");
}

#[test]
fn layer_at_its_critical_angle() {
    // Glass ambient, an air layer, a lossy substrate. At the air layer's
    // critical angle q = 0 there: the Γ recursion alone gives 0/0 and loses
    // digits as 1e-16/|q| nearby. Every cos θ within a few thousand ulps of
    // critical must be finite and equal the (smooth) limit, which the matrix
    // method gives accurately just off it.
    let n = [c(1.5, 0.0), c(1.0, 0.0), c(1.2, 0.3)];
    let d = [300.0];
    let c_crit = (1.0f64 - 1.0 / 2.25).sqrt();
    let reference = |h: f64| {
        let a = matrix_method(&n, &d, 550.0, c_crit * (1.0 + h));
        let b = matrix_method(&n, &d, 550.0, c_crit * (1.0 - h));
        [a.rs + b.rs, a.rp + b.rp, a.ts + b.ts, a.tp + b.tp].map(|v| v / 2.0)
    };
    let want = reference(1e-9);
    for i in -2000..=2000 {
        let r = solve(&n, &d, 550.0, c_crit * (1.0 + i as f64 * 1e-16));
        assert_finite(&r, "critical layer");
        for (a, b) in [r.rs, r.rp, r.ts, r.tp].iter().zip(want) {
            assert!((a - b).abs() < 1e-11, "{i} ulp-ish: {r:?} vs {want:?}");
        }
    }
    // Off critical, on both sides and at several distances, both agree.
    for e in [1e-12, 1e-8, 1e-5, 1e-3, 1e-2] {
        for sign in [-1.0, 1.0] {
            let ci = c_crit * (1.0 + sign * e);
            let (r, m) = (solve(&n, &d, 550.0, ci), matrix_method(&n, &d, 550.0, ci));
            assert_responses(&r, &m, 1e-11, &format!("offset {}", sign * e));
        }
    }
}

#[test]
fn runs_of_near_critical_layers() {
    // Several adjacent layers at or near their critical angle (some lossy,
    // some with gain), between ordinary ones: compared with the matrix method.
    let mut rng = Pcg64::seed_from_u64(9);
    let n0 = 1.6;
    for _ in 0..2000 {
        let ci: f64 = rng.random_range(0.3..0.9);
        let beta = n0 * (1.0 - ci * ci).sqrt();
        let mut n = vec![c(n0, 0.0)];
        let mut d = vec![];
        for _ in 0..rng.random_range(1..6) {
            let layer = if rng.random_bool(0.7) {
                c(
                    beta * (1.0 + rng.random_range(-1e-6..1e-6)),
                    rng.random_range(-1e-7..1e-6),
                )
            } else {
                c(rng.random_range(1.0..2.5), rng.random_range(0.0..0.2))
            };
            n.push(layer);
            d.push(rng.random_range(0.0..400.0));
        }
        n.push(c(rng.random_range(1.0..2.0), rng.random_range(0.0..3.0)));
        let wl = rng.random_range(400.0..700.0);
        let (r, m) = (solve(&n, &d, wl, ci), matrix_method(&n, &d, wl, ci));
        assert_responses(&r, &m, 1e-10, &format!("{n:?} {d:?}"));
    }
    // A thick, barely evanescent layer (|q| ≈ 0.005|n|): lossless, so
    // R + T = 1; thick enough, it transmits nothing. Around Im δ = 30, where
    // the field form switches to its overflow-safe scaling, it still agrees
    // with the matrix method, R absolutely and T relatively.
    let ci: f64 = 0.6;
    let (wl, n_amb) = (550.0, 1.5);
    let beta = n_amb * (1.0 - ci * ci).sqrt();
    let layer = c(beta * (1.0 - 1e-5), 0.0);
    let n = [c(n_amb, 0.0), layer, c(n_amb, 0.0)];
    let kappa = std::f64::consts::TAU / wl * (beta * beta - layer.re * layer.re).sqrt();
    for im_delta in [5.0, 25.0, 29.99, 30.01, 35.0] {
        let d = [im_delta / kappa];
        let (r, m) = (solve(&n, &d, wl, ci), matrix_method(&n, &d, wl, ci));
        for (a, b) in [(r.rs, m.rs), (r.rp, m.rp)] {
            assert!((a - b).abs() < 1e-12, "Im δ {im_delta}: {r:?} vs {m:?}");
        }
        for (a, b) in [(r.ts, m.ts), (r.tp, m.tp)] {
            assert!((a - b).abs() < 1e-9 * b, "Im δ {im_delta}: {r:?} vs {m:?}");
        }
    }
    for thickness_nm in [1e5, 1e6, 1e8] {
        let r = solve(&n, &[thickness_nm], wl, ci);
        assert_finite(&r, "thick near-critical barrier");
        assert_close(r.rs + r.ts, 1.0, 1e-12, "Rs + Ts");
        assert_close(r.rp + r.tp, 1.0, 1e-12, "Rp + Tp");
        if thickness_nm >= 1e6 {
            assert!(r.ts < 1e-40 && r.tp < 1e-40, "{r:?}");
        }
    }
}

#[test]
fn extreme_but_accepted_inputs_stay_finite() {
    // The edges of what materials and stacks accept: |n|, |k| up to 1e6 and
    // down to 1e-6, thickness 0 to 1e12 nm, wavelength 1e-3 to 1e9 nm, any
    // angle short of grazing.
    let mut rng = Pcg64::seed_from_u64(10);
    let pick = |rng: &mut Pcg64, v: &[f64]| v[rng.random_range(0..v.len())];
    let values = [1e-6, 0.3, 1.0, 1.5, 40.0, 1e6];
    for _ in 0..20_000 {
        let layers = rng.random_range(0..6);
        let mut n = vec![c(pick(&mut rng, &values), 0.0)];
        let mut d = vec![];
        for _ in 0..layers {
            let k = pick(&mut rng, &[0.0, 1e-6, 1.0, 1e6, -1e-3, -0.5]);
            n.push(c(pick(&mut rng, &values), k));
            d.push(pick(&mut rng, &[0.0, 1e-300, 1.0, 500.0, 1e6, 1e12]));
        }
        n.push(c(
            pick(&mut rng, &values),
            pick(&mut rng, &[0.0, 1e-6, 3.0, 1e6]),
        ));
        let wl = pick(&mut rng, &[1e-3, 550.0, 1e9]);
        let cos = pick(&mut rng, &[1.0, 0.5, 1e-3, 1e-9]);
        let r = solve(&n, &d, wl, cos);
        assert_finite(&r, &format!("{n:?} {d:?} {wl} {cos}"));
    }
}

#[test]
fn split_at_a_buried_layer_recomposes() {
    // The baker's decomposition: A = ambient..layer L (L seen as
    // semi-infinite), A' = A seen from inside L, B = L..substrate, then
    // Airy's sum over L's multiple reflections,
    //   r = r_A + t_A t'_A r_B φ² / (1 − r'_A r_B φ²),
    //   t = t_A t_B φ / (1 − r'_A r_B φ²),  φ = e^{i k0 q_L d},
    // must give the whole stack's r and t. Sub-stacks whose top medium is an
    // absorbing or gain layer go through solve_amplitudes_beta.
    use irid::optics::{solve_amplitudes, solve_amplitudes_beta};
    let mut rng = Pcg64::seed_from_u64(11);
    for i in 0..2000 {
        let s = random_stack(&mut rng, 1..8, Kind::WithGain, 500.0);
        let (n, d) = (&s.indices, &s.thicknesses_nm);
        let wl = rng.random_range(380.0..780.0);
        let cos: f64 = rng.random_range(0.1..1.0);
        let beta_sq = n[0].re * n[0].re * (1.0 - cos) * (1.0 + cos);
        let l = rng.random_range(1..n.len() - 1); // the buried layer's medium index
        let whole = solve_amplitudes(n, d, wl, cos);
        // The top medium of A is the (lossless) ambient: both entry points agree.
        let a = solve_amplitudes(&n[..=l], &d[..l - 1], wl, cos);
        let a_beta = solve_amplitudes_beta(&n[..=l], &d[..l - 1], wl, beta_sq);
        let pairs = [
            (a.rs, a_beta.rs),
            (a.rp, a_beta.rp),
            (a.ts, a_beta.ts),
            (a.tp, a_beta.tp),
        ];
        let agree = pairs
            .iter()
            .all(|(x, y)| (x - y).norm() <= 1e-12 * y.norm().max(1.0));
        assert!(agree, "stack {i}: {a:?} vs {a_beta:?}");
        let mut up_n: Vec<C64> = n[..=l].to_vec();
        up_n.reverse();
        let mut up_d: Vec<f64> = d[..l - 1].to_vec();
        up_d.reverse();
        let a_up = solve_amplitudes_beta(&up_n, &up_d, wl, beta_sq);
        let b = solve_amplitudes_beta(&n[l..], &d[l..], wl, beta_sq);
        let q_l = irid::optics::normal_index(n[l], beta_sq);
        let phi = (C64::new(0.0, std::f64::consts::TAU / wl * d[l - 1]) * q_l).exp();
        for (pol, (ra, ta, ra_up, ta_up, rb, tb, r, t)) in [
            (
                "s",
                (a.rs, a.ts, a_up.rs, a_up.ts, b.rs, b.ts, whole.rs, whole.ts),
            ),
            (
                "p",
                (a.rp, a.tp, a_up.rp, a_up.tp, b.rp, b.tp, whole.rp, whole.tp),
            ),
        ] {
            let den = 1.0 - ra_up * rb * phi * phi;
            let r_split = ra + ta * ta_up * rb * phi * phi / den;
            let t_split = ta * tb * phi / den;
            assert!(
                (r_split - r).norm() <= 1e-10 * r.norm().max(1.0),
                "stack {i} {pol}: r {r_split} vs {r}"
            );
            assert!(
                (t_split - t).norm() <= 1e-10 * t.norm().max(1.0),
                "stack {i} {pol}: t {t_split} vs {t}"
            );
        }
    }
}

/// A built-in TiO2 film absorbs at the violet end of the bakers' range (its
/// tabulated k, about 0.004 at 380 nm) and is as good as lossless in the
/// rest of the visible: R + T < 1 there, not at 600 nm.
#[test]
fn titania_film_absorbs_in_the_violet() {
    let text = "ambient = { n = 1.0 }\nsubstrate = { material = \"fused-silica\" }\n\
                [[layers]]\nmaterial = \"TiO2\"\nthickness_nm = 200.0\n";
    let stack = Stack::from_toml_str(text, std::path::Path::new(""), "tio2.toml").unwrap();
    let absorbed = |wavelength_nm: f64| {
        let r = stack.response(wavelength_nm, 1.0).unwrap();
        1.0 - r.r() - r.t()
    };
    let (violet, orange) = (absorbed(380.0), absorbed(600.0));
    assert!(violet > 0.01 && violet < 0.2, "380 nm: {violet}");
    assert!(orange.abs() < 1e-5, "600 nm: {orange}");
}
