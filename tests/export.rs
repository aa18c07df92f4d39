//! `irid export`: every example stack exports over every angle; the
//! directory holds what docs/gpu.md promises (an atlas of RGBA half EXRs,
//! film.json with its charts, sides and uniform array, shaders, PNGs); the
//! texel at every node of each side's charts is the exact response from
//! that side; an absorbing
//! substrate is opaque; bad input is one line and exit 2 with no directory
//! left behind, half-written or not.

mod common;

use std::path::Path;

use common::{irid_in, Scratch};
use irid::export::{critical_cos, exact_at, export, ExportSpec, Side, SHADERS, UNIFORM_VEC4};
use irid::optics::Stack;

fn luts() -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("luts")
}

fn film_json(dir: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(dir.join("film.json")).unwrap()).unwrap()
}

/// The channel names, sample type and size of an EXR texture.
fn exr_layout(path: &Path) -> (Vec<String>, bool, (usize, usize)) {
    let image = common::read_exr(path);
    let layer = &image.layer_data;
    let names = layer
        .channel_data
        .list
        .iter()
        .map(|c| c.name.to_string())
        .collect();
    let half = layer
        .channel_data
        .list
        .iter()
        .all(|c| matches!(c.sample_data, exr::prelude::FlatSamples::F16(_)));
    (names, half, (layer.size.width(), layer.size.height()))
}

/// film.json's `texture.row_check` names a texel of the written EXR and its
/// mirror about the middle row, with their values, and no texel pair
/// differs more (the check tells a flipped load from a right one).
fn row_check_matches_the_file(film: &serde_json::Value, dir: &Path, quantity: &str, name: &str) {
    let check = &film["texture"]["row_check"][quantity];
    let image = common::read_exr(&dir.join(format!("{quantity}.exr")));
    let layer = &image.layer_data;
    let (w, h) = (layer.size.width(), layer.size.height());
    let plane = |channel: &str| -> Vec<f32> {
        let c = layer
            .channel_data
            .list
            .iter()
            .find(|c| c.name.to_string() == channel)
            .unwrap();
        c.sample_data.values_as_f32().collect()
    };
    let planes = [plane("R"), plane("G"), plane("B")];
    let rgb = |x: usize, y: usize| [0, 1, 2].map(|k| f64::from(planes[k][y * w + x]));
    let at = |key: &str| check[key].as_u64().unwrap() as usize;
    let (x, y) = (at("x"), at("y"));
    assert!(y < h / 2, "{name} {quantity}: {check}");
    let listed = |key: &str| -> Vec<f64> {
        check[key]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap())
            .collect()
    };
    assert_eq!(listed("value"), rgb(x, y), "{name} {quantity}");
    assert_eq!(listed("mirrored"), rgb(x, h - 1 - y), "{name} {quantity}");
    let gap = |a: [f64; 3], b: [f64; 3]| (0..3).fold(0.0f64, |g, k| g.max((a[k] - b[k]).abs()));
    let listed_gap = gap(rgb(x, y), rgb(x, h - 1 - y));
    for yy in 0..h / 2 {
        for xx in 0..w {
            assert!(
                gap(rgb(xx, yy), rgb(xx, h - 1 - yy)) <= listed_gap,
                "{name} {quantity}"
            );
        }
    }
}

/// Nothing but `keep` in `dir`: no temporary directory left behind.
fn only(dir: &Path, keep: &[&str]) {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    let mut want: Vec<String> = keep.iter().map(|s| s.to_string()).collect();
    want.sort();
    assert_eq!(names, want);
}

/// The side (0 or 1) whose charts each side reads, or None without it.
fn sides(film: &serde_json::Value) -> [Option<u64>; 2] {
    ["front", "back"].map(|s| {
        let charts = film["sides"][s]["charts"].as_array()?;
        let first = charts.first()?.as_u64()? as usize;
        film["charts"][first]["side"].as_u64()
    })
}

