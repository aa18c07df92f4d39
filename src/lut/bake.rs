//! The baker: exact responses on a grid via the split-stack form, and the
//! segment-refining search that meets an error target.

use num_complex::Complex64 as C64;
use rayon::prelude::*;

use super::axis::{segment_nodes, share_intervals, Axis, Grading, Segment};
use super::header::{
    BakeCheck, Channel, ColorInfo, ErrorInfo, Header, BAKE_CHECK_METRIC, COS_AXIS, FORMAT_NAME,
    FORMAT_VERSION, THICKNESS_AXIS, WAVELENGTH_AXIS,
};
use super::sample::{channel_names, Lut};
use super::validate::{max_or_nan, validate};
use super::{BakeSpec, Kind, Resolution, MAX_AXIS_NODES, MAX_NODES};
use crate::color::SpectralIntegrator;
use crate::error::{Error, Result};
use crate::optics::twoport::{Scratch, VaryingLayer};
use crate::optics::{solve, Layer, Stack, StackGrid};
use crate::simd::avx2_dispatch;

/// The phase factor along a uniform thickness axis is advanced by complex
/// multiplications and recomputed exactly this often (see [`phases`]): the
/// rounding then stays near 1e-14 (tested), while the complex exponential
/// (a sincos) is paid on one node in 64.
const PHASE_RESYNC: usize = 64;

/// Bakes a table (no progress output; see [`bake_with_progress`]).
pub fn bake(spec: &BakeSpec) -> Result<Lut> {
    bake_with_progress(spec, &|_| {})
}

/// The seed of the validation a bake records (and `irid validate` uses by
/// default), so the two report the same points.
pub const VALIDATION_SEED: u64 = 1;

/// Refinement rounds before `--max-error` gives up.
const MAX_ROUNDS: usize = 24;
/// Upper bound on (fine-grid nodes × wavelengths) evaluated in one round,
/// about ten seconds of work: a target that needs more is reported, not
/// ground out.
const MAX_WORK: usize = 1 << 30;

