//! Lookup tables: the error of baked tables against the solver (for every
//! shipped stack and at the hard angles), the file round trip, bad files,
//! and the `bake`/`info`/`validate` commands.

// Not an API: a test crate has no public API to document.
#![allow(missing_docs)]

mod common;
mod tables;

use std::path::Path;

use common::Scratch;
#[cfg(feature = "cli")]
use common::{irid, Run};
use irid::color::Sampling;
use irid::lut::{bake, validate, BakeSpec, Kind, Layout, Lut, Resolution};
use irid::optics::{Layer, Material, Stack};
use rand::{Rng, SeedableRng};
use tables::{luts_dir, quick_spec, worst, worst_targeted};

/// Bakes, then validates at fresh random points: the table must meet the
/// bound recorded in its header (the --max-error target, which the bake
/// check and the bake's own 20000-point validation met) wherever it
/// applies.
fn bake_and_check(name: &str, spec: &BakeSpec, target: f64) -> irid::lut::Validation {
    let lut = bake(spec).unwrap_or_else(|e| panic!("{name}: {e}"));
    let h = lut.header();
    let bound = h.error.target_max_abs.expect("an error target");
    assert_eq!(bound, target);
    let check = h
        .error
        .bake_check
        .as_ref()
        .expect("a bake check")
        .max_abs_all;
    assert!(check <= bound, "{name}: bake check {check} > bound {bound}");
    let recorded = h.error.validation.as_ref().expect("validation recorded");
    assert!(worst_targeted(recorded) <= bound);
    let stats = validate(&lut, 3000, 7).unwrap();
    let sizes: Vec<usize> = match &h.atlas {
        Some(t) => vec![t.atlas.width, t.atlas.height],
        None => h.axes.iter().map(|a| a.nodes.len()).collect(),
    };
    eprintln!(
        "{name}: nodes or texels {sizes:?}, bake check {check:.3e}, validation max {:.3e} mean {:.3e}",
        worst(&stats.figures.max_abs),
        stats.figures.mean_abs.iter().sum::<f64>() / stats.figures.mean_abs.len() as f64
    );
    for r in &stats.regions {
        eprintln!(
            "  {:<9} {:>5} points  max {:.3e}  mean {:.3e}",
            r.name, r.points, r.max_abs, r.mean_abs
        );
    }
    // Fresh points can find a peak between the bake's points: a tenth to
    // spare.
    assert!(
        worst_targeted(&stats) <= 1.1 * bound,
        "{name}: validation max {} exceeds the recorded bound {bound}",
        worst_targeted(&stats)
    );
    stats
}

#[test]
fn every_shipped_stack_meets_its_recorded_bound() {
    // The gain film keeps away from its lasing poles (R → ∞ near grazing
    // incidence and at other thicknesses), which no table can follow.
    let default_cos = (irid::lut::DEFAULT_COS_MIN, 1.0);
    let ranges = [
        ("soap-film", (0.0, 1000.0), default_cos),
        ("oil-on-water", (0.0, 1000.0), default_cos),
        ("absorbing-film", (0.0, 1000.0), default_cos),
        ("gain-on-gold", (200.0, 300.0), (0.2, 1.0)),
        ("two-layer", (0.0, 500.0), default_cos),
        ("mirror-10", (0.0, 200.0), default_cos),
    ];
    for (name, thickness, cos) in ranges {
        let stack = Stack::load(&luts_dir().join(format!("{name}.toml"))).unwrap();
        let mut spec = quick_spec(stack, thickness, 2e-3);
        spec.cos_theta = cos;
        bake_and_check(name, &spec, 2e-3);
    }
}

fn dense_side_film() -> Stack {
    Stack {
        ambient: Material::constant(1.5, 0.0),
        layers: vec![Layer::new(Material::constant(1.38, 0.0), 100.0)],
        substrate: Material::constant(1.0, 0.0),
    }
}

