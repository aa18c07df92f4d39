//! The lane kernel over arbitrary points (`lanes::solve_points_on`, each
//! point its own indices, thicknesses, wavelength and angle) and
//! `Stack::solve_points` on top of it, against the scalar solver point by
//! point: random stacks of every kind with the points of one vector from
//! unrelated stacks, grazing, near-grazing and critical incidence, gain,
//! metals, thick absorbers, evanescent gaps, lengths around the vector width
//! and the block size; dispersive stacks from tables; and the bad input it
//! refuses. The wide copies equal the portable one bit for bit; all equal
//! the scalar solver to 1e-12.

use std::path::Path as FsPath;

use num_complex::Complex64 as C64;
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64;

use irid::optics::lanes::{best_copy, solve_points_on, Path};
use irid::optics::{
    solve, solve_incoherent, LayerThickness, PointSolver, Response, Stack, MAX_THICKNESS_NM,
};

mod common;
use common::random_stack::{random_stack, Kind, KINDS};

const TOLERANCE: f64 = 1e-12;

fn c(n: f64, k: f64) -> C64 {
    C64::new(n, k)
}

/// Points of one layer count, each with everything its own.
struct Points {
    what: String,
    layers: usize,
    /// N + 2 per point.
    indices: Vec<C64>,
    /// N per point.
    thicknesses_nm: Vec<f64>,
    wavelengths_nm: Vec<f64>,
    cos_theta0: Vec<f64>,
}

impl Points {
    fn new(what: impl Into<String>, layers: usize) -> Points {
        Points {
            what: what.into(),
            layers,
            indices: Vec::new(),
            thicknesses_nm: Vec::new(),
            wavelengths_nm: Vec::new(),
            cos_theta0: Vec::new(),
        }
    }

    fn push(&mut self, indices: &[C64], thicknesses_nm: &[f64], wavelength_nm: f64, cos: f64) {
        assert_eq!(indices.len(), self.layers + 2);
        assert_eq!(thicknesses_nm.len(), self.layers);
        self.indices.extend_from_slice(indices);
        self.thicknesses_nm.extend_from_slice(thicknesses_nm);
        self.wavelengths_nm.push(wavelength_nm);
        self.cos_theta0.push(cos);
    }

    fn len(&self) -> usize {
        self.wavelengths_nm.len()
    }

    fn run(&self, path: Path) -> Vec<Response> {
        let mut out = vec![Response::default(); self.len()];
        solve_points_on(
            path,
            self.layers,
            &self.indices,
            &self.thicknesses_nm,
            &self.wavelengths_nm,
            &self.cos_theta0,
            &mut out,
        );
        out
    }

    /// Every copy against the portable one (bits) and the scalar solver.
    fn check(&self) {
        let (best, avx2, portable) = (
            self.run(Path::Best),
            self.run(Path::Avx2),
            self.run(Path::Portable),
        );
        let media = self.layers + 2;
        for i in 0..self.len() {
            let want = solve(
                &self.indices[i * media..(i + 1) * media],
                &self.thicknesses_nm[i * self.layers..(i + 1) * self.layers],
                self.wavelengths_nm[i],
                self.cos_theta0[i],
            );
            let at = format!(
                "{}: point {i} ({} nm, cos {})",
                self.what, self.wavelengths_nm[i], self.cos_theta0[i]
            );
            assert!(
                same_bits(&avx2[i], &portable[i]),
                "{at}: AVX2 and portable differ"
            );
            assert!(
                same_bits(&best[i], &portable[i]),
                "{at}: {} and portable differ",
                best_copy()
            );
            assert_close(&at, &best[i], &want);
        }
    }
}

fn same_bits(a: &Response, b: &Response) -> bool {
    [a.rs, a.rp, a.ts, a.tp]
        .iter()
        .zip([b.rs, b.rp, b.ts, b.tp])
        .all(|(x, y)| x.to_bits() == y.to_bits())
}

/// Within [`TOLERANCE`], relative above 1; NaN only where both are NaN.
fn assert_close(at: &str, got: &Response, want: &Response) {
    for (g, w, name) in [
        (got.rs, want.rs, "Rs"),
        (got.rp, want.rp, "Rp"),
        (got.ts, want.ts, "Ts"),
        (got.tp, want.tp, "Tp"),
    ] {
        let scale = g.abs().max(w.abs()).max(1.0);
        let same = (g - w).abs() <= TOLERANCE * scale || (g.is_nan() && w.is_nan());
        assert!(
            same,
            "{at}: {name} lanes {g:e}, scalar {w:e} (Δ {:e})",
            g - w
        );
    }
}

