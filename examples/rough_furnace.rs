//! The white furnace of irid's renderer on rough spheres (docs/rough.md,
//! "Multiple scattering"): a sphere under a uniform white sky, the mean
//! radiance over the pixels it covers. A lossless surface returns 1; what
//! is missing is what the single-scattering lobe loses.
//!
//! Each sphere is rendered twice: single scattering (the compensation
//! taken off its material) and with the renderer's multiple-scattering
//! compensation.
//!
//! `cargo run --release --example rough_furnace [-- SPP SIZE DEPTH]`

use std::path::Path;

use irid::render::compensation::Compensation;
use irid::render::material::Material;
use irid::render::{self, FilmMode, RenderOptions, Scene};

/// The materials measured: a soap-like film on glass, bare glass (a layer
/// matched to its substrate), and a lossless film on silver.
const MATERIALS: [(&str, &str); 3] = [
    (
        "film on glass",
        "substrate = { n = 1.5 }, layers = [{ n = 1.33, thickness_nm = 500.0 }]",
    ),
    (
        "bare glass",
        "substrate = { n = 1.5 }, layers = [{ n = 1.5, thickness_nm = 100.0 }]",
    ),
    (
        "film on silver",
        "substrate = { material = \"silver\" }, layers = [{ n = 1.5, thickness_nm = 300.0 }]",
    ),
];

fn scene(material: &str, roughness: f32, sphere: bool, size: u32, spp: u32, depth: u32) -> Scene {
    let body = if sphere {
        format!(
            "kind = \"film\"\nstack = {{ ambient = {{ n = 1.0 }}, {material} }}\nroughness = {roughness}"
        )
    } else {
        // Black and diffuse: a pixel is the share of its samples that miss.
        "kind = \"diffuse\"\nalbedo = [0.0, 0.0, 0.0]".to_string()
    };
    let text = format!(
        r#"
        [render]
        width = {size}
        height = {size}
        spp = {spp}
        max_depth = {depth}
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

fn main() {
    let args: Vec<u32> = std::env::args()
        .skip(1)
        .map(|a| a.parse().expect("SPP SIZE DEPTH: whole numbers"))
        .collect();
    let (spp, size, depth) = (
        *args.first().unwrap_or(&16),
        *args.get(1).unwrap_or(&48),
        *args.get(2).unwrap_or(&8),
    );
    let cache = Path::new("target/tmp/rough-furnace-cache");
    let opts = RenderOptions::new(FilmMode::lut(cache));
    let mask = render::render(&scene("", 0.0, false, size, spp, depth), &opts).unwrap();
    let covered: f64 = mask.pixels.iter().map(|p| 1.0 - f64::from(p[1])).sum();
    println!(
        "white furnace, {size}×{size} pixels, {spp} spp, depth {depth}: mean R G B over the sphere"
    );
    for (name, material) in MATERIALS {
        for roughness in [0.0f32, 0.2, 0.4, 0.6, 0.8, 1.0] {
            for compensated in [false, true] {
                let mut scene = scene(material, roughness, true, size, spp, depth);
                if !compensated {
                    for m in &mut scene.materials {
                        if let Material::Film(f) = m {
                            f.compensation = Compensation::default();
                        }
                    }
                }
                let image = render::render(&scene, &opts).unwrap();
                let mean: Vec<f64> = (0..3)
                    .map(|c| {
                        let sum: f64 = image
                            .pixels
                            .iter()
                            .zip(&mask.pixels)
                            .map(|(p, m)| f64::from(p[c]) - f64::from(m[c]))
                            .sum();
                        sum / covered
                    })
                    .collect();
                let which = if compensated { "compensated" } else { "single" };
                println!(
                    "{name:15} roughness {roughness:.1} {which:11}: {:.4} {:.4} {:.4}",
                    mean[0], mean[1], mean[2]
                );
            }
        }
    }
}
