//! The rough-film definition against direct integrals, its quadrature's
//! convergence on real films, and its edge cases.

use std::f64::consts::PI;

use super::kernel::MIN_COS_VIEW;
use super::*;
use crate::color::{stack_colors, Sampling, SpectralIntegrator};
use crate::optics::{Layer, Material, Stack};

/// ∫ D G2 f(v·h) / (4 cos θ_v) dl and ∫ D G2 / (4 cos θ_v) dl by a midpoint
/// rule over the light's (cos θ_l, φ_l) on an n × n grid: the definition
/// written out directly, in the light's own coordinates.
fn over_light_directions(f: &dyn Fn(f64) -> f64, cv: f64, alpha: f64, n: usize) -> (f64, f64) {
    let a2 = alpha * alpha;
    let sv = (1.0 - cv * cv).sqrt();
    let lambda_v = ggx::lambda_cos(cv, a2);
    let (mut num, mut den) = (0.0, 0.0);
    for i in 0..n {
        let cl = (i as f64 + 0.5) / n as f64;
        let sl = (1.0 - cl * cl).sqrt();
        for j in 0..n {
            // φ over [0, π]: the lobe is symmetric about the plane of v.
            let phi = PI * (j as f64 + 0.5) / n as f64;
            let h = [sl * phi.cos() + sv, sl * phi.sin(), cl + cv];
            let len = (h[0] * h[0] + h[1] * h[1] + h[2] * h[2]).sqrt();
            let (hz, vh) = (h[2] / len, (h[0] * sv + h[2] * cv) / len);
            let sin2 = (h[0] * h[0] + h[1] * h[1]) / (len * len);
            let w = ggx::ndf(hz, sin2, a2) * ggx::g2(cv, lambda_v, cl, a2) / (4.0 * cv);
            num += w * f(vh);
            den += w;
        }
    }
    let cell = 2.0 * PI / (n * n) as f64;
    (num * cell, den * cell)
}

/// A kernel's F_eff of a function sampled at its grid's nodes.
fn applied(kernel: &Kernel, grid: &MuGrid, f: &dyn Fn(f64) -> f64) -> f64 {
    let values: Vec<[f64; 3]> = grid.nodes().iter().map(|&m| [f(m); 3]).collect();
    kernel.apply(&values)[0]
}

#[test]
fn kernels_agree_with_the_definition_integrated_over_light_directions() {
    let grid = MuGrid::new(128, None);
    let q = Quadrature::default();
    let f = |mu: f64| 0.4 + 0.3 * (9.0 * mu).sin() + 0.2 * mu * mu;
    let mut worst = (0.0f64, 0.0f64);
    for &cv in &[1.0, 0.8, 0.5, 0.2] {
        for &roughness in &[0.5, 0.7, 0.85, 1.0] {
            let alpha = ggx::alpha(roughness);
            let (num, den) = over_light_directions(&f, cv, alpha, 1500);
            let k = Kernel::new(&grid, cv, roughness, &q);
            let (de, df) = (
                (k.albedo() - den).abs(),
                (applied(&k, &grid, &f) - num / den).abs(),
            );
            assert!(
                de < 2e-5 && df < 2e-5,
                "cos {cv} r {roughness}: albedo {} vs {den}, F {df:e}",
                k.albedo()
            );
            worst = (worst.0.max(de), worst.1.max(df));
        }
    }
    println!(
        "against the light-direction integral: albedo {:.1e}, F_eff {:.1e}",
        worst.0, worst.1
    );
}

/// Known values of the white lobe: a mirror reflects everything, and at
/// normal view the albedo has the closed form of a cone of h about n.
#[test]
fn albedo_limits() {
    let grid = MuGrid::new(128, None);
    let q = Quadrature::default();
    for &cv in &[1.0, 0.7, 0.3, 0.05] {
        let k = Kernel::new(&grid, cv, 1e-3, &q);
        assert!((k.albedo() - 1.0).abs() < 1e-5, "{cv}: {}", k.albedo());
        assert_eq!(Kernel::new(&grid, cv, 0.0, &q).albedo(), 1.0);
    }
    // F ≡ 1 gives 1 whatever the lobe: the weights are normalized.
    for &r in &[0.05, 0.5, 1.0] {
        let k = Kernel::new(&grid, 0.4, r, &q);
        assert!((applied(&k, &grid, &|_| 1.0) - 1.0).abs() < 1e-14);
    }
}

fn constant(n: f64, k: f64) -> Material {
    Material::constant(n, k)
}

fn film(ambient: Material, layers: &[(Material, f64)], substrate: Material) -> Stack {
    Stack {
        ambient,
        layers: layers
            .iter()
            .map(|(m, d)| Layer::new(m.clone(), *d))
            .collect(),
        substrate,
    }
}

