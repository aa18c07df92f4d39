//! `irid fit`: thicknesses from a spectrum file and from colours, the fitted
//! stack file, and bad input (one line, exit 2, nothing written).

// Not an API: a test crate has no public API to document.
#![allow(missing_docs)]

mod common;

use common::{irid_in, Scratch};
use irid::color::{stack_colors, Sampling, SpectralIntegrator};
use irid::optics::{Response, Stack, StackGrid};

const STACK: &str = "ambient = { n = 1.0 }\nsubstrate = { n = 1.52 }\n\
                     [[layers]]\nn = 2.3\nthickness_nm = 130.0\n\
                     [[layers]]\nn = 1.45\nthickness_nm = 160.0\n";

const TRUTH: [f64; 2] = [118.0, 181.0];

/// The spectrum file of the stack with `TRUTH` thicknesses, with a
/// deterministic ripple of ±1e-3 standing for noise.
fn spectrum_csv() -> String {
    let dir = Scratch::new("fit-truth");
    let stack = Stack::from_toml_str(STACK, &dir, "stack").unwrap();
    let wavelengths: Vec<f64> = (0..201).map(|i| 380.0 + 2.0 * i as f64).collect();
    let grid = StackGrid::new(&stack, &wavelengths).unwrap();
    let mut out = vec![Response::default(); wavelengths.len()];
    let mut text = String::from("# synthetic\nwavelength_nm,angle_deg,R,sigma\n");
    for angle in [0.0f64, 45.0] {
        grid.solve_spectrum(&TRUTH, angle.to_radians().cos(), &mut out);
        for (i, (w, r)) in wavelengths.iter().zip(&out).enumerate() {
            let noise = 1e-3 * ((i as f64) * 1.7 + angle).sin();
            text += &format!("{w},{angle},{},1e-3\n", r.r() + noise);
        }
    }
    text
}

#[test]
fn fits_a_spectrum_and_writes_the_stack() {
    let dir = Scratch::new("fit");
    dir.write("stack.toml", STACK);
    dir.write("m.csv", spectrum_csv());
    let run = irid_in(
        &dir,
        [
            "fit",
            "stack.toml",
            "--spectrum",
            "m.csv",
            "--vary",
            "1,2",
            "-o",
            "out/fitted.toml",
            "--json",
        ],
    );
    // The output's folder does not exist: refused before any work.
    run.assert_one_line_error("missing folder", &["out"]);
    std::fs::create_dir(dir.join("out")).unwrap();
    let run = irid_in(
        &dir,
        [
            "fit",
            "stack.toml",
            "--spectrum",
            "m.csv",
            "--vary",
            "1,2",
            "-o",
            "out/fitted.toml",
            "--json",
        ],
    );
    assert!(run.success(), "{}", run.stderr);
    let fit: serde_json::Value = serde_json::from_str(&run.stdout).unwrap();
    let fitted = Stack::load(&dir.join("out/fitted.toml")).unwrap();
    for p in 0..2 {
        let d = fit["thickness_nm"][p].as_f64().unwrap();
        let s = fit["sigma_nm"][p].as_f64().unwrap();
        assert!((d - TRUTH[p]).abs() <= 3.0 * s && s <= 1.0, "{fit}");
        assert_eq!(fitted.layers[p].thickness_nm, d);
    }
    assert!(fit["alternatives"].as_array().unwrap().is_empty());
    // The table names each thickness, χ² and the residual.
    let run = irid_in(
        &dir,
        ["fit", "stack.toml", "--spectrum", "m.csv", "--vary", "2"],
    );
    assert!(run.success(), "{}", run.stderr);
    for needle in ["layer 2:", " ± ", "χ² =", "residual"] {
        assert!(run.stdout.contains(needle), "{}", run.stdout);
    }
}

#[test]
fn fits_colours_at_angles() {
    let dir = Scratch::new("fit-color");
    dir.write("stack.toml", STACK);
    let hidden = Stack::from_toml_str(STACK, &dir, "stack").unwrap();
    let mut hidden = hidden.clone();
    hidden.layers[1].thickness_nm = 175.0;
    let colors = stack_colors(
        &hidden,
        &SpectralIntegrator::new(Sampling::Exact),
        &[0.0, 40.0],
    )
    .unwrap();
    let mut args: Vec<String> = [
        "fit",
        "stack.toml",
        "--vary",
        "2",
        "--bounds",
        "120:200",
        "--json",
    ]
    .map(String::from)
    .to_vec();
    for c in &colors {
        let [r, g, b] = c.reflectance_rgb;
        args.push("--color".into());
        args.push(format!("{r},{g},{b}@{}", c.angle_deg));
    }
    let run = irid_in(&dir, &args);
    assert!(run.success(), "{}", run.stderr);
    let fit: serde_json::Value = serde_json::from_str(&run.stdout).unwrap();
    for de in fit["delta_e2000"].as_array().unwrap() {
        assert!(de.as_f64().unwrap() <= 0.5, "{fit}");
    }
}

