//! Spectral tables: the trilinear sampler, the spectral atlas over the
//! whole domain and beside the grid, and the wavelength range's errors.

// Not an API: a test crate has no public API to document.
#![allow(missing_docs)]

mod common;
mod tables;

#[cfg(feature = "cli")]
use std::path::Path;

#[cfg(feature = "cli")]
use common::irid;
use common::Scratch;
use irid::lut::{bake, validate, BakeSpec, Kind, Layout, Lut, Resolution};
use irid::optics::Stack;
use rand::{Rng, SeedableRng};
use tables::{luts_dir, quick_spec, worst, worst_targeted};

#[test]
fn spectral_table_and_trilinear_sampling() {
    let stack = Stack::load(&luts_dir().join("oil-on-water.toml")).unwrap();
    let mut spec = quick_spec(stack, (100.0, 500.0), 2e-3);
    spec.kind = Kind::Spectral;
    spec.wavelength_nm = (400.0, 700.0);
    spec.layout = Layout::Grid;
    let lut = bake(&spec).unwrap();
    let h = lut.header();
    assert_eq!(h.axes.len(), 3);
    assert_eq!(h.y_blocks.as_deref(), Some("wavelength_nm"));
    // Nodes reproduce the solver exactly (to f32).
    let (t, c, w) = (h.axes[0].nodes[3], h.axes[1].nodes[2], h.axes[2].nodes[4]);
    let mut stack = h.stack.clone();
    stack.layers[0].thickness_nm = t;
    let direct = stack.response(w, c).unwrap();
    let (r, tr) = lut.sample_spectral(t as f32, c as f32, w as f32);
    assert!((f64::from(r) - direct.r()).abs() < 1e-6);
    assert!((f64::from(tr) - direct.t()).abs() < 1e-6);
    let stats = validate(&lut, 2000, 5).unwrap();
    assert!(worst(&stats.figures.max_abs) <= 2e-3);
    // The table spans 400–700 nm only: no colour figures.
    assert!(stats.figures.max_delta_e00.is_none());
    assert!(lut.sample_rgb(t as f32, c as f32).reflectance[0].is_nan());
}

/// A spectral table of the free-standing soap film over its whole domain
/// (0–1000 nm, every angle, 360–830 nm) bakes to 1e-2 on the atlas, and
/// meets it against the solver at fresh random points wherever it claims
/// to (above its aliased strip, which stays within 2.5° of grazing); its
/// wavelength nodes are uniform in wavenumber; the file reads back the
/// same.
#[test]
fn spectral_atlas_over_the_whole_domain() {
    let stack = Stack::load(&luts_dir().join("soap-film.toml")).unwrap();
    let mut spec = BakeSpec::new(stack.clone());
    spec.kind = Kind::Spectral;
    spec.thickness_nm = (0.0, 1000.0);
    spec.cos_theta = (0.0, 1.0);
    spec.wavelength_nm = (360.0, 830.0);
    spec.resolution = Resolution::MaxError(1e-2);
    spec.validation_points = 4000;
    let lut = bake(&spec).unwrap();
    let h = lut.header();
    assert_eq!(h.version, 4);
    let table = h.atlas.as_ref().expect("an atlas table");
    let floor = table.aliased_below_cos;
    assert!(floor < 87f64.to_radians().cos(), "{floor}");
    let w = &h.axes[2].nodes;
    assert!(w.len() >= 2 && w[0] == 360.0 && w[w.len() - 1] == 830.0);
    let step = (1.0 / w[0] - 1.0 / w[w.len() - 1]) / (w.len() - 1) as f64;
    for (k, x) in w.iter().enumerate() {
        assert!((1.0 / x - (1.0 / w[0] - step * k as f64)).abs() < 1e-9 * step);
    }
    // Fresh points against the transfer-matrix solver, directly.
    let mut rng = rand_pcg::Pcg64::seed_from_u64(77);
    let mut worst_resolved = 0.0f64;
    for _ in 0..3000 {
        let d = rng.random::<f64>() * 1000.0;
        let c = floor + rng.random::<f64>() * (1.0 - floor);
        let lambda = 360.0 + rng.random::<f64>() * 470.0;
        let mut s = stack.clone();
        s.layers[0].thickness_nm = d;
        let direct = s.response(lambda, c).unwrap();
        let (r, t) = lut.sample_spectral(d as f32, c as f32, lambda as f32);
        worst_resolved = worst_resolved
            .max((f64::from(r) - direct.r()).abs())
            .max((f64::from(t) - direct.t()).abs());
    }
    assert!(worst_resolved <= 1e-2, "{worst_resolved}");
    let stats = h.error.validation.as_ref().expect("validated");
    assert!(worst_targeted(stats) <= 1e-2);
    let dir = Scratch::new("spectral-atlas");
    let path = dir.join("soap.exr");
    lut.write(&path).unwrap();
    let back = Lut::load(&path).unwrap();
    assert_eq!(back.header(), lut.header());
    for (d, c, l) in [(0.0, 0.0, 360.0), (512.3, 0.4, 611.1), (1000.0, 1.0, 830.0)] {
        assert_eq!(back.sample_spectral(d, c, l), lut.sample_spectral(d, c, l));
    }
}

