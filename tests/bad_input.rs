//! Bad input never panics: the binary prints one line naming what is wrong,
//! exits with code 2 and leaves no output file behind.

// Not an API: a test crate has no public API to document.
#![allow(missing_docs)]

mod common;

use std::path::Path;

use common::{command, irid_in, Scratch};

/// Runs `irid args...` in `dir`; asserts exit code 2, a single stderr line
/// that mentions every one of `names`, and that none of `outputs` exists.
fn rejects(dir: &Path, args: &[&str], names: &[&str], outputs: &[&str]) {
    irid_in(dir, args).assert_one_line_error(&format!("{args:?}"), names);
    for output in outputs {
        assert!(!dir.join(output).exists(), "{args:?} left {output}");
    }
}

const SOAP: &str = "ambient = { n = 1.0 }\nsubstrate = { n = 1.0 }\n\
                    [[layers]]\nn = 1.33\nthickness_nm = 500.0\n";

fn soap_dir() -> Scratch {
    let dir = Scratch::new("bad-input");
    dir.write("soap.toml", SOAP);
    dir
}

/// `irid bake soap.toml -o o.exr --resolution 4,4 EXTRA...` is rejected.
fn bake_rejects(dir: &Path, extra: &[&str], names: &[&str]) {
    let mut args = vec!["bake", "soap.toml", "-o", "o.exr", "--resolution", "4,4"];
    args.extend_from_slice(extra);
    rejects(dir, &args, names, &["o.exr"]);
}

#[test]
fn usage_errors_are_one_line() {
    let dir = soap_dir();
    let d = dir.path();
    rejects(
        d,
        &["bake", "soap.toml", "-o", "o.exr", "--layer", "x"],
        &["--layer"],
        &["o.exr"],
    );
    rejects(
        d,
        &["render", "bubbles-uniform", "--film", "foo"],
        &["--film"],
        &[],
    );
    rejects(d, &["eval"], &["STACKS"], &[]);
    rejects(d, &["frobnicate"], &["frobnicate"], &[]);
    rejects(d, &[], &["subcommand"], &[]);
}

#[test]
fn negative_flag_values_reach_the_checks() {
    let dir = soap_dir();
    let d = dir.path();
    let bake = |flag: &str, value: &str, name: &str| bake_rejects(d, &[flag, value], &[name]);
    bake("--thickness", "-5:600", "thickness");
    bake("--max-error", "-1", "max-error");
    bake("--angles", "-1:1", "angles");
    rejects(
        d,
        &["color", "soap.toml", "--angles", "-5"],
        &["--angles"],
        &[],
    );
    rejects(
        d,
        &["eval", "soap.toml", "--wavelengths", "-5"],
        &["--wavelengths"],
        &[],
    );
    rejects(d, &["validate", "t.exr", "--seed", "-1"], &["--seed"], &[]);
}

#[test]
fn bake_thickness_range_is_bounded() {
    // 1e300 nm is finite in f64 but infinite in the table's f32 axis: the
    // table was written and then could not be read back.
    let dir = soap_dir();
    bake_rejects(dir.path(), &["--thickness", "1e300:1e301"], &["thickness"]);
}

#[test]
fn closed_stdout_is_not_a_panic() {
    use std::process::Stdio;
    let table = concat!(env!("CARGO_MANIFEST_DIR"), "/luts/soap-film.exr");
    let mut child = command()
        .args(["info", table])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take());
    let out = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!stderr.contains("panicked"), "{stderr}");
    // Either it finished before the pipe closed or SIGPIPE ended it.
    assert!(
        matches!(out.status.code(), Some(0) | None),
        "{:?}",
        out.status
    );
}

#[test]
fn render_flags_are_bounded() {
    let dir = Scratch::new("bad-input");
    let render = |flag: &str, value: &str| {
        let args = [
            "render",
            "bubbles-uniform",
            "-o",
            "o.png",
            "--width",
            "8",
            "--height",
            "8",
            flag,
            value,
        ];
        rejects(dir.path(), &args, &[flag], &["o.png"]);
    };
    // The tracer recurses on the stack: 100000 overflowed it (SIGABRT).
    render("--max-depth", "100000");
    // Starting 100000 worker threads hung.
    render("--threads", "100000");
    render("--threads", "0");
}

