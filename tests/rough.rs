//! Rough films: the tracer's GGX lobe against the definition it samples,
//! scene files' roughness, and `irid color --roughness`.

// Not an API: a test crate has no public API to document.
#![allow(missing_docs)]

mod common;

use std::path::Path;

use irid::color::{Sampling, SpectralIntegrator};
use irid::render::{self, FilmMode, RenderOptions, Scene};
use irid::rough::{rough_reflectance, Quadrature};

/// A film on silver under a uniform white sky, seen by a one-pixel camera
/// whose rays all meet it at `angle_deg`.
fn furnace(angle_deg: f32, roughness: f32, spp: u32) -> Scene {
    let (s, c) = angle_deg.to_radians().sin_cos();
    let text = format!(
        r#"
        [render]
        width = 1
        height = 1
        spp = {spp}
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
        stack = {{ ambient = {{ n = 1.0 }}, substrate = {{ material = "silver" }}, layers = [{{ n = [1.5, 0.15], thickness_nm = 300.0 }}] }}
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
    Scene::from_toml_str(&text, Path::new("."), "furnace").unwrap()
}

/// In a white furnace with no bounce after the film, a pixel is the white
/// lobe's albedo times F_eff: the tracer's visible-normal sampling, its
/// G2 / G1 weights and the film per microfacet (from the tables, and from
/// the solver at every hit) reproduce the definition the library
/// integrates by quadrature, to the Monte Carlo noise of 4096 samples.
#[test]
fn the_tracer_samples_the_definition() {
    let cache = Path::new(env!("CARGO_TARGET_TMPDIR")).join("rough-test-cache");
    let exact = SpectralIntegrator::new(Sampling::Exact);
    for (angle, roughness) in [(0.0f32, 0.5f32), (40.0, 0.3), (65.0, 0.6)] {
        let mut scene = furnace(angle, roughness, 4096);
        // The single-scattering lobe: the multiple-scattering compensation
        // off (tests/rough_energy.rs tests it).
        for m in &mut scene.materials {
            if let irid::render::material::Material::Film(f) = m {
                f.compensation = Default::default();
            }
        }
        let want = rough_reflectance(
            &scene.films[0].stack,
            1,
            &exact,
            &[300.0],
            &[f64::from(angle).to_radians().cos()],
            &[f64::from(roughness)],
            &Quadrature::default(),
        )
        .unwrap();
        let expected = want.reflectance[0].map(|v| v * want.albedo[0]);
        for mode in [
            FilmMode::lut(&cache),
            FilmMode::Direct {
                sampling: Sampling::Exact,
            },
        ] {
            let image = render::render(&scene, &RenderOptions::new(mode.clone())).unwrap();
            let got = image.pixels[0];
            for c in 0..3 {
                let d = (f64::from(got[c]) - expected[c]).abs();
                assert!(
                    d < 5e-3,
                    "{angle}° r {roughness} {mode:?}: {got:?} vs {expected:?}"
                );
            }
        }
    }
}

/// The same seed gives the same rough image and another seed another one
/// (the lobe is sampled); at roughness 0 (the mirror path) the seed is only
/// the pixel jitter's, so one sample through the pixel centre ignores it.
#[test]
fn rough_renders_are_seeded() {
    let cache = Path::new(env!("CARGO_TARGET_TMPDIR")).join("rough-test-cache");
    let scene = furnace(30.0, 0.4, 16);
    let render_with = |seed: u64| {
        let mut opts = RenderOptions::new(FilmMode::lut(&cache));
        opts.seed = seed;
        render::render(&scene, &opts).unwrap()
    };
    assert_eq!(render_with(3), render_with(3));
    assert_ne!(render_with(3), render_with(4));
    let mirror = furnace(30.0, 0.0, 1);
    let a = render::render(&mirror, &RenderOptions::new(FilmMode::lut(&cache))).unwrap();
    let mut opts = RenderOptions::new(FilmMode::lut(&cache));
    opts.seed = 4;
    assert_eq!(a, render::render(&mirror, &opts).unwrap());
}

#[test]
fn scene_roughness_is_checked() {
    for bad in ["-0.1", "1.5", "nan", "inf"] {
        let text = format!(
            r#"
            [camera]
            position = [0.0, 1.0, 5.0]
            look_at = [0.0, 0.0, 0.0]
            fov_deg = 40.0
            [materials.f]
            kind = "film"
            stack = {{ ambient = {{ n = 1.0 }}, substrate = {{ n = 1.5 }}, layers = [{{ n = 1.38, thickness_nm = 300.0 }}] }}
            roughness = {bad}
            [[objects]]
            shape = "sphere"
            material = "f"
            center = [0.0, 0.0, 0.0]
            radius = 1.0
            "#
        );
        let e = Scene::from_toml_str(&text, Path::new("."), "s.toml")
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("materials.f.roughness: must be in [0, 1]") && !e.contains('\n'),
            "{bad}: {e}"
        );
    }
}