/// Incidences worth testing for a stack of indices `n`: random, normal,
/// grazing and near-grazing, and each layer's critical angle (exactly and
/// just off it) where the ambient is denser.
fn hard_cosines(rng: &mut Pcg64, n: &[C64]) -> Vec<f64> {
    let mut cos = vec![rng.random_range(0.0..1.0), 1.0, 0.0, 1e-9, 1e-4];
    let n0 = n[0].re;
    for layer in &n[1..n.len() - 1] {
        if layer.re < n0 {
            let cc = (1.0 - (layer.re / n0).powi(2)).sqrt();
            cos.extend([cc, cc * (1.0 + 1e-7), cc * (1.0 - 1e-5)]);
        }
    }
    cos
}

#[test]
fn every_point_its_own_stack() {
    // Neighbouring lanes come from unrelated stacks (of one layer count),
    // so nothing one lane computes can stand in for another's.
    let mut rng = Pcg64::seed_from_u64(41);
    for round in 0..200 {
        let layers = rng.random_range(0..7);
        let mut points = Points::new(format!("round {round}, {layers} layers"), layers);
        for _ in 0..rng.random_range(1..40) {
            let kind = KINDS[rng.random_range(0..4)];
            let (n, d) = random_stack(&mut rng, kind, layers, 2000.0);
            let cosines = hard_cosines(&mut rng, &n);
            let cos = cosines[rng.random_range(0..cosines.len())];
            points.push(&n, &d, rng.random_range(300.0..900.0), cos);
        }
        points.check();
    }
}

#[test]
fn one_stack_at_every_hard_angle() {
    // Each stack at all its hard incidences in a row, so grazing and
    // critical lanes sit in a vector with ordinary ones.
    let mut rng = Pcg64::seed_from_u64(42);
    for kind in KINDS {
        for layers in [1, 2, 5, 40] {
            let mut points = Points::new(format!("{kind:?}, {layers} layers"), layers);
            for _ in 0..6 {
                let (n, d) = random_stack(&mut rng, kind, layers, 800.0);
                for cos in hard_cosines(&mut rng, &n) {
                    points.push(&n, &d, rng.random_range(360.0..830.0), cos);
                }
            }
            points.check();
        }
    }
}

#[test]
fn thick_absorbers_gaps_and_gain() {
    let mut points = Points::new("hard layers", 1);
    let glass = c(1.5, 0.0);
    // Decays that underflow, and phases beyond the polynomial's range, each
    // beside an ordinary lane.
    for (k, d) in [
        (1e-3, 4e7),
        (0.9, 4e7),
        (0.0, 4e7),
        (1e-6, 4e7),
        (0.0, 300.0),
    ] {
        points.push(&[c(1.0, 0.0), c(1.5, k), glass], &[d], 500.0, 0.8);
    }
    // Frustrated total internal reflection: glass / air gap / glass.
    for gap in [0.0, 1.0, 50.0, 200.0, 1000.0, 1e5, 1e7] {
        for cos in [0.9, 0.6, 0.5, 0.3, 0.1, 0.0] {
            points.push(
                &[glass, c(1.0, 0.0), glass],
                &[gap],
                450.0 + gap.min(300.0),
                cos,
            );
        }
    }
    // A gain film on gold at every angle.
    for i in 0..=40 {
        points.push(
            &[c(1.0, 0.0), c(1.6, -0.08), c(0.27, 2.9)],
            &[350.0],
            620.0,
            f64::from(i) / 40.0,
        );
    }
    points.check();
}

#[test]
fn lengths_around_the_vector_width() {
    let mut rng = Pcg64::seed_from_u64(43);
    for len in 0..20 {
        let mut points = Points::new(format!("{len} points"), 2);
        for _ in 0..len {
            let (n, d) = random_stack(&mut rng, Kind::Passive, 2, 500.0);
            points.push(
                &n,
                &d,
                rng.random_range(360.0..830.0),
                rng.random_range(0.0..1.0),
            );
        }
        points.check();
    }
}

fn luts(name: &str) -> Stack {
    let path = FsPath::new(env!("CARGO_MANIFEST_DIR"))
        .join("luts")
        .join(name);
    Stack::load(&path).unwrap()
}

fn from_toml(text: &str) -> Stack {
    Stack::from_toml_str(text, FsPath::new("."), "test").unwrap()
}