/// Bakes a table, calling `progress` with the fraction of the current grid
/// evaluation done (it restarts at 0 for each grid the error search tries).
///
/// Every axis is a list of segments, each uniform (or graded towards a
/// critical angle). The baker evaluates the grid with every segment
/// subdivided once more, which gives the error of the table at every edge
/// midpoint and cell centre; with `--max-error` each segment whose error
/// exceeds its share is refined by the factor the h² error law predicts,
/// and the search repeats until the whole table meets the target (each
/// round copies what it shares with the previous round's grid instead of
/// evaluating it again, with the same result bit for bit). Then the
/// table is validated against the solver at `spec.validation_points` random
/// points; around any point above the target the search refines further.
/// The validation figures go into the header. A fixed resolution is baked
/// as asked, without validation (see [`super::validate`]); with
/// `spec.check` off it is evaluated at the table's nodes only and the header
/// records no bake check.
pub fn bake_with_progress(spec: &BakeSpec, progress: &(dyn Fn(f64) + Sync)) -> Result<Lut> {
    spec.validate()?;
    let prep = Prepared::new(spec)?;
    let mut axes = initial_axes(spec, &prep);
    if !spec.check {
        // Only a fixed resolution gets here (see BakeSpec::validate).
        let grid = Grid::new(&axes, spec.kind);
        let values = prep.eval(&grid, None, progress)?;
        let data: Vec<f32> = values.iter().map(|&v| stored(v, spec.half)).collect();
        representable(&data, &grid.nodes(), spec.kind, spec.half)?;
        return Lut::from_parts(header(spec, &prep, &grid, None, None), data)
            .map_err(|why| Error::invalid("baked table", why));
    }
    let target = match spec.resolution {
        Resolution::MaxError(e) => Some(e),
        Resolution::Nodes { .. } => None,
    };
    let wavelength_work = prep.stack_grid.wavelengths_nm().len().max(1);
    let mut round = 0;
    // The last round's grid and values: nodes it shares with the next one
    // are copied, not evaluated again.
    let mut previous: Option<(Grid, Vec<f64>)> = None;
    loop {
        round += 1;
        let coarse = Grid::new(&axes, spec.kind);
        let fine = Grid::new(&axes.clone().map(|a| doubled(&a)), spec.kind);
        if fine.total().saturating_mul(wavelength_work) > MAX_WORK
            || fine.axes.iter().any(|a| a.nodes.len() > 2 * MAX_AXIS_NODES)
            || coarse.total() > MAX_NODES
            || round > MAX_ROUNDS
        {
            return Err(match target {
                Some(target) => Error::invalid(
                    "max-error",
                    format!(
                        "{target} is not reached within the size limits (the last grid tried has {} nodes)",
                        coarse.total()
                    ),
                ),
                // A fixed grid whose error check (every interval halved) would
                // exceed the limits: the resolution itself is what is too large.
                None => Error::invalid(
                    "resolution",
                    format!(
                        "{} nodes is too large to bake and check within the size limits",
                        coarse.total()
                    ),
                ),
            });
        }
        let clock = std::time::Instant::now();
        let values = prep.eval(&fine, previous.as_ref(), progress)?;
        let eval_s = clock.elapsed().as_secs_f64();
        // The coarse table as it would be stored: the check interpolates it.
        let data = even_subgrid(&fine, &values, prep.channels, spec.half);
        let check = measure(&coarse, &fine, &values, &data, prep.channels);
        let measure_s = clock.elapsed().as_secs_f64() - eval_s;
        if std::env::var_os("IRID_DEBUG").is_some() {
            eprintln!(
                "grid {:?} check {:.3e} worst at {:?} eval {eval_s:.3}s measure {measure_s:.3}s",
                coarse
                    .axes
                    .iter()
                    .map(|a| a.nodes.len())
                    .collect::<Vec<_>>(),
                check.max_all,
                (0..3)
                    .map(|a| fine.axes[a].nodes[check.worst_at[a]])
                    .collect::<Vec<_>>()
            );
        }
        let e = match target {
            Some(e) if check.max_all > e => e,
            _ => {
                representable(&data, &coarse.nodes(), spec.kind, spec.half)?;
                let header = header(spec, &prep, &coarse, Some(&check), target);
                let mut lut = Lut::from_parts(header, data)
                    .map_err(|why| Error::invalid("baked table", why))?;
                if spec.validation_points == 0 || target.is_none() {
                    return Ok(lut);
                }
                let stats = validate(&lut, spec.validation_points, VALIDATION_SEED)?;
                let worst = max_or_nan(&stats.max_abs);
                match target {
                    // Midpoints are where interpolation error peaks for a
                    // smooth response, but a feature narrower than the grid
                    // (a resonance near grazing incidence) can peak between
                    // them: refine the segments around the worst point.
                    Some(t) if worst > t || worst.is_nan() => {
                        for (a, segments) in axes.iter_mut().enumerate() {
                            let x = stats.worst_point[a];
                            if let Some(k) = segments
                                .iter()
                                .position(|s| s.intervals > 0 && x >= s.start && x <= s.end)
                            {
                                let seg = segments[k];
                                let finer = refine(&seg, 2 * seg.intervals);
                                segments.splice(k..=k, finer);
                            }
                        }
                        previous = Some((fine, values));
                        continue;
                    }
                    _ => {
                        lut.set_validation(stats);
                        return Ok(lut);
                    }
                }
            }
        };
        let dims = coarse
            .axes
            .iter()
            .filter(|a| a.nodes.len() > 1)
            .count()
            .max(1);
        let share = e / dims as f64;
        let mut refined = false;
        for (a, segments) in axes.iter_mut().enumerate() {
            let mut next = Vec::with_capacity(segments.len() + 4);
            for (k, seg) in segments.iter().enumerate() {
                let err = check.segment_max[a][k];
                if seg.intervals == 0 || err <= share {
                    next.push(*seg);
                    continue;
                }
                refined = true;
                // Interpolation error falls as h²; aim 10% past the share,
                // but at most 4× per round: near a singularity (a gain
                // film's lasing pole) the h² law does not hold yet.
                let factor = ((err / share).sqrt() * 1.1).min(4.0);
                let m = ((seg.intervals as f64 * factor).ceil() as usize).max(seg.intervals + 1);
                next.extend(refine(seg, m));
            }
            *segments = next;
        }
        if !refined {
            // Only cell centres fail: split the segments around the worst one.
            for (a, segments) in axes.iter_mut().enumerate() {
                let i = check.worst_at[a];
                if i % 2 == 1 {
                    let k = coarse.axes[a].segment_of_interval[(i - 1) / 2];
                    segments[k].intervals *= 2;
                }
            }
        }
        previous = Some((fine, values));
    }
}

/// The stack and everything about it that is fixed for the whole bake.
struct Prepared {
    /// The stack actually evaluated: a layerless stack gets a zero-thickness
    /// layer of the ambient medium, which changes nothing optically.
    stack: Stack,
    layer: usize,
    channels: usize,
    /// rgb kind: the stack at the integration wavelengths and the
    /// linear-sRGB weight of each wavelength (the spectral kind has none).
    stack_grid: StackGrid,
    weights: Vec<[f64; 3]>,
    /// The substrate's critical cos θ (where its q has a branch point),
    /// when it is lossless and optically thinner than the ambient.
    critical_cos: Option<f64>,
}

impl Prepared {
    fn new(spec: &BakeSpec) -> Result<Prepared> {
        let mut stack = spec.stack.clone();
        let layer = if stack.layers.is_empty() {
            stack.layers.push(Layer {
                material: stack.ambient.clone(),
                thickness_nm: 0.0,
            });
            1
        } else {
            spec.layer
        };
        let (stack_grid, weights) = match spec.kind {
            Kind::Rgb => {
                let integrator = SpectralIntegrator::new(spec.sampling);
                (
                    StackGrid::new(&stack, integrator.wavelengths_nm())?,
                    rgb_weights(&integrator),
                )
            }
            Kind::Spectral => (StackGrid::new(&stack, &[])?, Vec::new()),
        };
        let critical_cos = critical_cos(&stack, spec.kind, spec.wavelength_nm);
        Ok(Prepared {
            stack,
            layer,
            channels: channel_names(spec.kind).len(),
            stack_grid,
            weights,
            critical_cos,
        })
    }

