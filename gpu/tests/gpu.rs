//! irid_film executed on a real graphics API: wgpu on Vulkan (lavapipe in
//! CI). For several exports a compute shader calls irid_film from each
//! side of the film at the export's own measurement points (20 000, uniform
//! over the domain), read from the files as a host reads them, and the
//! results are compared with irid's CPU emulation of the same filtered
//! atlas (float precision: this proves the mapping, the chart choice and
//! the file layout) and with the exact solver on the stack as seen from
//! that side (within the error film.json states): the back side against
//! the reversed stack, past its critical angle included. The generated
//! GLSL runs the same way. Without a Vulkan adapter these tests pass with a
//! note, unless IRID_REQUIRE_GPU=1 (CI), which makes that a failure.

mod harness;

use std::path::{Path, PathBuf};

use harness::{bind, glsl_program, gpu, program, read_dir, run, wgsl_program, Gpu, Source};
use irid::export::{
    critical_cos, exact_at, export, measurement_points, write_dir, Export, ExportSpec, Side,
};
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
    // Over every angle (cos θ 0 to 1, the default), the grazing corner
    // included.
    let dense = spec(
        stack_toml(
            "ambient = { n = 1.5 }\nsubstrate = { n = 1.0 }\n[[layers]]\nn = 1.33\nthickness_nm = 300.0\n",
        ),
        1,
        (0.0, 800.0),
    );
    // A quarter-wave mirror for 550 nm on glass (non-dispersive indices),
    // its first layer varying: seen from the glass, total internal
    // reflection beyond cos θ 0.7265, every angle.
    let mirror = spec(
        stack_toml(&format!(
            "ambient = {{ n = 1.0 }}\nsubstrate = {{ n = 1.46 }}\n{}",
            "[[layers]]\nn = 2.4\nthickness_nm = 57.3\n[[layers]]\nn = 1.46\nthickness_nm = 94.2\n"
                .repeat(3)
        )),
        1,
        (20.0, 100.0),
    );
    vec![
        // One chart for both sides: the stack reads the same from either.
        ("soap film", spec(stack_file("soap-film.toml"), 1, (0.0, 1000.0))),
        // Opaque: no back chart; back-side lookups read the front chart.
        (
            "film on gold",
            spec(
                stack_toml("ambient = { n = 1.0 }\nsubstrate = { material = \"gold\" }\n[[layers]]\nn = 1.45\nthickness_nm = 300.0\n"),
                1,
                (0.0, 600.0),
            ),
        ),
        // Coated glass: the back side has total internal reflection beyond
        // its critical angle (41.8°).
        (
            "film on glass",
            spec(
                stack_toml("ambient = { n = 1.0 }\nsubstrate = { n = 1.5 }\n[[layers]]\nn = 1.38\nthickness_nm = 300.0\n"),
                1,
                (0.0, 1000.0),
            ),
        ),
        ("6-layer mirror", mirror),
        ("dense-side film", dense),
        // Seen from its fused-silica side over 0–600 nm the absorbing film
        // needs 21 charts with its front (the dispersive critical band is
        // cut in many).
        (
            "absorbing film",
            spec(stack_file("absorbing-film.toml"), 1, (0.0, 600.0)),
        ),
    ]
}

struct Case {
    name: &'static str,
    export: Export,
    dir: tempfile::TempDir,
    points: Vec<[f32; 2]>,
    /// The exact response at the points, from each side (front, back).
    exact: [Vec<[f64; 6]>; 2],
}

fn make(name: &'static str, spec: ExportSpec) -> Case {
    let export = export(&spec, &|_| {}).unwrap_or_else(|e| panic!("{name}: {e}"));
    let dir = tempfile::tempdir().unwrap();
    write_dir(&export, &dir.path().join("film")).unwrap();
    let points = measurement_points(&spec);
    // Without a back side (an absorbing substrate, which no light leaves)
    // back-side lookups read the front chart.
    let exact = [Side::Front, Side::Back].map(|side| {
        let seen = if export.side(side).is_some() {
            side
        } else {
            Side::Front
        };
        exact_at(&spec, seen, &points).unwrap()
    });
    Case {
        name,
        export,
        dir,
        points,
        exact,
    }
}

