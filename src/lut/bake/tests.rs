//! Tests of the baker's parts together: the sweep, the grid and the
//! rounding as stored.

use num_complex::Complex64 as C64;

use super::grid::{doubled, initial_axes, refine, split_uniform, uniform, AxisGrid, Grid};
use super::store::stored;
use super::sweep::{chunks, phases, reuse_plan, rgb_weights, Piece, Prepared};
use super::*;
use crate::color::SpectralIntegrator;
use crate::optics::twoport::{Scratch, VaryingLayer};
use crate::optics::Layer;

/// The incremental phase of `phases` and the batched responses against an
/// exact exponential and `response` per node, on an absorbing and a gain
/// layer at a steep angle.
#[test]
fn sweep_matches_exact_phase() {
    for (n, k) in [(1.5, 0.15), (1.5, -0.05), (1.33, 0.0)] {
        let idx = [C64::new(1.0, 0.0), C64::new(n, k), C64::new(0.2, 3.0)];
        let mut scratch = Scratch::default();
        let v = VaryingLayer::new(&idx, &[0.0], 1, 420.0, 0.3, &mut scratch);
        // Equal spacings that join into one run, and unequal ones.
        let mut segments = split_uniform(0.0, 2000.0, 3, 700);
        segments.push(uniform(2000.0, 2003.0, 5));
        segments.push(uniform(2003.0, 2100.0, 131));
        let axis = AxisGrid::new(&segments);
        let mut worst = 0.0f64;
        let n = axis.nodes.len();
        // `phases` runs each chunk on to whole vectors.
        let (mut re, mut im) = (vec![0.0; n + 7], vec![0.0; n + 7]);
        phases(&v, &axis.nodes, &chunks(&axis), &mut re, &mut im);
        let (re, im) = (&re[..n], &im[..n]);
        for (j, &d) in axis.nodes.iter().enumerate() {
            let want = v.phase(d);
            worst = worst.max((C64::new(re[j], im[j]) - want).norm() / (1.0 + want.norm()));
        }
        let (mut r, mut t) = (vec![0.0; n], vec![0.0; n]);
        v.responses(re, im, &mut r, &mut t);
        for j in 0..n {
            let want = v.response(v.phase(axis.nodes[j]));
            for (g, w) in [(r[j], want.r()), (t[j], want.t())] {
                worst = worst.max((g - w).abs() / (1.0 + w.abs()));
            }
        }
        // The fused pass adds exactly what the separate one gives.
        let weights = [0.3, -0.7, 1.1];
        let start: Vec<f64> = (0..6 * n).map(|i| i as f64 * 1e-3).collect();
        let mut acc = start.clone();
        v.accumulate_responses(re, im, weights, &mut acc);
        for (k, (a, s)) in acc.chunks_exact(n).zip(start.chunks_exact(n)).enumerate() {
            let values = if k < 3 { &r } else { &t };
            for j in 0..n {
                let want = weights[k % 3].mul_add(values[j], s[j]);
                assert_eq!(a[j].to_bits(), want.to_bits(), "channel {k} node {j}");
            }
        }
        assert!(worst < 1e-12, "n = {n}{k:+}i: {worst:e}");
    }
}