/// One samples-per-pixel limit for the command line and for scene files (the
/// command line allowed 16384, scene files 4096), and both errors name it.
#[test]
fn spp_has_one_limit_named_in_the_error() {
    let dir = Scratch::new("bad-input");
    let d = dir.path();
    let small = ["-o", "o.png", "--width", "4", "--height", "4"];
    let cli = [&["render", "bubbles-uniform", "--spp", "4097"][..], &small].concat();
    rejects(
        d,
        &cli,
        &["--spp", "between 1 and 4096, got 4097"],
        &["o.png"],
    );

    let scene = include_str!("../luts/scenes/absorbing-sphere.toml");
    assert!(scene.contains("spp = 1\n"));
    for (spp, shown) in [("4097", "got 4097"), ("0", "got 0")] {
        let text = scene.replace("spp = 1\n", &format!("spp = {spp}\n"));
        std::fs::write(d.join("s.toml"), text).unwrap();
        let args = [&["render", "s.toml"][..], &small].concat();
        rejects(
            d,
            &args,
            &["s.toml", "render.spp", "between 1 and 4096", shown],
            &["o.png"],
        );
    }
}

#[test]
fn scene_file_rejects_negative_absorption_and_sun_radius() {
    let gem = include_str!("../luts/scenes/blue-gem.toml");
    let dir = Scratch::new("bad-input");
    let cases = [
        ("absorption = [1.6", "absorption = [-1.6", "absorption"),
        (
            "sun_radius_deg = 3.0",
            "sun_radius_deg = -3.0",
            "sun_radius_deg",
        ),
        (
            "sun_radiance = [40.0",
            "sun_radiance = [-40.0",
            "sun_radiance",
        ),
    ];
    for (from, to, field) in cases {
        assert!(gem.contains(from));
        std::fs::write(dir.path().join("s.toml"), gem.replace(from, to)).unwrap();
        let args = [
            "render", "s.toml", "-o", "o.png", "--width", "8", "--height", "8",
        ];
        rejects(dir.path(), &args, &["s.toml", field], &["o.png"]);
    }
}

#[test]
fn truncated_toml_says_what_is_wrong() {
    // toml gives no message for a value missing at the end of the file: the
    // line used to end after "column 19: ".
    let dir = Scratch::new("bad-input");
    let d = dir.path();
    std::fs::write(
        d.join("t.toml"),
        "ambient = { n = 1.0 }\nsubstrate = { n = ",
    )
    .unwrap();
    rejects(
        d,
        &["eval", "t.toml"],
        &["t.toml", "line 2", "end of file"],
        &[],
    );
    std::fs::write(d.join("s.toml"), "name = \"x\"\n[render]\nwidth = ").unwrap();
    rejects(
        d,
        &["render", "s.toml", "-o", "o.png"],
        &["s.toml", "end of file"],
        &["o.png"],
    );
}

#[test]
fn bake_names_the_stack_whose_material_fails() {
    // The table covers 360–830 nm (exact sampling) but the CSV only 500–600:
    // the error surfaced from the baker without the stack file's name.
    let dir = Scratch::new("bad-input");
    let d = dir.path();
    std::fs::write(d.join("narrow.csv"), "wl,n\n0.5,1.5\n0.6,1.5\n").unwrap();
    std::fs::write(
        d.join("narrow.toml"),
        "ambient = { n = 1.0 }\nsubstrate = { table = \"narrow.csv\" }\n",
    )
    .unwrap();
    let args = ["bake", "narrow.toml", "-o", "o.exr", "--resolution", "4,4"];
    rejects(
        d,
        &args,
        &["narrow.toml", "narrow.csv", "360 nm"],
        &["o.exr"],
    );
}

#[test]
fn scene_film_thickness_is_bounded() {
    // 1e20 nm is finite in f32 but beyond what the baker accepts: the error
    // came from the bake without the scene file or the field.
    let scene = include_str!("../luts/scenes/bubbles-noise.toml");
    let dir = Scratch::new("bad-input");
    assert!(scene.contains("max_nm = 1100.0"));
    let text = scene.replace("max_nm = 1100.0", "max_nm = 1e20");
    std::fs::write(dir.path().join("s.toml"), text).unwrap();
    let args = [
        "render", "s.toml", "-o", "o.png", "--width", "8", "--height", "8",
    ];
    rejects(
        dir.path(),
        &args,
        &["s.toml", "thickness.max_nm"],
        &["o.png"],
    );
}

#[test]
fn absurd_point_counts_fail_instead_of_aborting() {
    // Each of these aborted on a multi-terabyte allocation (SIGABRT).
    let dir = soap_dir();
    let d = dir.path();
    let table = concat!(env!("CARGO_MANIFEST_DIR"), "/luts/soap-film.exr");
    let huge = "100000000000";
    rejects(d, &["validate", table, "--points", huge], &["points"], &[]);
    rejects(
        d,
        &["bench", "--quick", "--out", "b", "--points", huge],
        &["--points"],
        &["b"],
    );
    let args = [
        "bake",
        "soap.toml",
        "-o",
        "o.exr",
        "--validate-points",
        huge,
    ];
    rejects(d, &args, &["validate-points"], &["o.exr"]);
    let args = [
        "eval",
        "soap.toml",
        "--wavelengths",
        "1:10000000:1",
        "--angles",
        "0:89:0.01",
    ];
    rejects(d, &args, &["--wavelengths", "--angles"], &[]);
}

