//! Every input in `tests/hostile/` (see its README) as a regression test:
//! one line `irid: ...` and exit code 2, or a correct result where the input
//! is legal; never a panic, an abort, or a file left behind. Each runs in a
//! scratch copy of its folder.

mod common;

use std::path::{Path, PathBuf};

use common::{irid_in, Run, Scratch};

/// A scratch copy of `tests/hostile/FOLDER`.
fn copy_of(folder: &str) -> Scratch {
    let scratch = Scratch::new(&format!("hostile-{folder}"));
    let from = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/hostile")
        .join(folder);
    copy_dir(&from, scratch.path());
    scratch
}

fn copy_dir(from: &Path, to: &Path) {
    for entry in std::fs::read_dir(from).unwrap() {
        let entry = entry.unwrap();
        let target = to.join(entry.file_name());
        if entry.file_type().unwrap().is_dir() {
            std::fs::create_dir_all(&target).unwrap();
            copy_dir(&entry.path(), &target);
        } else {
            std::fs::copy(entry.path(), &target).unwrap();
        }
    }
}

/// Every file under `dir`, relative, sorted.
fn listing(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for entry in std::fs::read_dir(&d).unwrap() {
            let entry = entry.unwrap();
            if entry.file_type().unwrap().is_dir() {
                stack.push(entry.path());
            } else {
                out.push(entry.path().strip_prefix(dir).unwrap().to_path_buf());
            }
        }
    }
    out.sort();
    out
}

/// Runs `args` in a copy of `folder`; asserts one error line naming each of
/// `needles`, exit 2, and that the folder holds exactly what it held.
fn refused(folder: &str, args: &[&str], needles: &[&str]) -> Run {
    let dir = copy_of(folder);
    let before = listing(dir.path());
    let run = irid_in(dir.path(), args);
    run.assert_one_line_error(&format!("{folder}: {args:?}"), needles);
    assert_eq!(listing(dir.path()), before, "{folder}: {args:?} left files");
    run
}

const SMALL_RENDER: [&str; 8] = [
    "--width",
    "16",
    "--height",
    "16",
    "--film",
    "direct",
    "--sampling",
    "rgb3",
];