#[test]
fn every_example_stack_exports() {
    let scratch = Scratch::new("export");
    let mut stacks: Vec<_> = std::fs::read_dir(luts())
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .collect();
    stacks.sort();
    assert!(stacks.len() >= 6);
    for stack in &stacks {
        let name = stack.file_stem().unwrap().to_string_lossy().into_owned();
        let out = scratch.path().join(&name);
        let mut args = vec![
            "export",
            stack.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
        ];
        // Every table over every angle (cos θ 0 to 1, the default). The
        // gain film reflects up to 3, where f16 steps by 2e-3: a 1e-3
        // target is out of f16's reach there.
        let target = match name.as_str() {
            // Near grazing incidence (85°) it is resonant (R up to 3.8)
            // and its fringes sharpen beyond any chart: the range of its
            // table.
            "gain-on-gold" => {
                args.extend([
                    "--angles",
                    "0.2:1",
                    "--thickness",
                    "200:300",
                    "--max-error",
                    "3e-3",
                ]);
                3e-3
            }
            // Seen from its fused-silica side the mirror's critical angle
            // moves with the dispersion, and the exact solver there takes
            // minutes (docs/gpu.md): the front alone here.
            "mirror-10" => {
                args.push("--front-only");
                1e-3
            }
            _ => 1e-3,
        };
        let run = irid_in(scratch.path(), &args);
        assert!(run.success(), "{name}: {}", run.stderr);
        assert!(run.stdout.contains("texels"), "{name}: {}", run.stdout);
        let film = film_json(&out);
        assert_eq!(film["format"], "irid-film");
        assert_eq!(film["version"], 3);
        if name != "gain-on-gold" {
            assert_eq!(film["domain"]["cos_theta"], serde_json::json!([0.0, 1.0]));
        }
        let (w, h) = (
            film["texture"]["width"].as_u64().unwrap() as usize,
            film["texture"]["height"].as_u64().unwrap() as usize,
        );
        for texture in ["reflectance.exr", "transmittance.exr"] {
            let (channels, half, size) = exr_layout(&out.join(texture));
            assert_eq!(
                channels,
                ["A", "B", "G", "R"],
                "{name}: EXR lists channels sorted"
            );
            assert!(half, "{name}: {texture} is half float");
            assert_eq!(size, (w, h), "{name}: {texture}");
        }
        for (file, text) in SHADERS {
            assert_eq!(std::fs::read_to_string(out.join(file)).unwrap(), text);
        }
        for quantity in ["reflectance", "transmittance"] {
            row_check_matches_the_file(&film, &out, quantity, &name);
        }
        let uniform = film["uniform_f32"].as_array().unwrap();
        assert_eq!(uniform.len(), 4 * UNIFORM_VEC4);
        assert_eq!(
            (uniform[0].as_f64(), uniform[1].as_f64()),
            (Some(w as f64), Some(h as f64))
        );
        // A gold substrate absorbs: opaque, no back side. The others are
        // lossless: a back side, in the front chart when the stack reads
        // the same from both sides (the soap film), else in its own.
        let opaque = matches!(name.as_str(), "two-layer" | "gain-on-gold");
        assert_eq!(film["opaque"], opaque, "{name}");
        let want = match name.as_str() {
            _ if opaque => [Some(0), None],
            "mirror-10" => [Some(0), None],
            "soap-film" => [Some(0), Some(0)],
            _ => [Some(0), Some(1)],
        };
        assert_eq!(sides(&film), want, "{name}");
        let charts = film["charts"].as_array().unwrap();
        assert_eq!(uniform[2].as_f64(), Some(charts.len() as f64), "{name}");
        assert_eq!(uniform[3].as_f64(), Some(want[1].unwrap_or(0) as f64));
        for (k, chart) in charts.iter().enumerate() {
            let rect: Vec<usize> = chart["rect"]
                .as_array()
                .unwrap()
                .iter()
                .map(|v| v.as_u64().unwrap() as usize)
                .collect();
            assert!(
                rect[0] + rect[2] <= w && rect[1] + rect[3] <= h,
                "{name}: {rect:?}"
            );
            assert_eq!(chart["params"]["width"].as_f64().unwrap() as usize, rect[2]);
            assert!(["band", "corner"].contains(&chart["kind"].as_str().unwrap()));
            // The uniform array holds the chart's rectangle where docs/gpu.md says.
            let at = 4 * (2 + 4 * k);
            assert_eq!(
                uniform[at + 3].as_f64().unwrap() as usize,
                rect[3],
                "{name}"
            );
            assert_eq!(uniform[at + 4].as_f64(), chart["side"].as_f64(), "{name}");
        }
        assert_eq!(film["white"], "d65");
        for side in ["front", "back"]
            .iter()
            .take(if want[1].is_some() { 2 } else { 1 })
        {
            let e = &film["error"][side];
            let max: Vec<f64> = e["max_abs"]
                .as_array()
                .unwrap()
                .iter()
                .map(|v| v.as_f64().unwrap())
                .collect();
            assert_eq!(max.len(), 6);
            assert!(max.iter().all(|&e| e <= target), "{name} {side}: {max:?}");
            assert_eq!(e["points"], 20_000);
            assert_eq!(e["target_max_abs"], target);
        }
        assert!(film["texture"]["png"].is_null());
    }
    only(
        scratch.path(),
        &stacks
            .iter()
            .map(|s| s.file_stem().unwrap().to_str().unwrap())
            .collect::<Vec<_>>(),
    );
}