    /// Exact values on a grid, layout `[w][c][t][channel]`. Rows (one cos θ
    /// and wavelength) that `previous` also has keep the values of its
    /// thickness chunks that are computed the same way (see [`reuse_plan`]),
    /// so the result is the same bit for bit as evaluating everything.
    fn eval(
        &self,
        grid: &Grid,
        previous: Option<&(Grid, Vec<f64>)>,
        progress: &(dyn Fn(f64) + Sync),
    ) -> Result<Vec<f64>> {
        let [t_axis, c_axis, w_axis] = &grid.axes;
        let ch = self.channels;
        let row_len = t_axis.nodes.len() * ch;
        let rows = c_axis.nodes.len() * w_axis.nodes.len();
        let nc = c_axis.nodes.len();
        let mut out = vec![0.0; rows * row_len];
        let done = std::sync::atomic::AtomicUsize::new(0);
        let tick = || {
            let d = done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
            if d.is_multiple_of(16) || d == rows {
                progress(d as f64 / rows as f64);
            }
        };
        let chunks = chunks(t_axis);
        let all = [Piece::Compute(0..chunks.len())];
        let (plan, old_rows) = match previous {
            Some((old, values)) => (reuse_plan(&chunks, t_axis, &old.axes[0]), {
                let old_row_len = old.axes[0].nodes.len() * ch;
                let key = |w: f64, c: f64| (w.to_bits(), c.to_bits());
                let old_nc = old.axes[1].nodes.len();
                let index: std::collections::HashMap<_, _> = (0..old.axes[2].nodes.len())
                    .flat_map(|w| (0..old_nc).map(move |c| (w, c)))
                    .map(|(w, c)| {
                        let row = w * old_nc + c;
                        (
                            key(old.axes[2].nodes[w], old.axes[1].nodes[c]),
                            &values[row * old_row_len..(row + 1) * old_row_len],
                        )
                    })
                    .collect();
                (0..rows)
                    .map(|row| {
                        let (w, c) = (row / nc, row % nc);
                        index.get(&key(w_axis.nodes[w], c_axis.nodes[c])).copied()
                    })
                    .collect()
            }),
            None => (Vec::new(), vec![None; rows]),
        };
        // The stack at the wavelengths a row integrates over (rgb) or the
        // one it holds (spectral: the row's wavelength node).
        let spectral_grid;
        let stack_grid = if grid.spectral {
            spectral_grid = StackGrid::new(&self.stack, &w_axis.nodes)?;
            &spectral_grid
        } else {
            &self.stack_grid
        };
        let n = t_axis.nodes.len();
        out.par_chunks_mut(row_len).enumerate().for_each_init(
            || Worker::new(n, stack_grid.thicknesses_nm()),
            |wk, (row_index, row)| {
                let (w, c) = (row_index / nc, row_index % nc);
                let cos = c_axis.nodes[c];
                let wavelengths = if grid.spectral {
                    w..w + 1
                } else {
                    0..stack_grid.wavelengths_nm().len()
                };
                let (pieces, old_row) = match old_rows[row_index] {
                    Some(old_row) => (&plan[..], old_row),
                    None => (&all[..], &[][..]),
                };
                // The row's split stacks, one per wavelength, made at its
                // first computed piece and shared by the others.
                wk.splits.clear();
                for piece in pieces {
                    let range = match piece {
                        Piece::Copy {
                            old_start,
                            start,
                            len,
                        } => {
                            row[start * ch..(start + len) * ch]
                                .copy_from_slice(&old_row[old_start * ch..(old_start + len) * ch]);
                            continue;
                        }
                        Piece::Compute(range) => &chunks[range.clone()],
                    };
                    if wk.splits.is_empty() {
                        for i in wavelengths.clone() {
                            let v = self.split(stack_grid, i, cos, &mut wk.scratch);
                            wk.splits.push((i, v));
                        }
                    }
                    let start = range[0].start;
                    let m = range.iter().map(|k| k.start + k.len).max().unwrap_or(start) - start;
                    let nodes = &t_axis.nodes[start..start + m];
                    let dst = &mut row[start * ch..(start + m) * ch];
                    if grid.spectral {
                        let split = wk.splits[0];
                        self.responses(&split, stack_grid, cos, nodes, range, wk);
                        for (o, (&r, &t)) in dst.chunks_exact_mut(2).zip(wk.r.iter().zip(&wk.t)) {
                            o[0] = r;
                            o[1] = t;
                        }
                        continue;
                    }
                    // Channel-major accumulators ([channel][node]), so the
                    // weighting loop below runs over contiguous arrays.
                    wk.acc.clear();
                    wk.acc.resize(6 * m, 0.0);
                    for k in 0..wk.splits.len() {
                        let split = wk.splits[k];
                        self.responses(&split, stack_grid, cos, nodes, range, wk);
                        accumulate(&mut wk.acc, &wk.r[..m], &wk.t[..m], self.weights[split.0]);
                    }
                    for (j, o) in dst.chunks_exact_mut(6).enumerate() {
                        for (k, o) in o.iter_mut().enumerate() {
                            *o = wk.acc[k * m + j];
                        }
                    }
                }
                tick();
            },
        );
        Ok(out)
    }

