//! The scene file (TOML) and the built-in scenes, one per figure of the
//! paper. The format is documented in `docs/scene-format.md` and by the
//! built-in scenes under `luts/scenes/`.

//!
//! [`sections`] is the file as parsed; [`build`] turns each section into
//! the scene's part, one function per section (and per material and shape
//! kind), checking every field.

mod build;
mod sections;

use std::path::Path;

use super::scene::Scene;
use crate::error::{Error, Result};
use build::build;
use sections::SceneFile;

/// Built-in scenes: (name, TOML text).
const BUILTIN: [(&str, &str); 7] = [
    (
        "bubbles-uniform",
        include_str!("../../../luts/scenes/bubbles-uniform.toml"),
    ),
    (
        "bubbles-noise",
        include_str!("../../../luts/scenes/bubbles-noise.toml"),
    ),
    (
        "absorbing-sphere",
        include_str!("../../../luts/scenes/absorbing-sphere.toml"),
    ),
    (
        "absorbing-sphere-rough",
        include_str!("../../../luts/scenes/absorbing-sphere-rough.toml"),
    ),
    (
        "gain-ring",
        include_str!("../../../luts/scenes/gain-ring.toml"),
    ),
    (
        "blue-gem",
        include_str!("../../../luts/scenes/blue-gem.toml"),
    ),
    (
        "two-layer-noise",
        include_str!("../../../luts/scenes/two-layer-noise.toml"),
    ),
];

/// Angle nodes of a bare metal's reflectance table: Fresnel of a metal is
/// smooth in cos θ, so linear interpolation over 257 nodes is exact to
/// well below an 8-bit step.
const METAL_TABLE_NODES: usize = 257;

/// The names of the scenes compiled into the binary, for
/// [`Scene::builtin`] and [`Scene::load_named`] (which prefer them over a
/// file path of the same name).
pub fn builtin_names() -> Vec<&'static str> {
    BUILTIN.iter().map(|(n, _)| *n).collect()
}

impl Scene {
    /// A built-in scene by name.
    pub fn builtin(name: &str) -> Option<Result<Scene>> {
        let (n, text) = BUILTIN.iter().find(|(n, _)| *n == name)?;
        Some(Scene::from_toml_str(
            text,
            Path::new("."),
            &format!("built-in scene {n}"),
        ))
    }

    /// Loads a scene file; relative paths inside it are relative to the file.
    pub fn load(path: &Path) -> Result<Scene> {
        let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
        let base = path.parent().unwrap_or(Path::new("."));
        Scene::from_toml_str(&text, base, &path.display().to_string())
    }

    /// A built-in name, or else a path to a scene file.
    pub fn load_named(spec: &str) -> Result<Scene> {
        match Scene::builtin(spec) {
            Some(scene) => scene,
            None if Path::new(spec).exists() => Scene::load(Path::new(spec)),
            None => Err(Error::invalid(
                format!("scene '{spec}'"),
                format!(
                    "neither a file nor a built-in scene ({})",
                    builtin_names().join(", ")
                ),
            )),
        }
    }

    /// Parses scene text; `origin` names it in error messages.
    pub fn from_toml_str(text: &str, base_dir: &Path, origin: &str) -> Result<Scene> {
        let file: SceneFile =
            toml::from_str(text).map_err(|e| crate::error::toml_error(origin, &e, text))?;
        build(file, base_dir, origin)
    }
}

/// The deepest reflection/refraction recursion: the tracer recurses on the
/// call stack, and far deeper paths carry no visible light anyway.
pub const MAX_DEPTH: u32 = 64;

/// The widest or tallest image, in pixels: scene files and `irid render
/// --width/--height` alike.
pub const MAX_IMAGE_SIDE: u32 = 16384;

