//! The white furnace of irid's renderer (docs/rough.md, "Multiple
//! scattering"): a sphere under a uniform white sky, the mean radiance over
//! the pixels it covers. Shared by `tests/rough_energy.rs` and
//! `examples/rough_furnace.rs` (which includes this file by path).

use std::path::Path;

use irid::render::compensation::Compensation;
use irid::render::material::Material;
use irid::render::{self, FilmMode, Image, RenderOptions, Scene};

/// Pixels per side, samples per pixel and the path depth of a furnace.
#[derive(Clone, Copy, Debug)]
pub struct Furnace {
    pub size: u32,
    pub spp: u32,
    pub depth: u32,
}

impl Furnace {
    /// A sphere whose material's stack is `{ ambient = { n = 1.0 }, STACK }`
    /// with `roughness`, or, with `None`, a black diffuse one (its pixels
    /// are then the share of their samples that miss it).
    pub fn sphere(&self, stack: Option<&str>, roughness: f32) -> Scene {
        let body = match stack {
            Some(m) => format!(
                "kind = \"film\"\nstack = {{ ambient = {{ n = 1.0 }}, {m} }}\nroughness = {roughness}"
            ),
            None => "kind = \"diffuse\"\nalbedo = [0.0, 0.0, 0.0]".to_string(),
        };
        let Furnace { size, spp, depth } = *self;
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

    /// The mean radiance per channel over the pixels the sphere of `scene`
    /// covers, rendered with tables cached in `cache` (the same seed draws
    /// the same pixel samples for the black sphere, which measures
    /// coverage).
    pub fn mean(&self, scene: &Scene, cache: &Path) -> [f64; 3] {
        let opts = RenderOptions::new(FilmMode::lut(cache));
        let mask: Image = render::render(&self.sphere(None, 0.0), &opts).unwrap();
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
}

/// `scene` with the compensation taken off its films: single scattering.
pub fn single_scattering(mut scene: Scene) -> Scene {
    for m in &mut scene.materials {
        if let Material::Film(f) = m {
            f.compensation = Compensation::default();
        }
    }
    scene
}
