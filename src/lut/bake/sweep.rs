//! Evaluating a grid: the stack split around the varying layer once per
//! cos θ and wavelength, then the phase factor swept along the thickness
//! axis, with rows the previous round's grid shares copied instead.

use num_complex::Complex64 as C64;
use rayon::prelude::*;

use super::critical_cos;
use super::grid::{AxisGrid, Grid};
use std::sync::OnceLock;

use crate::color::refine::{Refinement, MAX_SUB_STEPS};
use crate::color::{Sampling, SpectralIntegrator};
use crate::error::{Error, Result};
use crate::lut::sample::channel_names;
use crate::lut::{BakeSpec, Kind};
use crate::optics::lanes::{one_way_many, Path, MAX_LANES};
use crate::optics::twoport::{Scratch, VaryingLayer};
use crate::optics::{solve_mixed, Layer, Stack, StackGrid};
use crate::simd::simd_dispatch;

/// The phase factor along a uniform thickness axis is advanced by complex
/// multiplications and recomputed exactly this often (see [`phases`]): the
/// rounding then stays near 1e-14 (tested), while the complex exponential
/// (a sincos) is paid on one node in 64.
pub(super) const PHASE_RESYNC: usize = 64;

/// The stack a sweep evaluates and its varying layer: a layerless stack gets
/// a zero-thickness layer of the ambient medium (layer 1), which changes
/// nothing optically but gives the sweep a layer to vary.
pub(crate) fn with_varying_layer(stack: &Stack, layer: usize) -> (Stack, usize) {
    let mut stack = stack.clone();
    if stack.layers.is_empty() {
        stack.layers.push(Layer::new(stack.ambient.clone(), 0.0));
        return (stack, 1);
    }
    (stack, layer)
}

/// The stack and everything about it that is fixed for the whole bake.
pub(crate) struct Prepared {
    /// The stack actually evaluated: a layerless stack gets a zero-thickness
    /// layer of the ambient medium, which changes nothing optically.
    pub(crate) stack: Stack,
    pub(crate) layer: usize,
    pub(crate) channels: usize,
    /// rgb kind: the stack at the integration wavelengths and the
    /// linear-sRGB weight of each wavelength (the spectral kind has none).
    pub(crate) stack_grid: StackGrid,
    pub(super) weights: Vec<[f64; 3]>,
    /// The substrate's critical cos θ (where its q has a branch point),
    /// when it is lossless and optically thinner than the ambient.
    pub(super) critical_cos: Option<f64>,
    /// The split around the varying layer is the same at every wavelength
    /// but for the layer's own phase (one layer, no dispersion: see
    /// [`VaryingLayer::at_wavelength`]), so a row splits the stack once.
    pub(super) split_per_angle: bool,
    /// rgb kind with the exact sampling: the colour integrated again, with
    /// more points per nanometre, at the nodes where the film's fringes
    /// are narrower than a step.
    pub(crate) refined: Option<Box<Refined>>,
}

/// The refinement of a bake's colour integration (see
/// [`crate::color::refine`]): where it is needed, and the sweep at each
/// density, made on first use.
pub(crate) struct Refined {
    pub(crate) criterion: Refinement,
    levels: Vec<OnceLock<Prepared>>,
}

impl Refined {
    /// The sweep integrating with `m` points per nanometre.
    fn level(&self, m: usize, base: &Prepared) -> Result<&Prepared> {
        let slot = &self.levels[m.trailing_zeros() as usize];
        if let Some(p) = slot.get() {
            return Ok(p);
        }
        let integrator = self.criterion.integrator(m);
        let prep = Prepared::plain(base.stack.clone(), base.layer, Kind::Rgb, &integrator, None)?;
        Ok(slot.get_or_init(|| prep))
    }
}

impl Prepared {
    pub(super) fn new(spec: &BakeSpec) -> Result<Prepared> {
        Prepared::of(
            &spec.stack,
            spec.layer,
            spec.kind,
            SpectralIntegrator::with_white(spec.sampling, spec.white),
            spec.wavelength_nm,
        )
    }

    /// The stack with `layer` varying, for a table of `kind` integrated by
    /// `integrator` (rgb) or over `wavelength_nm` (spectral).
    pub(crate) fn of(
        stack: &Stack,
        layer: usize,
        kind: Kind,
        integrator: SpectralIntegrator,
        wavelength_nm: (f64, f64),
    ) -> Result<Prepared> {
        let (stack, layer) = with_varying_layer(stack, layer);
        let mut prep = Prepared::plain(stack, layer, kind, &integrator, Some(wavelength_nm))?;
        if kind == Kind::Rgb && integrator.sampling() == Sampling::Exact {
            let criterion = Refinement::new(&prep.stack, Some(layer), &integrator)?;
            prep.refined = Some(Box::new(Refined {
                criterion,
                levels: (0..=MAX_SUB_STEPS.trailing_zeros())
                    .map(|_| OnceLock::new())
                    .collect(),
            }));
        }
        Ok(prep)
    }