/// `Stack::solve_points` on every copy against the stack's indices at each
/// point's wavelength through the scalar solver.
fn check_stack(
    what: &str,
    stack: &Stack,
    varying: Option<LayerThickness<'_>>,
    wl: &[f64],
    cos: &[f64],
) {
    let run = |path: Path| {
        let mut out = vec![Response::default(); wl.len()];
        PointSolver::new(stack)
            .unwrap()
            .solve_on(path, varying, wl, cos, &mut out)
            .unwrap();
        out
    };
    let (best, portable) = (run(Path::Best), run(Path::Portable));
    let mut public = vec![Response::default(); wl.len()];
    stack.solve_points(varying, wl, cos, &mut public).unwrap();
    let mut n = Vec::new();
    for i in 0..wl.len() {
        let mut d = stack.thicknesses_nm();
        if let Some(v) = varying {
            d[v.layer] = v.thickness_nm[i];
        }
        stack.indices_at(wl[i], &mut n).unwrap();
        let want = solve(&n, &d, wl[i], cos[i]);
        let at = format!("{what}: point {i} ({} nm, cos {})", wl[i], cos[i]);
        assert!(same_bits(&best[i], &portable[i]), "{at}: copies differ");
        assert!(
            same_bits(&best[i], &public[i]),
            "{at}: solve_points is not Path::Best"
        );
        assert_close(&at, &best[i], &want);
    }
}

#[test]
fn dispersive_stacks_at_random_points() {
    let mut rng = Pcg64::seed_from_u64(44);
    let film_on_copper = from_toml(
        "ambient = { n = 1.0 }\nsubstrate = { material = \"copper\" }\n\
         [[layers]]\nmaterial = \"TiO2\"\nthickness_nm = 300.0\n",
    );
    let gain = from_toml(
        "ambient = { n = 1.33 }\nsubstrate = { material = \"gold\" }\n\
         [[layers]]\nn = [1.6, -0.05]\nthickness_nm = 250.0\n\
         [[layers]]\nn = 1.2\nthickness_nm = 40.0\n",
    );
    let stacks = [
        ("two-layer.toml", luts("two-layer.toml")),
        ("soap-film.toml", luts("soap-film.toml")),
        ("mirror-10.toml", luts("mirror-10.toml")),
        ("TiO2 on copper", film_on_copper),
        ("gain film and low-index layer on gold", gain),
    ];
    // Past the block of 256 points, and not a multiple of any width.
    for len in [1, 7, 255, 256, 257, 1031] {
        for (name, stack) in &stacks {
            let wl: Vec<f64> = (0..len).map(|_| rng.random_range(360.0..830.0)).collect();
            let mut cos: Vec<f64> = (0..len).map(|_| rng.random_range(0.0..1.0)).collect();
            // Grazing, normal and (for the low-index layer under water) critical.
            let critical = (1.0 - (1.2f64 / 1.33).powi(2)).sqrt();
            for (i, special) in [0.0, 1.0, 1e-9, critical].into_iter().enumerate() {
                if let Some(c) = cos.get_mut(i * 3) {
                    *c = special;
                }
            }
            let thickness: Vec<f64> = (0..len).map(|_| rng.random_range(0.0..2000.0)).collect();
            let what = format!("{name}, {len} points");
            check_stack(&what, stack, None, &wl, &cos);
            for layer in 0..stack.layers.len().min(2) {
                let varying = LayerThickness {
                    layer,
                    thickness_nm: &thickness,
                };
                check_stack(
                    &format!("{what}, layer {layer} varied"),
                    stack,
                    Some(varying),
                    &wl,
                    &cos,
                );
            }
        }
    }
}

#[test]
fn a_bare_interface() {
    let stack = from_toml("ambient = { n = 1.0 }\nsubstrate = { material = \"gold\" }\n");
    let wl: Vec<f64> = (0..50).map(|i| 360.0 + 9.0 * f64::from(i)).collect();
    let cos: Vec<f64> = (0..50).map(|i| f64::from(i) / 49.0).collect();
    check_stack("bare gold", &stack, None, &wl, &cos);
}