/// At every node of each side's chart the texel is the exact response
/// from that side rounded to f16, and film.json's axes list those nodes;
/// between nodes what the GPU computes meets the target at fresh points
/// too. Seen from the glass, past the critical angle, that is total
/// reflection.
#[test]
fn texels_are_the_exact_response_at_the_listed_nodes() {
    // Glass under a water-like film over air: the front has a critical
    // angle, the back (from the air) none.
    let text = "ambient = { n = 1.5 }\nsubstrate = { n = 1.0 }\n[[layers]]\nn = 1.33\nthickness_nm = 300.0\n";
    let stack = Stack::from_toml_str(text, Path::new("."), "dense").unwrap();
    let mut spec = ExportSpec::new(stack);
    spec.thickness_nm = (0.0, 600.0);
    spec.cos_theta = (0.05, 1.0);
    spec.points = 5000;
    let e = export(&spec, &|_| {}).unwrap();
    assert_eq!(e.sides.len(), 2);
    for side in [Side::Front, Side::Back] {
        let seen = spec.seen_from(side);
        let charts = &e.side(side).unwrap().charts;
        if let Some(cc) = critical_cos(&seen.stack) {
            // The critical angle is the edge of two bands.
            let edges = charts
                .iter()
                .filter(|&&k| match e.atlas.charts[k].coords {
                    irid::atlas::Coords::Band { c, .. } => c.lo == cc || c.hi == cc,
                    _ => false,
                })
                .count();
            assert!(edges >= 2, "{side:?}: {edges} bands end at {cc}");
        }
        for &k in charts {
            let chart = &e.atlas.charts[k];
            let r = chart.rect;
            let nodes: Vec<(usize, usize)> = (0..r.height)
                .step_by(3)
                .flat_map(|j| (0..r.width).step_by(11).map(move |i| (i, j)))
                .filter(|&(i, j)| {
                    // Nodes of the domain (a band's corners lie beyond it).
                    let (d, c) = chart.node(i, j);
                    d <= spec.thickness_nm.1 && c >= spec.cos_theta.0
                })
                .collect();
            let points: Vec<[f32; 2]> = nodes
                .iter()
                .map(|&(i, j)| {
                    let (d, c) = chart.node(i, j);
                    [d as f32, c as f32]
                })
                .collect();
            let exact = exact_at(&spec, side, &points).unwrap();
            for ((i, j), x) in nodes.iter().zip(&exact) {
                let texel = e.reflectance.texels[(r.y + j) * e.atlas.width + r.x + i];
                for k in 0..3 {
                    // f16 rounding, and the f32 node position's distance
                    // from the f64 one.
                    assert!(
                        (f64::from(texel[k]) - x[k]).abs() < 6e-4,
                        "{side:?} node {i},{j}: {texel:?} vs {x:?}"
                    );
                }
            }
        }
        // Fresh points (another seed's worth: every third of 3× as many).
        let mut fresh = spec.clone();
        fresh.points = 15_000;
        let pts: Vec<[f32; 2]> = irid::export::measurement_points(&fresh)
            .into_iter()
            .skip(5000)
            .collect();
        let exact = exact_at(&spec, side, &pts).unwrap();
        let mut worst = 0.0f64;
        let mut total = 0;
        for (p, x) in pts.iter().zip(&exact) {
            let (r, t) = e.sample(p[0], p[1], side);
            for k in 0..3 {
                worst = worst.max((f64::from(r[k]) - x[k]).abs());
                worst = worst.max((f64::from(t[k]) - x[3 + k]).abs());
            }
            // Seen from the glass, beyond the critical angle: total reflection.
            if side == Side::Front && f64::from(p[1]) < critical_cos(&spec.stack).unwrap() - 1e-3 {
                assert!(r.iter().all(|&v| (v - 1.0).abs() < 1e-3), "{p:?}: {r:?}");
                total += 1;
            }
        }
        assert!(worst <= 1e-3, "{side:?}: {worst}");
        assert!(
            side == Side::Back || total > 1000,
            "{total} points past the critical angle"
        );
    }
}