    /// [`Self::of`] on a stack that has its varying layer, never refined
    /// (`wavelength_nm`: a spectral table's range, for its critical angle).
    fn plain(
        stack: Stack,
        layer: usize,
        kind: Kind,
        integrator: &SpectralIntegrator,
        wavelength_nm: Option<(f64, f64)>,
    ) -> Result<Prepared> {
        let (stack_grid, weights) = match kind {
            Kind::Rgb => (
                StackGrid::new(&stack, integrator.wavelengths_nm())?,
                rgb_weights(integrator),
            ),
            Kind::Spectral => (StackGrid::new(&stack, &[])?, Vec::new()),
        };
        let critical_cos = wavelength_nm.and_then(|w| critical_cos(&stack, kind, w));
        let split_per_angle = stack.layers.len() == 1 && stack_grid.is_non_dispersive();
        Ok(Prepared {
            split_per_angle,
            stack,
            layer,
            channels: channel_names(kind).len(),
            stack_grid,
            weights,
            critical_cos,
            refined: None,
        })
    }

    /// The colour at the thickness `nodes` of one rgb row (cos θ `cos`;
    /// `dst`: their values, six each) integrated again where the film's
    /// fringes are narrower than the sampling step, with the points per
    /// nanometre each node needs.
    fn refine_row(&self, cos: f64, nodes: &[f64], dst: &mut [f64]) -> Result<()> {
        let Some(refined) = &self.refined else {
            return Ok(());
        };
        let mut groups: Vec<(usize, Vec<usize>)> = Vec::new();
        for (j, &d) in nodes.iter().enumerate() {
            let m = refined.criterion.sub_steps(d, cos);
            if m <= 1 {
                continue;
            }
            match groups.iter_mut().find(|g| g.0 == m) {
                Some(g) => g.1.push(j),
                None => groups.push((m, vec![j])),
            }
        }
        for (m, at) in groups {
            let level = refined.level(m, self)?;
            let grid = &level.stack_grid;
            let thickness: Vec<f64> = at.iter().map(|&j| nodes[j]).collect();
            let mut wk = Worker::new(thickness.len(), grid.thicknesses_nm());
            let mut values = vec![0.0; 6 * thickness.len()];
            level.split_row(grid, 0..grid.wavelengths_nm().len(), cos, &mut wk);
            level.compute_nodes(
                false,
                grid,
                cos,
                &thickness,
                Phases::Exact,
                &mut values,
                &mut wk,
            );
            for (&j, v) in at.iter().zip(values.chunks_exact(6)) {
                dst[6 * j..6 * j + 6].copy_from_slice(v);
            }
        }
        Ok(())
    }

    /// Exact values at atlas rows: each row one cos θ (and, for a spectral
    /// table, one wavelength of `wavelengths_nm`) with its own thickness
    /// nodes, spaced as the row's chart places them. The values of each row,
    /// node by node, `channels` each, one row after another.
    pub(crate) fn eval_rows(&self, rows: &[Row], wavelengths_nm: &[f64]) -> Result<Vec<f64>> {
        let ch = self.channels;
        let spectral_grid;
        let stack_grid = if wavelengths_nm.is_empty() {
            &self.stack_grid
        } else {
            spectral_grid = StackGrid::new(&self.stack, wavelengths_nm)?;
            &spectral_grid
        };
        let spectral = !wavelengths_nm.is_empty();
        let longest = rows.iter().map(|r| r.thickness_nm.len()).max().unwrap_or(0);
        let values: Vec<Vec<f64>> = rows
            .par_iter()
            .map_init(
                || Worker::new(longest, stack_grid.thicknesses_nm()),
                |wk, row| -> Result<Vec<f64>> {
                    let mut dst = vec![0.0; row.thickness_nm.len() * ch];
                    if row.thickness_nm.is_empty() {
                        return Ok(dst);
                    }
                    let wavelengths = if spectral {
                        row.wavelength..row.wavelength + 1
                    } else {
                        0..stack_grid.wavelengths_nm().len()
                    };
                    self.split_row(stack_grid, wavelengths, row.cos, wk);
                    self.compute_nodes(
                        spectral,
                        stack_grid,
                        row.cos,
                        row.thickness_nm,
                        Phases::Exact,
                        &mut dst,
                        wk,
                    );
                    if !spectral {
                        self.refine_row(row.cos, row.thickness_nm, &mut dst)?;
                    }
                    Ok(dst)
                },
            )
            .collect::<Result<_>>()?;
        Ok(values.concat())
    }

