//! Evaluating a grid: the stack split around the varying layer once per
//! cos θ and wavelength, then the phase factor swept along the thickness
//! axis, with rows the previous round's grid shares copied instead.

use rayon::prelude::*;
use std::sync::OnceLock;

use super::grid::Grid;
use super::phases::{
    chunks, padded, phase_factors, previous_rows, reuse_plan, Chunk, Phases, Piece, PAD,
};
use super::{critical_cos, Kind};
use crate::cancel::Cancel;
use crate::color::refine::{Refinement, MAX_SUB_STEPS};
use crate::color::{Sampling, SpectralIntegrator};
use crate::error::{Error, Result};
use crate::optics::twoport::{Scratch, VaryingLayer};
use crate::optics::{solve_mixed, Layer, Stack, StackGrid};
use crate::simd::simd_dispatch;

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
    pub(crate) critical_cos: Option<f64>,
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
    /// The stack with `layer` varying, for a table of `kind` integrated by
    /// `integrator` (rgb) or over `wavelength_nm` (spectral). Stops with
    /// [`Error::Cancelled`] once `cancel` is set (examining where the colour
    /// needs refining takes seconds on hundreds of layers).
    pub(crate) fn of(
        stack: &Stack,
        layer: usize,
        kind: Kind,
        integrator: SpectralIntegrator,
        wavelength_nm: (f64, f64),
        cancel: &Cancel,
    ) -> Result<Prepared> {
        let (stack, layer) = with_varying_layer(stack, layer);
        let mut prep = Prepared::plain(stack, layer, kind, &integrator, Some(wavelength_nm))?;
        if kind == Kind::Rgb && integrator.sampling() == Sampling::Exact {
            let criterion =
                Refinement::new_cancellable(&prep.stack, Some(layer), &integrator, cancel)?;
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
            channels: kind.channels(),
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
    /// Each row looks at `cancel` first ([`Error::Cancelled`] once set).
    pub(crate) fn eval(
        &self,
        grid: &Grid,
        previous: Option<&(Grid, Vec<f64>)>,
        progress: &(dyn Fn(f64) + Sync),
        cancel: &Cancel,
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
                cancel.check()?;
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
pub(crate) fn rgb_weights(integrator: &SpectralIntegrator) -> Vec<[f64; 3]> {
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