/// A dispersive film on a coated glass takes more wavelength nodes than
/// d/λ alone explains, and its spectral atlas still meets its target; a
/// grid table of the same spec is still baked and read (format version
/// 2, full axes).
#[test]
fn spectral_atlas_of_a_dispersive_stack_and_the_grid_beside_it() {
    let stack = Stack::load(&luts_dir().join("oil-on-water.toml")).unwrap();
    let mut spec = quick_spec(stack, (100.0, 500.0), 5e-3);
    spec.kind = Kind::Spectral;
    spec.wavelength_nm = (400.0, 700.0);
    spec.cos_theta = (0.3, 1.0);
    spec.validation_points = 4000;
    let atlas = bake(&spec).unwrap();
    assert_eq!(atlas.header().version, 4);
    let stats = validate(&atlas, 4000, 9).unwrap();
    assert!(worst_targeted(&stats) <= 5e-3, "{stats:?}");
    spec.layout = Layout::Grid;
    let grid = bake(&spec).unwrap();
    assert_eq!(grid.header().version, 2);
    assert!(grid.header().atlas.is_none());
    assert!(worst(&validate(&grid, 4000, 9).unwrap().figures.max_abs) <= 5e-3);
}

/// `--wavelengths` outside what the stack's data cover, reversed or not
/// finite, and `--max-de` on a spectral table: one line, exit code 2, no
/// table written.
#[cfg(feature = "cli")]
#[test]
fn spectral_wavelength_range_errors() {
    let dir = Scratch::new("spectral-flags");
    let out = dir.join("t.exr");
    let gold = luts_dir().join("gain-on-gold.toml");
    let soap = luts_dir().join("soap-film.toml");
    let bake = |stack: &Path, extra: &[&str]| {
        let mut args = vec![
            "bake",
            stack.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
            "--kind",
            "spectral",
            "--thickness",
            "0:100",
        ];
        args.extend_from_slice(extra);
        irid(&args)
    };
    for (extra, needles) in [
        (
            &["--wavelengths", "100:5000"][..],
            &["wavelengths", "gold", "187.9–1937 nm"][..],
        ),
        (
            &["--wavelengths", "830:360"],
            &["--wavelengths", "min ≤ max"],
        ),
        (
            &["--wavelengths", "nan:830"],
            &["--wavelengths", "not finite"],
        ),
        (&["--wavelengths", "0:830"], &["wavelengths", "0 < min"]),
    ] {
        bake(&gold, extra).assert_one_line_error(&format!("{extra:?}"), needles);
    }
    bake(&soap, &["--max-de", "1"]).assert_one_line_error("max-de", &["max-de", "rgb tables"]);
    assert!(!out.exists());
}