    /// The row's split stacks, one per wavelength of `wavelengths`, into
    /// `wk.splits` (one split serving the whole spectrum where
    /// [`Self::split_per_angle`] allows).
    fn split_row(
        &self,
        stack_grid: &StackGrid,
        wavelengths: std::ops::Range<usize>,
        cos: f64,
        wk: &mut Worker,
    ) {
        wk.splits.clear();
        let mut first = None;
        for i in wavelengths {
            let v = match first {
                Some(f) if self.split_per_angle => {
                    VaryingLayer::at_wavelength(&f, stack_grid.wavelengths_nm()[i])
                }
                _ => self.split(stack_grid, i, cos, &mut wk.scratch),
            };
            first.get_or_insert(v);
            wk.splits.push((i, v));
        }
    }

    /// Exact values on a grid, layout `[w][c][t][channel]`. Rows (one cos θ
    /// and wavelength) that `previous` also has keep the values of its
    /// thickness chunks that are computed the same way (see [`reuse_plan`]),
    /// so the result is the same bit for bit as evaluating everything.
    pub(super) fn eval(
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
            Some((old, values)) => (
                reuse_plan(&chunks, t_axis, &old.axes[0]),
                previous_rows(grid, old, values, ch),
            ),
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
        out.par_chunks_mut(row_len).enumerate().try_for_each_init(
            || Worker::new(n, stack_grid.thicknesses_nm()),
            |wk, (row_index, row)| -> Result<()> {
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
                        self.split_row(stack_grid, wavelengths.clone(), cos, wk);
                    }
                    self.compute(grid, stack_grid, cos, range, row, wk);
                }
                if !grid.spectral {
                    self.refine_row(cos, &t_axis.nodes, row)?;
                }
                tick();
                Ok(())
            },
        )?;
        if let Some(k) = out.iter().position(|v| !v.is_finite()) {
            if !self.stack.is_coherent() {
                let (row, node) = (k / row_len, (k % row_len) / ch);
                return Err(self.lasing(grid, stack_grid, row, node));
            }
        }
        Ok(out)
    }

    /// The error for a node whose value came out infinite in a stack with
    /// incoherent layers: the lasing layer at the first of the row's
    /// wavelengths where it lases (see [`crate::optics::incoherent`]).
    fn lasing(&self, grid: &Grid, stack_grid: &StackGrid, row: usize, node: usize) -> Error {
        let [t_axis, c_axis, w_axis] = &grid.axes;
        let (w, c) = (row / c_axis.nodes.len(), row % c_axis.nodes.len());
        let cos = c_axis.nodes[c];
        let mut thicknesses_nm = stack_grid.thicknesses_nm().to_vec();
        thicknesses_nm[self.layer - 1] = t_axis.nodes[node];
        let wavelengths = if grid.spectral {
            w..w + 1
        } else {
            0..stack_grid.wavelengths_nm().len()
        };
        wavelengths
            .into_iter()
            .find_map(|i| {
                let diverged = stack_grid.diverged(i, &thicknesses_nm, cos)?;
                Some(diverged.error(stack_grid.wavelengths_nm()[i], cos))
            })
            .unwrap_or_else(|| {
                Error::invalid(
                    "baked table",
                    format!(
                        "not finite at thickness {:.2} nm, cos θ {cos:.5}{}",
                        t_axis.nodes[node],
                        if grid.spectral {
                            format!(", wavelength {:.1} nm", w_axis.nodes[w])
                        } else {
                            String::new()
                        }
                    ),
                )
            })
    }

    /// The values of consecutive thickness `chunks` of one row (cos θ `cos`,
    /// split stacks in `wk.splits`) into the row's slice of the output.
    fn compute(
        &self,
        grid: &Grid,
        stack_grid: &StackGrid,
        cos: f64,
        chunks: &[Chunk],
        row: &mut [f64],
        wk: &mut Worker,
    ) {
        let ch = self.channels;
        let start = chunks[0].start;
        let m = chunks
            .iter()
            .map(|k| k.start + k.len)
            .max()
            .unwrap_or(start)
            - start;
        let nodes = &grid.axes[0].nodes[start..start + m];
        let dst = &mut row[start * ch..(start + m) * ch];
        let phases = Phases::Chunks(chunks);
        self.compute_nodes(grid.spectral, stack_grid, cos, nodes, phases, dst, wk);
    }

    /// The values at thickness `nodes` of one row (cos θ `cos`, split
    /// stacks in `wk.splits`) into `dst`, the phase factors formed as
    /// `phases` says.
    #[allow(clippy::too_many_arguments)]
    fn compute_nodes(
        &self,
        spectral: bool,
        stack_grid: &StackGrid,
        cos: f64,
        nodes: &[f64],
        chunks: Phases,
        dst: &mut [f64],
        wk: &mut Worker,
    ) {
        let m = nodes.len();
        if spectral {
            let split = wk.splits[0];
            self.responses(&split, stack_grid, cos, nodes, chunks, wk);
            for (o, (&r, &t)) in dst.chunks_exact_mut(2).zip(wk.r.iter().zip(&wk.t)) {
                o[0] = r;
                o[1] = t;
            }
            return;
        }
        // Channel-major accumulators ([channel][node]), so the
        // weighting loop runs over contiguous arrays, each padded to
        // whole vectors (see `padded`).
        let mp = padded(m);
        wk.acc.clear();
        wk.acc.resize(6 * mp, 0.0);
        for k in 0..wk.splits.len() {
            let (i, v) = wk.splits[k];
            let weights = self.weights[i];
            if v.is_degenerate() {
                self.responses(&(i, v), stack_grid, cos, nodes, chunks, wk);
                accumulate(&mut wk.acc, &wk.r[..mp], &wk.t[..mp], weights);
                continue;
            }
            phase_factors(&v, nodes, chunks, wk);
            let (re, im) = (&wk.phase_re[..mp], &wk.phase_im[..mp]);
            v.accumulate_responses(re, im, weights, &mut wk.acc);
        }
        for (j, o) in dst.chunks_exact_mut(6).enumerate() {
            for (k, o) in o.iter_mut().enumerate() {
                *o = wk.acc[k * mp + j];
            }
        }
    }

    /// Unpolarized R and T at the thickness `nodes` (the nodes `chunks`
    /// cover, from the first chunk's start) into `wk.r`, `wk.t` (zero from
    /// there up to [`padded`] length): the
    /// split-stack form (`split`: the stack split at `stack_grid`'s wavelength
    /// of that index), or the solver node by node where the split is
    /// degenerate (the varying layer at its own critical angle, or a stack
    /// with incoherent layers that does not split there).
    pub(super) fn responses(
        &self,
        &(i, ref v): &(usize, VaryingLayer),
        stack_grid: &StackGrid,
        cos: f64,
        nodes: &[f64],
        chunks: Phases,
        wk: &mut Worker,
    ) {
        let (m, mp) = (nodes.len(), padded(nodes.len()));
        if !v.is_degenerate() {
            phase_factors(v, nodes, chunks, wk);
            let (re, im) = (&wk.phase_re[..mp], &wk.phase_im[..mp]);
            v.responses(re, im, &mut wk.r[..mp], &mut wk.t[..mp]);
            wk.r[m..mp].fill(0.0);
            wk.t[m..mp].fill(0.0);
            return;
        }
        wk.r[m..mp].fill(0.0);
        wk.t[m..mp].fill(0.0);
        let (idx, wavelength_nm) = (stack_grid.indices_at(i), stack_grid.wavelengths_nm()[i]);
        for (j, &t) in nodes.iter().enumerate() {
            wk.thicknesses_nm[self.layer - 1] = t;
            let resp = solve_mixed(
                idx,
                &wk.thicknesses_nm,
                stack_grid.coherence(),
                wavelength_nm,
                cos,
            );
            wk.r[j] = resp.r();
            wk.t[j] = resp.t();
        }
    }

    /// The stack split around the varying layer at `stack_grid`'s `i`-th
    /// wavelength and `cos`.
    #[inline]
    pub(super) fn split(
        &self,
        stack_grid: &StackGrid,
        i: usize,
        cos: f64,
        scratch: &mut Scratch,
    ) -> VaryingLayer {
        VaryingLayer::new_mixed(
            stack_grid.indices_at(i),
            stack_grid.thicknesses_nm(),
            stack_grid.coherence(),
            self.layer,
            stack_grid.wavelengths_nm()[i],
            cos,
            scratch,
        )
    }
}

