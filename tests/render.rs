//! The tracer: table renders against the direct exact reference for every
//! built-in scene, determinism, the physics the pictures must show, and the
//! command line's handling of bad scene files.

// Not an API: a test crate has no public API to document.
#![allow(missing_docs)]

mod common;

use std::path::{Path, PathBuf};

#[cfg(feature = "cli")]
use common::{irid_in, Scratch};
use irid::color::Sampling;
use irid::render::{
    self, builtin_names, DirectFilm, FilmMode, FilmShading, Image, RenderOptions, Scene, Side,
};

/// Tables baked by these tests persist here between runs (keyed by content).
fn cache_dir() -> PathBuf {
    Path::new(env!("CARGO_TARGET_TMPDIR")).join("render-test-cache")
}

fn small(scene: &Scene, film: FilmMode, width: u32) -> Image {
    let s = scene.settings;
    let mut opts = RenderOptions::new(film);
    opts.width = Some(width);
    opts.height = Some((width * s.height / s.width).max(1));
    render::render(scene, &opts).expect("render")
}

/// For a figure of the paper, the LUT render and the direct render with
/// exact (1 nm) integration agree: mean CIEDE2000 ≤ 0.5, 99th percentile ≤ 2.
fn lut_matches_direct_exact(name: &str, width: u32) {
    let scene = Scene::builtin(name).unwrap().unwrap();
    let lut = small(&scene, FilmMode::lut(cache_dir()), width);
    let direct = small(
        &scene,
        FilmMode::Direct {
            sampling: Sampling::Exact,
        },
        width,
    );
    let de = lut.delta_e2000(&direct).unwrap();
    println!(
        "{name}: dE00 mean {:.4} p99 {:.4} max {:.4}",
        de.mean, de.p99, de.max
    );
    assert!(de.mean <= 0.5 && de.p99 <= 2.0, "{name}: {de:?}");
    // Guard against a vacuous pass: the scene must actually show something.
    let lit = lut
        .pixels
        .iter()
        .filter(|p| p.iter().any(|&c| c > 0.02))
        .count();
    assert!(lit > lut.pixels.len() / 2, "{name}: mostly black");
}

#[test]
fn every_builtin_scene_is_tested() {
    let tested = [
        "bubbles-uniform",
        "bubbles-noise",
        "absorbing-sphere",
        "absorbing-sphere-rough",
        "gain-ring",
        "blue-gem",
        "two-layer-noise",
    ];
    assert_eq!(builtin_names(), tested);
}

#[test]
fn lut_matches_direct_bubbles_uniform() {
    lut_matches_direct_exact("bubbles-uniform", 64);
}

#[test]
fn lut_matches_direct_bubbles_noise() {
    lut_matches_direct_exact("bubbles-noise", 64);
}

#[test]
fn lut_matches_direct_absorbing_sphere() {
    lut_matches_direct_exact("absorbing-sphere", 64);
}

/// The rough variant: the same microfacet normals in both modes (the
/// renders share their seeds), only the film's values differ.
#[test]
fn lut_matches_direct_absorbing_sphere_rough() {
    lut_matches_direct_exact("absorbing-sphere-rough", 64);
}

#[test]
fn lut_matches_direct_gain_ring() {
    lut_matches_direct_exact("gain-ring", 64);
}

#[test]
fn lut_matches_direct_blue_gem() {
    lut_matches_direct_exact("blue-gem", 48);
}

#[test]
fn lut_matches_direct_two_layer_noise() {
    lut_matches_direct_exact("two-layer-noise", 56);
}

/// Coarse wavelength sampling (the paper's first method) is visibly off on
/// a thin-film scene, so the comparison above is able to fail.
#[test]
fn rgb3_sampling_is_measurably_worse_than_the_tables() {
    let scene = Scene::builtin("bubbles-noise").unwrap().unwrap();
    let exact = small(
        &scene,
        FilmMode::Direct {
            sampling: Sampling::Exact,
        },
        60,
    );
    let rgb3 = small(
        &scene,
        FilmMode::Direct {
            sampling: Sampling::Rgb3,
        },
        60,
    );
    let lut = small(&scene, FilmMode::lut(cache_dir()), 60);
    let bad = rgb3.delta_e2000(&exact).unwrap();
    let good = lut.delta_e2000(&exact).unwrap();
    assert!(
        bad.p99 > 2.0 && bad.p99 > 10.0 * good.p99,
        "rgb3 {bad:?} vs lut {good:?}"
    );
}