/// The weights the bake accumulates are the integrator's colour of a
/// unit impulse at each wavelength, bit for bit (its dot product adds
/// only zeros to the one weight), so folding the integration into the
/// bake gives what integrating each spectrum would.
#[test]
fn rgb_weights_are_the_color_of_an_impulse() {
    use crate::color::Sampling;
    for sampling in [
        Sampling::Exact,
        Sampling::Rgb3,
        Sampling::Uniform(9),
        Sampling::Uniform(16),
        Sampling::Uniform(81),
    ] {
        let integrator = SpectralIntegrator::new(sampling);
        let weights = rgb_weights(&integrator);
        let mut impulse = vec![0.0; integrator.wavelengths_nm().len()];
        assert_eq!(weights.len(), impulse.len());
        for (i, w) in weights.iter().enumerate() {
            impulse[i] = 1.0;
            let want = integrator.rgb(&impulse);
            impulse[i] = 0.0;
            assert_eq!(
                w.map(f64::to_bits),
                want.map(f64::to_bits),
                "{sampling} {i}"
            );
        }
    }
}

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
        let prep = Prepared::new(&spec).unwrap();
        let axes = initial_axes(&spec, &prep);
        let coarse = Grid::new(&axes, kind);
        let fine = Grid::new(&axes.clone().map(|a| doubled(&a)), kind);
        for (c, f) in coarse.axes.iter().zip(&fine.axes) {
            let even: Vec<f64> = f.nodes.iter().step_by(2).copied().collect();
            assert_eq!(c.nodes, even);
        }
        let table = prep.eval(&coarse, None, &|_| {}).unwrap();
        let checked = prep.eval(&fine, None, &|_| {}).unwrap();
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
        let prep = Prepared::new(&spec).unwrap();
        let mut axes = initial_axes(&spec, &prep);
        let mut previous: Option<(Grid, Vec<f64>)> = None;
        let (mut copied_total, mut copied_rows) = (0, 0);
        for round in 0..4 {
            let fine = Grid::new(&axes.clone().map(|a| doubled(&a)), kind);
            let reused = prep.eval(&fine, previous.as_ref(), &|_| {}).unwrap();
            let fresh = prep.eval(&fine, None, &|_| {}).unwrap();
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
                let marked = prep.eval(&fine, Some(&poisoned), &|_| {}).unwrap();
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

/// A free-standing film of thickness 0 is no film: the sweep gives R = 0
/// and T = the colour of a flat spectrum at every angle, including cos θ
/// 1e-9, where its interfaces reflect all but 5e-9 of the light and (n0
/// cos θ)² is below the rounding of n0² (it once gave 0/0 there).
#[test]
fn a_film_of_no_thickness_is_no_film_at_grazing_incidence() {
    let stack = crate::optics::Stack {
        ambient: crate::optics::Material::constant(1.0, 0.0),
        layers: vec![Layer::new(
            crate::optics::Material::constant(1.33, 0.0),
            0.0,
        )],
        substrate: crate::optics::Material::constant(1.0, 0.0),
    };
    let integrator = SpectralIntegrator::new(crate::color::Sampling::Exact);
    let white = integrator.rgb(&vec![1.0; integrator.wavelengths_nm().len()]);
    let cos = [1e-9, 1e-7, 1e-3, 0.5, 1.0];
    let values = rgb_at_nodes(&stack, 1, integrator, &[0.0], &cos).unwrap();
    for (v, c) in values.iter().zip(cos) {
        for k in 0..3 {
            assert!(v[k].abs() < 1e-5, "cos θ {c}: R {v:?}");
            assert!((v[3 + k] - white[k]).abs() < 1e-5, "cos θ {c}: T {v:?}");
        }
    }
}

/// `rgb_at_nodes` (the sweep on caller-chosen nodes, as the GPU export uses
/// it) against the solver and the integrator node by node, on a
/// square-root thickness axis, an evenly spaced one and an uneven cos θ
/// axis, for a two-layer stack with an absorbing film on gold.
#[test]
fn sweep_on_given_nodes_matches_the_solver() {
    let stack = crate::optics::Stack {
        ambient: crate::optics::Material::constant(1.0, 0.0),
        layers: vec![
            Layer::new(crate::optics::Material::constant(1.5, 0.15), 300.0),
            Layer::new(crate::optics::library::builtin("TiO2").unwrap(), 80.0),
        ],
        substrate: crate::optics::library::builtin("gold").unwrap(),
    };
    let integrator = SpectralIntegrator::new(crate::color::Sampling::Exact);
    let cos: Vec<f64> = (0..7)
        .map(|i| (f64::from(i) / 6.0).powf(0.7).max(0.01))
        .collect();
    let sqrt_axis: Vec<f64> = (0..150)
        .map(|i| 500.0 * (f64::from(i) / 149.0).powi(2))
        .collect();
    let even_axis: Vec<f64> = (0..150).map(|i| 500.0 * f64::from(i) / 149.0).collect();
    let grid = crate::optics::StackGrid::new(&stack, integrator.wavelengths_nm()).unwrap();
    // Near grazing incidence some nodes integrate more finely (see
    // crate::color::refine), at the wavelengths of their level.
    let refinement = crate::color::refine::Refinement::new(&stack, Some(1), &integrator).unwrap();
    let mut refined = 0;
    for axis in [&sqrt_axis, &even_axis, &vec![250.0]] {
        let values = rgb_at_nodes(&stack, 1, integrator.clone(), axis, &cos).unwrap();
        assert_eq!(values.len(), axis.len() * cos.len());
        let mut worst = 0.0f64;
        for (c_index, &c) in cos.iter().enumerate() {
            for (t_index, &t) in axis.iter().enumerate().step_by(7) {
                let mut thick = grid.thicknesses_nm().to_vec();
                thick[0] = t;
                let m = refinement.sub_steps(t, c);
                refined += usize::from(m > 1);
                let (grid, integrator) = if m > 1 {
                    let level = refinement.level(m).unwrap();
                    (&level.grid, &level.integrator)
                } else {
                    (&grid, &integrator)
                };
                let mut spectrum =
                    vec![crate::optics::Response::default(); grid.wavelengths_nm().len()];
                grid.solve_spectrum(&thick, c, &mut spectrum);
                let r: Vec<f64> = spectrum.iter().map(|x| x.r()).collect();
                let tr: Vec<f64> = spectrum.iter().map(|x| x.t()).collect();
                let (want_r, want_t) = (integrator.rgb(&r), integrator.rgb(&tr));
                let got = values[c_index * axis.len() + t_index];
                for k in 0..3 {
                    worst = worst.max((got[k] - want_r[k]).abs());
                    worst = worst.max((got[3 + k] - want_t[k]).abs());
                }
            }
        }
        assert!(worst < 1e-12, "{} nodes: worst {worst:e}", axis.len());
    }
    assert!(refined > 0, "no node at cos θ 0.01 integrated more finely");
}
