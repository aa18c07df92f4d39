//! Every table the project ships (luts/*.toml, at their own thickness) and
//! every stack of the bench (over its thickness range) exports over every
//! angle, cos θ 0 to 1, at the defaults, and what the export states holds:
//! each side's error is within its target where the target is sought (above
//! its aliased strip, outside a dispersive critical band it states apart),
//! and within what it states in that band, re-measured here through
//! `Export::sample` against the solver at points of our own.
//!
//! The mirror seen from its glass side is the case of the critical band:
//! fused silica's dispersion moves its critical angle over a band of cos θ
//! where the colour asks for about a million texels
//! (docs/limits.md#the-mirror-from-its-glass-side).

use std::path::Path;

use irid::export::{exact_at, export, Export, ExportSpec};
use irid::optics::Stack;

/// Points of our own (not the export's), uniform over the domain.
fn points(spec: &ExportSpec, n: usize) -> Vec<[f32; 2]> {
    let (t, c) = (spec.thickness_nm, spec.cos_theta);
    // A Weyl sequence: evenly spread, no generator needed.
    (0..n)
        .map(|k| {
            let (a, b) = (
                (k as f64 * 0.754_877_666).fract(),
                (k as f64 * 0.569_840_291).fract(),
            );
            [
                (t.0 + a * (t.1 - t.0)) as f32,
                (c.0 + b * (c.1 - c.0)) as f32,
            ]
        })
        .collect()
}

/// The largest error an export may state in a dispersive critical band,
/// where its target is not sought (the mirror's glass side states 3.8e-3).
const CRITICAL_BAND_BOUND: f64 = 1e-2;

/// The largest error of what `result` gives on `side` at `points` against
/// the solver, and where.
fn worst_at(
    result: &Export,
    spec: &ExportSpec,
    side: irid::export::Side,
    points: &[[f32; 2]],
) -> (f64, [f32; 2]) {
    let exact = exact_at(spec, side, points).unwrap();
    let mut worst = (0.0f64, [0.0f32; 2]);
    for (p, want) in points.iter().zip(&exact) {
        let (r, t) = result.sample(p[0], p[1], side);
        for (k, got) in r.iter().chain(&t).enumerate() {
            let err = (f64::from(*got) - want[k]).abs() / want[k].abs().max(1.0);
            if err > worst.0 {
                worst = (err, *p);
            }
        }
    }
    worst
}

/// Exports `spec` and checks every side: film.json's figures are finite,
/// the error over the whole domain is within the target when nothing is
/// aliased and no critical band is stated apart, at points of our own above
/// the aliased strip and outside the band what the GPU computes is within
/// the target (with the f16 rounding and filter the export measures, and
/// the same relative reading above 1), and in the band within what the
/// export states there.
fn exports_within_target(name: &str, spec: &ExportSpec) -> Export {
    let result = export(spec, &|_| {}).unwrap_or_else(|e| panic!("{name}: {e}"));
    assert_eq!(result.spec.cos_theta, (0.0, 1.0), "{name}");
    assert!(!result.sides.is_empty(), "{name}");
    for side in &result.sides {
        let target = spec.target(side.side);
        let e = &side.error;
        assert!(
            e.max_all().is_finite() && e.points > 0,
            "{name} {:?}",
            side.side
        );
        if let Some(sought) = &side.sought_error {
            assert!(
                sought.max_all() <= target,
                "{name} {:?}: states {} where the target is sought (target {target})",
                side.side,
                sought.max_all()
            );
        }
        if side.aliased_error.is_none() && side.critical_error.is_none() {
            assert!(
                e.max_all() <= target,
                "{name} {:?}: stated {} over target {target}",
                side.side,
                e.max_all()
            );
        }
        let in_band = |c: f32| {
            side.critical_band
                .is_some_and(|(a, b)| f64::from(c) >= a && f64::from(c) <= b)
        };
        let ours: Vec<[f32; 2]> = points(spec, 3000)
            .into_iter()
            .filter(|p| f64::from(p[1]) >= side.aliased_below && !in_band(p[1]))
            .collect();
        let worst = worst_at(&result, spec, side.side, &ours);
        if let (Some((a, b)), Some(stated)) = (side.critical_band, &side.critical_error) {
            let stated = stated.max_all();
            assert!(
                stated.is_finite() && stated <= CRITICAL_BAND_BOUND,
                "{name} {:?}: critical band {a}–{b} states {stated}",
                side.side
            );
            let band = ExportSpec {
                cos_theta: (a, b),
                ..spec.clone()
            };
            let (in_band, at) = worst_at(&result, spec, side.side, &points(&band, 400));
            assert!(
                in_band <= 1.5 * stated,
                "{name} {:?}: {in_band} at {at:?} in the critical band, which states {stated}",
                side.side
            );
        }
        // The export measures 20 000 points; ours fall elsewhere, where
        // the filter may do slightly worse than at any of its own.
        assert!(
            worst.0 <= 1.5 * target,
            "{name} {:?}: {} at {:?} (target {target})",
            side.side,
            worst.0,
            worst.1
        );
    }
    result
}

