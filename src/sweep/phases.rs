//! The phase factor e^{i k₀ q d} of the varying layer along a row of
//! thickness nodes: chunks of evenly spaced nodes advanced by complex
//! multiplication from an exact exponential at each chunk's start, and the
//! plan that copies the chunks a previous grid's row already holds.

use num_complex::Complex64 as C64;

use super::grid::{AxisGrid, Grid};
use super::prepared::Worker;
use crate::optics::lanes::{one_way_many, Path, MAX_LANES};
use crate::optics::twoport::VaryingLayer;
use crate::simd::simd_dispatch;

/// The phase factor along a uniform thickness axis is advanced by complex
/// multiplications and recomputed exactly this often (see [`phases`]): the
/// rounding then stays near 1e-14 (tested), while the complex exponential
/// (a sincos) is paid on one node in 64.
pub(crate) const PHASE_RESYNC: usize = 64;

/// For each row of `grid` (one cos θ and wavelength), the same row of the
/// previous grid `old` (values `values`, `channels` per node), if it has one.
pub(super) fn previous_rows<'a>(
    grid: &Grid,
    old: &Grid,
    values: &'a [f64],
    channels: usize,
) -> Vec<Option<&'a [f64]>> {
    let [_, c_axis, w_axis] = &grid.axes;
    let nc = c_axis.nodes.len();
    let old_row_len = old.axes[0].nodes.len() * channels;
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
    (0..nc * w_axis.nodes.len())
        .map(|row| {
            let (w, c) = (row / nc, row % nc);
            index.get(&key(w_axis.nodes[w], c_axis.nodes[c])).copied()
        })
        .collect()
}

/// Node counts are rounded up to this many for the vectorised loops (the
/// widest vector holds 8 f64), so that they never end in a scalar
/// remainder: on the check's 255-node rows the 7 left over, one at a time,
/// took about 8 % of the fused loop's samples. The padding's values are
/// computed (from zeros) and discarded.
pub(super) const PAD: usize = 8;

/// `nodes` rounded up to whole [`PAD`]s.
pub(super) fn padded(nodes: usize) -> usize {
    nodes.next_multiple_of(PAD)
}

/// How a row's phase factors are formed.
#[derive(Clone, Copy)]
pub(crate) enum Phases<'a> {
    /// Chunks of evenly spaced nodes, each advanced by a recurrence from an
    /// exact exponential at its start (see [`phases`]).
    Chunks(&'a [Chunk]),
    /// An exact exponential at every node (nodes spaced unevenly, as an
    /// atlas chart's are).
    Exact,
}

/// The phase factors at `nodes` (see [`phases`]) into `wk.phase_re`,
/// `wk.phase_im`, zero from there up to [`padded`] length.
pub(super) fn phase_factors(v: &VaryingLayer, nodes: &[f64], plan: Phases, wk: &mut Worker) {
    let (m, mp) = (nodes.len(), padded(nodes.len()));
    let (re, im) = (&mut wk.phase_re[..m + PAD], &mut wk.phase_im[..m + PAD]);
    match plan {
        Phases::Chunks(chunks) => phases(v, nodes, chunks, re, im),
        Phases::Exact => exact_phases(v, nodes, re, im),
    }
    re[m..mp].fill(0.0);
    im[m..mp].fill(0.0);
}

/// The phase factor at every node from the lanes' exponential, eight at a
/// time.
fn exact_phases(v: &VaryingLayer, nodes: &[f64], re: &mut [f64], im: &mut [f64]) {
    for (k, group) in nodes.chunks(MAX_LANES).enumerate() {
        let mut angles = [C64::new(0.0, 0.0); MAX_LANES];
        for (a, &d) in angles.iter_mut().zip(group) {
            *a = v.phase_angle(d);
        }
        let exact = one_way_many(Path::Best, &angles);
        for (l, e) in exact.iter().enumerate().take(group.len()) {
            re[k * MAX_LANES + l] = e.re;
            im[k * MAX_LANES + l] = e.im;
        }
    }
}

/// A stretch of at most [`PHASE_RESYNC`] thickness nodes whose phase
/// factors start from an exact exponential at the first and advance by the
/// spacing `step` (see [`phases`]). Their values depend only on that first
/// node, `step` and the stack, cos θ and wavelength: a chunk that appears
/// in two grids gives the same values in both.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Chunk {
    pub(crate) start: usize,
    pub(crate) len: usize,
    pub(crate) step: f64,
}

