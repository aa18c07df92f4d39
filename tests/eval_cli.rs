//! `irid eval` run as a program: output formats, and bad input giving one
//! `irid: ...` line that names the file and field, exit code 2, no panic.

// Not an API: a test crate has no public API to document.
#![allow(missing_docs)]

mod common;

use common::{irid, Scratch};

#[test]
fn json_has_exactly_the_agreed_keys_and_the_airy_value() {
    let out = irid([
        "eval",
        "luts/soap-film.toml",
        "--wavelengths",
        "450:650:100",
        "--angles",
        "0,45",
        "--json",
    ]);
    assert!(out.success(), "{}", out.stderr);
    let rows: Vec<serde_json::Map<String, serde_json::Value>> =
        serde_json::from_str(&out.stdout).unwrap();
    assert_eq!(rows.len(), 6);
    for row in &rows {
        let mut keys: Vec<&str> = row.keys().map(String::as_str).collect();
        keys.sort();
        assert_eq!(
            keys,
            [
                "R",
                "Rp",
                "Rs",
                "T",
                "Tp",
                "Ts",
                "angle_deg",
                "wavelength_nm"
            ]
        );
    }
    // Wavelength-major order.
    let pairs: Vec<(f64, f64)> = rows
        .iter()
        .map(|r| {
            (
                r["wavelength_nm"].as_f64().unwrap(),
                r["angle_deg"].as_f64().unwrap(),
            )
        })
        .collect();
    assert_eq!(
        pairs,
        [
            (450.0, 0.0),
            (450.0, 45.0),
            (550.0, 0.0),
            (550.0, 45.0),
            (650.0, 0.0),
            (650.0, 45.0)
        ]
    );
    // A free-standing film at normal incidence (Airy): r1 = (1 − n)/(1 + n),
    // r2 = −r1, R = |r1 + r2 e^{2iδ}|² / |1 + r1 r2 e^{2iδ}|², δ = 2π n d / λ.
    let (n, d) = (1.33f64, 500.0f64);
    let r1 = (1.0 - n) / (1.0 + n);
    for row in rows.iter().filter(|r| r["angle_deg"].as_f64() == Some(0.0)) {
        let wl = row["wavelength_nm"].as_f64().unwrap();
        let phase = 2.0 * std::f64::consts::TAU * n * d / wl;
        let num = num_complex::Complex64::from_polar(1.0, phase) * -r1 + r1;
        let den = num_complex::Complex64::from_polar(1.0, phase) * (-r1 * r1) + 1.0;
        let want = (num / den).norm_sqr();
        let got = row["R"].as_f64().unwrap();
        assert!((got - want).abs() < 1e-14, "{wl} nm: {got} vs {want}");
        assert!((got + row["T"].as_f64().unwrap() - 1.0).abs() < 1e-14);
    }
}

#[test]
fn several_stacks_and_the_table() {
    let out = irid([
        "eval",
        "luts/soap-film.toml",
        "luts/two-layer.toml",
        "--wavelengths",
        "500",
        "--angles",
        "0",
        "--json",
    ]);
    assert!(out.success());
    let text = out.stdout;
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines.len(), 2, "one JSON array per stack");
    for line in lines {
        let rows: Vec<serde_json::Value> = serde_json::from_str(line).unwrap();
        assert_eq!(rows.len(), 1);
    }
    // Defaults: 380:780:10 × 0,30,60, as a table with a header.
    let out = irid(["eval", "luts/mirror-10.toml"]);
    assert!(out.success());
    let text = out.stdout;
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines.len(), 1 + 41 * 3);
    assert!(lines[0].contains("wavelength_nm") && lines[0].contains("Tp"));
}

/// Runs irid expecting failure: exit 2, one stderr line starting `irid:`
/// and containing every needle, nothing on stdout, no panic.
fn fails(args: &[&str], needles: &[&str]) {
    let out = irid(args);
    out.assert_one_line_error(&format!("{args:?}"), needles);
    assert!(out.stdout.is_empty(), "{args:?} printed to stdout");
    assert!(!out.stderr.contains("panicked"), "{}", out.stderr);
}

