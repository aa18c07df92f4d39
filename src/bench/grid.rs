//! Grid evaluation: R and T of one stack over angle × thickness × wavelength,
//! the workload the Python peers are timed on. The output layout is
//! `[angle][thickness][wavelength]`, row-major.
//!
//! Without a thickness axis every point is one call of the solver. With one,
//! the grid is swept the way the baker sweeps it: per (angle, wavelength) the
//! stack is split once around the varying layer, and each thickness node
//! then costs one complex exponential and one division per polarization.

use std::time::Instant;

use num_complex::Complex64 as C64;
use rayon::prelude::*;

use super::stacks::BenchStack;
use crate::color::{Sampling, SpectralIntegrator};
use crate::error::{Error, Result};
use crate::lut;
use crate::optics::twoport::{Scratch, VaryingLayer};
use crate::optics::{solve_mixed, Response, Stack, StackGrid};
use crate::simd::simd_dispatch;

/// The points of a grid evaluation: every combination of angle, thickness
/// and wavelength.
#[derive(Clone, Debug)]
pub struct Grid {
    /// Vacuum wavelengths in nm.
    pub wavelengths_nm: Vec<f64>,
    /// Incidence angles in the ambient, degrees from the normal, in
    /// [0, 90].
    pub angles_deg: Vec<f64>,
    /// Values for the varying layer; `None` keeps the stack's own thickness.
    pub thicknesses_nm: Option<Vec<f64>>,
}

impl Grid {
    /// Nodes on the thickness axis: 1 without one (the stack's own
    /// thickness).
    pub fn thickness_count(&self) -> usize {
        self.thicknesses_nm.as_ref().map_or(1, Vec::len)
    }

    /// Total points: thickness × angle × wavelength counts.
    pub fn points(&self) -> usize {
        self.thickness_count() * self.angles_deg.len() * self.wavelengths_nm.len()
    }
}

/// The result of [`evaluate`]: R and T at every grid point, and what a peer
/// needs to check them.
#[derive(Clone, Debug)]
pub struct GridOutput {
    /// Unpolarized reflectance at each point, `[angle][thickness][wavelength]`
    /// row-major.
    pub r: Vec<f64>,
    /// Unpolarized transmittance (power into the substrate), same layout.
    pub t: Vec<f64>,
    /// Complex indices of ambient, layers and substrate at each wavelength,
    /// `[wavelength][medium]`: what a peer must be given to solve the same problem.
    pub indices: Vec<C64>,
    /// Media per wavelength in `indices`: the layers plus 2.
    pub media: usize,
    /// Wall time of the fastest repetition.
    pub seconds: f64,
}

/// Untimed work before the timed repetitions: the pool's threads are woken
/// and the outputs' pages mapped, as they are in a peer's process that has
/// already been called (the Python peers are timed in-process, after their
/// own first call). Without it the first 100 or so milliseconds on two
/// threads run at about half speed here.
const WARM_UP_SECONDS: f64 = 0.2;

/// Evaluates the grid `repeat` times on `threads` threads, after an untimed
/// warm-up of [`WARM_UP_SECONDS`], and keeps the fastest wall time. Indices
/// are looked up once per wavelength inside the timed region, as a renderer
/// would look them up once per stack.
pub fn evaluate(
    stack: &Stack,
    varying_layer: usize,
    grid: &Grid,
    threads: usize,
    repeat: usize,
) -> Result<GridOutput> {
    stack.validate()?;
    if varying_layer >= stack.layers.len() && grid.thicknesses_nm.is_some() {
        return Err(Error::invalid(
            "varying layer",
            format!(
                "{} but the stack has {} layers",
                varying_layer + 1,
                stack.layers.len()
            ),
        ));
    }
    if let Some(a) = grid.angles_deg.iter().find(|a| !(0.0..=90.0).contains(*a)) {
        return Err(Error::invalid(
            "angle",
            format!("{a} is outside [0, 90] degrees"),
        ));
    }
    let pool = thread_pool(threads)?;
    let rows = grid.thickness_count() * grid.angles_deg.len();
    let mut r = vec![0.0; rows * grid.wavelengths_nm.len()];
    let mut t = vec![0.0; rows * grid.wavelengths_nm.len()];
    let mut once = || -> Result<(f64, StackGrid)> {
        let start = Instant::now();
        let sg = StackGrid::new(stack, &grid.wavelengths_nm)?;
        pool.install(|| sweep(&sg, varying_layer, grid, &mut r, &mut t));
        Ok((start.elapsed().as_secs_f64(), sg))
    };
    let warm_up = Instant::now();
    while warm_up.elapsed().as_secs_f64() < WARM_UP_SECONDS {
        once()?;
    }
    let mut best = f64::INFINITY;
    let mut stack_grid = None;
    for _ in 0..repeat.max(1) {
        let (seconds, sg) = once()?;
        best = best.min(seconds);
        stack_grid = Some(sg);
    }
    let stack_grid = stack_grid.ok_or_else(|| Error::invalid("repeat", "no repetition ran"))?;
    Ok(GridOutput {
        r,
        t,
        indices: stack_grid.indices().to_vec(),
        media: stack.layers.len() + 2,
        seconds: best,
    })
}

