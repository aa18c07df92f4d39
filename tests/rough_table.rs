//! `irid bake --rough`: the CPU rough table against the smooth table at
//! roughness 0, against irid's rough reflectance at random points of its
//! own, through its file, and refused when broken.

// Not an API: a test crate has no public API to document.
#![allow(missing_docs)]

mod common;

use std::path::Path;

use irid::color::SpectralIntegrator;
use irid::lut::rough::bake_rough;
use irid::lut::RoughLut;
use irid::lut::{bake, BakeSpec};
use irid::optics::Stack;
use irid::rough::{rough_reflectance, Quadrature};
use rand::{Rng, SeedableRng};

const TARGET: f64 = 2e-3;

fn soap_spec() -> BakeSpec {
    let stack = Stack::load(Path::new("luts/soap-film.toml")).expect("stack");
    let mut spec = BakeSpec::new(stack);
    spec.thickness_nm = (200.0, 600.0);
    spec.validation_points = 0;
    spec
}

/// One rough table for every check: the soap film over 200–600 nm.
fn soap_rough() -> &'static RoughLut {
    static TABLE: std::sync::OnceLock<RoughLut> = std::sync::OnceLock::new();
    TABLE.get_or_init(|| bake_rough(&soap_spec(), TARGET, &|_| {}).expect("rough bake"))
}

/// Slice 0 is the smooth film: the smooth atlas's texels where a chart kept
/// its size, the film evaluated on the chart's nodes where the rough atlas
/// grew it; so at roughness 0 the two tables agree within their two
/// interpolation errors (each within the smooth bake's 1e-3).
#[test]
fn roughness_zero_is_the_smooth_table() {
    let rough = soap_rough();
    let smooth = bake(&soap_spec()).expect("smooth bake");
    let mut rng = rand_pcg::Pcg64::seed_from_u64(3);
    for _ in 0..2000 {
        let d = 200.0 + 400.0 * rng.random::<f64>();
        let c = rng.random::<f64>();
        let want = smooth.sample_rgb(d as f32, c as f32).reflectance;
        let got = rough.sample(d, c, 0.0);
        for k in 0..3 {
            assert!(
                (got[k] - f64::from(want[k])).abs() < 2e-3,
                "{d} nm, cos {c}: {got:?} against {want:?}"
            );
        }
    }
}

/// Points of a stream of their own (not the bake's measurement), F_eff
/// computed by `rough_reflectance` directly: within the target the table
/// states it meets (cos θ ≥ the grazing strip).
#[test]
fn samples_meet_the_target_against_irids_rough_reflectance() {
    let rough = soap_rough();
    let h = rough.header();
    assert!(h.error.measured.max_all() <= TARGET && h.error.measured.points > 0);
    let mut rng = rand_pcg::Pcg64::seed_from_u64(11);
    let mut draw = |lo: f64, hi: f64, n: usize| {
        let mut v: Vec<f64> = (0..n)
            .map(|_| lo + (hi - lo) * rng.random::<f64>())
            .collect();
        v.sort_by(f64::total_cmp);
        v
    };
    let thickness = draw(200.0, 600.0, 30);
    let cos = draw(h.error.grazing_cos, 1.0, 15);
    let roughness = draw(0.0, 1.0, 15);
    let integrator =
        SpectralIntegrator::with_white(irid::color::Sampling::Exact, irid::color::White::D65);
    let exact = rough_reflectance(
        &h.stack,
        h.layer,
        &integrator,
        &thickness,
        &cos,
        &roughness,
        &Quadrature::default(),
    )
    .expect("rough reflectance");
    let mut worst = 0.0f64;
    for (r, &rv) in roughness.iter().enumerate() {
        for (c, &cv) in cos.iter().enumerate() {
            for (t, &tv) in thickness.iter().enumerate() {
                let want = exact.at(t, c, r);
                let got = rough.sample(tv, cv, rv);
                for k in 0..3 {
                    worst = worst.max((got[k] - want[k]).abs());
                }
            }
        }
    }
    println!(
        "{} points: max abs {worst:.3e}",
        thickness.len() * cos.len() * roughness.len()
    );
    assert!(worst <= TARGET, "{worst}");
}