#[test]
fn critical_angle_and_grazing_from_the_dense_side() {
    // Glass | MgF2-like film | air, seen from the glass: total internal
    // reflection beyond θc = 41.8°, and incidence all the way to 90°. A grid
    // puts a node on the critical angle.
    let mut spec = quick_spec(dense_side_film(), (0.0, 400.0), 1e-3);
    spec.cos_theta = (0.0, 1.0);
    spec.layout = Layout::Grid;
    let stats = bake_and_check("dense side", &spec, 1e-3);
    let lut = bake(&spec).unwrap();
    let cos_nodes = &lut.header().axes[1].nodes;
    let cc = (1.0f64 - (1.0 / 1.5f64).powi(2)).sqrt();
    assert!(
        cos_nodes.iter().any(|&c| (c - cc).abs() < 1e-12),
        "the critical angle is a node"
    );
    for region in ["critical", "grazing"] {
        let r = stats
            .regions
            .iter()
            .find(|r| r.name == region)
            .unwrap_or_else(|| panic!("no {region} region reported"));
        assert!(r.points > 50, "{region}: only {} points", r.points);
        assert!(r.max_abs <= 1e-3, "{region}: max {}", r.max_abs);
    }
}

#[test]
fn graded_critical_angle_beats_a_uniform_grid_of_the_same_size() {
    // The same node count, with and without the graded nodes around θc.
    let mut spec = quick_spec(dense_side_film(), (100.0, 100.0), 1.0);
    spec.cos_theta = (0.0, 1.0);
    spec.resolution = Resolution::Nodes {
        thickness: 1,
        angle: 65,
        wavelength: 1,
    };
    let graded = validate(&bake(&spec).unwrap(), 4000, 3).unwrap();
    let mut uniform_spec = spec.clone();
    // A substrate of k = 1e-9 has no sharp critical angle for the baker to
    // grade around, yet the same response to 1e-7.
    uniform_spec.stack.substrate = Material::constant(1.0, 1e-9);
    let uniform = validate(&bake(&uniform_spec).unwrap(), 4000, 3).unwrap();
    eprintln!(
        "65 angle nodes: graded max {:.3e}, uniform max {:.3e}",
        worst(&graded.figures.max_abs),
        worst(&uniform.figures.max_abs)
    );
    assert!(worst(&graded.figures.max_abs) * 5.0 < worst(&uniform.figures.max_abs));
}

#[test]
fn free_standing_film_at_grazing_incidence() {
    // A soap film near 89°, where the response changes fastest (around zero
    // thickness its scale shrinks with cos θ).
    let stack = Stack::load(&luts_dir().join("soap-film.toml")).unwrap();
    let mut spec = quick_spec(stack, (0.0, 300.0), 1e-3);
    spec.cos_theta = (irid::lut::DEFAULT_COS_MIN, 0.2);
    let stats = bake_and_check("soap film, 78°–89°", &spec, 1e-3);
    // With 31 wavelengths the colour integration itself aliases near 89°
    // (its fringes narrower than two of its 13 nm steps): the target holds
    // above that, and the strip below is a few percent of the range.
    let grazing = stats.regions.iter().find(|r| r.name == "grazing").unwrap();
    let resolved = stats.regions.iter().find(|r| r.name == "resolved");
    assert!(resolved.is_none_or(|r| r.max_abs <= 1.1e-3));
    let aliased = stats.regions.iter().find(|r| r.name == "aliased");
    assert!(aliased.is_none_or(|a| a.points < grazing.points / 4));
}

/// A TiO2 film on one face of a millimetre of glass with an MgF2 coating on
/// the other, in air: the glass is incoherent.
fn coated_sheet() -> Stack {
    let builtin = |name| irid::optics::library::builtin(name).unwrap();
    Stack {
        ambient: Material::constant(1.0, 0.0),
        layers: vec![
            Layer::new(builtin("TiO2"), 100.0),
            Layer {
                coherent: false,
                ..Layer::new(builtin("fused-silica"), 1e6)
            },
            Layer::new(builtin("MgF2"), 100.0),
        ],
        substrate: Material::constant(1.0, 0.0),
    }
}