/// One evaluation of the whole grid into `r` and `t`, one angle per task.
fn sweep(sg: &StackGrid, varying_layer: usize, grid: &Grid, r: &mut [f64], t: &mut [f64]) {
    let n_w = grid.wavelengths_nm.len();
    let n_t = grid.thickness_count();
    let cosines: Vec<f64> = grid
        .angles_deg
        .iter()
        .map(|a| a.to_radians().cos())
        .collect();
    let uniform_step_nm = grid.thicknesses_nm.as_deref().and_then(uniform_step);
    r.par_chunks_mut(n_t * n_w)
        .zip(t.par_chunks_mut(n_t * n_w))
        .zip(&cosines)
        .for_each_init(
            || AngleScratch::new(sg.thicknesses_nm(), n_w),
            |scratch, ((r_block, t_block), &cos)| match &grid.thicknesses_nm {
                None => {
                    // One angle's wavelengths in one batch, eight or four per vector.
                    sg.solve_spectrum(&scratch.thick, cos, &mut scratch.spectrum);
                    for ((resp, r), t) in scratch
                        .spectrum
                        .iter()
                        .zip(r_block.iter_mut())
                        .zip(t_block.iter_mut())
                    {
                        *r = resp.r();
                        *t = resp.t();
                    }
                }
                Some(ts) => {
                    let split = SplitAngle {
                        sg,
                        varying_layer,
                        cos,
                        uniform_step_nm,
                    };
                    split.sweep_thicknesses(ts, scratch, r_block, t_block);
                }
            },
        );
}

/// Per-task buffers of [`sweep`], reused from one angle to the next.
struct AngleScratch {
    thick: Vec<f64>,
    twoport: Scratch,
    splits: Vec<VaryingLayer>,
    rotations: Vec<C64>,
    phases: Vec<C64>,
    spectrum: Vec<Response>,
}

impl AngleScratch {
    fn new(thicknesses_nm: &[f64], n_w: usize) -> AngleScratch {
        AngleScratch {
            thick: thicknesses_nm.to_vec(),
            twoport: Scratch::default(),
            splits: Vec::with_capacity(n_w),
            rotations: Vec::with_capacity(n_w),
            phases: Vec::with_capacity(n_w),
            spectrum: vec![Response::default(); n_w],
        }
    }
}

/// One angle of a grid with a thickness axis, swept as the baker sweeps it.
struct SplitAngle<'a> {
    sg: &'a StackGrid,
    varying_layer: usize,
    cos: f64,
    uniform_step_nm: Option<f64>,
}