#[test]
fn the_file_reads_back_and_broken_files_are_refused() {
    let rough = soap_rough();
    let dir = common::Scratch::new("rough-table");
    let path = dir.path().join("rough.exr");
    rough.write(&path).expect("write");
    let back = RoughLut::load(&path).expect("load");
    assert_eq!(back.header(), rough.header());
    for (d, c, r) in [(250.0, 0.3, 0.0), (400.0, 0.9, 0.37), (599.0, 0.05, 1.0)] {
        assert_eq!(back.sample(d, c, r), rough.sample(d, c, r));
    }
    let bytes = std::fs::read(&path).expect("read");
    let refused = |name: &str, data: &[u8]| {
        let p = dir.path().join(name);
        std::fs::write(&p, data).expect("write");
        let e = RoughLut::load(&p).expect_err(name).to_string();
        assert_eq!(e.lines().count(), 1, "{name}: {e}");
        e
    };
    refused("truncated.exr", &bytes[..bytes.len() / 2]);
    refused("empty.exr", &[]);
    let swap = |from: &str, to: &str| {
        let text = String::from_utf8_lossy(&bytes).into_owned();
        assert!(text.contains(from), "{from}");
        let at = bytes
            .windows(from.len())
            .position(|w| w == from.as_bytes())
            .expect(from);
        let mut b = bytes.clone();
        b.splice(at..at + from.len(), to.bytes());
        b
    };
    let n = rough.header().slices;
    let e = refused(
        "slices.exr",
        &swap(&format!("\"slices\":{n}"), &format!("\"slices\":{}", n + 1)),
    );
    assert!(e.contains("slices"), "{e}");
    let e = refused("format.exr", &swap("\"irid-rough\"", "\"irid-rouge\""));
    assert!(e.contains("not a rough table"), "{e}");
    let e = refused("version.exr", &swap("\"version\":1", "\"version\":7"));
    assert!(e.contains("version 7"), "{e}");
    // The smooth table's loader is not fooled either.
    assert!(irid::lut::Lut::load(&path).is_err());
}

#[cfg(feature = "cli")]
#[test]
fn bad_rough_bakes_are_one_line_errors() {
    let dir = common::Scratch::new("rough-bad");
    let out = dir.path().join("x.exr");
    let out = out.to_str().expect("utf-8");
    let stack = "luts/soap-film.toml";
    common::irid(["bake", stack, "--rough", "--kind", "spectral", "-o", out])
        .assert_one_line_error("spectral", &["spectral"]);
    for bad in ["0", "-1", "NaN"] {
        common::irid([
            "bake",
            stack,
            "--rough",
            "--rough-max-error",
            bad,
            "-o",
            out,
        ])
        .assert_one_line_error(bad, &["rough-max-error"]);
    }
    assert!(!Path::new(out).exists());
    std::fs::write(dir.path().join("junk.exr"), b"not an exr").expect("write");
    let junk = dir.path().join("junk.exr");
    common::irid(["info", junk.to_str().expect("utf-8")])
        .assert_one_line_error("junk", &["junk.exr"]);
}

/// The mirror seen from its glass side (the stack reversed, fused silica
/// the ambient): its smooth atlas states the critical band apart, so the
/// rough table, whose smallest roughness is that atlas, is refused with one
/// line naming the band, and nothing is written.
#[cfg(feature = "cli")]
#[test]
fn a_rough_table_over_an_unsought_critical_band_is_refused() {
    let dir = common::Scratch::new("rough-band");
    let layers: String = (0..5)
        .map(|_| {
            "[[layers]]\nmaterial = \"fused-silica\"\nthickness_nm = 94.18\n\n\
             [[layers]]\nmaterial = \"TiO2\"\nthickness_nm = 56.45\n\n"
        })
        .collect();
    let toml = dir.path().join("mirror-back.toml");
    std::fs::write(
        &toml,
        format!(
            "ambient = {{ material = \"fused-silica\" }}\nsubstrate = {{ n = 1.0 }}\n\n{layers}"
        ),
    )
    .expect("write");
    let out = dir.path().join("rough.exr");
    let out = out.to_str().expect("utf-8");
    let args = ["bake", toml.to_str().expect("utf-8"), "--layer", "10"];
    common::irid(
        args.iter()
            .chain(&[
                "--thickness",
                "0:200",
                "--rough",
                "--validate-points",
                "0",
                "-o",
                out,
            ])
            .copied(),
    )
    .assert_one_line_error("critical band", &["rough", "0.7254–0.7352", "--max-error"]);
    assert!(!Path::new(out).exists());
}