    /// Unpolarized R and T at the thickness `nodes` (the nodes `chunks`
    /// cover, from the first chunk's start) into `wk.r`, `wk.t`: the
    /// split-stack form (`split`: the stack split at `stack_grid`'s wavelength
    /// of that index), or the solver node by node where the split is
    /// degenerate (the varying layer at its own critical angle).
    fn responses(
        &self,
        &(i, ref v): &(usize, VaryingLayer),
        stack_grid: &StackGrid,
        cos: f64,
        nodes: &[f64],
        chunks: &[Chunk],
        wk: &mut Worker,
    ) {
        let m = nodes.len();
        if !v.is_degenerate() {
            let (re, im) = (&mut wk.phase_re[..m], &mut wk.phase_im[..m]);
            phases(v, nodes, chunks, re, im);
            v.responses(re, im, &mut wk.r[..m], &mut wk.t[..m]);
            return;
        }
        let (idx, wavelength_nm) = (stack_grid.indices_at(i), stack_grid.wavelengths_nm()[i]);
        for (j, &t) in nodes.iter().enumerate() {
            wk.thicknesses_nm[self.layer - 1] = t;
            let resp = solve(idx, &wk.thicknesses_nm, wavelength_nm, cos);
            wk.r[j] = resp.r();
            wk.t[j] = resp.t();
        }
    }

    /// The stack split around the varying layer at `stack_grid`'s `i`-th
    /// wavelength and `cos`.
    #[inline]
    fn split(
        &self,
        stack_grid: &StackGrid,
        i: usize,
        cos: f64,
        scratch: &mut Scratch,
    ) -> VaryingLayer {
        VaryingLayer::new(
            stack_grid.indices_at(i),
            stack_grid.thicknesses_nm(),
            self.layer,
            stack_grid.wavelengths_nm()[i],
            cos,
            scratch,
        )
    }
}

/// The substrate's critical cos θ (where its normal index has a square-root
/// branch point), when it is lossless and optically thinner than the
/// ambient, at 550 nm for rgb tables or mid-range for spectral ones.
pub(crate) fn critical_cos(stack: &Stack, kind: Kind, wavelength_nm: (f64, f64)) -> Option<f64> {
    let reference_nm = match kind {
        Kind::Rgb => 550.0,
        Kind::Spectral => 0.5 * (wavelength_nm.0 + wavelength_nm.1),
    };
    match (
        stack.ambient.index_at(reference_nm),
        stack.substrate.index_at(reference_nm),
    ) {
        (Ok(n0), Ok(ns)) if ns.im == 0.0 && ns.re < n0.re => {
            Some((1.0 - (ns.re / n0.re).powi(2)).sqrt())
        }
        _ => None,
    }
}

/// The linear-sRGB weight of each integration wavelength, as triples: the
/// integrator is linear in the spectrum, so the bake accumulates weight × R
/// per node instead of storing whole spectra.
fn rgb_weights(integrator: &SpectralIntegrator) -> Vec<[f64; 3]> {
    let [r, g, b] = integrator.rgb_weights();
    r.iter()
        .zip(g)
        .zip(b)
        .map(|((&r, &g), &b)| [r, g, b])
        .collect()
}

avx2_dispatch! {
    /// Adds `weights` × R and × T to channel-major accumulators
    /// (`[channel][node]`, R channels first).
    fn accumulate(acc: &mut [f64], r: &[f64], t: &[f64], weights: [f64; 3]) {
        let n = r.len();
        let (acc_r, acc_t) = acc.split_at_mut(3 * n);
        for (acc, values) in [(acc_r, r), (acc_t, t)] {
            for (a, wt) in acc.chunks_exact_mut(n).zip(weights) {
                for (a, &v) in a.iter_mut().zip(values) {
                    *a += wt * v;
                }
            }
        }
    }
}

/// One worker's buffers, allocated once per rayon task.
struct Worker {
    scratch: Scratch,
    /// The current row's split stacks, each with its wavelength's index.
    splits: Vec<(usize, VaryingLayer)>,
    thicknesses_nm: Vec<f64>,
    phase_re: Vec<f64>,
    phase_im: Vec<f64>,
    r: Vec<f64>,
    t: Vec<f64>,
    acc: Vec<f64>,
}

impl Worker {
    fn new(nodes: usize, thicknesses_nm: &[f64]) -> Worker {
        Worker {
            scratch: Scratch::default(),
            splits: Vec::new(),
            thicknesses_nm: thicknesses_nm.to_vec(),
            phase_re: vec![0.0; nodes],
            phase_im: vec![0.0; nodes],
            r: vec![0.0; nodes],
            t: vec![0.0; nodes],
            acc: Vec::with_capacity(6 * nodes),
        }
    }
}

/// A stretch of at most [`PHASE_RESYNC`] thickness nodes whose phase
/// factors start from an exact exponential at the first and advance by the
/// spacing `step` (see [`phases`]). Their values depend only on that first
/// node, `step` and the stack, cos θ and wavelength: a chunk that appears
/// in two grids gives the same values in both.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Chunk {
    start: usize,
    len: usize,
    step: f64,
}

