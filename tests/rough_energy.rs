//! Multiple scattering in irid's renderer: white furnaces of rough spheres
//! (docs/rough.md, "Multiple scattering").

// Not an API: a test crate has no public API to document.
#![allow(missing_docs)]

mod common;

use std::path::Path;

use common::furnace::{single_scattering, Furnace};
use irid::color::{Sampling, SpectralIntegrator};
use irid::render::{self, FilmMode, RenderOptions, Scene};
use irid::rough::{rough_reflectance, Quadrature};

const FILM_ON_GLASS: &str =
    "substrate = { n = 1.5 }, layers = [{ n = 1.33, thickness_nm = 500.0 }]";

/// 24 × 24 pixels, 8 samples, 8 bounces: about a second per sphere.
const FURNACE: Furnace = Furnace {
    size: 24,
    spp: 8,
    depth: 8,
};

fn furnace(scene: &Scene) -> [f64; 3] {
    let cache = Path::new(env!("CARGO_TARGET_TMPDIR")).join("rough-energy-cache");
    FURNACE.mean(scene, &cache)
}

/// A lossless coated rough glass sphere keeps the light within 2 % at
/// roughness 0.2–0.8, and the single-scattering lobe visibly does not at
/// 0.4 and above (so the furnace can fail).
#[test]
fn coated_glass_sphere_passes_the_furnace() {
    for roughness in [0.2f32, 0.4, 0.6, 0.8] {
        let scene = FURNACE.sphere(Some(FILM_ON_GLASS), roughness);
        let got = furnace(&scene);
        for v in got {
            assert!((v - 1.0).abs() < 0.02, "roughness {roughness}: {got:?}");
        }
        if roughness >= 0.4 {
            let single = furnace(&single_scattering(scene));
            assert!(single.iter().all(|&v| v < 0.95), "{roughness}: {single:?}");
        }
    }
}

/// A film on a metal, seen at one angle with no bounce after it, is
/// Turquin's multiple-scattering GGX: its single scattering S times
/// 1 + F_eff (1 − A_R) / A_R, with F_eff and A_R the library's (the
/// renderer uses each microfacet's own F, which on silver varies too little
/// over the lobe to tell apart, and ρ = F: what enters the metal is
/// absorbed). S is the renderer's own from the same samples (4096 of them
/// scatter it by about 1 % around the library's A_R F_eff).
#[test]
fn film_on_metal_is_turquins_multiple_scattering() {
    let cache = Path::new(env!("CARGO_TARGET_TMPDIR")).join("rough-energy-cache");
    let exact = SpectralIntegrator::new(Sampling::Exact);
    for (angle, roughness) in [(0.0f64, 0.8f64), (60.0, 0.6)] {
        let (s, c) = angle.to_radians().sin_cos();
        let text = format!(
            r#"
            [render]
            width = 1
            height = 1
            spp = 4096
            max_depth = 0
            [camera]
            position = [{x}, {y}, 0.0]
            look_at = [0.0, 0.0, 0.0]
            up = [0.0, 0.0, 1.0]
            fov_deg = 0.01
            [environment]
            kind = "sky"
            zenith = [1.0, 1.0, 1.0]
            horizon = [1.0, 1.0, 1.0]
            ground = [1.0, 1.0, 1.0]
            [materials.coated]
            kind = "film"
            stack = {{ ambient = {{ n = 1.0 }}, substrate = {{ material = "silver" }}, layers = [{{ n = 1.5, thickness_nm = 300.0 }}] }}
            roughness = {roughness}
            [[objects]]
            shape = "plane"
            material = "coated"
            point = [0.0, 0.0, 0.0]
            normal = [0.0, 1.0, 0.0]
            "#,
            x = 10.0 * s,
            y = 10.0 * c,
        );
        let scene = Scene::from_toml_str(&text, Path::new("."), "plane").unwrap();
        let single = rough_reflectance(
            &scene.films[0].stack,
            1,
            &exact,
            &[300.0],
            &[c],
            &[roughness],
            &Quadrature::default(),
        )
        .unwrap();
        let a = single.albedo[0];
        let opts = RenderOptions::new(FilmMode::lut(&cache));
        let image = render::render(&scene, &opts).unwrap();
        let lobe = render::render(&single_scattering(scene), &opts).unwrap();
        for ch in 0..3 {
            let f = single.reflectance[0][ch];
            let s = f64::from(lobe.pixels[0][ch]);
            let want = s * (1.0 + f * (1.0 - a) / a);
            let got = f64::from(image.pixels[0][ch]);
            assert!(
                (got - want).abs() < 2e-3 && want - s > 0.02 && (s - a * f).abs() < 0.02 * a * f,
                "{angle}° r {roughness}: {got} vs {want} (single {s}, the library's {})",
                a * f
            );
        }
    }
}