/// A film over copper is opaque: what enters the metal is absorbed, and
/// film.json says so though the transmittance is not zero; there is no
/// back side. Over glass the same film transmits and has a back side with
/// total internal reflection.
#[test]
fn an_absorbing_substrate_is_opaque() {
    let scratch = Scratch::new("export");
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    for (stack, opaque) in [("film-on-copper.toml", true), ("film-on-glass.toml", false)] {
        let path = root.join("tests/blender").join(stack);
        let run = irid_in(
            scratch.path(),
            [
                "export",
                path.to_str().unwrap(),
                "-o",
                "out",
                "--thickness",
                "200:400",
                "--points",
                "2000",
            ],
        );
        assert!(run.success(), "{stack}: {}", run.stderr);
        let film = film_json(&scratch.path().join("out"));
        assert_eq!(film["opaque"], opaque, "{stack}");
        let back = &film["sides"]["back"];
        assert_eq!(back.is_null(), opaque, "{stack}");
        let t = film["error"]["front"]["max_abs"][3].as_f64().unwrap();
        assert!(t.is_finite(), "{stack}");
        let ratio = &film["refraction"]["substrate_over_ambient"];
        assert_eq!(ratio.as_f64(), (!opaque).then_some(1.5), "{stack}");
        if !opaque {
            let first = back["charts"][0].as_u64().unwrap() as usize;
            assert_eq!(film["charts"][first]["side"], 1);
            assert_eq!(back["stack"], "reversed");
            let cc = back["critical_cos"].as_f64().unwrap();
            assert!((cc - (1.0f64 - 1.0 / 2.25).sqrt()).abs() < 1e-12, "{cc}");
        }
    }
    // The copper film's transmittance (into the metal) is not zero: it is
    // the absorbing substrate that makes it opaque.
    let stack = Stack::load(&root.join("tests/blender/film-on-copper.toml")).unwrap();
    let mut spec = ExportSpec::new(stack);
    spec.points = 100;
    let e = export(&spec, &|_| {}).unwrap();
    assert!(e.opaque && e.sides.len() == 1);
    assert!(e.transmittance.texels.iter().any(|t| t[0] > 0.1));
}