/// The films the convergence is measured on: a soap film, an absorbing film
/// on silver, a film on glass seen from the glass (the square-root kink at
/// the critical angle, inside the lobe), and a three-layer stack on gold.
pub(super) fn test_films() -> Vec<(&'static str, Stack, (f64, f64))> {
    let lib = |name: &str| crate::optics::library::builtin(name).unwrap();
    vec![
        (
            "soap",
            film(
                constant(1.0, 0.0),
                &[(constant(1.33, 0.0), 500.0)],
                constant(1.0, 0.0),
            ),
            (0.0, 1000.0),
        ),
        (
            "absorbing on silver",
            film(
                constant(1.0, 0.0),
                &[(constant(1.5, 0.15), 300.0)],
                lib("silver"),
            ),
            (100.0, 500.0),
        ),
        (
            "film on glass from the glass",
            film(
                constant(1.5, 0.0),
                &[(constant(1.38, 0.0), 300.0)],
                constant(1.0, 0.0),
            ),
            (0.0, 800.0),
        ),
        (
            "three layers on gold",
            film(
                constant(1.0, 0.0),
                &[
                    (constant(2.3, 0.0), 90.0),
                    (constant(1.38, 0.01), 120.0),
                    (constant(1.6, 0.0), 60.0),
                ],
                lib("gold"),
            ),
            (0.0, 400.0),
        ),
    ]
}

/// The view cosines (0–89°) and roughness (0.02–1) the doubled-quadrature
/// checks run over, and a film's 9 thickness nodes over `(t0, t1)`.
pub(super) fn convergence_nodes((t0, t1): (f64, f64)) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
    let cos = [0.0, 10.0, 30.0, 45.0, 60.0, 70.0, 80.0, 89.0]
        .iter()
        .map(|a: &f64| a.to_radians().cos())
        .collect();
    let roughness = vec![0.02, 0.1, 0.2, 0.35, 0.5, 0.7, 1.0];
    let thickness = (0..9).map(|i| t0 + (t1 - t0) * i as f64 / 8.0).collect();
    (thickness, cos, roughness)
}

/// The largest difference between two equally long lists of values (a
/// table's RGB flattened, or its albedos).
pub(super) fn largest_gap(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max)
}

/// The default quadrature against one with every count doubled, on real
/// films over their thickness range, view angles 0–89° and roughness
/// 0.02–1: the largest difference in any channel. This is the error
/// docs/rough.md states for F_eff.
#[test]
fn default_quadrature_converges_on_real_films() {
    let integrator = SpectralIntegrator::new(Sampling::Exact);
    let q = Quadrature::default();
    let mut overall = 0.0f64;
    for (name, stack, range) in test_films() {
        let (thickness, cos, roughness) = convergence_nodes(range);
        let run = |q: &Quadrature| {
            rough_reflectance(&stack, 1, &integrator, &thickness, &cos, &roughness, q).unwrap()
        };
        let (coarse, fine) = (run(&q), run(&q.finer()));
        let worst = largest_gap(
            coarse.reflectance.as_flattened(),
            fine.reflectance.as_flattened(),
        );
        let albedo = largest_gap(&coarse.albedo, &fine.albedo);
        println!("{name}: F_eff {worst:.1e}, albedo {albedo:.1e}");
        assert!(
            worst < 1e-5 && albedo < 1e-5,
            "{name}: {worst:e} {albedo:e}"
        );
        overall = overall.max(worst);
    }
    println!("default against doubled quadrature, worst channel: {overall:.1e}");
}

#[test]
fn roughness_zero_is_the_smooth_colour_and_small_roughness_near_it() {
    let integrator = SpectralIntegrator::new(Sampling::Exact);
    for (name, stack, _) in test_films() {
        let angles = [0.0, 25.0, 50.0, 75.0, 89.0];
        let smooth = stack_colors(&stack, &integrator, &angles).unwrap();
        let zero = rough_colors(&stack, &integrator, &angles, 0.0).unwrap();
        let small = rough_colors(&stack, &integrator, &angles, 0.01).unwrap();
        for ((s, z), r) in smooth.iter().zip(&zero).zip(&small) {
            assert_eq!(s.reflectance_rgb, z.reflectance_rgb, "{name}");
            assert_eq!(s.reflectance_xyz, z.reflectance_xyz, "{name}");
            for c in 0..3 {
                let d = (s.reflectance_rgb[c] - r.reflectance_rgb[c]).abs();
                assert!(d < 1e-4, "{name} {}°: {d:e}", s.angle_deg);
            }
            assert!((r.lobe_albedo - 1.0).abs() < 1e-4);
        }
    }
}

#[test]
fn grazing_view_is_continuous() {
    let integrator = SpectralIntegrator::new(Sampling::Exact);
    let (_, stack, _) = test_films().remove(0);
    let at = |c: f64| {
        rough_reflectance(
            &stack,
            1,
            &integrator,
            &[400.0],
            &[c],
            &[0.5],
            &Quadrature::default(),
        )
        .unwrap()
        .reflectance[0]
    };
    let (zero, near) = (at(0.0), at(1e-4));
    assert_eq!(zero, at(MIN_COS_VIEW));
    for c in 0..3 {
        assert!(
            zero[c].is_finite() && (zero[c] - near[c]).abs() < 1e-3,
            "{zero:?} {near:?}"
        );
    }
}