#[test]
fn a_film_on_one_face_of_a_thick_sheet() {
    // The thickness axis on the film, the sheet's two faces summed in power:
    // the table meets its target against the incoherent solver, rgb and
    // spectral, and its nodes are the solver's values.
    let spec = quick_spec(coated_sheet(), (0.0, 400.0), 1e-3);
    bake_and_check("coated sheet", &spec, 1e-3);
    // On a grid, whose nodes are the solver's values (the atlas reads its
    // wavelength nodes at scaled thicknesses).
    let mut spec = quick_spec(coated_sheet(), (0.0, 300.0), 2e-3);
    spec.kind = Kind::Spectral;
    spec.wavelength_nm = (400.0, 700.0);
    spec.layout = Layout::Grid;
    let lut = bake(&spec).unwrap();
    let h = lut.header();
    let (t, c, w) = (h.axes[0].nodes[5], h.axes[1].nodes[3], h.axes[2].nodes[2]);
    let mut stack = h.stack.clone();
    assert!(!stack.layers[1].coherent, "the header keeps the flag");
    stack.layers[0].thickness_nm = t;
    let direct = stack.response(w, c).unwrap();
    let (r, tr) = lut.sample_spectral(t as f32, c as f32, w as f32);
    assert!(
        (f64::from(r) - direct.r()).abs() < 1e-6,
        "{r} vs {}",
        direct.r()
    );
    assert!(
        (f64::from(tr) - direct.t()).abs() < 1e-6,
        "{tr} vs {}",
        direct.t()
    );
}

fn small_table(half: bool) -> Lut {
    let stack = Stack::load(&luts_dir().join("two-layer.toml")).unwrap();
    let mut spec = quick_spec(stack, (50.0, 400.0), 1.0);
    spec.resolution = Resolution::Nodes {
        thickness: 37,
        angle: 11,
        wavelength: 1,
    };
    spec.half = half;
    bake(&spec).unwrap()
}

#[test]
fn write_read_round_trip_is_bit_exact() {
    let dir = Scratch::new("lut-roundtrip");
    for half in [false, true] {
        let lut = small_table(half);
        let path = dir.join(format!("t-{half}.exr"));
        lut.write(&path).unwrap();
        let back = Lut::load(&path).unwrap();
        assert_eq!(back.header(), lut.header());
        let bits = |l: &Lut| l.data().iter().map(|v| v.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&back), bits(&lut), "half = {half}");
        // Half floats are deflated; 32-bit floats, which deflate hardly
        // shrinks, are stored as they are.
        let compression = common::read_exr(&path).layer_data.encoding.compression;
        let expected = if half {
            exr::compression::Compression::ZIP16
        } else {
            exr::compression::Compression::Uncompressed
        };
        assert_eq!(compression, expected, "half = {half}");
        // No temporary file is left beside the table.
        let left: Vec<_> = std::fs::read_dir(&dir)
            .unwrap()
            .filter_map(|e| e.ok())
            .filter(|e| e.file_name().to_string_lossy().contains("tmp"))
            .collect();
        assert!(left.is_empty());
    }
    // A spectral table too, with its wavelength blocks folded into y.
    let stack = Stack::load(&luts_dir().join("oil-on-water.toml")).unwrap();
    let mut spec = quick_spec(stack, (100.0, 300.0), 1.0);
    spec.kind = Kind::Spectral;
    spec.half = true;
    spec.validation_points = 0;
    spec.resolution = Resolution::Nodes {
        thickness: 9,
        angle: 5,
        wavelength: 7,
    };
    let lut = bake(&spec).unwrap();
    let path = dir.join("spectral.exr");
    lut.write(&path).unwrap();
    let back = Lut::load(&path).unwrap();
    assert_eq!(back.header(), lut.header());
    assert_eq!(back.data(), lut.data());
    // f16 tables are about half the size of f32 ones and their recorded
    // error includes the rounding.
    let f32_size = std::fs::metadata(dir.join("t-false.exr")).unwrap().len();
    let f16_size = std::fs::metadata(dir.join("t-true.exr")).unwrap().len();
    assert!(f16_size < f32_size);
}