#[test]
fn png_option_writes_16_bit_pngs_with_their_own_error() {
    let scratch = Scratch::new("export");
    let stack = luts().join("soap-film.toml");
    let run = irid_in(
        scratch.path(),
        [
            "export",
            stack.to_str().unwrap(),
            "-o",
            "soap",
            "--thickness",
            "0:800",
            "--png",
            "--white",
            "e",
        ],
    );
    assert!(run.success(), "{}", run.stderr);
    assert!(run.stdout.contains("PNG"), "{}", run.stdout);
    let dir = scratch.path().join("soap");
    let film = film_json(&dir);
    assert_eq!(film["white"], "e");
    // Saturated colours of a passive film can exceed 1 in one channel (the
    // sRGB matching functions have negative lobes): the scale covers them.
    let scale = film["texture"]["png"]["scale"].as_f64().unwrap();
    assert!(scale >= 1.0 && (scale * 16.0).fract() == 0.0, "{scale}");
    let png = image::open(dir.join("reflectance.png")).unwrap();
    assert_eq!(png.color(), image::ColorType::Rgba16);
    assert_eq!(
        png.width() as u64,
        film["texture"]["width"].as_u64().unwrap()
    );
    let png_err = film["error"]["front"]["png"]["max_abs"].as_array().unwrap();
    let exr_err = film["error"]["front"]["max_abs"].as_array().unwrap();
    // The PNGs clamp out-of-gamut (negative) values to 0, which the EXRs
    // keep, and quantize to 16 bits: their measured error is stated on its
    // own, finite, and never below the EXRs' beyond quantization (1.5e-5).
    for (p, x) in png_err.iter().zip(exr_err) {
        let (p, x) = (p.as_f64().unwrap(), x.as_f64().unwrap());
        assert!(p.is_finite() && p + 2e-5 >= x, "png {p} exr {x}");
    }
    assert!(film["error"]["front"]["png"]["max_delta_e00"][0]
        .as_f64()
        .unwrap()
        .is_finite());
}

#[test]
fn export_replaces_an_earlier_export_atomically_and_nothing_else() {
    let scratch = Scratch::new("export");
    let stack = luts().join("soap-film.toml");
    let s = stack.to_str().unwrap();
    let d = scratch.path();
    assert!(irid_in(d, ["export", s, "-o", "out", "--thickness", "0:300"]).success());
    let first = film_json(&d.join("out"));
    assert!(irid_in(d, ["export", s, "-o", "out", "--thickness", "0:600"]).success());
    let second = film_json(&d.join("out"));
    assert_ne!(first["domain"], second["domain"]);
    assert_eq!(second["domain"]["thickness_nm"][1], 600.0);
    only(d, &["out"]);
    // An empty directory is filled.
    std::fs::create_dir(d.join("empty")).unwrap();
    assert!(irid_in(d, ["export", s, "-o", "empty"]).success());
    // A directory with other things is not deleted.
    std::fs::create_dir(d.join("mine")).unwrap();
    std::fs::write(d.join("mine/notes.txt"), "keep").unwrap();
    irid_in(d, ["export", s, "-o", "mine"])
        .assert_one_line_error("foreign dir", &["mine", "irid export"]);
    assert_eq!(
        std::fs::read_to_string(d.join("mine/notes.txt")).unwrap(),
        "keep"
    );
    only(d, &["out", "empty", "mine"]);
}

#[test]
fn bad_input_is_one_line_and_leaves_no_directory() {
    let scratch = Scratch::new("export");
    let d = scratch.path();
    let soap = luts().join("soap-film.toml");
    let soap = soap.to_str().unwrap();
    let gain = luts().join("gain-on-gold.toml");
    let gain = gain.to_str().unwrap();
    std::fs::write(d.join("file"), "x").unwrap();
    let cases: [(&[&str], &[&str]); 9] = [
        (&["export", soap, "-o", "file"], &["file", "not a folder"]),
        (
            &["export", soap, "-o", "o", "--max-error", "1e-5"],
            &["max-error", "f16"],
        ),
        (&["export", soap, "-o", "o", "--layer", "3"], &["layer"]),
        (
            &["export", soap, "-o", "o", "--thickness", "-5:10"],
            &["thickness"],
        ),
        (
            &["export", soap, "-o", "o", "--angles", "0:1.5"],
            &["angles"],
        ),
        (&["export", soap, "-o", "o", "--white", "d50"], &["white"]),
        (
            &["export", soap, "-o", "o", "--back-max-error", "0"],
            &["back-max-error", "positive"],
        ),
        (
            &["export", soap, "-o", "o", "--back-max-error", "1e-4"],
            &["back-max-error", "f16"],
        ),
        (
            &[
                "export",
                gain,
                "-o",
                "o",
                "--thickness",
                "0:1000",
                "--angles",
                "0:1",
            ],
            &["gain film", "lasing pole"],
        ),
    ];
    for (args, names) in cases {
        irid_in(d, args).assert_one_line_error(&format!("{args:?}"), names);
    }
    assert_eq!(std::fs::read_to_string(d.join("file")).unwrap(), "x");
    only(d, &["file"]);
}