#[test]
fn absurd_grids_fail_instead_of_aborting() {
    let dir = soap_dir();
    let d = dir.path();
    // 8.9 million angles × 471 wavelengths aborted on allocation.
    let args = ["color", "soap.toml", "--angles", "0:89:0.00001"];
    rejects(d, &args, &["--angles"], &[]);
    let grid = ["bench", "--grid", "soap", "--repeat", "1"];
    let bench = |extra: &[&str], names: &[&str]| {
        let args: Vec<&str> = grid.iter().chain(extra).copied().collect();
        rejects(d, &args, names, &[]);
    };
    bench(&["--wavelengths", "1:10000000:1"], &["--wavelengths"]);
    bench(&["--thicknesses", "1e300"], &["--thicknesses"]);
    bench(&["--repeat", "1000000000"], &["--repeat"]);
}

#[test]
fn a_fixed_resolution_too_large_to_check_names_resolution() {
    let dir = soap_dir();
    rejects(
        dir.path(),
        &[
            "bake",
            "soap.toml",
            "-o",
            "o.exr",
            "--resolution",
            "2000,2000",
            "--thickness",
            "100:900",
        ],
        &["resolution", "soap.toml"],
        &["o.exr"],
    );
}

#[test]
fn no_check_needs_a_fixed_resolution() {
    let dir = soap_dir();
    let d = dir.path();
    let bake = ["bake", "soap.toml", "-o", "o.exr", "--thickness", "100:900"];
    for extra in [&["--no-check"][..], &["--no-check", "--max-error", "1e-3"]] {
        let args: Vec<&str> = bake.iter().chain(extra).copied().collect();
        rejects(d, &args, &["--no-check", "--resolution"], &["o.exr"]);
    }
}

/// A gain film near its resonance reflects beyond f16's largest value: a
/// `--half` table would store infinity, so the baker refuses it and names
/// where; the same table in f32 bakes.
#[test]
fn half_table_that_overflows_f16_is_refused() {
    let dir = Scratch::new("bad-input");
    let stack = concat!(env!("CARGO_MANIFEST_DIR"), "/luts/gain-on-gold.toml");
    let grid = [
        "--resolution",
        "256,32",
        "--angles",
        "0:1",
        "--thickness",
        "0:1000",
    ];
    let mut args = vec!["bake", stack, "-o", "g.exr", "--half"];
    args.extend_from_slice(&grid);
    rejects(
        dir.path(),
        &args,
        &["--half", "f16", "thickness"],
        &["g.exr"],
    );

    let mut args = vec!["bake", stack, "-o", "g.exr", "--validate-points", "0"];
    args.extend_from_slice(&grid);
    let out = irid_in(dir.path(), &args);
    assert!(out.success(), "{}", out.stderr);
    assert!(dir.path().join("g.exr").exists());
}

#[test]
fn incoherent_layers_are_refused_where_they_cannot_be() {
    let dir = Scratch::new("bad-input-incoherent");
    let d = dir.path();
    dir.write(
        "sheet.toml",
        "ambient = { n = 1.0 }\nsubstrate = { n = 1.0 }\n\
         [[layers]]\nn = 1.52\nthickness_nm = 1e6\ncoherent = false\n\
         [[layers]]\nn = 1.38\nthickness_nm = 100\n",
    );
    dir.write(
        "lasing.toml",
        "ambient = { n = 1.0 }\nsubstrate = { n = 1.5 }\n\
         [[layers]]\nn = 1.38\nthickness_nm = 100\n\
         [[layers]]\nn = [1.5, -0.01]\nthickness_nm = 1e6\ncoherent = false\n",
    );
    dir.write(
        "flagged.toml",
        "ambient = { n = 1.0, coherent = false }\nsubstrate = { n = 1.0 }\n",
    );
    // The thickness axis on the incoherent layer (layer 1 by default).
    rejects(
        d,
        &["bake", "sheet.toml", "-o", "o.exr"],
        &["layer", "layer 1 is incoherent", "coherent layers: 2"],
        &["o.exr"],
    );
    rejects(
        d,
        &["export", "sheet.toml", "-o", "out", "--layer", "1"],
        &["layer 1 is incoherent"],
        &["out"],
    );
    for args in [
        &["eval", "lasing.toml"][..],
        &["color", "lasing.toml"],
        &[
            "bake",
            "lasing.toml",
            "-o",
            "o.exr",
            "--resolution",
            "4,4",
            "--thickness",
            "0:0",
        ],
    ] {
        rejects(
            d,
            args,
            &["lasing.toml", "layers[2]: this incoherent layer lases at"],
            &["o.exr"],
        );
    }
    rejects(
        d,
        &["eval", "flagged.toml"],
        &["flagged.toml", "ambient.coherent: not allowed"],
        &[],
    );
}