#[test]
fn sampling_clamps_outside_the_axes() {
    let lut = small_table(false);
    let inside = lut.sample_rgb(50.0, 1.0);
    assert_eq!(lut.sample_rgb(-20.0, 3.0), inside);
    assert_eq!(lut.sample_rgb(f32::NAN, 1.0), inside);
    let far = lut.sample_rgb(400.0, lut.header().axes[1].nodes[0] as f32);
    assert_eq!(lut.sample_rgb(1e9, -1.0), far);
}

#[test]
fn cache_key_follows_the_spec() {
    let stack = Stack::load(&luts_dir().join("soap-film.toml")).unwrap();
    let a = quick_spec(stack, (0.0, 100.0), 1e-3);
    assert_eq!(a.cache_key(), a.clone().cache_key());
    let mut b = a.clone();
    b.half = true;
    let mut c = a.clone();
    c.stack.layers[0].thickness_nm = 501.0;
    let mut d = a.clone();
    d.thickness_nm.1 = 101.0;
    let mut e = a.clone();
    e.layout = Layout::Grid;
    let keys = [
        a.cache_key(),
        b.cache_key(),
        c.cache_key(),
        d.cache_key(),
        e.cache_key(),
    ];
    for i in 0..keys.len() {
        for j in 0..i {
            assert_ne!(keys[i], keys[j]);
        }
    }
    // Where the layout decides nothing (a fixed resolution), naming it
    // does not change the key: the command line names the grid, the
    // library's default spec does not.
    let mut fixed = a.clone();
    fixed.resolution = Resolution::Nodes {
        thickness: 96,
        angle: 24,
        wavelength: 1,
    };
    let mut named = fixed.clone();
    named.layout = Layout::Grid;
    assert_eq!(fixed.cache_key(), named.cache_key());
}

#[test]
fn without_a_range_one_thickness_row() {
    // The stack's own thickness, and a stack with no layers at all.
    let stack = Stack::load(&luts_dir().join("oil-on-water.toml")).unwrap();
    let mut spec = BakeSpec::new(stack.clone());
    spec.sampling = Sampling::Uniform(31);
    let lut = bake(&spec).unwrap();
    assert_eq!(lut.header().axes[0].nodes, vec![300.0]);
    let mut bare = stack;
    bare.layers.clear();
    let mut spec = BakeSpec::new(bare.clone());
    spec.sampling = Sampling::Uniform(31);
    let lut = bake(&spec).unwrap();
    assert_eq!(lut.header().layer, 0);
    assert_eq!(lut.header().axes[0].nodes.len(), 1);
    let stats = validate(&lut, 500, 2).unwrap();
    assert!(
        worst(&stats.figures.max_abs)
            <= lut
                .header()
                .error
                .bake_check
                .as_ref()
                .unwrap()
                .max_abs_all
                .max(1e-6)
    );
    // Any thickness reads the one row.
    assert_eq!(lut.sample_rgb(0.0, 0.5), lut.sample_rgb(1e4, 0.5));
}

#[test]
fn cache_bakes_once_and_rebakes_stale_tables() {
    let dir = Scratch::new("lut-cache");
    let stack = Stack::load(&luts_dir().join("absorbing-film.toml")).unwrap();
    let spec = quick_spec(stack, (0.0, 200.0), 5e-3);
    let first = irid::lut::cached(&spec, &dir).unwrap();
    let path = dir.join(format!("{}.exr", spec.cache_key()));
    let written = std::fs::metadata(&path).unwrap().modified().unwrap();
    let again = irid::lut::cached(&spec, &dir).unwrap();
    assert_eq!(again.data(), first.data());
    assert_eq!(
        std::fs::metadata(&path).unwrap().modified().unwrap(),
        written
    );
    // A corrupt cache entry is rebaked, not an error.
    std::fs::write(&path, b"not an exr").unwrap();
    let rebaked = irid::lut::cached(&spec, &dir).unwrap();
    assert_eq!(rebaked.data(), first.data());
    assert!(Lut::load(&path).is_ok());
}