/// `--white e`: a flat spectrum is (1, 1, 1) channel by channel; a table
/// baked with it says so in its header (version 3), reads back, and
/// validates against the same convention.
#[test]
fn white_e_is_flat_and_recorded_in_tables() {
    use irid::color::{Sampling, SpectralIntegrator, White};
    for sampling in [Sampling::Exact, Sampling::Uniform(41)] {
        let e = SpectralIntegrator::with_white(sampling, White::E);
        let flat = vec![0.37; e.wavelengths_nm().len()];
        for c in e.rgb(&flat) {
            assert!((c - 0.37).abs() < 1e-12, "{sampling}: {c}");
        }
        // A single-wavelength spike: E weighs wavelengths by the CMFs
        // alone, D65 by D65 × CMFs, so they differ in colour.
        let d = SpectralIntegrator::new(sampling);
        let mut spike = vec![0.0; flat.len()];
        spike[flat.len() / 4] = 1.0;
        assert_ne!(e.rgb(&spike), d.rgb(&spike));
    }
    let stack = Stack::from_toml_str(
        "ambient = { n = 1.0 }\nsubstrate = { n = 1.5 }\n[[layers]]\nn = 1.33\nthickness_nm = 300.0\n",
        Path::new("."),
        "film",
    )
    .unwrap();
    let mut spec = irid::lut::BakeSpec::new(stack);
    spec.thickness_nm = (100.0, 400.0);
    spec.sampling = Sampling::Uniform(31);
    spec.white = White::E;
    spec.validation_points = 2000;
    // An error target bakes an atlas (version 4, whatever the white) by
    // default; the grid layout keeps versions 2 and 3.
    spec.layout = irid::lut::Layout::Grid;
    let lut = irid::lut::bake(&spec).unwrap();
    assert_eq!(lut.header().version, irid::lut::WHITE_E_VERSION);
    assert_eq!(lut.header().color.white, White::E);
    let scratch = Scratch::new("export");
    let path = scratch.path().join("e.exr");
    lut.write(&path).unwrap();
    let back = irid::lut::Lut::load(&path).unwrap();
    assert_eq!(back.header().color.white, White::E);
    assert_eq!(back.header().version, irid::lut::WHITE_E_VERSION);
    let stats = irid::lut::validate(&back, 2000, 3).unwrap();
    assert!(
        stats.figures.max_abs.iter().all(|&e| e <= 1e-3),
        "{:?}",
        stats.figures.max_abs
    );
    // The D65 table of the same spec keeps version 2 and no white field.
    spec.white = White::D65;
    let d65 = irid::lut::bake(&spec).unwrap();
    assert_eq!(d65.header().version, irid::lut::FORMAT_VERSION);
    let json = serde_json::to_string(d65.header()).unwrap();
    assert!(!json.contains("\"white\""));
    spec.white = White::E;
    spec.layout = irid::lut::Layout::Atlas;
    let atlas = irid::lut::bake(&spec).unwrap();
    assert_eq!(atlas.header().version, irid::lut::ATLAS_VERSION);
    assert_eq!(atlas.header().color.white, White::E);
}