#[test]
fn same_seed_same_image_whatever_the_thread_count() {
    let scene = Scene::builtin("bubbles-noise").unwrap().unwrap();
    let mut opts = RenderOptions::new(FilmMode::lut(cache_dir()));
    opts.width = Some(48);
    opts.height = Some(32);
    opts.spp = Some(4);
    opts.seed = 17;
    let films = render::prepare_films(&scene, &opts.film).unwrap();
    let on = |threads: usize, opts: &RenderOptions| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| render::render_with(&scene, &films, opts))
    };
    let a = on(1, &opts);
    let b = on(2, &opts);
    assert!(a
        .pixels
        .iter()
        .zip(&b.pixels)
        .all(|(x, y)| x.map(f32::to_bits) == y.map(f32::to_bits)));
    opts.seed = 18;
    let c = on(2, &opts);
    assert_ne!(
        a.pixels, c.pixels,
        "another seed moves the jittered samples"
    );
}

/// Fig. 9: with gain in the film, the coated gold reflects more than all of
/// the light somewhere in the ring's thickness range; bare gold never does.
#[test]
fn gain_film_amplifies() {
    let scene = Scene::builtin("gain-ring").unwrap().unwrap();
    let film = DirectFilm::new(&scene.films[0], Sampling::Exact).unwrap();
    let (lo, hi) = scene.films[0].thickness_range_nm;
    let max_r = (0..=40)
        .map(|i| lo + (hi - lo) * i as f32 / 40.0)
        .map(|d| {
            film.shade(d, 1.0, Side::Front)
                .reflectance
                .into_iter()
                .fold(0.0f32, f32::max)
        })
        .fold(0.0f32, f32::max);
    assert!(max_r > 1.0, "max reflectance {max_r}");
}

/// Fig. 7: a thick soap film shows almost no colour (its fringes average out
/// over the visible range), a thin one a strong colour.
#[test]
fn thick_films_fade_to_white() {
    let scene = Scene::builtin("bubbles-uniform").unwrap().unwrap();
    let chroma = |d: f32| {
        let f = scene
            .films
            .iter()
            .find(|f| f.thickness_range_nm.0 == d)
            .unwrap();
        let rgb = DirectFilm::new(f, Sampling::Exact)
            .unwrap()
            .shade(d, 0.9, Side::Front)
            .reflectance;
        let (mx, mn) = rgb
            .iter()
            .fold((0.0f32, 1.0f32), |(a, b), &v| (a.max(v), b.min(v)));
        (mx - mn) / (mx + mn)
    };
    let (thin, thick) = (chroma(350.0), chroma(1500.0));
    assert!(
        thin > 0.3 && thick < 0.5 * thin,
        "chroma 350 nm {thin}, 1500 nm {thick}"
    );
}

/// Light meeting the gem's film from inside beyond the critical angle is
/// totally reflected: nothing is transmitted.
#[test]
fn reversed_stack_reflects_totally_beyond_the_critical_angle() {
    let scene = Scene::builtin("blue-gem").unwrap().unwrap();
    let film = DirectFilm::new(&scene.films[0], Sampling::Exact).unwrap();
    let critical_cos = (1.0f32 - 1.0 / (1.76f32 * 1.76)).sqrt();
    let inside = film.shade(400.0, 0.5 * critical_cos, Side::Back);
    assert!(
        inside.transmittance.iter().all(|&t| t.abs() < 1e-6),
        "{inside:?}"
    );
    assert!(
        inside.reflectance.iter().all(|&r| (r - 1.0).abs() < 1e-3),
        "{inside:?}"
    );
    let outside = film.shade(400.0, 0.5 * critical_cos, Side::Front);
    assert!(
        outside.transmittance.iter().all(|&t| t > 0.1),
        "{outside:?}"
    );
}

#[cfg(feature = "cli")]
const GOOD: &str = r#"
[render]
width = 8
height = 6
[camera]
position = [0.0, 0.0, 5.0]
look_at = [0.0, 0.0, 0.0]
fov_deg = 40.0
[materials.soap]
kind = "film"
stack = { ambient = { n = 1.0 }, substrate = { n = 1.0 }, layers = [{ n = 1.33, thickness_nm = 400.0 }] }
[materials.white]
kind = "diffuse"
albedo = [0.8, 0.8, 0.8]
[[objects]]
shape = "sphere"
material = "soap"
center = [0.0, 0.0, 0.0]
radius = 1.0
"#;

#[cfg(feature = "cli")]
#[test]
fn cli_renders_a_scene_file_to_png_and_exr() {
    let dir = Scratch::new("render-cli-ok");
    dir.write("s.toml", GOOD);
    let cache = cache_dir();
    let run = irid_in(
        &dir,
        [
            "render",
            "s.toml",
            "-o",
            "s.png",
            "--exr",
            "s.exr",
            "--cache",
            cache.to_str().unwrap(),
        ],
    );
    assert_eq!(run.code, Some(0), "{}", run.stderr);
    let out = &run.stdout;
    assert!(out.contains("render") && out.contains("8x6"), "{out}");
    let png = ::image::open(dir.join("s.png")).unwrap();
    assert_eq!((png.width(), png.height()), (8, 6));
    let exr = exr::prelude::read_first_rgba_layer_from_file(
        dir.join("s.exr"),
        |res, _| vec![[0.0f32; 3]; res.width() * res.height()],
        |px, pos, (r, g, b, _a): (f32, f32, f32, f32)| px[pos.y() * 8 + pos.x()] = [r, g, b],
    )
    .unwrap();
    assert_eq!(exr.layer_data.size.width(), 8);
    // Linear radiance in the EXR, the same pixels sRGB-encoded in the PNG.
    let rgb = png.to_rgb8();
    let p = exr.layer_data.channel_data.pixels[3 * 8 + 4];
    let want = irid::color::linear_to_srgb8(p.map(f64::from));
    assert_eq!(rgb.get_pixel(4, 3).0, want);
    assert!(dir.join("s.exr").is_file());
}