#[cfg(feature = "cli")]
mod cli {
    use super::common::irid;

    fn json(args: &[&str]) -> Vec<serde_json::Map<String, serde_json::Value>> {
        let out = irid(args);
        assert!(out.success(), "{args:?}: {}", out.stderr);
        serde_json::from_str(&out.stdout).unwrap()
    }

    fn triple(row: &serde_json::Map<String, serde_json::Value>, key: &str) -> Vec<f64> {
        row[key]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap())
            .collect()
    }

    /// The agreed keys; roughness 0 prints the smooth reflectance to the
    /// bit; a rough lobe's colour differs from it and its albedo is below 1.
    #[test]
    fn json_keys_and_the_mirror_limit() {
        let base = [
            "color",
            "luts/soap-film.toml",
            "--angles",
            "0,40,70",
            "--json",
        ];
        let smooth = json(&base);
        let zero = json(&[&base[..], &["--roughness", "0"]].concat());
        let rough = json(&[&base[..], &["--roughness", "0.5"]].concat());
        for ((s, z), r) in smooth.iter().zip(&zero).zip(&rough) {
            let mut keys: Vec<&str> = r.keys().map(String::as_str).collect();
            keys.sort();
            assert_eq!(
                keys,
                [
                    "angle_deg",
                    "lobe_albedo",
                    "reflectance_ms_rgb",
                    "reflectance_ms_xyz",
                    "reflectance_rgb",
                    "reflectance_xyz",
                    "roughness",
                    "transmission_lobe_albedo",
                    "transmittance_ms_rgb",
                    "transmittance_ms_xyz",
                    "transmittance_rgb",
                    "transmittance_xyz"
                ]
            );
            // Roughness 0 scatters once: the compensated outputs are the
            // single-scattering ones, to the bit.
            for (ms, single) in [
                ("reflectance_ms_rgb", "reflectance_rgb"),
                ("reflectance_ms_xyz", "reflectance_xyz"),
                ("transmittance_ms_rgb", "transmittance_rgb"),
                ("transmittance_ms_xyz", "transmittance_xyz"),
            ] {
                assert_eq!(triple(z, ms), triple(z, single), "{ms}");
            }
            assert_eq!(
                triple(s, "transmittance_rgb"),
                triple(z, "transmittance_rgb")
            );
            assert_eq!(triple(s, "reflectance_rgb"), triple(z, "reflectance_rgb"));
            assert_eq!(z["lobe_albedo"].as_f64(), Some(1.0));
            let (a, b) = (triple(s, "reflectance_rgb"), triple(r, "reflectance_rgb"));
            assert!((0..3).any(|c| (a[c] - b[c]).abs() > 1e-3), "{a:?} {b:?}");
            let albedo = r["lobe_albedo"].as_f64().unwrap();
            assert!(albedo > 0.5 && albedo < 1.0, "{albedo}");
        }
        let text = irid(["color", "luts/soap-film.toml", "--roughness", "0.3"]);
        assert!(text.success() && text.stdout.contains("lobe albedo"));
        assert!(text.stdout.contains("transmittance"));
    }

    /// `--side substrate` is the reversed stack seen from its ambient,
    /// smooth and rough; a lossless film transmits what it does not
    /// reflect at roughness 0 from either side.
    #[test]
    fn the_substrate_side_is_the_reversed_stack() {
        let dir = tempfile::tempdir().unwrap();
        let (film, reversed) = (dir.path().join("f.toml"), dir.path().join("r.toml"));
        std::fs::write(
            &film,
            "ambient = { n = 1.0 }\nsubstrate = { n = 1.5 }\n[[layers]]\nn = 2.1\nthickness_nm = 150.0\n[[layers]]\nn = 1.38\nthickness_nm = 90.0\n",
        )
        .unwrap();
        std::fs::write(
            &reversed,
            "ambient = { n = 1.5 }\nsubstrate = { n = 1.0 }\n[[layers]]\nn = 1.38\nthickness_nm = 90.0\n[[layers]]\nn = 2.1\nthickness_nm = 150.0\n",
        )
        .unwrap();
        let (film, reversed) = (film.to_str().unwrap(), reversed.to_str().unwrap());
        for rough in [&[][..], &["--roughness", "0"], &["--roughness", "0.4"]] {
            let args = |stack, side| {
                let mut a = vec!["color", stack, "--angles", "0,30,60", "--json"];
                a.extend_from_slice(rough);
                a.extend_from_slice(&["--side", side]);
                a
            };
            let back = json(&args(film, "substrate"));
            let want = json(&args(reversed, "front"));
            assert_eq!(back, want, "{rough:?}");
            if rough.len() == 2 && rough[1] == "0" {
                for row in &back {
                    let (r, t) = (
                        triple(row, "reflectance_rgb"),
                        triple(row, "transmittance_rgb"),
                    );
                    for c in 0..3 {
                        assert!((r[c] + t[c] - 1.0).abs() < 1e-9, "{row:?}");
                    }
                }
                // 60° in the glass is past its critical angle: nothing through.
                assert_eq!(back[2]["transmission_lobe_albedo"].as_f64(), Some(0.0));
            }
        }
    }

    #[test]
    fn sides_a_stack_cannot_be_seen_from_are_one_line() {
        let dir = tempfile::tempdir().unwrap();
        let on_silver = dir.path().join("on-silver.toml");
        std::fs::write(
            &on_silver,
            "ambient = { n = 1.0 }\nsubstrate = { material = \"silver\" }\n[[layers]]\nn = 1.5\nthickness_nm = 300.0\n",
        )
        .unwrap();
        let on_silver = on_silver.to_str().unwrap();
        for rough in [&[][..], &["--roughness", "0.3"]] {
            let mut args = vec!["color", on_silver, "--side", "substrate"];
            args.extend_from_slice(rough);
            irid(&args)
                .assert_one_line_error("absorbing", &[on_silver, "side: the substrate", "absorbs"]);
        }
        irid(["color", "luts/soap-film.toml", "--side", "back"])
            .assert_one_line_error("back", &["--side 'back'", "front or substrate"]);
    }

    /// A_R F_ms + A_T T_ms per channel of every row of `rows`.
    fn furnace(row: &serde_json::Map<String, serde_json::Value>) -> [f64; 3] {
        let (a_r, a_t) = (
            row["lobe_albedo"].as_f64().unwrap(),
            row["transmission_lobe_albedo"].as_f64().unwrap(),
        );
        let (f, t) = (
            triple(row, "reflectance_ms_rgb"),
            triple(row, "transmittance_ms_rgb"),
        );
        std::array::from_fn(|c| a_r * f[c] + a_t * t[c])
    }

    /// A lossless coated dielectric (n = 1.33 on glass 1.5), seen from
    /// either side, returns the white furnace to 1 within 1 % per channel
    /// once compensated for multiple scattering (the fluxes being the white
    /// lobes' albedos times the compensated outputs), where single
    /// scattering loses more than 5 % somewhere.
    #[test]
    fn compensated_coated_glass_passes_the_furnace() {
        let dir = tempfile::tempdir().unwrap();
        let coated = dir.path().join("coated.toml");
        std::fs::write(
            &coated,
            "ambient = { n = 1.0 }\nsubstrate = { n = 1.5 }\n[[layers]]\nn = 1.33\nthickness_nm = 300.0\n",
        )
        .unwrap();
        let coated = coated.to_str().unwrap();
        let mut worst_single = 1.0f64;
        for side in ["front", "substrate"] {
            for r in ["0.2", "0.4", "0.6", "0.8", "1"] {
                let rows = json(&[
                    "color",
                    coated,
                    "--side",
                    side,
                    "--roughness",
                    r,
                    "--angles",
                    "0,10,20,30,40,50,60,70,80",
                    "--json",
                ]);
                for row in &rows {
                    let sum = furnace(row);
                    assert!(
                        sum.iter().all(|s| (s - 1.0).abs() < 0.01),
                        "{side} r {r} at {}: {sum:?}",
                        row["angle_deg"]
                    );
                    let (a_r, a_t) = (
                        row["lobe_albedo"].as_f64().unwrap(),
                        row["transmission_lobe_albedo"].as_f64().unwrap(),
                    );
                    let (f, t) = (
                        triple(row, "reflectance_rgb"),
                        triple(row, "transmittance_rgb"),
                    );
                    worst_single = worst_single.min(a_r * f[1] + a_t * t[1]);
                }
            }
        }
        assert!(worst_single < 0.95, "{worst_single}");
    }

    /// A film on a metal (opaque) and a thin metal film on glass: the
    /// compensated reflectance is at least the single-scattering one,
    /// strictly above it at roughness 1, and the compensated flux (the
    /// lobes' albedos times the outputs) at most 1. F_ms itself may pass 1
    /// where A_R is small: Turquin's white reflector has F_ms = 1 / A_R.
    #[test]
    fn metal_films_gain_what_multiple_scattering_keeps() {
        let dir = tempfile::tempdir().unwrap();
        let gold_film = dir.path().join("gold-film.toml");
        std::fs::write(
            &gold_film,
            "ambient = { n = 1.0 }\nsubstrate = { n = 1.5 }\n[[layers]]\nmaterial = \"gold\"\nthickness_nm = 20.0\n",
        )
        .unwrap();
        for stack in ["luts/two-layer.toml", gold_film.to_str().unwrap()] {
            for r in ["0.3", "1"] {
                let rows = json(&[
                    "color",
                    stack,
                    "--roughness",
                    r,
                    "--angles",
                    "0,40,80",
                    "--json",
                ]);
                for row in &rows {
                    let (f, f_ms) = (
                        triple(row, "reflectance_rgb"),
                        triple(row, "reflectance_ms_rgb"),
                    );
                    for c in 0..3 {
                        assert!(f_ms[c] >= f[c], "{stack} {r}: {f:?} {f_ms:?}");
                    }
                    if r == "1" {
                        assert!(f_ms[1] > f[1] * 1.01, "{stack}: {f:?} {f_ms:?}");
                    }
                    let sum = furnace(row);
                    assert!(sum.iter().all(|s| *s <= 1.0 + 1e-9), "{stack} {r}: {sum:?}");
                }
            }
        }
    }

    #[test]
    fn bad_roughness_is_one_line() {
        for bad in ["nan", "NaN", "-0.1", "1.0001", "inf", "x", ""] {
            irid(["color", "luts/soap-film.toml", "--roughness", bad])
                .assert_one_line_error(bad, &["--roughness"]);
        }
    }
}