/// The chunks of a thickness axis, in order. Adjacent uniform segments with
/// the same spacing (the halves of a refined one) form one run, cut into
/// chunks of [`PHASE_RESYNC`] nodes from its start; consecutive runs share
/// their boundary node, which the later run's chunk sets.
fn chunks(t_axis: &AxisGrid) -> Vec<Chunk> {
    let mut runs = Vec::new();
    let (mut run_start, mut run_step, mut j) = (0, 0.0, 0);
    for seg in &t_axis.segments {
        if seg.intervals == 0 {
            continue;
        }
        let step = (seg.end - seg.start) / seg.intervals as f64;
        if (step - run_step).abs() > 1e-12 * step {
            if j > run_start {
                runs.push((run_start, j, run_step));
            }
            run_start = j;
            run_step = step;
        }
        j += seg.intervals;
    }
    runs.push((run_start, j, run_step));
    let mut out = Vec::new();
    for (start, last, step) in runs {
        for chunk in (start..=last).step_by(PHASE_RESYNC) {
            out.push(Chunk {
                start: chunk,
                len: (chunk + PHASE_RESYNC).min(last + 1) - chunk,
                step,
            });
        }
    }
    out
}

/// One step of evaluating a row: copy a chunk's values from the previous
/// grid's row, or compute consecutive chunks.
#[derive(Clone, Debug)]
enum Piece {
    Copy {
        old_start: usize,
        start: usize,
        len: usize,
    },
    Compute(std::ops::Range<usize>),
}

/// How to evaluate a row that the previous grid also has (same cos θ and
/// wavelength): each chunk whose first node and step match a chunk of the
/// old axis at least as long, with the same node positions, is copied;
/// the rest are computed. Pieces follow chunk order, so the node two runs
/// share gets the later run's value, as in a full evaluation.
fn reuse_plan(chunks: &[Chunk], t_axis: &AxisGrid, old_axis: &AxisGrid) -> Vec<Piece> {
    let key = |c: &Chunk, nodes: &[f64]| (nodes[c.start].to_bits(), c.step.to_bits());
    let old: std::collections::HashMap<_, _> = self::chunks(old_axis)
        .into_iter()
        .map(|c| (key(&c, &old_axis.nodes), c))
        .collect();
    let same_nodes =
        |a: &[f64], b: &[f64]| a.iter().zip(b).all(|(x, y)| x.to_bits() == y.to_bits());
    let mut plan: Vec<Piece> = Vec::new();
    for (i, c) in chunks.iter().enumerate() {
        let found = old.get(&key(c, &t_axis.nodes)).filter(|o| {
            o.len >= c.len
                && same_nodes(
                    &old_axis.nodes[o.start..o.start + c.len],
                    &t_axis.nodes[c.start..c.start + c.len],
                )
        });
        match (found, plan.last_mut()) {
            (Some(o), _) => plan.push(Piece::Copy {
                old_start: o.start,
                start: c.start,
                len: c.len,
            }),
            (None, Some(Piece::Compute(range))) => range.end = i + 1,
            (None, _) => plan.push(Piece::Compute(i..i + 1)),
        }
    }
    plan
}

avx2_dispatch! {
    /// The phase factor at the nodes `chunks` cover, from the first chunk's
    /// start (`nodes`, `re` and `im` begin there). Each chunk starts from an
    /// exact exponential, its first [`PHASE_LANES`] nodes follow by one
    /// complex multiplication each, and every later node is the one
    /// [`PHASE_LANES`] back times δ^[`PHASE_LANES`]: the lanes are
    /// independent chains, so the loop is not one long chain of dependent
    /// multiplications.
    fn phases(v: &VaryingLayer, nodes: &[f64], chunks: &[Chunk], re: &mut [f64], im: &mut [f64]) {
        let origin = chunks.first().map_or(0, |c| c.start);
        let mut step_bits = None;
        let (mut delta, mut lanes_step) = (C64::new(1.0, 0.0), C64::new(1.0, 0.0));
        for c in chunks {
            if step_bits != Some(c.step.to_bits()) {
                step_bits = Some(c.step.to_bits());
                delta = v.phase(c.step);
                lanes_step = delta;
                for _ in 0..PHASE_LANES.trailing_zeros() {
                    lanes_step = lanes_step * lanes_step;
                }
            }
            let (start, end) = (c.start - origin, c.start - origin + c.len);
            let mut phase = v.phase(nodes[start]);
            for j in start..end.min(start + PHASE_LANES) {
                re[j] = phase.re;
                im[j] = phase.im;
                phase *= delta;
            }
            for j in start + PHASE_LANES..end {
                let (a, b) = (re[j - PHASE_LANES], im[j - PHASE_LANES]);
                re[j] = a * lanes_step.re - b * lanes_step.im;
                im[j] = a * lanes_step.im + b * lanes_step.re;
            }
        }
    }
}

/// Independent multiplication chains in [`phases`].
const PHASE_LANES: usize = 8;

/// The nodes of one axis and the segment each interval belongs to.
#[derive(Clone, Debug)]
struct AxisGrid {
    segments: Vec<Segment>,
    nodes: Vec<f64>,
    segment_of_interval: Vec<usize>,
}

impl AxisGrid {
    fn new(segments: &[Segment]) -> AxisGrid {
        let segment_of_interval = segments
            .iter()
            .enumerate()
            .flat_map(|(k, s)| std::iter::repeat_n(k, s.intervals))
            .collect();
        AxisGrid {
            segments: segments.to_vec(),
            nodes: segment_nodes(segments),
            segment_of_interval,
        }
    }
}

