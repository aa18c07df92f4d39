//! irid_film executed on a real graphics API: wgpu on Vulkan (lavapipe in
//! CI). For several exports a compute shader calls irid_film at the
//! export's own measurement points (20 000, uniform over the domain), read
//! from the files as a host reads them, and the results are compared with
//! irid's CPU emulation of the same filtered texture (float precision: this
//! proves the mapping and the file layout) and with the exact solver
//! (within the error film.json states). The generated GLSL runs the same
//! way. Without a Vulkan adapter these tests pass with a note, unless
//! IRID_REQUIRE_GPU=1 (CI), which makes that a failure.

mod harness;

use std::path::{Path, PathBuf};

use harness::{bind, glsl_program, gpu, program, read_dir, run, wgsl_program, Gpu, Source};
use irid::export::{exact_at, export, measurement_points, write_dir, Export, ExportSpec};
use irid::optics::Stack;

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn shader(name: &str) -> String {
    std::fs::read_to_string(repo().join("shaders").join(name)).unwrap()
}

fn stack_file(name: &str) -> Stack {
    Stack::load(&repo().join("luts").join(name)).unwrap()
}

fn stack_toml(text: &str) -> Stack {
    Stack::from_toml_str(text, &repo(), "test stack").unwrap()
}

/// The exports the shaders are checked on.
fn cases() -> Vec<(&'static str, ExportSpec)> {
    let spec = |stack: Stack, layer: usize, thickness: (f64, f64)| {
        let mut s = ExportSpec::new(stack);
        s.layer = layer;
        s.thickness_nm = thickness;
        s
    };
    let mirror = stack_file("mirror-10.toml");
    let mirror_back = mirror.reversed();
    let mut dense = spec(
        stack_toml(
            "ambient = { n = 1.5 }\nsubstrate = { n = 1.0 }\n[[layers]]\nn = 1.33\nthickness_nm = 300.0\n",
        ),
        1,
        (0.0, 800.0),
    );
    dense.cos_theta = (0.02, 1.0);
    vec![
        ("soap film", spec(stack_file("soap-film.toml"), 1, (0.0, 1000.0))),
        (
            "film on gold",
            spec(
                stack_toml("ambient = { n = 1.0 }\nsubstrate = { material = \"gold\" }\n[[layers]]\nn = 1.45\nthickness_nm = 300.0\n"),
                1,
                (0.0, 600.0),
            ),
        ),
        ("10-layer mirror, front", spec(mirror, 1, (20.0, 100.0))),
        ("10-layer mirror, back", spec(mirror_back, 10, (20.0, 100.0))),
        ("dense-side film", dense),
        ("absorbing film", spec(stack_file("absorbing-film.toml"), 1, (0.0, 600.0))),
    ]
}

struct Case {
    name: &'static str,
    export: Export,
    dir: tempfile::TempDir,
    points: Vec<[f32; 2]>,
    exact: Vec<[f64; 6]>,
}

fn make(name: &'static str, spec: ExportSpec) -> Case {
    let export = export(&spec, &|_| {}).unwrap_or_else(|e| panic!("{name}: {e}"));
    let dir = tempfile::tempdir().unwrap();
    write_dir(&export, &dir.path().join("film")).unwrap();
    let points = measurement_points(&spec);
    let exact = exact_at(&spec, &points).unwrap();
    Case {
        name,
        export,
        dir,
        points,
        exact,
    }
}

/// Largest |GPU − CPU emulation| and per-channel max |GPU − exact|.
fn compare(case: &Case, got: &[[f32; 6]]) -> (f64, [f64; 6]) {
    let mut emulation = 0.0f64;
    let mut exact = [0.0f64; 6];
    for ((p, g), e) in case.points.iter().zip(got).zip(&case.exact) {
        let (r, t) = case.export.sample(p[0], p[1]);
        let cpu = [r[0], r[1], r[2], t[0], t[1], t[2]];
        for k in 0..6 {
            emulation = emulation.max(f64::from((g[k] - cpu[k]).abs()));
            exact[k] = exact[k].max((f64::from(g[k]) - e[k]).abs());
        }
    }
    (emulation, exact)
}

/// Float precision of the filtered result: the texel coordinates and
/// weights are f32 on both sides, but a driver may order the lerps
/// differently.
const EMULATION_TOLERANCE: f64 = 2e-6;

fn check(gpu: &Gpu, case: &Case, language: &str, source: Source) {
    let files = read_dir(&case.dir.path().join("film"));
    assert_eq!(
        files.reflectance, case.export.reflectance,
        "{}: reflectance.exr",
        case.name
    );
    assert_eq!(
        files.transmittance, case.export.transmittance,
        "{}: transmittance.exr",
        case.name
    );
    let bound = bind(gpu, &files);
    let program = program(gpu, &bound.layout, source);
    let (got, _) = run(gpu, &program, &bound, &case.points, 1);
    let (emulation, exact) = compare(case, &got);
    let stated = case.export.error.max_abs;
    eprintln!(
        "{} [{language}, {}×{}]: |GPU − CPU emulation| ≤ {emulation:.2e}; |GPU − exact| max {:.2e} (film.json states {:.2e})",
        case.name,
        case.export.mapping.size_u,
        case.export.mapping.size_v,
        exact.iter().fold(0.0f64, |a, &b| a.max(b)),
        case.export.error.max_all()
    );
    assert!(
        emulation <= EMULATION_TOLERANCE,
        "{} [{language}]: GPU differs from the CPU emulation by {emulation:e}",
        case.name
    );
    for k in 0..6 {
        assert!(
            exact[k] <= stated[k] + EMULATION_TOLERANCE,
            "{} [{language}]: channel {k} error {:e} above the stated {:e}",
            case.name,
            exact[k],
            stated[k]
        );
    }
    assert!(case.export.error.max_all() <= case.export.spec.max_error);
}

#[test]
fn irid_film_on_vulkan_matches_emulation_and_solver() {
    let gpu = gpu();
    if let Some(gpu) = &gpu {
        eprintln!(
            "adapter: {} ({:?}, driver {})",
            gpu.info.name, gpu.info.backend, gpu.info.driver_info
        );
    }
    let wgsl = shader("irid_film.wgsl");
    let glsl = shader("irid_film.glsl");
    let glsl_es = shader("irid_film_es.glsl");
    for (name, spec) in cases() {
        let critical = irid::export::critical_cos(&spec.stack);
        let case = make(name, spec);
        // A dense-side stack has its critical angle exactly on a node.
        if let Some(cc) = critical {
            assert_eq!(case.export.mapping.cos_crit, cc, "{name}");
            assert!(case.export.mapping.cos_nodes().contains(&cc), "{name}");
        }
        let Some(gpu) = &gpu else { continue };
        check(gpu, &case, "WGSL", wgsl_program(&wgsl, "irid_film"));
        check(gpu, &case, "GLSL 4.50", glsl_program(&glsl));
        check(gpu, &case, "GLSL ES 3.00", glsl_program(&glsl_es));
    }
}