/// Rewrites the `irid` header of a table file in place of the original,
/// through the exr crate, keeping the pixels.
fn rewrite_header(src: &Path, dst: &Path, edit: impl Fn(&mut serde_json::Value)) {
    use exr::prelude::*;
    let mut image = read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .first_valid_layer()
        .all_attributes()
        .from_file(src)
        .unwrap();
    let key = Text::from("irid");
    let AttributeValue::Text(text) = &image.layer_data.attributes.other[&key] else {
        panic!("no text header");
    };
    let mut json: serde_json::Value = serde_json::from_str(&text.to_string()).unwrap();
    edit(&mut json);
    // EXR text is bytes: escape non-ASCII as irid's writer does.
    let ascii: String = json
        .to_string()
        .chars()
        .map(|c| {
            if c.is_ascii() {
                c.to_string()
            } else {
                let mut buf = [0u16; 2];
                c.encode_utf16(&mut buf)
                    .iter()
                    .map(|u| format!("\\u{u:04x}"))
                    .collect()
            }
        })
        .collect();
    image
        .layer_data
        .attributes
        .other
        .insert(key, AttributeValue::Text(Text::from(ascii.as_str())));
    image.write().to_file(dst).unwrap();
}

#[test]
fn bad_files_give_clear_errors() {
    let dir = Scratch::new("lut-bad");
    let good = dir.join("good.exr");
    small_table(false).write(&good).unwrap();
    let bytes = std::fs::read(&good).unwrap();

    let expect = |path: &Path, needle: &str| {
        let err = Lut::load(path).expect_err("must fail").to_string();
        assert!(err.contains(&path.display().to_string()), "{err}");
        assert!(err.contains(needle), "'{err}' lacks '{needle}'");
    };

    let truncated = dir.join("truncated.exr");
    std::fs::write(&truncated, &bytes[..bytes.len() * 2 / 3]).unwrap();
    expect(&truncated, "OpenEXR");

    let garbage = dir.join("garbage.exr");
    let mut corrupt = bytes.clone();
    for b in corrupt.iter_mut().skip(8).take(64) {
        *b = 0xA5;
    }
    std::fs::write(&garbage, &corrupt).unwrap();
    expect(&garbage, "OpenEXR");

    let version = dir.join("version.exr");
    rewrite_header(&good, &version, |j| j["version"] = 99.into());
    expect(&version, "format version 99");

    let mismatch = dir.join("mismatch.exr");
    rewrite_header(&good, &mismatch, |j| {
        let nodes = j["axes"][1]["nodes"].as_array_mut().unwrap();
        nodes.pop();
    });
    expect(&mismatch, "header's axes give");

    let channels = dir.join("channels.exr");
    rewrite_header(&good, &channels, |j| j["kind"] = "spectral".into());
    expect(&channels, "channel");

    let missing = dir.join("missing.exr");
    expect(&missing, "No such file");
}

#[cfg(feature = "cli")]
/// `irid bake luts/soap-film.toml -o OUT` over 100–400 nm with 16-sample
/// integration, then `extra`.
fn bake_soap(out: &Path, extra: &[&str]) -> Run {
    let stack = luts_dir().join("soap-film.toml");
    let mut args = vec![
        "bake",
        stack.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--thickness",
        "100:400",
        "--sampling",
        "uniform:16",
    ];
    args.extend_from_slice(extra);
    irid(&args)
}