fn shipped(file: &str) -> ExportSpec {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("luts")
        .join(file);
    ExportSpec::new(Stack::load(&path).unwrap())
}

/// Every luts/*.toml.
#[test]
fn every_shipped_table_exports_over_every_angle() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("luts");
    let mut files: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .filter_map(|e| e.ok()?.file_name().into_string().ok())
        .filter(|f| f.ends_with(".toml"))
        .collect();
    files.sort();
    assert!(files.len() >= 7, "{files:?}");
    for file in files.iter().filter(|f| f.as_str() != "mirror-10.toml") {
        exports_within_target(file, &shipped(file));
    }
}

/// The mirror over its top layer's whole range, from both sides: from its
/// glass side the critical band (where fused silica's dispersion moves the
/// critical angle) is stated apart, the rest within the target.
#[test]
fn the_mirror_exports_from_its_glass_side_over_every_angle() {
    let spec = ExportSpec {
        thickness_nm: (0.0, 200.0),
        ..shipped("mirror-10.toml")
    };
    let result = exports_within_target("mirror-10.toml", &spec);
    let back = result.side(irid::export::Side::Back).expect("a back side");
    let (a, b) = back.critical_band.expect("the glass side's critical band");
    // Fused silica's critical angle against air over 360–830 nm.
    assert!(
        (a - 0.7254).abs() < 1e-3 && (b - 0.7352).abs() < 1e-3,
        "{a}–{b}"
    );
    let stated = back.critical_error.as_ref().unwrap();
    assert_eq!(stated.points, irid::atlas::search::CRITICAL_BAND_POINTS);
    let front = result.side(irid::export::Side::Front).unwrap();
    assert!(front.critical_band.is_none());
    // A range that starts inside the band keeps the band's part in it.
    let partial = ExportSpec {
        cos_theta: (0.73, 1.0),
        ..spec
    };
    let result = export(&partial, &|_| {}).unwrap();
    let back = result.side(irid::export::Side::Back).unwrap();
    assert_eq!(back.critical_band.map(|(a, _)| a), Some(0.73));
}

/// A loose target still resolves the grazing corner of a free-standing
/// film: its jump from 0 to 1 is far above 2e-2 or 5e-2, so it takes the
/// corner chart as it does at 1e-3.
#[test]
fn loose_targets_resolve_the_grazing_corner() {
    for max_error in [2e-2, 5e-2] {
        let spec = ExportSpec {
            thickness_nm: (0.0, 300.0),
            max_error,
            ..shipped("soap-film.toml")
        };
        exports_within_target(&format!("soap-film.toml 0:300 at {max_error}"), &spec);
    }
}

/// The shipped gain film reflects up to 2.99: the target holds relative to
/// the value above 1, where f16 rounds by up to 9.8e-4 of it.
#[test]
fn the_gain_film_exports_at_values_above_one() {
    let result = exports_within_target("gain-on-gold.toml", &shipped("gain-on-gold.toml"));
    let largest = result
        .reflectance
        .texels
        .iter()
        .flat_map(|t| t[..3].iter())
        .fold(0.0f32, |a, &b| a.max(b));
    assert!(largest > 2.5, "{largest}");
}

#[cfg(feature = "bench")]
fn bench_spec(name: &str) -> ExportSpec {
    let b = irid::bench::stacks::find(name).unwrap().unwrap();
    ExportSpec {
        layer: b.varying_layer + 1,
        thickness_nm: b.thickness_range_nm,
        // The bench's stacks are each one side: the mirror's back is a
        // stack of its own.
        front_only: true,
        ..ExportSpec::new(b.stack)
    }
}

/// Every bench stack over its thickness range but the gain film (see
/// [`the_bench_gain_film_reaches_lasing_poles`]).
#[cfg(feature = "bench")]
#[test]
fn every_bench_stack_exports_over_every_angle() {
    let names = irid::bench::stacks::names();
    for name in names {
        if name == "gain-on-gold" {
            continue;
        }
        exports_within_target(name, &bench_spec(name));
    }
}

/// Over 0–1000 nm the gain film reaches lasing poles, where R and T are
/// unbounded (docs/limits.md#lasing-poles): the export refuses, naming
/// the point, within seconds.
#[cfg(feature = "bench")]
#[test]
fn the_bench_gain_film_reaches_lasing_poles() {
    let Err(e) = export(&bench_spec("gain-on-gold"), &|_| {}) else {
        panic!("the range reaches lasing poles");
    };
    let message = e.to_string();
    assert!(message.contains("lasing pole"), "{message}");
    assert!(message.contains("at thickness"), "{message}");
}