impl SplitAngle<'_> {
    /// All wavelengths of this angle split first, then thickness-major so
    /// the writes are contiguous.
    fn sweep_thicknesses(
        &self,
        ts: &[f64],
        s: &mut AngleScratch,
        r_block: &mut [f64],
        t_block: &mut [f64],
    ) {
        let n_w = self.sg.wavelengths_nm().len();
        s.splits.clear();
        for (wavelength_nm, n) in self.sg.iter() {
            s.splits.push(VaryingLayer::new_mixed(
                n,
                &s.thick,
                self.sg.coherence(),
                self.varying_layer + 1,
                wavelength_nm,
                self.cos,
                &mut s.twoport,
            ));
        }
        s.rotations.clear();
        if let Some(dt) = self.uniform_step_nm {
            s.rotations.extend(s.splits.iter().map(|x| x.phase(dt)));
        }
        s.phases.clear();
        s.phases.resize(n_w, C64::new(1.0, 0.0));
        for (k, &d) in ts.iter().enumerate() {
            let r_row = &mut r_block[k * n_w..(k + 1) * n_w];
            let t_row = &mut t_block[k * n_w..(k + 1) * n_w];
            // On a uniform axis the phase advances by one fixed rotation per
            // node, re-anchored with the exact exponential every REANCHOR
            // nodes so rounding in the product never accumulates.
            if s.rotations.is_empty() || k % REANCHOR == 0 {
                for (p, split) in s.phases.iter_mut().zip(s.splits.iter()) {
                    *p = split.phase(d);
                }
            } else {
                for (p, rot) in s.phases.iter_mut().zip(s.rotations.iter()) {
                    *p *= rot;
                }
            }
            responses_row(&s.splits, &s.phases, r_row, t_row);
            self.unsplit(d, s, r_row, t_row);
        }
    }

    /// The solver's R and T at thickness `d` where a stack with incoherent
    /// layers does not split (see [`VaryingLayer::new_mixed`]).
    fn unsplit(&self, d: f64, s: &mut AngleScratch, r_row: &mut [f64], t_row: &mut [f64]) {
        if self.sg.coherence().is_coherent() {
            return;
        }
        s.thick[self.varying_layer] = d;
        for (w, (wavelength_nm, n)) in self.sg.iter().enumerate() {
            if s.splits[w].is_degenerate() {
                let resp = solve_mixed(n, &s.thick, self.sg.coherence(), wavelength_nm, self.cos);
                (r_row[w], t_row[w]) = (resp.r(), resp.t());
            }
        }
    }
}

simd_dispatch! {
    /// R and T of each split at its phase factor. `VaryingLayer::response`
    /// fuses its products (`mul_add`), which only a copy compiled for FMA
    /// turns into instructions rather than library calls: this loop is
    /// compiled with the CPU's widest instructions, once per row.
    fn responses_row(splits: &[VaryingLayer], phases: &[C64], r_row: &mut [f64], t_row: &mut [f64]) {
        for (((split, p), r), t) in splits
            .iter()
            .zip(phases.iter())
            .zip(r_row.iter_mut())
            .zip(t_row.iter_mut())
        {
            let resp = split.response(*p);
            *r = resp.r();
            *t = resp.t();
        }
    }
}

/// Wall times of baking one table two ways, and how many points each
/// evaluated (thickness × angle × wavelength).
#[derive(Clone, Copy, Debug)]
pub struct BakeTimes {
    /// The default bake: the grid with every interval halved, so that the
    /// table's interpolation error is measured (the header's bake check).
    pub checked_s: f64,
    /// Points the checked bake evaluated.
    pub checked_points: usize,
    /// `--no-check`: the table's own nodes only, the same points a peer
    /// computes to build the table.
    pub table_s: f64,
    /// Points the unchecked bake evaluated.
    pub table_points: usize,
}