fn render_args<'a>(scene: &'a str, extra: &[&'a str]) -> Vec<&'a str> {
    let mut args = vec!["render", scene, "-o", "r.png"];
    args.extend_from_slice(extra);
    args
}

#[test]
fn table_layer_outside_the_stack() {
    for cmd in [
        &["info", "t.exr"][..],
        &["validate", "t.exr", "--points", "200"],
    ] {
        refused("exr_layer", cmd, &["t.exr", "layer 2"]);
    }
}

#[test]
fn table_statistics_shorter_than_the_channels() {
    let run = refused(
        "exr_short_stats",
        &["info", "t.exr"],
        &["max_abs", "per channel"],
    );
    assert!(
        run.stdout.is_empty(),
        "info printed before failing: {}",
        run.stdout
    );
}

#[test]
fn table_axes_that_collapse_or_overflow_in_f32() {
    for (file, why) in [
        ("cos_1e-300_steps.exr", "f32"),
        ("thickness_1e-300_steps.exr", "f32"),
        ("thickness_near_duplicates.exr", "f32"),
        ("thickness_beyond_f32.exr", "range"),
        ("spectral_thickness_huge_span.exr", "range"),
    ] {
        refused(
            "exr_f32_axis",
            &["validate", file, "--points", "200"],
            &[file, why],
        );
    }
}

#[test]
fn table_windows_larger_than_the_file() {
    for file in [
        "cols_2e9.exr",
        "rows_2e9.exr",
        "rows_67M.exr",
        "side_16M.exr",
    ] {
        for cmd in ["info", "validate"] {
            refused("exr_huge_window", &[cmd, file], &[file]);
        }
    }
}

/// A broken table in the render cache is a stale cache entry: the render
/// bakes it again, replaces it and succeeds.
#[test]
fn a_planted_cache_table_is_baked_again() {
    let dir = copy_of("render_planted_table");
    let run = irid_in(
        dir.path(),
        [
            "render",
            "scene.toml",
            "-o",
            "r.png",
            "--width",
            "16",
            "--height",
            "16",
            "--cache",
            "cache",
        ],
    );
    assert!(run.success(), "{run:?}");
    assert!(dir.path().join("r.png").is_file());
    for entry in std::fs::read_dir(dir.path().join("cache")).unwrap() {
        let path = entry.unwrap().path();
        irid::lut::Lut::load(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    }
}

#[test]
fn an_environment_map_declaring_a_vast_window() {
    let args = render_args("scene.toml", &SMALL_RENDER);
    refused("envmap_huge_window", &args, &["env.exr", "memory limit"]);
}

#[test]
fn bake_resolutions_that_wrap_or_have_no_limit() {
    for resolution in [
        "65536,65536,4294967296",
        "1,1,60000000",
        "4294967296,4294967296,1",
    ] {
        refused(
            "bake_spectral_resolution",
            &[
                "bake",
                "soap-film.toml",
                "-o",
                "t.exr",
                "--kind",
                "spectral",
                "--resolution",
                resolution,
                "--no-check",
                "--validate-points",
                "0",
            ],
            &["resolution"],
        );
    }
    for tiny in ["1e-300", "1e-12"] {
        let run = refused(
            "bake_spectral_resolution",
            &["bake", "soap-film.toml", "-o", "t.exr", "--max-error", tiny],
            &["max-error", tiny],
        );
        assert!(run.stderr.len() < 200, "{}", run.stderr);
    }
}

#[test]
fn a_failed_exr_leaves_no_png() {
    let dir = copy_of("render_exr_fail");
    std::fs::create_dir_all(dir.path().join("out/exrdir")).unwrap();
    let mut args = vec![
        "render",
        "scene.toml",
        "-o",
        "out/r.png",
        "--exr",
        "out/exrdir",
    ];
    args.extend_from_slice(&SMALL_RENDER);
    irid_in(dir.path(), &args).assert_one_line_error("exr into a directory", &["exrdir"]);
    assert!(!dir.path().join("out/r.png").exists());
    assert_eq!(listing(&dir.path().join("out")), Vec::<PathBuf>::new());

    std::fs::write(dir.path().join("x.png"), b"keep").unwrap();
    for exr in ["x.png", "./x.png"] {
        let mut args = vec!["render", "scene.toml", "-o", "x.png", "--exr", exr];
        args.extend_from_slice(&SMALL_RENDER);
        irid_in(dir.path(), &args).assert_one_line_error("-o X --exr X", &["different files"]);
        assert_eq!(std::fs::read(dir.path().join("x.png")).unwrap(), b"keep");
    }
}

#[test]
fn indices_too_small_for_the_solver() {
    for file in [
        "ambient.toml",
        "layer.toml",
        "substrate.toml",
        "substrate_1e-300.toml",
        "substrate_k.toml",
    ] {
        let run = refused(
            "stack_denormal",
            &["eval", file, "--wavelengths", "500", "--angles", "0,30"],
            &[file, "1e-6"],
        );
        assert!(run.stderr.len() < 300, "{}", run.stderr);
    }
}

/// Control characters in a name echoed by an error are escaped.
#[test]
fn control_characters_in_names_are_escaped() {
    let dir = Scratch::new("hostile-control");
    dir.write(
        "s.toml",
        "ambient = { n = 1.0 }\nsubstrate = \"glass\\u001b[31m\\u0000x\"\n",
    );
    let run = irid_in(dir.path(), ["eval", "s.toml", "--wavelengths", "500"]);
    run.assert_one_line_error("control characters", &["\\u{1b}[31m"]);
    assert!(!run.stderr.contains('\u{1b}') && !run.stderr.contains('\0'));
}

#[test]
fn meshes_without_a_usable_triangle() {
    let args = render_args("scene.toml", &SMALL_RENDER);
    refused("mesh_empty", &args, &["objects[1]", "no usable triangle"]);
    refused("gem_tiny", &args, &["objects[1]", "no usable triangle"]);
    for scene in ["scene_one_vertex_face.toml", "scene_two_vertex_face.toml"] {
        let args = render_args(scene, &SMALL_RENDER);
        refused("mesh_short_faces", &args, &["vertex_face.obj"]);
    }
}

/// `irid info` prints names from the table's header with control
/// characters escaped.
#[test]
fn info_escapes_names_from_the_header() {
    let dir = Scratch::new("hostile-info");
    let mut stack = irid::optics::Stack::from_toml_str(
        "ambient = { n = 1.0 }\nsubstrate = { n = 1.5 }\n[[layers]]\nn = 1.33\nthickness_nm = 300\n",
        dir.path(),
        "s",
    )
    .unwrap();
    stack.substrate.name = "glass\u{1b}[2J\u{7}".into();
    let mut spec = irid::lut::BakeSpec::new(stack);
    spec.resolution = irid::lut::Resolution::Nodes {
        thickness: 1,
        angle: 4,
        wavelength: 1,
    };
    spec.check = false;
    let path = dir.path().join("t.exr");
    irid::lut::bake(&spec).unwrap().write(&path).unwrap();
    let run = irid_in(dir.path(), ["info", "t.exr"]);
    assert!(run.success(), "{run:?}");
    assert!(
        run.stdout.contains("glass\\u{1b}[2J\\u{7}"),
        "{}",
        run.stdout
    );
    assert!(!run.stdout.contains('\u{1b}') && !run.stdout.contains('\u{7}'));
}