/// Largest |GPU − CPU emulation| and per-channel max |GPU − exact| from `side`.
fn compare(case: &Case, side: Side, got: &[[f32; 6]]) -> (f64, [f64; 6]) {
    let mut emulation = 0.0f64;
    let mut exact = [0.0f64; 6];
    for ((p, g), e) in case
        .points
        .iter()
        .zip(got)
        .zip(&case.exact[side.index() as usize])
    {
        let (r, t) = case.export.sample(p[0], p[1], side);
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
/// differently, and its log and atan2 (the bands' thickness and cos θ
/// warps, the corner's angle) need not be correctly rounded: WGSL allows
/// log an absolute error of 2^-21 near 1, which moves a texel coordinate of
/// a 963-texel band by up to 5e-4 of a texel, times the step between
/// neighbouring texels.
const EMULATION_TOLERANCE: f64 = 5e-5;

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
    for side in [Side::Front, Side::Back] {
        let (got, _) = run(gpu, &program, &bound, &case.points, 1, side.index());
        let (emulation, exact) = compare(case, side, &got);
        assert!(
            emulation <= EMULATION_TOLERANCE,
            "{} [{language}, {side:?}]: GPU differs from the CPU emulation by {emulation:e}",
            case.name
        );
        // A side the export has is within the error it states; an opaque
        // film's back-side lookups read the front chart.
        let Some(stated) = case.export.side(side) else {
            assert!(
                case.export.opaque || case.export.spec.front_only,
                "{}: no {side:?} side",
                case.name
            );
            continue;
        };
        eprintln!(
            "{} [{language}, {side:?}, {} charts in {}×{}]: |GPU − CPU emulation| ≤ {emulation:.2e}; |GPU − exact| max {:.2e} (film.json states {:.2e})",
            case.name,
            stated.charts.len(),
            case.export.atlas.width,
            case.export.atlas.height,
            exact.iter().fold(0.0f64, |a, &b| a.max(b)),
            stated.error.max_all()
        );
        for (k, (&got, &bound)) in exact.iter().zip(&stated.error.max_abs).enumerate() {
            assert!(
                got <= bound + EMULATION_TOLERANCE,
                "{} [{language}, {side:?}]: channel {k} error {got:e} above the stated {bound:e}",
                case.name,
            );
        }
        assert!(stated.error.max_all() <= case.export.spec.target(side));
    }
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
        let case = make(name, spec);
        check_charts(&case);
        let Some(gpu) = &gpu else { continue };
        check(gpu, &case, "WGSL", wgsl_program(&wgsl, "irid_film"));
        check(gpu, &case, "GLSL 4.50", glsl_program(&glsl));
        check(gpu, &case, "GLSL ES 3.00", glsl_program(&glsl_es));
    }
}

/// Which sides an export has and how its charts are laid out: a dense
/// side's critical angle (inside the range, or the band a dispersive
/// substrate moves it over) is the edge of its bands; a
/// lossless substrate gets a back side, the reversed stack's own charts
/// unless the stack reads the same from both sides; past a lossless back
/// side's critical angle the exact response is total reflection.
fn check_charts(case: &Case) {
    let e = &case.export;
    let spec = &e.spec;
    let absorbs = spec.substrate_absorbs().unwrap();
    assert_eq!(e.opaque, absorbs, "{}: opaque", case.name);
    assert_eq!(
        e.side(Side::Back).is_some(),
        !absorbs && !spec.front_only,
        "{}: back side",
        case.name
    );
    for side in &e.sides {
        let seen = spec.seen_from(side.side);
        let (c0, c1) = seen.cos_theta;
        let charts: Vec<&irid::atlas::Chart> =
            side.charts.iter().map(|&k| &e.atlas.charts[k]).collect();
        if let Some(cc) = critical_cos(&seen.stack).filter(|&cc| cc > c0 && cc < c1) {
            // A dispersive substrate moves the critical angle over a band of
            // cos θ, whose ends the bands are cut at.
            let (lo, hi) = critical_band(&seen.stack, cc);
            let on_edge = charts.iter().any(|c| match c.coords {
                irid::atlas::Coords::Band { c: a, .. } => {
                    (a.lo >= lo - 1e-9 && a.lo <= hi + 1e-9)
                        || (a.hi >= lo - 1e-9 && a.hi <= hi + 1e-9)
                }
                _ => false,
            });
            assert!(on_edge, "{}: no band ends at cos θc {cc}", case.name);
        }
        let symmetric = seen.stack == spec.stack;
        let own = if side.side == Side::Back && !symmetric {
            Side::Back
        } else {
            Side::Front
        };
        assert!(
            charts.iter().all(|c| c.side == own),
            "{}: {:?} reads side {own:?}",
            case.name,
            side.side
        );
    }
    let back = spec.seen_from(Side::Back);
    let lossless = back.stack.layers.iter().all(|l| l.material.is_lossless());
    let past = critical_cos(&back.stack).filter(|&cc| cc - 0.01 > back.cos_theta.0);
    if let (Some(cc), false, true) = (past, absorbs, lossless) {
        let beyond: Vec<_> = case
            .points
            .iter()
            .zip(&case.exact[1])
            .filter(|(p, _)| f64::from(p[1]) < cc - 0.01)
            .collect();
        assert!(
            beyond.len() > 100,
            "{}: points past the critical angle",
            case.name
        );
        for (_, x) in beyond {
            assert!(
                x[..3].iter().all(|&r| (r - 1.0).abs() < 1e-3),
                "{}: {x:?}",
                case.name
            );
        }
    }
}

/// The cos θ the critical angle of `stack` (`cc` at 550 nm) moves over
/// from 380 to 780 nm.
fn critical_band(stack: &irid::optics::Stack, cc: f64) -> (f64, f64) {
    let (mut lo, mut hi) = (cc, cc);
    for nm in [380.0, 780.0] {
        if let (Ok(n0), Ok(ns)) = (stack.ambient.index_at(nm), stack.substrate.index_at(nm)) {
            if ns.re < n0.re {
                let c = (1.0 - (ns.re / n0.re).powi(2)).sqrt();
                lo = lo.min(c);
                hi = hi.max(c);
            }
        }
    }
    (lo, hi)
}