/// Times [`lut::bake`] of an rgb table (1 nm exact integration, the `irid
/// bake` default) over the stack's thickness range and all angles, with the
/// given node counts, on `threads` threads, with and without the bake check;
/// keeps the fastest of `repeat` for each. Returns those times and the grid
/// of the table's nodes (thickness × angle × the integration's wavelengths):
/// what a peer must compute point by point to build the same table.
pub fn time_bake(
    bench: &BenchStack,
    thickness_nodes: usize,
    angle_nodes: usize,
    threads: usize,
    repeat: usize,
) -> Result<(BakeTimes, Grid)> {
    let checked = bench.bake_spec(thickness_nodes, angle_nodes, false);
    let table_only = lut::BakeSpec {
        check: false,
        ..checked.clone()
    };
    let pool = thread_pool(threads)?;
    let (mut checked_s, mut table_s) = (f64::INFINITY, f64::INFINITY);
    let time = |spec: &lut::BakeSpec| -> Result<(f64, lut::Lut)> {
        let start = Instant::now();
        let lut = pool.install(|| lut::bake(spec))?;
        Ok((start.elapsed().as_secs_f64(), lut))
    };
    let mut baked = None;
    for _ in 0..repeat.max(1) {
        let (s, with_check) = time(&checked)?;
        checked_s = checked_s.min(s);
        let (s, table) = time(&table_only)?;
        table_s = table_s.min(s);
        baked = Some((with_check, table));
    }
    let Some((with_check, table)) = baked else {
        return Err(Error::invalid("bake", "no repetition ran"));
    };
    let axes = &table.header().axes;
    let (Some(thickness), Some(cos)) = (axes.first(), axes.get(1)) else {
        return Err(Error::invalid("bake", "the table has fewer than two axes"));
    };
    let grid = Grid {
        wavelengths_nm: SpectralIntegrator::new(Sampling::Exact)
            .wavelengths_nm()
            .to_vec(),
        angles_deg: cos
            .nodes
            .iter()
            .map(|c| c.clamp(0.0, 1.0).acos().to_degrees())
            .collect(),
        thicknesses_nm: Some(thickness.nodes.clone()),
    };
    // The check compares every node of the halved grid, so its point count
    // is that grid's size.
    let checked_nodes = with_check
        .header()
        .error
        .bake_check
        .as_ref()
        .map_or(0, |c| c.points);
    let times = BakeTimes {
        checked_s,
        checked_points: checked_nodes * grid.wavelengths_nm.len(),
        table_s,
        table_points: grid.points(),
    };
    Ok((times, grid))
}

/// Wall time of [`crate::rough::rough_reflectance`] over a grid.
#[derive(Clone, Copy, Debug)]
pub struct RoughTimes {
    /// The fastest run, seconds.
    pub seconds: f64,
    /// Nodes: thickness, cos θ, roughness.
    pub nodes: [usize; 3],
    /// μ = v·h nodes the film's smooth colour was computed on.
    pub mu_nodes: usize,
}

/// Times the rough engine (F_eff, exact 1 nm colour, D65, the default
/// quadrature) over `nodes` = (thickness, cos θ, roughness) nodes evenly
/// spaced over the stack's thickness range, cos θ ∈ [0, 1] and roughness
/// ∈ [0, 1], on `threads` threads; keeps the fastest of `repeat`. This is
/// the work a table with a roughness axis costs (the smooth sweep on the μ
/// grid, a kernel per (cos θ, roughness), the weighting).
pub fn time_rough(
    bench: &BenchStack,
    nodes: [usize; 3],
    threads: usize,
    repeat: usize,
) -> Result<RoughTimes> {
    let even = |lo: f64, hi: f64, n: usize| -> Vec<f64> {
        (0..n)
            .map(|i| lo + (hi - lo) * i as f64 / (n.max(2) - 1) as f64)
            .collect()
    };
    let (t0, t1) = bench.thickness_range_nm;
    let thickness = even(t0, t1, nodes[0]);
    let cos = even(0.0, 1.0, nodes[1]);
    let roughness = even(0.0, 1.0, nodes[2]);
    let integrator = SpectralIntegrator::new(Sampling::Exact);
    let quadrature = crate::rough::Quadrature::default();
    let pool = thread_pool(threads)?;
    let mut seconds = f64::INFINITY;
    for _ in 0..repeat.max(1) {
        let start = Instant::now();
        pool.install(|| {
            crate::rough::rough_reflectance(
                &bench.stack,
                bench.varying_layer + 1,
                &integrator,
                &thickness,
                &cos,
                &roughness,
                &quadrature,
            )
        })?;
        seconds = seconds.min(start.elapsed().as_secs_f64());
    }
    let mu_nodes = crate::rough::MuGrid::for_stack(&bench.stack, quadrature.mu_intervals)
        .nodes()
        .len();
    Ok(RoughTimes {
        seconds,
        nodes,
        mu_nodes,
    })
}

/// Nodes between exact re-evaluations of the phase on a uniform axis.
const REANCHOR: usize = 64;