/// Node positions of one grid: thickness, cos θ, wavelength (a single
/// unused node for the rgb kind).
#[derive(Clone)]
struct Grid {
    axes: [AxisGrid; 3],
    spectral: bool,
}

impl Grid {
    fn new(axes: &[Vec<Segment>; 3], kind: Kind) -> Grid {
        Grid {
            axes: [
                AxisGrid::new(&axes[0]),
                AxisGrid::new(&axes[1]),
                AxisGrid::new(&axes[2]),
            ],
            spectral: kind == Kind::Spectral,
        }
    }

    fn total(&self) -> usize {
        self.axes.iter().map(|a| a.nodes.len()).product()
    }

    fn nodes(&self) -> [&[f64]; 3] {
        self.axes.each_ref().map(|a| &a.nodes[..])
    }
}

fn doubled(segments: &[Segment]) -> Vec<Segment> {
    segments
        .iter()
        .map(|s| Segment {
            intervals: 2 * s.intervals,
            ..*s
        })
        .collect()
}

/// A segment with `intervals` intervals in place of its own. A uniform one
/// is also halved, so that refinement concentrates where the error is (a
/// film near zero thickness at grazing incidence); a graded one keeps its
/// grading.
fn refine(seg: &Segment, intervals: usize) -> Vec<Segment> {
    if seg.grading == Grading::Uniform {
        let mid = 0.5 * (seg.start + seg.end);
        let half = intervals.div_ceil(2);
        vec![uniform(seg.start, mid, half), uniform(mid, seg.end, half)]
    } else {
        vec![Segment { intervals, ..*seg }]
    }
}

fn uniform(start: f64, end: f64, intervals: usize) -> Segment {
    Segment {
        start,
        end,
        grading: Grading::Uniform,
        intervals: if end > start { intervals.max(1) } else { 0 },
    }
}

/// `count` equal uniform segments of `per` intervals each over a range.
fn split_uniform(start: f64, end: f64, count: usize, per: usize) -> Vec<Segment> {
    if end <= start {
        return vec![uniform(start, start, 0)];
    }
    (0..count)
        .map(|k| {
            let a = start + (end - start) * k as f64 / count as f64;
            let b = if k + 1 == count {
                end
            } else {
                start + (end - start) * (k + 1) as f64 / count as f64
            };
            uniform(a, b, per)
        })
        .collect()
}

/// The starting grid. A fixed `--resolution` is one uniform segment per
/// axis (graded around a critical angle). For an error target the axes
/// start coarse and split into segments that refine independently:
/// thickness in pieces of about 50 nm (the response of a film is hardest
/// near zero thickness at grazing incidence, where it changes on a scale
/// proportional to cos θ), cos θ in quarters, wavelength as one piece.
fn initial_axes(spec: &BakeSpec, prep: &Prepared) -> [Vec<Segment>; 3] {
    let (t0, t1) = spec.thickness_nm;
    let (c0, c1) = spec.cos_theta;
    let (w0, w1) = match spec.kind {
        Kind::Rgb => (0.0, 0.0),
        Kind::Spectral => spec.wavelength_nm,
    };
    let critical = prep
        .critical_cos
        .filter(|&cc| cc > c0 + 1e-6 && cc < c1 - 1e-6);
    let graded = |c_int: usize| {
        let cc = critical.unwrap_or(c0);
        let mut segments = vec![
            Segment {
                start: c0,
                end: cc,
                grading: Grading::TowardEnd,
                intervals: 0,
            },
            Segment {
                start: cc,
                end: c1,
                grading: Grading::TowardStart,
                intervals: 0,
            },
        ];
        share_intervals(&mut segments, c_int.max(2));
        segments
    };
    match spec.resolution {
        Resolution::Nodes {
            thickness,
            angle,
            wavelength,
        } => [
            vec![uniform(t0, t1, thickness - 1)],
            match critical {
                Some(_) if angle >= 3 => graded(angle - 1),
                _ => vec![uniform(c0, c1, angle - 1)],
            },
            vec![uniform(w0, w1, wavelength.saturating_sub(1))],
        ],
        Resolution::MaxError(_) => {
            let pieces = (((t1 - t0) / 50.0).round() as usize).clamp(1, 32);
            [
                split_uniform(t0, t1, pieces, 4),
                match critical {
                    Some(_) => graded(16),
                    None => split_uniform(c0, c1, 4, 4),
                },
                vec![uniform(w0, w1, ((w1 - w0) / 20.0).ceil() as usize)],
            ]
        }
    }
}

/// A table must hold the values it was baked from: a gain film near a
/// lasing pole reflects far more than f16's largest value (65504), which
/// would be stored as infinity. Names the first node that does not fit
/// (`nodes`: thickness, cos θ and wavelength axes; the last unused for rgb).
fn representable(data: &[f32], nodes: &[&[f64]; 3], kind: Kind, half: bool) -> Result<()> {
    let Some(k) = data.iter().position(|v| !v.is_finite()) else {
        return Ok(());
    };
    let names = channel_names(kind);
    let (node, channel) = (k / names.len(), names[k % names.len()]);
    let [t_nodes, c_nodes, w_nodes] = nodes;
    let (nt, nc) = (t_nodes.len(), c_nodes.len());
    let mut at = format!(
        "thickness {:.2} nm, cos θ {:.5}",
        t_nodes[node % nt],
        c_nodes[(node / nt) % nc]
    );
    if kind == Kind::Spectral {
        at += &format!(", wavelength {:.1} nm", w_nodes[node / (nt * nc)]);
    }
    Err(if half {
        Error::HalfOverflow {
            why: format!(
                "{channel} exceeds f16's largest value (65504) at {at}; bake in f32 (without --half) or narrow --thickness or --angles"
            ),
        }
    } else {
        Error::invalid("baked table", format!("{channel} is not finite at {at}"))
    })
}

