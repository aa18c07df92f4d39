//! `irid export --rough`: the rough table (F_eff over thickness × cos θ ×
//! roughness slices, docs/gpu.md). Slice 0 is the smooth front chart texel
//! for texel and `irid_film_rough` at roughness 0 is `irid_film`'s front
//! reflectance; the error film.json states is what the emulated GPU lookup
//! gives against `irid::rough` at the stated points, and within the target;
//! the folder holds the texture, the four shaders and film.json's `rough`;
//! bad input is one line and exit 2 with nothing written.

mod common;

use std::path::Path;

use common::{irid_in, Scratch};
use irid::export::{
    export, rough_exact_at, write_dir, Export, ExportSpec, RoughPoints, Side, GRAZING_COS,
    ROUGH_SHADERS, ROUGH_VEC4,
};
use irid::optics::Stack;

fn luts() -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("luts")
}

/// A soap film 200–400 nm at every angle, rough table at 2e-3 (the most the
/// issue allows): small enough for a test, thick enough that F_eff
/// changes over roughness.
fn soap_rough() -> &'static Export {
    static EXPORT: std::sync::OnceLock<Export> = std::sync::OnceLock::new();
    EXPORT.get_or_init(make_soap_rough)
}

fn make_soap_rough() -> Export {
    let stack = Stack::load(&luts().join("soap-film.toml")).unwrap();
    let mut spec = ExportSpec::new(stack);
    spec.thickness_nm = (200.0, 400.0);
    spec.max_error = 2e-3;
    spec.points = 2000;
    spec.rough_max_error = Some(2e-3);
    export(&spec, &|_| {}).unwrap()
}

/// The largest error per channel of the emulated lookup against `exact`
/// over the cosines `cos_range` of `points.all_cos()`.
fn worst_over(
    rough: &irid::export::RoughExport,
    points: &RoughPoints,
    exact: &irid::rough::RoughTable,
    cos_range: std::ops::Range<usize>,
) -> [f64; 3] {
    let cos = points.all_cos();
    let mut worst = [0.0f64; 3];
    for (k, &rk) in points.roughness.iter().enumerate() {
        for j in cos_range.clone() {
            for (i, &ti) in points.thickness.iter().enumerate() {
                let got = rough.sample(ti, cos[j], rk);
                let want = exact.at(i, j, k);
                for n in 0..3 {
                    worst[n] = worst[n].max((f64::from(got[n]) - want[n]).abs());
                }
            }
        }
    }
    worst
}

#[test]
fn rough_table_meets_its_stated_error_and_is_smooth_at_roughness_zero() {
    let e = soap_rough();
    let rough = e.rough.as_ref().expect("a rough table");
    let nodes = rough.roughness_nodes();
    assert_eq!((nodes[0], nodes[rough.slices - 1]), (0.0, 1.0));
    // The stated error, recomputed from the public pieces: the emulated
    // lookup at every combination of the stated points against
    // irid::rough, apart below the grazing cosine.
    let points = RoughPoints::of(&e.spec);
    assert!(points.cos.iter().all(|&c| f64::from(c) >= GRAZING_COS));
    assert!(points
        .grazing_cos
        .iter()
        .all(|&c| f64::from(c) < GRAZING_COS));
    let exact = rough_exact_at(&e.spec, &points).unwrap();
    let (n_cos, n_all) = (points.cos.len(), points.all_cos().len());
    let main = worst_over(rough, &points, &exact, 0..n_cos);
    assert_eq!(main, rough.error.max_abs);
    let grazing = rough.grazing_error.as_ref().expect("angles reach grazing");
    assert_eq!(
        worst_over(rough, &points, &exact, n_cos..n_all),
        grazing.max_abs
    );
    let per_slice = points.thickness.len() * points.roughness.len();
    assert_eq!(rough.error.points, n_cos * per_slice);
    assert_eq!(grazing.points, (n_all - n_cos) * per_slice);
    assert!(rough.error.max_all() <= 2e-3, "{:?}", rough.error);
    // At roughness 0 the rough lookup and irid_film's front reflectance read
    // the same film (slice 0 is the smooth atlas's texels where a chart kept
    // its size): they agree within their two targets, and exactly on the
    // smooth atlas's nodes of charts that kept their size.
    for &c in &points.all_cos() {
        for &t in &points.thickness {
            let (smooth, _) = e.sample(t, c, Side::Front);
            let zero = rough.sample(t, c, 0.0);
            let both = e.spec.max_error + 2e-3;
            for n in 0..3 {
                assert!(
                    f64::from((zero[n] - smooth[n]).abs()) <= both,
                    "{t} nm, cos {c}: {zero:?} {smooth:?}"
                );
            }
        }
    }
    eprintln!(
        "soap 200-400 nm: {} slices of {}x{}, error max {:.2e} mean {:.2e}, grazing max {:.2e}",
        rough.slices,
        rough.atlas.width,
        rough.atlas.height,
        rough.error.max_all(),
        rough.error.mean_abs.iter().sum::<f64>() / 3.0,
        grazing.max_all(),
    );
}

