//! Rough films as the command line shows them: `irid color --roughness`.

// Not an API: a test crate has no public API to document.
#![allow(missing_docs)]

mod common;

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
                    "reflectance_rgb",
                    "reflectance_xyz",
                    "roughness"
                ]
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
    }

    #[test]
    fn bad_roughness_is_one_line() {
        for bad in ["nan", "NaN", "-0.1", "1.0001", "inf", "x", ""] {
            irid(["color", "luts/soap-film.toml", "--roughness", bad])
                .assert_one_line_error(bad, &["--roughness"]);
        }
    }
}