#[cfg(feature = "cli")]
#[test]
fn bake_info_validate_commands() {
    let dir = Scratch::new("lut-cli");
    let out = dir.join("soap.exr");
    let stack = luts_dir().join("soap-film.toml");
    // The grid layout, and the atlas (the default).
    let grid = dir.join("soap-grid.exr");
    let o = bake_soap(
        &grid,
        &[
            "--max-error",
            "3e-3",
            "--validate-points",
            "500",
            "--layout",
            "grid",
        ],
    );
    assert!(o.success(), "{}", o.stderr);
    let o = bake_soap(&out, &["--max-error", "3e-3", "--validate-points", "500"]);
    assert!(o.success(), "{}", o.stderr);
    for (file, needles) in [
        (&grid, &["thickness_nm", "cos_theta", "v2"][..]),
        (
            &out,
            &["atlas:", "band cos θ", "optical thickness", "v4"][..],
        ),
    ] {
        let info = irid(["info", file.to_str().unwrap()]);
        let text = &info.stdout;
        assert!(info.success());
        for needle in needles
            .iter()
            .chain(&["soap film", "uniform:16", "bake check", "CIEDE2000"])
        {
            assert!(text.contains(needle), "info lacks {needle}:\n{text}");
        }
    }
    let v = irid([
        "validate",
        out.to_str().unwrap(),
        "--points",
        "300",
        "--json",
    ]);
    assert!(v.success());
    let json: serde_json::Value = serde_json::from_str(&v.stdout).unwrap();
    for key in [
        "max_abs",
        "mean_abs",
        "p99_abs",
        "max_de2000",
        "mean_de2000",
    ] {
        assert!(json.get(key).is_some(), "no {key}");
    }
    assert_eq!(json["max_abs"].as_array().unwrap().len(), 6);
    let strict = irid([
        "validate",
        out.to_str().unwrap(),
        "--points",
        "300",
        "--max-error",
        "1e-9",
    ]);
    assert_eq!(strict.code, Some(1));

    let bad = irid(["info", stack.to_str().unwrap()]);
    assert_eq!(bad.code, Some(2));
    let err = &bad.stderr;
    assert!(
        err.starts_with("irid: ") && err.contains("soap-film.toml"),
        "{err}"
    );
    let bad_layer = irid([
        "bake",
        stack.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--layer",
        "3",
    ]);
    assert_eq!(bad_layer.code, Some(2));
    assert!(bad_layer.stderr.contains("layer"));
}

/// A fixed resolution baked without the check: the same nodes as the
/// checked bake and, stored as f32, the same values to the last rounding
/// step (the f64 responses agree to 1e-12, see the baker's unit test); no
/// bake check in the header, and the table writes, loads and validates.
#[cfg(feature = "cli")]
#[test]
fn unchecked_bake_matches_the_checked_one() {
    let dir = Scratch::new("lut-nocheck");
    for (name, kind, wavelength) in [
        ("two-layer", Kind::Rgb, 1),
        ("oil-on-water", Kind::Spectral, 9),
    ] {
        let stack = Stack::load(&luts_dir().join(format!("{name}.toml"))).unwrap();
        let mut spec = quick_spec(stack, (0.0, 600.0), 1.0);
        spec.kind = kind;
        spec.resolution = Resolution::Nodes {
            thickness: 97,
            angle: 19,
            wavelength,
        };
        let checked = bake(&spec).unwrap();
        spec.check = false;
        let table = bake(&spec).unwrap();
        let (h, hc) = (table.header(), checked.header());
        assert_eq!(h.axes, hc.axes);
        assert!(hc.error.bake_check.is_some());
        assert_eq!(h.error.bake_check, None);
        assert_ne!(h.cache_key, hc.cache_key);
        for (a, b) in table.data().iter().zip(checked.data()) {
            let ulps = (a.to_bits() as i64 - b.to_bits() as i64).abs();
            assert!(ulps <= 1, "{name}: {a} vs {b}");
        }
        let path = dir.join(format!("{name}.exr"));
        table.write(&path).unwrap();
        let back = Lut::load(&path).unwrap();
        assert_eq!(back.header(), h);
        assert_eq!(back.header().version, irid::lut::FORMAT_VERSION);
        let stats = validate(&back, 300, 3).unwrap();
        assert!(worst(&stats.figures.max_abs) > 0.0 && worst(&stats.figures.max_abs) < 0.5);
    }
    // An error target chooses its grid by the check: it cannot be skipped.
    let stack = Stack::load(&luts_dir().join("soap-film.toml")).unwrap();
    let mut spec = quick_spec(stack, (0.0, 600.0), 1e-3);
    spec.check = false;
    let err = bake(&spec)
        .expect_err("--no-check with an error target")
        .to_string();
    assert!(
        err.contains("no-check") && err.contains("max-error"),
        "{err}"
    );

    // The commands: bake says no check was made, info too, validate works.
    let out = dir.join("cli.exr");
    let o = bake_soap(
        &out,
        &[
            "--resolution",
            "31,9",
            "--no-check",
            "--validate-points",
            "0",
        ],
    );
    assert!(o.success(), "{}", o.stderr);
    assert!(o.stdout.contains("bake check: not made (--no-check)"));
    let info = irid(["info", out.to_str().unwrap()]);
    assert!(info.success());
    let text = &info.stdout;
    assert!(text.contains("not made (baked with --no-check)"), "{text}");
    let v = irid(["validate", out.to_str().unwrap(), "--points", "100"]);
    assert!(v.success(), "{}", v.stderr);
}