#[test]
fn bad_points_are_refused_by_name() {
    let stack = luts("two-layer.toml");
    let mut out = vec![Response::default(); 3];
    let wl = [400.0, 500.0, 600.0];
    let good_cos = [0.5, 0.5, 0.5];
    let vary = |t: &'static [f64], layer: usize| {
        Some(LayerThickness {
            layer,
            thickness_nm: t,
        })
    };
    let error =
        |varying: Option<LayerThickness<'_>>, wl: &[f64], cos: &[f64], out: &mut [Response]| {
            stack
                .solve_points(varying, wl, cos, out)
                .unwrap_err()
                .to_string()
        };
    let message = error(None, &wl, &[0.5, f64::NAN, 0.5], &mut out);
    assert!(
        message.starts_with("cos_theta: NaN is outside [0, 1]"),
        "{message}"
    );
    let message = error(None, &wl, &[0.5, 1.5, 0.5], &mut out);
    assert!(message.starts_with("cos_theta: 1.5"), "{message}");
    let message = error(None, &wl, &[-0.1, 0.5, 0.5], &mut out);
    assert!(message.starts_with("cos_theta: -0.1"), "{message}");
    for bad in [
        [10.0, f64::NAN, 1.0],
        [10.0, -1.0, 1.0],
        [10.0, 2.0 * MAX_THICKNESS_NM, 1.0],
        [f64::INFINITY, 1.0, 1.0],
    ] {
        let leaked: &'static [f64] = Box::leak(Box::new(bad));
        let message = error(vary(leaked, 0), &wl, &good_cos, &mut out);
        assert!(
            message.starts_with("thickness_nm: must be finite"),
            "{message}"
        );
    }
    let message = error(vary(&[1.0, 2.0, 3.0], 2), &wl, &good_cos, &mut out);
    assert!(
        message.starts_with("layer: the stack has 2 layers"),
        "{message}"
    );
    // Gold's table starts above 100 nm; NaN and infinite wavelengths.
    for bad in [100.0, f64::NAN, f64::INFINITY, -5.0] {
        let message = error(None, &[400.0, bad, 600.0], &good_cos, &mut out);
        assert!(message.contains("wavelength"), "{bad}: {message}");
    }
    // A stack that validate() refuses: a lossy ambient.
    let lossy = Stack {
        ambient: irid::optics::Material::constant(1.0, 0.1),
        ..stack.clone()
    };
    let message = lossy
        .solve_points(None, &wl, &good_cos, &mut out)
        .unwrap_err()
        .to_string();
    assert!(
        message.starts_with("ambient: must be lossless"),
        "{message}"
    );
    // Nothing to do is no error.
    stack.solve_points(None, &[], &[], &mut []).unwrap();
}

/// A stack with an incoherent layer (the coated sheet of `luts/`) at random
/// points, its front film's thickness per point: each point equals
/// `solve_incoherent` at the stack's indices exactly (the same function on
/// the same inputs), and a gain layer that lases at a point is refused,
/// naming that layer.
#[test]
fn stacks_with_incoherent_layers() {
    let mut rng = Pcg64::seed_from_u64(45);
    let sheet = luts("coated-sheet.toml");
    let points = 700;
    let wl: Vec<f64> = (0..points)
        .map(|_| rng.random_range(380.0..780.0))
        .collect();
    let cos: Vec<f64> = (0..points).map(|_| rng.random_range(0.0..=1.0)).collect();
    let front: Vec<f64> = (0..points).map(|_| rng.random_range(0.0..500.0)).collect();
    let varying = Some(LayerThickness {
        layer: 0,
        thickness_nm: &front,
    });
    let mut out = vec![Response::default(); points];
    sheet.solve_points(varying, &wl, &cos, &mut out).unwrap();
    let coherence = sheet.coherence();
    let mut n = Vec::new();
    for i in 0..points {
        let mut d = sheet.thicknesses_nm();
        d[0] = front[i];
        sheet.indices_at(wl[i], &mut n).unwrap();
        let want = solve_incoherent(&n, &d, &coherence, wl[i], cos[i]).unwrap();
        assert!(
            same_bits(&out[i], &want),
            "point {i}: {:?} against {want:?}",
            out[i]
        );
    }
    // 1 mm of a gain medium in air: its round trip exceeds 1.
    let lasing = from_toml(
        "ambient = { n = 1.0 }\nsubstrate = { n = 1.0 }\n\
         [[layers]]\nn = [1.5, -0.01]\nthickness_nm = 1e6\ncoherent = false\n",
    );
    let mut one = vec![Response::default(); 1];
    let err = lasing
        .solve_points(None, &[550.0], &[1.0], &mut one)
        .unwrap_err()
        .to_string();
    assert!(err.contains("layers[1]"), "{err}");
}