/// For each row of `grid` (one cos θ and wavelength), the same row of the
/// previous grid `old` (values `values`, `channels` per node), if it has one.
fn previous_rows<'a>(
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

/// One row of an atlas chart for [`Prepared::eval_rows`].
pub(crate) struct Row<'a> {
    /// cos θ of the row.
    pub(crate) cos: f64,
    /// The wavelength node of a spectral table's row (ignored for rgb).
    pub(crate) wavelength: usize,
    /// The thickness nodes (nm), in any order.
    pub(crate) thickness_nm: &'a [f64],
}

/// The linear-sRGB weight of each integration wavelength, as triples: the
/// integrator is linear in the spectrum, so the bake accumulates weight × R
/// per node instead of storing whole spectra.
pub(super) fn rgb_weights(integrator: &SpectralIntegrator) -> Vec<[f64; 3]> {
    let [r, g, b] = integrator.rgb_weights();
    r.iter()
        .zip(g)
        .zip(b)
        .map(|((&r, &g), &b)| [r, g, b])
        .collect()
}

simd_dispatch! {
    /// Adds `weights` × R and × T to channel-major accumulators
    /// (`[channel][node]`, R channels first), each product and sum fused as
    /// in [`VaryingLayer::accumulate_responses`].
    fn accumulate(acc: &mut [f64], r: &[f64], t: &[f64], weights: [f64; 3]) {
        let n = r.len();
        let (acc_r, acc_t) = acc.split_at_mut(3 * n);
        for (acc, values) in [(acc_r, r), (acc_t, t)] {
            for (a, wt) in acc.chunks_exact_mut(n).zip(weights) {
                for (a, &v) in a.iter_mut().zip(values) {
                    *a = wt.mul_add(v, *a);
                }
            }
        }
    }
}