#[test]
fn bad_input_exits_2_with_one_line() {
    let dir = Scratch::new("eval-cli");
    let write = |name: &str, text: &str| -> String { dir.write(name, text).display().to_string() };
    let base = "ambient = { n = 1.0 }\nsubstrate = { n = 1.5 }\n";
    let malformed = write("malformed.toml", "ambient = { n = 1.0 \n");
    let unknown = write(
        "unknown.toml",
        &format!("{base}[[layers]]\nmaterial = \"kryptonite\"\nthickness_nm = 5\n"),
    );
    let negative = write(
        "negative.toml",
        &format!("{base}[[layers]]\nn = 1.2\nthickness_nm = -1\n"),
    );
    let nan = write(
        "nan.toml",
        &format!("{base}[[layers]]\nn = 1.2\nthickness_nm = nan\n"),
    );
    let inf = write(
        "inf.toml",
        &format!("{base}[[layers]]\nn = 1.2\nthickness_nm = inf\n"),
    );
    let lossy = write(
        "lossy.toml",
        "ambient = { n = [1.0, 0.01] }\nsubstrate = { n = 1.5 }\n",
    );
    let table = write(
        "table.toml",
        &format!("{base}[[layers]]\ntable = \"missing.csv\"\nthickness_nm = 5\n"),
    );
    let bad_csv_file = write("bad.csv", "wl,n,k\n0.4,1.5,oops\n");
    let _ = bad_csv_file;
    let bad_csv = write(
        "badcsv.toml",
        &format!("{base}[[layers]]\ntable = \"bad.csv\"\nthickness_nm = 5\n"),
    );
    let ok = "luts/soap-film.toml";

    fails(&["eval", &malformed], &["malformed.toml", "line"]);
    fails(
        &["eval", &unknown],
        &["unknown.toml", "layers[1].material", "kryptonite"],
    );
    fails(
        &["eval", &negative],
        &["negative.toml", "layers[1].thickness_nm"],
    );
    fails(&["eval", &nan], &["nan.toml", "layers[1].thickness_nm"]);
    fails(&["eval", &inf], &["inf.toml", "layers[1].thickness_nm"]);
    fails(&["eval", &lossy], &["lossy.toml", "ambient", "lossless"]);
    fails(
        &["eval", &table],
        &["table.toml", "layers[1].table", "missing.csv"],
    );
    fails(
        &["eval", &bad_csv],
        &["badcsv.toml", "layers[1].table", "bad.csv", "line 2"],
    );
    fails(&["eval", "no/such/stack.toml"], &["no/such/stack.toml"]);
    let missing = irid(["eval", "no/such/stack.toml"]);
    let err = &missing.stderr;
    assert_eq!(err.matches("os error").count(), 1, "said once: {err}");
    fails(
        &[
            "eval",
            "luts/two-layer.toml",
            "--wavelengths",
            "100:500:100",
        ],
        // TiO2's table (from 120 nm) is the first to run out; gold's from 188 nm.
        &["two-layer.toml", "TiO2", "table", "100 nm"],
    );
    fails(
        &["eval", ok, "--wavelengths", "400:500"],
        &["--wavelengths", "400:500"],
    );
    fails(
        &["eval", ok, "--wavelengths", "400,abc"],
        &["--wavelengths", "abc"],
    );
    fails(&["eval", ok, "--wavelengths", "-5"], &["--wavelengths"]);
    fails(
        &["eval", ok, "--wavelengths", "1e-300"],
        &["--wavelengths", "outside"],
    );
    fails(&["eval", ok, "--angles", "0,90"], &["--angles", "90"]);
    fails(&["eval", ok, "--angles", "1:2:0"], &["--angles", "step"]);
    // A good stack before a bad one: still nothing printed.
    fails(&["eval", ok, &unknown, "--json"], &["unknown.toml"]);
    assert!(dir.exists());
}
