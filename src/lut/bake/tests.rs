//! Tests of the baker's parts together: the sweep over its grids, the
//! grids' refinement and the rounding as stored.

use super::grid::{doubled, initial_axes, refine};
use super::store::stored;
use super::*;
use crate::lut::Kind;
use crate::optics::{Layer, Stack};
use crate::sweep::{chunks, reuse_plan, Grid, Piece};

/// A slightly absorbing film seen from glass, over all angles: the cos θ
/// axis is graded around the substrate's critical angle.
fn dense_side_spec(kind: Kind) -> BakeSpec {
    let mut spec = BakeSpec::new(Stack {
        ambient: crate::optics::Material::constant(1.5, 0.0),
        layers: vec![Layer::new(
            crate::optics::Material::constant(1.38, 0.02),
            100.0,
        )],
        substrate: crate::optics::Material::constant(1.0, 0.0),
    });
    spec.kind = kind;
    spec.cos_theta = (0.0, 1.0);
    spec.sampling = crate::color::Sampling::Uniform(16);
    spec
}

/// A table baked without the check evaluates the same nodes as the
/// checked bake's even subgrid (node positions equal bit for bit), but
/// the phase recurrence steps over the table's spacing instead of half
/// of it and re-syncs at other nodes: the f64 responses agree to
/// rounding (1e-12), so the stored f32 values can differ at most where
/// that rounding straddles an f32 rounding boundary.
#[test]
fn unchecked_nodes_match_the_checked_even_subgrid() {
    for (kind, nodes) in [(Kind::Rgb, (301, 23, 1)), (Kind::Spectral, (150, 9, 5))] {
        let mut spec = dense_side_spec(kind);
        spec.thickness_nm = (0.0, 1500.0);
        spec.resolution = Resolution::Nodes {
            thickness: nodes.0,
            angle: nodes.1,
            wavelength: nodes.2,
        };
        let prep = prepare(&spec).unwrap();
        let axes = initial_axes(&spec, &prep);
        let coarse = Grid::new(&axes, kind);
        let fine = Grid::new(&axes.clone().map(|a| doubled(&a)), kind);
        for (c, f) in coarse.axes.iter().zip(&fine.axes) {
            let even: Vec<f64> = f.nodes.iter().step_by(2).copied().collect();
            assert_eq!(c.nodes, even);
        }
        let table = prep.eval(&coarse, None, &|_| {}, Cancel::never()).unwrap();
        let checked = prep.eval(&fine, None, &|_| {}, Cancel::never()).unwrap();
        let ch = prep.channels;
        let [nt, nc, _] = fine.axes.clone().map(|a| a.nodes.len());
        let mut worst = 0.0f64;
        for (k, v) in table.chunks_exact(ch).enumerate() {
            let t = k % coarse.axes[0].nodes.len();
            let rest = k / coarse.axes[0].nodes.len();
            let (c, w) = (
                rest % coarse.axes[1].nodes.len(),
                rest / coarse.axes[1].nodes.len(),
            );
            let at = ((2 * w * nc + 2 * c) * nt + 2 * t) * ch;
            for (a, b) in v.iter().zip(&checked[at..at + ch]) {
                worst = worst.max((a - b).abs());
            }
        }
        assert!(worst <= 1e-12, "{kind}: {worst:e}");
        eprintln!("{kind}: largest difference {worst:e}");
    }
}