/// The shipped tables are format version 1 (the bake check always
/// present): they load, sample and validate, and a table read from version
/// 1 is written back as the current version.
#[test]
fn version_1_tables_still_load() {
    let dir = Scratch::new("lut-v1");
    let mut seen = 0;
    for entry in std::fs::read_dir(luts_dir()).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().and_then(|e| e.to_str()) != Some("exr") {
            continue;
        }
        let lut = Lut::load(&path).unwrap_or_else(|e| panic!("{e}"));
        let h = lut.header();
        if h.version != 1 {
            continue;
        }
        seen += 1;
        assert!(h.error.bake_check.is_some(), "version 1 has a bake check");
        // The first points of the recorded validation's stream: within its
        // figures, channel by channel.
        let recorded = h.error.validation.as_ref().expect("validation recorded");
        let stats = validate(&lut, 200, recorded.figures.seed.unwrap()).unwrap();
        for (now, then) in stats.figures.max_abs.iter().zip(&recorded.figures.max_abs) {
            assert!(now <= then, "{}: {now} > {then}", path.display());
        }
        let copy = dir.join("copy.exr");
        lut.write(&copy).unwrap();
        let back = Lut::load(&copy).unwrap();
        assert_eq!(back.header().version, irid::lut::FORMAT_VERSION);
        assert_eq!(back.header().error, h.error);
        assert_eq!(back.data(), lut.data());
    }
    assert!(seen > 0, "no version-1 table in luts/");
}

/// Bilinear interpolation of the stored channels, written out from the
/// data layout (`[cos][thickness][6]`), as a reference for `sample_rgb`.
fn bilinear_reference(lut: &Lut, thickness_nm: f64, cos: f64) -> [f64; 6] {
    let axes = &lut.header().axes;
    let locate = |nodes: &[f64], x: f64| {
        let i = nodes.partition_point(|&n| n <= x).clamp(1, nodes.len() - 1) - 1;
        (
            i,
            ((x - nodes[i]) / (nodes[i + 1] - nodes[i])).clamp(0.0, 1.0),
        )
    };
    let (t_nodes, c_nodes) = (&axes[0].nodes, &axes[1].nodes);
    let (i, fx) = locate(t_nodes, thickness_nm);
    let (j, fy) = locate(c_nodes, cos);
    let at =
        |i: usize, j: usize, ch: usize| f64::from(lut.data()[(j * t_nodes.len() + i) * 6 + ch]);
    std::array::from_fn(|ch| {
        let lo = at(i, j, ch) + fx * (at(i + 1, j, ch) - at(i, j, ch));
        let hi = at(i, j + 1, ch) + fx * (at(i + 1, j + 1, ch) - at(i, j + 1, ch));
        lo + fy * (hi - lo)
    })
}

