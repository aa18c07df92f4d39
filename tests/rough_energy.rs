//! Multiple scattering in irid's renderer: white furnaces of rough spheres
//! (docs/rough.md, "Multiple scattering").

// Not an API: a test crate has no public API to document.
#![allow(missing_docs)]

use std::path::Path;

use irid::color::{Sampling, SpectralIntegrator};
use irid::render::compensation::Compensation;
use irid::render::material::Material;
use irid::render::{self, FilmMode, RenderOptions, Scene};
use irid::rough::{rough_reflectance, Quadrature};

const FILM_ON_GLASS: &str =
    "substrate = { n = 1.5 }, layers = [{ n = 1.33, thickness_nm = 500.0 }]";

/// A sphere of `material` (or, with `None`, a black one: its pixels are
/// then the share of their samples that miss it) under a uniform white sky.
fn sphere(material: Option<&str>, roughness: f32) -> Scene {
    let body = match material {
        Some(m) => format!(
            "kind = \"film\"\nstack = {{ ambient = {{ n = 1.0 }}, {m} }}\nroughness = {roughness}"
        ),
        None => "kind = \"diffuse\"\nalbedo = [0.0, 0.0, 0.0]".to_string(),
    };
    let text = format!(
        r#"
        [render]
        width = 24
        height = 24
        spp = 8
        max_depth = 8
        [camera]
        position = [0.0, 0.0, 5.0]
        look_at = [0.0, 0.0, 0.0]
        fov_deg = 24.0
        [environment]
        kind = "sky"
        zenith = [1.0, 1.0, 1.0]
        horizon = [1.0, 1.0, 1.0]
        ground = [1.0, 1.0, 1.0]
        [materials.m]
        {body}
        [[objects]]
        shape = "sphere"
        material = "m"
        center = [0.0, 0.0, 0.0]
        radius = 1.0
        "#
    );
    Scene::from_toml_str(&text, Path::new("."), "furnace").unwrap()
}

/// The mean radiance over the pixels the sphere covers (the same seed draws
/// the same pixel samples for the black sphere, which measures coverage).
fn furnace(scene: &Scene) -> [f64; 3] {
    let cache = Path::new(env!("CARGO_TARGET_TMPDIR")).join("rough-energy-cache");
    let opts = RenderOptions::new(FilmMode::lut(&cache));
    let mask = render::render(&sphere(None, 0.0), &opts).unwrap();
    let image = render::render(scene, &opts).unwrap();
    let covered: f64 = mask.pixels.iter().map(|p| 1.0 - f64::from(p[1])).sum();
    std::array::from_fn(|c| {
        let sum: f64 = image
            .pixels
            .iter()
            .zip(&mask.pixels)
            .map(|(p, m)| f64::from(p[c]) - f64::from(m[c]))
            .sum();
        sum / covered
    })
}

fn single_scattering(mut scene: Scene) -> Scene {
    for m in &mut scene.materials {
        if let Material::Film(f) = m {
            f.compensation = Compensation::default();
        }
    }
    scene
}

/// A lossless coated rough glass sphere keeps the light within 2 % at
/// roughness 0.2–0.8, and the single-scattering lobe visibly does not at
/// 0.4 and above (so the furnace can fail).
#[test]
fn coated_glass_sphere_passes_the_furnace() {
    for roughness in [0.2f32, 0.4, 0.6, 0.8] {
        let scene = sphere(Some(FILM_ON_GLASS), roughness);
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
/// Turquin's multiple-scattering GGX: A_R F_eff (1 + F_eff (1 − A_R) / A_R),
/// with F_eff and A_R the library's (the renderer uses each microfacet's own
/// F, which on silver varies too little over the lobe to tell apart).
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
        let image = render::render(&scene, &RenderOptions::new(FilmMode::lut(&cache))).unwrap();
        for ch in 0..3 {
            let f = single.reflectance[0][ch];
            let want = a * f * (1.0 + f * (1.0 - a) / a);
            let got = f64::from(image.pixels[0][ch]);
            assert!(
                (got - want).abs() < 5e-3 && want - a * f > 0.02,
                "{angle}° r {roughness}: {got} vs {want} (single {})",
                a * f
            );
        }
    }
}