/// A grid evaluated with the previous round's values at hand equals, bit
/// for bit, the same grid evaluated from scratch, and copies some of it:
/// rgb and spectral, a critical-angle (graded) axis, refined segments of
/// both kinds, and an error target's starting grid refined as the
/// search refines it.
#[test]
fn reusing_the_previous_round_changes_no_bit() {
    for kind in [Kind::Rgb, Kind::Spectral] {
        let mut spec = dense_side_spec(kind);
        spec.thickness_nm = (0.0, 1000.0);
        spec.wavelength_nm = (400.0, 700.0);
        let prep = prepare(&spec).unwrap();
        let mut axes = initial_axes(&spec, &prep);
        let mut previous: Option<(Grid, Vec<f64>)> = None;
        let (mut copied_total, mut copied_rows) = (0, 0);
        for round in 0..4 {
            let fine = Grid::new(&axes.clone().map(|a| doubled(&a)), kind);
            let reused = prep
                .eval(&fine, previous.as_ref(), &|_| {}, Cancel::never())
                .unwrap();
            let fresh = prep.eval(&fine, None, &|_| {}, Cancel::never()).unwrap();
            let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert!(bits(&reused) == bits(&fresh), "{kind} round {round}");
            if let Some((old, _)) = &previous {
                let chunks = chunks(&fine.axes[0]);
                let plan = reuse_plan(&chunks, &fine.axes[0], &old.axes[0]);
                let copied: usize = plan
                    .iter()
                    .map(|p| match p {
                        Piece::Copy { len, .. } => *len,
                        Piece::Compute(_) => 0,
                    })
                    .sum();
                copied_total += copied;
                // Poisoned old values show which values were copied:
                // some were, in whole rows' chunks.
                let (old, values) = previous.as_ref().unwrap();
                let poisoned = (old.clone(), vec![f64::NAN; values.len()]);
                let marked = prep
                    .eval(&fine, Some(&poisoned), &|_| {}, Cancel::never())
                    .unwrap();
                copied_rows += marked.iter().filter(|v| v.is_nan()).count();
            }
            previous = Some((fine, fresh));
            // Refine every other segment of each axis, by odd and even
            // factors, as the error search does.
            for segments in axes.iter_mut() {
                let mut next = Vec::new();
                for (k, seg) in segments.iter().enumerate() {
                    if seg.intervals == 0 || k % 2 == round % 2 {
                        next.push(*seg);
                    } else {
                        next.extend(refine(seg, seg.intervals * 2 + k % 3));
                    }
                }
                *segments = next;
            }
        }
        assert!(
            copied_total > 0 && copied_rows > 0,
            "{kind}: nothing reused"
        );
    }
}

/// The f32 table rounded to f16 is the `--half` bake of the same spec,
/// bit for bit; a value beyond f16's range is refused as the baker
/// refuses it.
#[test]
fn rounding_an_f32_table_to_half_is_the_half_bake() {
    for kind in [Kind::Rgb, Kind::Spectral] {
        let mut spec = dense_side_spec(kind);
        spec.thickness_nm = (0.0, 1500.0);
        spec.resolution = Resolution::Nodes {
            thickness: 301,
            angle: 23,
            wavelength: 5,
        };
        let full = bake(&spec).unwrap();
        spec.half = true;
        let baked = bake(&spec).unwrap();
        let rounded = full.rounded_to_half().unwrap();
        assert_eq!(rounded.header().precision, "f16");
        assert_eq!(rounded.header().axes, baked.header().axes);
        let bits = |l: &Lut| l.data().iter().map(|v| v.to_bits()).collect::<Vec<_>>();
        assert!(bits(&rounded) == bits(&baked), "{kind}");

        let mut data = full.data().to_vec();
        data[7] = 1e5;
        let big = Lut::from_parts(full.header().clone(), data).unwrap();
        assert!(matches!(
            big.rounded_to_half(),
            Err(Error::HalfOverflow { .. })
        ));
    }
}

/// f16 values are rounded from f32 ones: at an f64 value just past an
/// f16 tie, which f32 rounds onto the tie, the result is the tie's even
/// neighbour, as with F16C, on any machine.
#[test]
fn half_values_round_through_f32() {
    // 1 + 2^-11 is halfway between the f16 values 1 and 1 + 2^-10.
    let just_past_tie = 1.0 + 2f64.powi(-11) + 2f64.powi(-40);
    assert_eq!(just_past_tie as f32, 1.0 + 2f32.powi(-11));
    assert_eq!(stored(just_past_tie, true), 1.0);
    assert_eq!(
        stored(1.0 + 2f64.powi(-11) + 2f64.powi(-20), true),
        1.0 + 2f32.powi(-10)
    );
}

/// An air gap seen from glass has its critical angle at the substrate's,
/// which is a node of the graded angle axis: the split is degenerate
/// there and the baker must fall back to the solver, not write NaN.
#[test]
fn frustrated_tir_gap_at_its_critical_angle() {
    let stack = Stack {
        ambient: crate::optics::Material::constant(1.5, 0.0),
        layers: vec![Layer::new(
            crate::optics::Material::constant(1.0, 0.0),
            100.0,
        )],
        substrate: crate::optics::Material::constant(1.0, 0.0),
    };
    let mut spec = BakeSpec::new(stack);
    spec.thickness_nm = (0.0, 400.0);
    spec.cos_theta = (0.0, 1.0);
    spec.sampling = crate::color::Sampling::Uniform(16);
    spec.resolution = Resolution::Nodes {
        thickness: 21,
        angle: 17,
        wavelength: 1,
    };
    let lut = bake(&spec).unwrap();
    let cc = (1.0f64 - (1.0 / 1.5f64).powi(2)).sqrt();
    assert!(lut.header().axes[1].nodes.contains(&cc));
    assert!(lut.data().iter().all(|v| v.is_finite()));
}