/// A lossless film's table is sampled from its reflectance alone, with the
/// transmittance as white − R; both agree with the stored channels. Tables
/// of absorbing films, or films on a metal, keep both channels.
#[test]
fn lossless_tables_sample_reflectance_only() {
    let nodes = Resolution::Nodes {
        thickness: 41,
        angle: 9,
        wavelength: 1,
    };
    let soap = Stack::load(&luts_dir().join("soap-film.toml")).unwrap();
    let mut spec = quick_spec(soap, (100.0, 900.0), 1.0);
    spec.resolution = nodes;
    let lut = bake(&spec).unwrap();
    assert!(lut.samples_as_lossless());
    let mut rng = rand_pcg::Pcg64::seed_from_u64(11);
    for _ in 0..2000 {
        let (d, c) = (100.0 + 800.0 * rng.random::<f64>(), rng.random::<f64>());
        let got = lut.sample_rgb(d as f32, c as f32);
        let want = bilinear_reference(&lut, d, c);
        for ch in 0..3 {
            assert!(
                (f64::from(got.reflectance[ch]) - want[ch]).abs() < 2e-5,
                "R at {d} {c}"
            );
            assert!(
                (f64::from(got.transmittance[ch]) - want[3 + ch]).abs() < 2e-5,
                "T at {d} {c}"
            );
        }
    }
    for name in ["absorbing-film.toml", "two-layer.toml", "gain-on-gold.toml"] {
        let stack = Stack::load(&luts_dir().join(name)).unwrap();
        let mut spec = quick_spec(stack, (100.0, 300.0), 1.0);
        spec.resolution = nodes;
        assert!(!bake(&spec).unwrap().samples_as_lossless(), "{name}");
    }
}

/// An atlas table's critical band (where a dispersive ambient moves the
/// critical angle and the target is not sought) is its own validation
/// region, apart from `resolved`; a band that is not one is refused.
#[test]
fn a_stated_critical_band_is_validated_apart() {
    let dir = Scratch::new("lut-critical-band");
    let stack = Stack::load(&luts_dir().join("soap-film.toml")).unwrap();
    let mut spec = quick_spec(stack, (100.0, 300.0), 1e-3);
    spec.cos_theta = (0.3, 1.0);
    spec.validation_points = 0;
    let good = dir.join("atlas.exr");
    bake(&spec).unwrap().write(&good).unwrap();
    let banded = dir.join("banded.exr");
    rewrite_header(&good, &banded, |j| {
        j["atlas"]["critical_band_cos"] = serde_json::json!([0.5, 0.6]);
    });
    let lut = Lut::load(&banded).unwrap();
    let table = lut.header().atlas.as_ref().unwrap();
    assert_eq!(table.critical_band_cos, Some([0.5, 0.6]));
    let stats = validate(&lut, 3000, 5).unwrap();
    let region = |name: &str| stats.regions.iter().find(|r| r.name == name).unwrap();
    let (band, resolved) = (region("critical band"), region("resolved"));
    // cos θ is uniform over 0.3..1: a seventh of the points in the band.
    assert!((300..560).contains(&band.points), "{}", band.points);
    assert_eq!(band.points + resolved.points, 3000);
    assert!(band.description.contains("0.500000 to 0.600000"));
    for bad in [[0.6, 0.5], [-0.1, 0.5], [0.5, 1.5]] {
        let path = dir.join("bad-band.exr");
        rewrite_header(&good, &path, |j| {
            j["atlas"]["critical_band_cos"] = serde_json::json!(bad);
        });
        let err = Lut::load(&path).expect_err("must fail").to_string();
        assert!(err.contains("critical_band_cos"), "{err}");
    }
}

/// Over 0–1000 nm the gain film reaches lasing poles: an rgb or spectral
/// atlas bake names the pole, as the export does, instead of a size limit.
#[test]
fn a_bake_over_a_lasing_pole_names_it() {
    let stack = Stack::load(&luts_dir().join("gain-on-gold.toml")).unwrap();
    for kind in [Kind::Rgb, Kind::Spectral] {
        let mut spec = BakeSpec::new(stack.clone());
        spec.kind = kind;
        spec.thickness_nm = (0.0, 1000.0);
        spec.cos_theta = (0.0, 1.0);
        spec.resolution = Resolution::MaxError(if kind == Kind::Rgb { 1e-3 } else { 1e-2 });
        let message = bake(&spec).expect_err("a lasing pole").to_string();
        assert!(
            message.contains("lasing pole") && message.contains("at thickness"),
            "{kind:?}: {message}"
        );
    }
}