#[test]
fn rough_folder_holds_texture_shaders_and_film_json_rough() {
    let e = soap_rough();
    let rough = e.rough.as_ref().unwrap();
    let scratch = Scratch::new("export-rough");
    let dir = scratch.path().join("film");
    write_dir(e, &dir).unwrap();
    let image = common::read_exr(&dir.join("rough.exr"));
    assert_eq!(
        (
            image.layer_data.size.width(),
            image.layer_data.size.height()
        ),
        (rough.texture.width, rough.texture.height)
    );
    for (name, text) in ROUGH_SHADERS {
        assert_eq!(std::fs::read_to_string(dir.join(name)).unwrap(), text);
        assert!(text.contains("irid_film_rough("), "{name}");
    }
    let film: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("film.json")).unwrap()).unwrap();
    let j = &film["rough"];
    assert_eq!(j["texture"]["file"], "rough.exr");
    assert_eq!(j["layout"]["slices"], rough.slices);
    assert_eq!(j["uniform_vec4"], ROUGH_VEC4);
    let uniform: Vec<f32> = j["uniform_f32"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap() as f32)
        .collect();
    assert_eq!(uniform, rough.uniform_f32());
    assert_eq!(j["error"]["max_abs"][0], rough.error.max_abs[0]);
    assert_eq!(j["error"]["target_max_abs"], 2e-3);
    assert_eq!(
        j["nodes"]["roughness"].as_array().unwrap().len(),
        rough.slices
    );
    // Without --rough there is no rough section and no rough file.
    let mut plain = e.clone();
    plain.rough = None;
    let dir = scratch.path().join("plain");
    write_dir(&plain, &dir).unwrap();
    assert!(!dir.join("rough.exr").exists());
    let film: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("film.json")).unwrap()).unwrap();
    assert!(film["rough"].is_null());
}

#[test]
fn rough_bad_input_is_one_line_and_leaves_no_directory() {
    let scratch = Scratch::new("export-rough-bad");
    let d = scratch.path();
    let soap = luts().join("soap-film.toml");
    let soap = soap.to_str().unwrap();
    let cases: [(&[&str], &[&str]); 4] = [
        (
            &[
                "export",
                soap,
                "-o",
                "o",
                "--rough",
                "--rough-max-error",
                "nan",
            ],
            &["rough-max-error", "positive"],
        ),
        (
            &[
                "export",
                soap,
                "-o",
                "o",
                "--rough",
                "--rough-max-error",
                "-1",
            ],
            &["rough-max-error", "positive"],
        ),
        (
            &[
                "export",
                soap,
                "-o",
                "o",
                "--rough",
                "--rough-max-error",
                "1e-4",
            ],
            &["rough-max-error", "f16"],
        ),
        // A rough target without the rough table.
        (
            &["export", soap, "-o", "o", "--rough-max-error", "1e-3"],
            &["--rough"],
        ),
    ];
    for (args, names) in cases {
        irid_in(d, args).assert_one_line_error(&format!("{args:?}"), names);
    }
    assert!(std::fs::read_dir(d).unwrap().next().is_none());
}