impl Lut {
    /// This table with every value rounded to f16, for a caller that has the
    /// f32 table and wants the f16 one too without baking again: the values a
    /// `--half` bake of the same spec stores (it rounds through f32 too), but
    /// the header keeps no error figures (they measured the f32 table's
    /// rounding) and no cache key (a bake's header differs). Refused, as by
    /// the baker, when a value overflows f16.
    pub(crate) fn rounded_to_half(&self) -> Result<Lut> {
        let data: Vec<f32> = self
            .data()
            .iter()
            .map(|&v| stored(f64::from(v), true))
            .collect();
        let h = self.header();
        let axis = |k: usize| h.axes.get(k).map_or(&[][..], |a| &a.nodes[..]);
        representable(&data, &[axis(0), axis(1), axis(2)], h.kind, true)?;
        let mut header = h.clone();
        header.precision = "f16".into();
        header.error.bake_check = None;
        header.error.validation = None;
        header.cache_key.clear();
        Lut::from_parts(header, data).map_err(|why| Error::invalid("rounded table", why))
    }
}

/// Rounds a value as it will be stored. An f16 value is rounded from the
/// f32 one, as the `half` crate's f64 conversion does on x86 with F16C; its
/// other paths (no F16C, aarch64) work from the f64, which differs where the
/// f32 value lies exactly halfway between two f16 values. Through f32
/// everywhere, a table is the same on every machine and an f32 table rounded
/// to f16 is the f16 table (see [`Lut::rounded_to_half`]).
#[inline]
fn stored(v: f64, half: bool) -> f32 {
    let single = v as f32;
    if half {
        half::f16::from_f32(single).to_f32()
    } else {
        single
    }
}

struct Check {
    /// Per channel, over every fine point.
    max_channel: Vec<f64>,
    max_all: f64,
    /// Per axis and segment: the largest error (over channels) at fine
    /// points that are midpoints along that axis inside that segment.
    segment_max: [Vec<f64>; 3],
    points: usize,
    /// Fine indices of the worst point.
    worst_at: [usize; 3],
}

/// Compares exact values at every fine node with the multilinear
/// interpolation of the stored coarse table `data` (the fine values at even
/// indices, rounded as stored: see [`even_subgrid`]).
fn measure(coarse: &Grid, fine: &Grid, values: &[f64], data: &[f32], channels: usize) -> Check {
    let dims = fine.axes.each_ref().map(|a| a.nodes.len());
    let coarse_dims = coarse.axes.each_ref().map(|a| a.nodes.len());
    // Interpolation weight of the right-hand coarse neighbour at each odd
    // fine index (1/2 on uniform segments, not on graded ones).
    let weights: Vec<Vec<f64>> = fine
        .axes
        .iter()
        .map(|a| {
            (0..a.nodes.len())
                .map(|i| {
                    if i % 2 == 1 {
                        (a.nodes[i] - a.nodes[i - 1]) / (a.nodes[i + 1] - a.nodes[i - 1])
                    } else {
                        0.0
                    }
                })
                .collect()
        })
        .collect();
    let strides = [channels, dims[0] * channels, dims[0] * dims[1] * channels];
    let coarse_strides = [
        channels,
        coarse_dims[0] * channels,
        coarse_dims[0] * coarse_dims[1] * channels,
    ];
    let mut check = Check {
        max_channel: vec![0.0; channels],
        max_all: 0.0,
        segment_max: coarse.axes.clone().map(|a| vec![0.0; a.segments.len()]),
        points: 0,
        worst_at: [0; 3],
    };
    let mut corners = [(0usize, 1.0f64); 8];
    for w in 0..dims[2] {
        for c in 0..dims[1] {
            for t in 0..dims[0] {
                let at_idx = [t, c, w];
                let at = t * strides[0] + c * strides[1] + w * strides[2];
                // Corners of the coarse cell: each odd axis contributes its
                // two neighbours, the coarse nodes i / 2 and i / 2 + 1.
                corners[0] = ((0..3).map(|a| at_idx[a] / 2 * coarse_strides[a]).sum(), 1.0);
                let mut count = 1;
                for a in 0..3 {
                    let i = at_idx[a];
                    if i % 2 == 1 {
                        let wt = weights[a][i];
                        for k in 0..count {
                            let (base, cw) = corners[k];
                            corners[k] = (base, cw * (1.0 - wt));
                            corners[count + k] = (base + coarse_strides[a], cw * wt);
                        }
                        count *= 2;
                    }
                }
                let mut worst = 0.0f64;
                for ch in 0..channels {
                    let interp: f64 = corners[..count]
                        .iter()
                        .map(|&(base, wt)| wt * f64::from(data[base + ch]))
                        .sum();
                    let err = (interp - values[at + ch]).abs();
                    check.max_channel[ch] = check.max_channel[ch].max(err);
                    worst = worst.max(err);
                }
                if worst > check.max_all {
                    check.max_all = worst;
                    check.worst_at = at_idx;
                }
                // Edge midpoints measure one axis's spacing alone; cell
                // centres mix them and only break ties (see the caller).
                let odd: Vec<usize> = (0..3).filter(|&a| at_idx[a] % 2 == 1).collect();
                if let [a] = odd[..] {
                    let k = coarse.axes[a].segment_of_interval[(at_idx[a] - 1) / 2];
                    let m = &mut check.segment_max[a][k];
                    *m = m.max(worst);
                }
                check.points += 1;
            }
        }
    }
    check
}