/// A 2.0-index film on glass of 92 nm: at 0° alone its third order (near
/// 358 nm) reflects a colour within 1 ΔE00, which the report says, in text
/// and JSON; at 0°, 45° and 70° the fit is unique.
#[test]
fn says_when_the_colours_cannot_tell_two_thicknesses_apart() {
    let dir = Scratch::new("fit-color-ambiguous");
    let film = "ambient = { n = 1.0 }\nsubstrate = { n = 1.52 }\n\
                [[layers]]\nn = 2.0\nthickness_nm = 92.0\n";
    dir.write("film.toml", film);
    let hidden = Stack::from_toml_str(film, &dir, "film").unwrap();
    let integrator = SpectralIntegrator::new(Sampling::Exact);
    let run_at = |angles: &[f64], json: bool| {
        let mut args: Vec<String> = ["fit", "film.toml", "--vary", "1", "--bounds", "60:420"]
            .map(String::from)
            .to_vec();
        for c in &stack_colors(&hidden, &integrator, angles).unwrap() {
            let [r, g, b] = c.reflectance_rgb;
            args.push("--color".into());
            args.push(format!("{r},{g},{b}@{}", c.angle_deg));
        }
        if json {
            args.push("--json".into());
        }
        let run = irid_in(&dir, &args);
        assert!(run.success(), "{}", run.stderr);
        run.stdout
    };
    let text = run_at(&[0.0], false);
    let line = text
        .lines()
        .find(|l| l.starts_with("ambiguous: thicknesses 3"))
        .unwrap_or_else(|| panic!("{text}"));
    assert!(line.contains("within 1 of the best"), "{text}");
    let fit: serde_json::Value = serde_json::from_str(&run_at(&[0.0], true)).unwrap();
    let third = fit["alternatives"][0]["thickness_nm"][0].as_f64().unwrap();
    assert!((third - 358.0).abs() < 10.0, "{fit}");
    assert_eq!(fit["tolerance_de2000"].as_f64(), Some(1.0), "{fit}");

    let text = run_at(&[0.0, 45.0, 70.0], false);
    assert!(text.contains("unique: no other thickness"), "{text}");
    let fit: serde_json::Value = serde_json::from_str(&run_at(&[0.0, 45.0, 70.0], true)).unwrap();
    assert_eq!(
        fit["alternatives"].as_array().map(Vec::len),
        Some(0),
        "{fit}"
    );
}

#[test]
fn bad_input_is_one_line_and_writes_nothing() {
    let dir = Scratch::new("fit-bad");
    dir.write("stack.toml", STACK);
    dir.write("m.csv", spectrum_csv());
    for (name, text) in [
        ("nocol.csv", "wavelength_nm,R\n500,0.1\n"),
        (
            "nan.csv",
            "wavelength_nm,angle_deg,R\n500,0,nan\n600,0,0.1\n700,0,0.1\n",
        ),
        ("neg.csv", "wavelength_nm,angle_deg,R\n-500,0,0.1\n"),
        ("angle.csv", "wavelength_nm,angle_deg,R\n500,90,0.1\n"),
    ] {
        dir.write(name, text);
    }
    let cases: [(&[&str], &[&str]); 10] = [
        (
            &["--spectrum", "nocol.csv", "--vary", "1"],
            &["nocol.csv", "angle_deg"],
        ),
        (
            &["--spectrum", "nan.csv", "--vary", "1"],
            &["nan.csv", "line 2", "R"],
        ),
        (
            &["--spectrum", "neg.csv", "--vary", "1"],
            &["neg.csv", "wavelength_nm"],
        ),
        (
            &["--spectrum", "angle.csv", "--vary", "1"],
            &["angle.csv", "angle_deg", "[0, 90)"],
        ),
        (
            &["--spectrum", "m.csv", "--vary", "0"],
            &["--vary", "0 names no layer"],
        ),
        (
            &["--spectrum", "m.csv", "--vary", "3"],
            &["--vary", "substrate"],
        ),
        (
            &["--spectrum", "m.csv", "--vary", "9"],
            &["--vary", "9 names no layer"],
        ),
        (
            &["--spectrum", "m.csv", "--vary", "1", "--bounds", "10:20"],
            &["--bounds[0]", "excludes the start"],
        ),
        (
            &["--color", "3,0,0@0", "--vary", "1"],
            &["--color '3,0,0@0'", "passive film"],
        ),
        (
            &["--color", "0.1,0.1@0", "--vary", "1"],
            &["--color", "three channels"],
        ),
    ];
    for (extra, needles) in cases {
        let mut args = vec!["fit", "stack.toml", "-o", "fitted.toml"];
        args.extend_from_slice(extra);
        irid_in(&dir, &args).assert_one_line_error(&format!("{args:?}"), needles);
        assert!(
            !dir.join("fitted.toml").exists(),
            "{args:?} wrote fitted.toml"
        );
    }
}