/// The chunks of a thickness axis, in order. Adjacent uniform segments with
/// the same spacing (the halves of a refined one) form one run, cut into
/// chunks of [`PHASE_RESYNC`] nodes from its start; consecutive runs share
/// their boundary node, which the later run's chunk sets.
pub(crate) fn chunks(t_axis: &AxisGrid) -> Vec<Chunk> {
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
pub(crate) enum Piece {
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
pub(crate) fn reuse_plan(chunks: &[Chunk], t_axis: &AxisGrid, old_axis: &AxisGrid) -> Vec<Piece> {
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

simd_dispatch! {
    /// The phase factor at the nodes `chunks` cover, from the first chunk's
    /// start (`nodes`, `re` and `im` begin there). Each chunk starts from an
    /// exact exponential, its first [`PHASE_LANES`] nodes follow by one
    /// complex multiplication each, and every later node is the one
    /// [`PHASE_LANES`] back times δ^[`PHASE_LANES`]: the lanes are
    /// independent chains, so the loop is not one long chain of dependent
    /// multiplications. The first nodes' chains of [`PHASE_GROUP`] chunks
    /// run side by side for the same reason, and the lanes advance a whole
    /// vector of [`PHASE_LANES`] at a time, so no scalar remainder loop
    /// runs: `re` and `im` need [`PHASE_LANES`] − 1 spare entries past the
    /// last node.
    pub(crate) fn phases(v: &VaryingLayer, nodes: &[f64], chunks: &[Chunk], re: &mut [f64], im: &mut [f64]) {
        let origin = chunks.first().map_or(0, |c| c.start);
        let one = C64::new(1.0, 0.0);
        let mut step_bits = None;
        let (mut delta, mut lanes_step) = (one, one);
        for group in chunks.chunks(PHASE_GROUP) {
            // The exact factors this group needs, all in one call to the
            // lanes' exponential: each chunk's first node (lanes 0–3) and the
            // spacing of each chunk whose spacing differs from the one
            // before it (lanes 4–7). Scalar library calls for these were
            // 5 % of a bake.
            let mut angles = [C64::new(0.0, 0.0); MAX_LANES];
            let mut new_step = [false; PHASE_GROUP];
            for (g, c) in group.iter().enumerate() {
                angles[g] = v.phase_angle(nodes[c.start - origin]);
                if step_bits != Some(c.step.to_bits()) {
                    step_bits = Some(c.step.to_bits());
                    new_step[g] = true;
                    angles[PHASE_GROUP + g] = v.phase_angle(c.step);
                }
            }
            let exact = one_way_many(Path::Best, &angles);
            let mut deltas = [one; PHASE_GROUP];
            let mut steps = [one; PHASE_GROUP];
            let mut phase = [one; PHASE_GROUP];
            for g in 0..group.len() {
                if new_step[g] {
                    delta = exact[PHASE_GROUP + g];
                    lanes_step = delta;
                    for _ in 0..PHASE_LANES.trailing_zeros() {
                        lanes_step = lanes_step * lanes_step;
                    }
                }
                (deltas[g], steps[g]) = (delta, lanes_step);
                phase[g] = exact[g];
            }
            // heads[g]: the first PHASE_LANES phases of chunk g, real then
            // imaginary parts.
            let mut heads = [([0.0; PHASE_LANES], [0.0; PHASE_LANES]); PHASE_GROUP];
            for l in 0..PHASE_LANES {
                for g in 0..PHASE_GROUP {
                    heads[g].0[l] = phase[g].re;
                    heads[g].1[l] = phase[g].im;
                    phase[g] *= deltas[g];
                }
            }
            // A chunk runs on to whole vectors (the buffers have room): the
            // values past its end are a later chunk's to overwrite or the
            // caller's to discard. Where the group's chunks tile their nodes
            // in whole vectors (the chunks of one run, but for its last),
            // none writes another's nodes, and their chains advance side by
            // side: each alone waits on its own multiplications.
            let tiled = group
                .windows(2)
                .all(|w| w[0].start + w[0].len == w[1].start && w[0].len % PHASE_LANES == 0);
            // Otherwise one chunk at a time, in chunk order: the node two
            // runs share gets the later run's value.
            let together = if tiled { group.len() } else { 1 };
            let mut lanes = heads;
            for first in (0..group.len()).step_by(together) {
                let mut vectors = [0; PHASE_GROUP];
                for g in first..(first + together).min(group.len()) {
                    vectors[g] = group[g].len.div_ceil(PHASE_LANES);
                }
                let longest = vectors.iter().copied().max().unwrap_or(0);
                for k in 0..longest {
                    for g in 0..PHASE_GROUP {
                        if k >= vectors[g] {
                            continue;
                        }
                        let (a, b) = &mut lanes[g];
                        if k > 0 {
                            let s = steps[g];
                            for l in 0..PHASE_LANES {
                                (a[l], b[l]) = (a[l] * s.re - b[l] * s.im, a[l] * s.im + b[l] * s.re);
                            }
                        }
                        let j = group[g].start - origin + k * PHASE_LANES;
                        re[j..j + PHASE_LANES].copy_from_slice(a);
                        im[j..j + PHASE_LANES].copy_from_slice(b);
                    }
                }
            }
        }
    }
}

/// Chunks whose first [`PHASE_LANES`] phases [`phases`] computes side by
/// side: each is a chain of dependent complex multiplications.
const PHASE_GROUP: usize = 4;

// `phases` asks the lanes for a group's first phases and spacings at once.
const _: () = assert!(2 * PHASE_GROUP <= MAX_LANES);

/// Independent multiplication chains in [`phases`].
pub(crate) const PHASE_LANES: usize = 8;