/// The coarse table: fine values at even indices, rounded as stored.
fn even_subgrid(fine: &Grid, values: &[f64], channels: usize, half: bool) -> Vec<f32> {
    let dims = fine.axes.each_ref().map(|a| a.nodes.len());
    let mut out = Vec::with_capacity(values.len() / 4);
    for w in (0..dims[2]).step_by(2) {
        for c in (0..dims[1]).step_by(2) {
            for t in (0..dims[0]).step_by(2) {
                let at = ((w * dims[1] + c) * dims[0] + t) * channels;
                out.extend(values[at..at + channels].iter().map(|&v| stored(v, half)));
            }
        }
    }
    out
}

fn header(
    spec: &BakeSpec,
    prep: &Prepared,
    coarse: &Grid,
    check: Option<&Check>,
    target: Option<f64>,
) -> Header {
    let channel_meaning = |name: &str| -> String {
        let (quantity, rest) = name.split_once('.').unwrap_or((name, ""));
        let what = if quantity == "reflectance" {
            "unpolarized reflectance"
        } else {
            "unpolarized transmittance (power into the substrate)"
        };
        match rest {
            "" => format!("{what} at the node's wavelength"),
            c => format!("{what}, linear sRGB {c} under D65 (a perfect reflector is 1)"),
        }
    };
    let mut axes = vec![
        Axis {
            name: THICKNESS_AXIS.into(),
            unit: "nm".into(),
            nodes: coarse.axes[0].nodes.clone(),
        },
        Axis {
            name: COS_AXIS.into(),
            unit: "1".into(),
            nodes: coarse.axes[1].nodes.clone(),
        },
    ];
    if spec.kind == Kind::Spectral {
        axes.push(Axis {
            name: WAVELENGTH_AXIS.into(),
            unit: "nm".into(),
            nodes: coarse.axes[2].nodes.clone(),
        });
    }
    let names = channel_names(spec.kind);
    Header {
        format: FORMAT_NAME.into(),
        version: FORMAT_VERSION,
        kind: spec.kind,
        x_axis: THICKNESS_AXIS.into(),
        y_axis: COS_AXIS.into(),
        y_blocks: (spec.kind == Kind::Spectral).then(|| WAVELENGTH_AXIS.into()),
        axes,
        channels: names
            .iter()
            .map(|n| Channel {
                name: (*n).into(),
                meaning: channel_meaning(n),
            })
            .collect(),
        precision: if spec.half { "f16" } else { "f32" }.into(),
        stack: spec.stack.clone(),
        layer: if spec.stack.layers.is_empty() {
            0
        } else {
            prep.layer
        },
        color: ColorInfo {
            illuminant: "CIE D65".into(),
            observer: "CIE 1931 2°".into(),
            space: "linear sRGB (ITU-R BT.709 primaries, D65 white)".into(),
            sampling: spec.sampling.to_string(),
        },
        error: ErrorInfo {
            target_max_abs: target,
            bake_check: check.map(|check| BakeCheck {
                metric: BAKE_CHECK_METRIC.into(),
                points: check.points,
                max_abs: check.max_channel.clone(),
                max_abs_all: check.max_all,
            }),
            validation: None,
        },
        tool: format!("irid {}", env!("CARGO_PKG_VERSION")),
        cache_key: spec.cache_key(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
            let (mut re, mut im) = (vec![0.0; n], vec![0.0; n]);
            phases(&v, &axis.nodes, &chunks(&axis), &mut re, &mut im);
            for (j, &d) in axis.nodes.iter().enumerate() {
                let want = v.phase(d);
                worst = worst.max((C64::new(re[j], im[j]) - want).norm() / (1.0 + want.norm()));
            }
            let (mut r, mut t) = (vec![0.0; n], vec![0.0; n]);
            v.responses(&re, &im, &mut r, &mut t);
            for j in 0..n {
                let want = v.response(v.phase(axis.nodes[j]));
                for (g, w) in [(r[j], want.r()), (t[j], want.t())] {
                    worst = worst.max((g - w).abs() / (1.0 + w.abs()));
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
    fn rgb_weights_are_the_colour_of_an_impulse() {
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
            layers: vec![Layer {
                material: crate::optics::Material::constant(1.38, 0.02),
                thickness_nm: 100.0,
            }],
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
            layers: vec![Layer {
                material: crate::optics::Material::constant(1.0, 0.0),
                thickness_nm: 100.0,
            }],
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
}