/// The spacing of an evenly spaced axis (to 1e-12 of its span), if it is one.
fn uniform_step(nodes: &[f64]) -> Option<f64> {
    let (first, last) = (*nodes.first()?, *nodes.last()?);
    if nodes.len() < 3 || last <= first {
        return None;
    }
    let step = (last - first) / (nodes.len() - 1) as f64;
    let tol = 1e-12 * (last - first);
    nodes
        .iter()
        .enumerate()
        .all(|(i, &x)| (x - (first + step * i as f64)).abs() <= tol)
        .then_some(step)
}

fn thread_pool(threads: usize) -> Result<rayon::ThreadPool> {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads.max(1))
        .build()
        .map_err(|e| Error::invalid("threads", e.to_string()))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bench::stacks::find;

    #[test]
    fn grid_matches_pointwise_solve_in_any_thread_count() {
        let b = find("two-layer").unwrap().unwrap();
        let grid = Grid {
            wavelengths_nm: vec![400.0, 550.0, 700.0],
            angles_deg: vec![0.0, 45.0],
            thicknesses_nm: Some(vec![0.0, 120.0, 480.0]),
        };
        let one = evaluate(&b.stack, 0, &grid, 1, 1).unwrap();
        let two = evaluate(&b.stack, 0, &grid, 2, 1).unwrap();
        assert_eq!(one.r, two.r);
        // The sweep (split stack) against the plain solver, point by point.
        for (a, angle) in grid.angles_deg.iter().enumerate() {
            for (k, &d) in grid.thicknesses_nm.as_ref().unwrap().iter().enumerate() {
                for (w, &wl) in grid.wavelengths_nm.iter().enumerate() {
                    let mut s = b.stack.clone();
                    s.layers[0].thickness_nm = d;
                    let direct = s.response(wl, angle.to_radians().cos()).unwrap();
                    let i = (a * 3 + k) * 3 + w;
                    assert!((one.r[i] - direct.r()).abs() < 1e-12, "{a} {k} {w}");
                    assert!((one.t[i] - direct.t()).abs() < 1e-12, "{a} {k} {w}");
                }
            }
        }
        assert!(evaluate(&b.stack, 5, &grid, 1, 1).is_err());

        // A long uniform axis takes the rotation path: still the solver's answer.
        let long = Grid {
            wavelengths_nm: vec![380.0, 612.5],
            angles_deg: vec![0.0, 70.0],
            thicknesses_nm: Some((0..1001).map(|i| i as f64 * 0.5).collect()),
        };
        let swept = evaluate(&b.stack, 0, &long, 2, 1).unwrap();
        for (a, angle) in long.angles_deg.iter().enumerate() {
            for k in [0, 1, 63, 64, 65, 500, 999, 1000] {
                for (w, &wl) in long.wavelengths_nm.iter().enumerate() {
                    let mut s = b.stack.clone();
                    s.layers[0].thickness_nm = k as f64 * 0.5;
                    let direct = s.response(wl, angle.to_radians().cos()).unwrap();
                    let i = (a * 1001 + k) * 2 + w;
                    assert!((swept.r[i] - direct.r()).abs() < 1e-11, "{a} {k} {w}");
                }
            }
        }
        // A film on an incoherent sheet: the sweep splits its group.
        let sheet = find("coated-sheet").unwrap().unwrap();
        let swept = evaluate(&sheet.stack, 0, &grid, 2, 1).unwrap();
        for (a, angle) in grid.angles_deg.iter().enumerate() {
            for (k, &d) in grid.thicknesses_nm.as_ref().unwrap().iter().enumerate() {
                for (w, &wl) in grid.wavelengths_nm.iter().enumerate() {
                    let mut s = sheet.stack.clone();
                    s.layers[0].thickness_nm = d;
                    let direct = s.response(wl, angle.to_radians().cos()).unwrap();
                    let i = (a * 3 + k) * 3 + w;
                    assert!((swept.r[i] - direct.r()).abs() < 1e-12, "{a} {k} {w}");
                    assert!((swept.t[i] - direct.t()).abs() < 1e-12, "{a} {k} {w}");
                }
            }
        }
        assert_eq!(uniform_step(&[0.0, 1.0, 2.0]), Some(1.0));
        assert_eq!(uniform_step(&[0.0, 1.0, 3.0]), None);
    }
}