/// The most samples per pixel, in scene files and on the command line alike.
/// Noise falls as 1/√spp: at 4096 it is 1/64 of one sample's, and more only
/// multiplies the render time.
pub const MAX_SPP: u32 = 4096;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::environment::Environment;

    #[test]
    fn builtin_scenes_load_with_the_films_they_need() {
        for name in builtin_names() {
            let scene = Scene::builtin(name).unwrap().unwrap();
            assert!(!scene.films.is_empty(), "{name} has no film");
            for f in &scene.films {
                let (lo, hi) = f.thickness_range_nm;
                assert!(lo <= hi && hi <= 1500.0, "{name}: {lo}..{hi}");
            }
        }
        let gem = Scene::builtin("blue-gem").unwrap().unwrap();
        assert!(
            gem.films[0].back_side,
            "light inside the gem meets the reversed stack"
        );
        let ring = Scene::builtin("gain-ring").unwrap().unwrap();
        assert!(!ring.films[0].back_side, "nothing passes into gold");
        assert!(ring.films[0].stack.layers[0].material.has_gain());
        let two = Scene::builtin("two-layer-noise").unwrap().unwrap();
        assert_eq!((two.settings.width, two.settings.height), (500, 500));
        assert_eq!(
            (two.films[0].stack.layers.len(), two.films[0].layer),
            (2, 1)
        );
        assert!(Scene::builtin("no-such-scene").is_none());
    }

    const MINIMAL: &str = r#"
        [camera]
        position = [0.0, 0.0, 5.0]
        look_at = [0.0, 0.0, 0.0]
        fov_deg = 40.0
        [materials.m]
        kind = "dielectric"
        ior = 1.5
        [[objects]]
        shape = "sphere"
        material = "m"
        center = [0.0, 0.0, 0.0]
        radius = 1.0
    "#;

    fn parse(text: &str) -> Result<Scene> {
        Scene::from_toml_str(text, Path::new("."), "test.toml")
    }

    #[test]
    fn defaults_and_typos() {
        let s = parse(MINIMAL).unwrap();
        assert_eq!(
            (s.settings.width, s.settings.height, s.settings.spp),
            (640, 480, 1)
        );
        assert!(matches!(s.environment, Environment::Sky(_)));
        // A misspelt field is an error naming the line, not silently ignored.
        let e = parse(&MINIMAL.replace("radius = 1.0", "radius = 1.0\nradus = 2.0"))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("test.toml") && e.contains("radus") && e.contains("line"),
            "{e}"
        );
        let e = parse(&MINIMAL.replace("fov_deg = 40.0", "fov_deg = 200.0"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("camera.fov_deg"), "{e}");
        let e = parse(&MINIMAL.replace("look_at = [0.0, 0.0, 0.0]", "look_at = [0.0, 0.0, 5.0]"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("camera"), "{e}");
    }

    #[test]
    fn film_fields_are_checked() {
        let film = MINIMAL.replace(
            "kind = \"dielectric\"\n        ior = 1.5",
            "kind = \"film\"\n        stack = { ambient = { n = 1.0 }, substrate = { n = 1.5 }, layers = [{ n = 2.0, thickness_nm = 100.0 }] }",
        );
        let s = parse(&film).unwrap();
        assert_eq!(s.films[0].thickness_range_nm, (100.0, 100.0));
        let bad_layer = film.replace("stack =", "layer = 2\n        stack =");
        let e = parse(&bad_layer).unwrap_err().to_string();
        assert!(e.contains("materials.m.layer"), "{e}");
        let both = film.replace("stack =", "thickness_nm = 50.0\n        thickness = { min_nm = 1.0, max_nm = 2.0, scale = 1.0 }\n        stack =");
        assert!(parse(&both).unwrap_err().to_string().contains("not both"));
        let reversed = film.replace(
            "stack =",
            "thickness = { min_nm = 300.0, max_nm = 200.0, scale = 1.0 }\n        stack =",
        );
        assert!(parse(&reversed)
            .unwrap_err()
            .to_string()
            .contains("max_nm < min_nm"));
        let unknown = film.replace("n = 2.0,", "material = \"unobtainium\",");
        let e = parse(&unknown).unwrap_err().to_string();
        assert!(
            e.contains("materials.m.stack") && e.contains("unobtainium"),
            "{e}"
        );
    }

    /// A syntax error is placed where it is: a value error on line 3 and
    /// one at the very start of line 3 (which counting `lines()` of the
    /// text before it put on line 2).
    #[test]
    fn toml_errors_name_their_line_and_column() {
        let err = |text: &str| {
            Scene::from_toml_str(text, Path::new("."), "s.toml")
                .unwrap_err()
                .to_string()
        };
        let e = err("name = \"x\"\n[render]\nwidth = \"a\"\n");
        assert!(e.contains("line 3, column 9"), "{e}");
        let e = err("[camera]\nposition = [0.0, 1.0\n");
        assert!(e.contains("line 3, column 1"), "{e}");
    }
}