#[test]
fn bad_nodes_are_refused() {
    let integrator = SpectralIntegrator::new(Sampling::Exact);
    let (_, stack, _) = test_films().remove(0);
    let q = Quadrature::default();
    let run = |t: &[f64], c: &[f64], r: &[f64]| {
        rough_reflectance(&stack, 1, &integrator, t, c, r, &q)
            .unwrap_err()
            .to_string()
    };
    for r in [f64::NAN, -0.1, 1.5, f64::INFINITY] {
        assert!(run(&[1.0], &[0.5], &[r]).starts_with("roughness: "), "{r}");
        assert!(rough_colors(&stack, &integrator, &[0.0], r).is_err());
    }
    assert!(run(&[1.0], &[1.2], &[0.5]).starts_with("angles: "));
    assert!(run(&[1.0], &[f64::NAN], &[0.5]).starts_with("angles: "));
    assert!(run(&[2.0, 1.0], &[0.5], &[0.5]).starts_with("thickness: "));
    assert!(run(&[-1.0], &[0.5], &[0.5]).starts_with("thickness: "));
    assert!(run(&[], &[0.5], &[0.5]).starts_with("thickness: "));
    assert!(rough_colors(&stack, &integrator, &[90.0], 0.5).is_err());
}

#[test]
fn stacks_with_incoherent_layers_sweep_a_coherent_one() {
    // A film behind a 1 mm incoherent sheet, and the sheet alone: the
    // colour sweeps the first coherent layer, or a zero-thickness layer of
    // the ambient's medium on top, and agrees with the same stack given
    // that layer explicitly (another split of the same stack) and, at small
    // roughness, with the smooth colour.
    let integrator = SpectralIntegrator::new(Sampling::Exact);
    let sheet = Layer {
        coherent: false,
        ..Layer::new(constant(1.52, 0.0), 1e6)
    };
    let mut behind = film(
        constant(1.0, 0.0),
        &[(constant(1.52, 0.0), 1e6), (constant(2.3, 0.0), 120.0)],
        constant(1.0, 0.0),
    );
    behind.layers[0] = sheet.clone();
    let mut alone = behind.clone();
    alone.layers.truncate(1);
    let angles = [0.0, 40.0, 70.0];
    for stack in [behind, alone] {
        let mut explicit = stack.clone();
        explicit
            .layers
            .insert(0, Layer::new(constant(1.0, 0.0), 0.0));
        let smooth = stack_colors(&stack, &integrator, &angles).unwrap();
        for roughness in [0.01, 0.3] {
            let got = rough_colors(&stack, &integrator, &angles, roughness).unwrap();
            let want = rough_colors(&explicit, &integrator, &angles, roughness).unwrap();
            for ((g, w), s) in got.iter().zip(&want).zip(&smooth) {
                for c in 0..3 {
                    let d = (g.reflectance_rgb[c] - w.reflectance_rgb[c]).abs();
                    assert!(d < 1e-12, "{roughness} {}°: {d:e}", g.angle_deg);
                    if roughness == 0.01 {
                        let d = (g.reflectance_rgb[c] - s.reflectance_rgb[c]).abs();
                        assert!(d < 1e-4, "{}°: {d:e}", g.angle_deg);
                    }
                }
            }
        }
    }
}

/// The colour fits' reflection-only path skips the transmission kernel and
/// gives `rough_colors`' F_eff bit for bit: on the test films (lossless,
/// absorbing, metal substrates, seen from the dense side), behind an
/// incoherent sheet, at roughness 0, small and large, and it refuses what
/// `rough_colors` refuses.
#[test]
fn reflection_only_colours_are_rough_colours_reflectance() {
    let integrator = SpectralIntegrator::new(Sampling::Exact);
    let mut stacks: Vec<Stack> = test_films().into_iter().map(|(_, s, _)| s).collect();
    let mut sheet = stacks[0].clone();
    sheet.layers[0].coherent = false;
    sheet.layers[0].thickness_nm = 1e6;
    stacks.push(sheet);
    let angles = [0.0, 25.0, 50.0, 75.0, 89.0];
    for stack in &stacks {
        for roughness in [0.0, 0.05, 0.4, 1.0] {
            let full = rough_colors(stack, &integrator, &angles, roughness).unwrap();
            let only = rough_reflectance_colors(stack, &integrator, &angles, roughness).unwrap();
            let want: Vec<[f64; 3]> = full.iter().map(|c| c.reflectance_rgb).collect();
            assert_eq!(only, want, "roughness {roughness}");
        }
    }
    let stack = &stacks[0];
    assert!(rough_reflectance_colors(stack, &integrator, &[], 0.5)
        .unwrap()
        .is_empty());
    for (angle, r) in [(90.0, 0.5), (-1.0, 0.5), (10.0, 1.5), (10.0, f64::NAN)] {
        assert!(rough_colors(stack, &integrator, &[angle], r).is_err());
        assert!(rough_reflectance_colors(stack, &integrator, &[angle], r).is_err());
    }
}