/// In LUT mode a noise film's thickness is baked to a grid, and the run
/// says so; `--exact-noise` evaluates the noise at every hit instead. The
/// two images agree to within a few 8-bit levels (the grid's 2 nm).
#[cfg(feature = "cli")]
#[test]
fn cli_bakes_noise_thickness_unless_told_not_to() {
    let dir = Scratch::new("render-cli-noise");
    let cache = cache_dir();
    let render = |png: &str, extra: &[&str]| {
        let mut args = vec![
            "render",
            "two-layer-noise",
            "--width",
            "48",
            "--height",
            "48",
            "-o",
            png,
            "--cache",
            cache.to_str().unwrap(),
        ];
        args.extend_from_slice(extra);
        let run = irid_in(&dir, args);
        assert_eq!(run.code, Some(0), "{}", run.stderr);
        run.stdout
    };
    let gridded = render("grid.png", &[]);
    assert!(
        gridded.contains("thickness baked to 1 grid(s)") && gridded.contains("max error"),
        "{gridded}"
    );
    let exact = render("exact.png", &["--exact-noise"]);
    assert!(!exact.contains("thickness baked"), "{exact}");
    let a = ::image::open(dir.join("grid.png")).unwrap().to_rgb8();
    let b = ::image::open(dir.join("exact.png")).unwrap().to_rgb8();
    let worst = a
        .pixels()
        .zip(b.pixels())
        .flat_map(|(p, q)| (0..3).map(move |c| p.0[c].abs_diff(q.0[c])))
        .max()
        .unwrap();
    assert!(worst <= 6, "largest 8-bit difference {worst}");
}

/// Each bad input gives exit code 2, one line naming the problem, and no
/// output file.
#[cfg(feature = "cli")]
#[test]
fn cli_rejects_bad_scenes_with_one_line() {
    let cases: [(&str, String, &str); 6] = [
        ("malformed", "[camera\nposition = 1".into(), "s.toml"),
        (
            "unknown-material",
            GOOD.replace("material = \"soap\"", "material = \"glass\""),
            "unknown material 'glass'",
        ),
        (
            "unknown-kind",
            GOOD.replace("kind = \"diffuse\"", "kind = \"velvet\""),
            "velvet",
        ),
        (
            "missing-mesh",
            GOOD.replace(
                "shape = \"sphere\"\nmaterial = \"soap\"\ncenter = [0.0, 0.0, 0.0]\nradius = 1.0",
                "shape = \"obj\"\nmaterial = \"soap\"\npath = \"teapot.obj\"",
            ),
            "teapot.obj",
        ),
        (
            "missing-table",
            GOOD.replace(
                "layers = [{ n = 1.33,",
                "layers = [{ table = \"soap-nk.csv\",",
            ),
            "soap-nk.csv",
        ),
        (
            "bad-value",
            GOOD.replace("radius = 1.0", "radius = -1.0"),
            "radius",
        ),
    ];
    for (name, text, needle) in cases {
        let dir = Scratch::new(&format!("render-cli-{name}"));
        dir.write("s.toml", text);
        irid_in(&dir, ["render", "s.toml", "-o", "s.png", "--cache", "c"])
            .assert_one_line_error(name, &[needle]);
        assert!(!dir.join("s.png").exists(), "{name}: wrote an image");
    }
    let dir = Scratch::new("render-cli-no-scene");
    let run = irid_in(&dir, ["render", "no-such-scene"]);
    assert_eq!(run.code, Some(2));
    let err = &run.stderr;
    assert!(
        err.contains("no-such-scene") && err.contains("bubbles-noise"),
        "{err}"
    );
    let run = irid_in(
        &dir,
        [
            "render",
            "bubbles-noise",
            "--film",
            "lut",
            "--sampling",
            "rgb3",
        ],
    );
    assert_eq!(run.code, Some(2), "{}", run.stderr);
    let run = irid_in(
        &dir,
        [
            "render",
            "bubbles-noise",
            "--film",
            "direct",
            "--sampling",
            "uniform:1",
        ],
    );
    assert_eq!(run.code, Some(2), "{}", run.stderr);
}