/// Node counts are rounded up to this many for the vectorised loops (the
/// widest vector holds 8 f64), so that they never end in a scalar
/// remainder: on the check's 255-node rows the 7 left over, one at a time,
/// took about 8 % of the fused loop's samples. The padding's values are
/// computed (from zeros) and discarded.
const PAD: usize = 8;

/// `nodes` rounded up to whole [`PAD`]s.
fn padded(nodes: usize) -> usize {
    nodes.next_multiple_of(PAD)
}

/// How a row's phase factors are formed.
#[derive(Clone, Copy)]
pub(super) enum Phases<'a> {
    /// Chunks of evenly spaced nodes, each advanced by a recurrence from an
    /// exact exponential at its start (see [`phases`]).
    Chunks(&'a [Chunk]),
    /// An exact exponential at every node (nodes spaced unevenly, as an
    /// atlas chart's are).
    Exact,
}

/// The phase factors at `nodes` (see [`phases`]) into `wk.phase_re`,
/// `wk.phase_im`, zero from there up to [`padded`] length.
fn phase_factors(v: &VaryingLayer, nodes: &[f64], plan: Phases, wk: &mut Worker) {
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

/// One worker's buffers, allocated once per rayon task.
pub(super) struct Worker {
    pub(super) scratch: Scratch,
    /// The current row's split stacks, each with its wavelength's index.
    pub(super) splits: Vec<(usize, VaryingLayer)>,
    pub(super) thicknesses_nm: Vec<f64>,
    pub(super) phase_re: Vec<f64>,
    pub(super) phase_im: Vec<f64>,
    pub(super) r: Vec<f64>,
    pub(super) t: Vec<f64>,
    pub(super) acc: Vec<f64>,
}

impl Worker {
    pub(super) fn new(nodes: usize, thicknesses_nm: &[f64]) -> Worker {
        // Room for the padding, and for `phases` running a chunk on to
        // whole vectors.
        let nodes = padded(nodes) + PAD;
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
pub(super) struct Chunk {
    pub(super) start: usize,
    pub(super) len: usize,
    pub(super) step: f64,
}

/// The chunks of a thickness axis, in order. Adjacent uniform segments with
/// the same spacing (the halves of a refined one) form one run, cut into
/// chunks of [`PHASE_RESYNC`] nodes from its start; consecutive runs share
/// their boundary node, which the later run's chunk sets.
pub(super) fn chunks(t_axis: &AxisGrid) -> Vec<Chunk> {
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
pub(super) enum Piece {
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
pub(super) fn reuse_plan(chunks: &[Chunk], t_axis: &AxisGrid, old_axis: &AxisGrid) -> Vec<Piece> {
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
    pub(super) fn phases(v: &VaryingLayer, nodes: &[f64], chunks: &[Chunk], re: &mut [f64], im: &mut [f64]) {
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
pub(super) const PHASE_LANES: usize = 8;
