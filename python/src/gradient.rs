//! The `gradient=True` parts of `Stack.solve` and `Stack.color`: the
//! derivatives of R, T and the colour by every layer's thickness (and, with
//! `index_gradient=True`, R and T by every layer's n and k)
//! (irid::optics::gradient, irid::color::gradient), as numpy arrays with
//! the layers first.

use pyo3::prelude::*;
use pyo3::types::PyDict;
use rayon::prelude::*;

use irid::color::gradient::{colors_with_gradient_cancellable, ColorGradient};
use irid::color::SpectralIntegrator;
use irid::optics::gradient::{
    solve_stack_grid_with_gradient, solve_stack_grid_with_index_gradient, GradientGrid,
};
use irid::optics::{Amplitudes, Response, Stack, StackGrid};
use num_complex::Complex64 as C64;

use crate::arrays::array;
use crate::budget::Footprint;
use crate::pool::compute_cancellable;
use crate::{invalid, py_error};

/// One power output of `Stack.solve`: its value from a point's R and T.
type PowerColumn = fn(&Response) -> f64;

/// One amplitude output of `Stack.solve`: its value from a point's r and t.
type AmplitudeColumn = fn(&Amplitudes) -> C64;

/// One derivative array of a gradient grid, laid out (layer, wavelength,
/// angle).
type DerivativeColumn = fn(&GradientGrid) -> &Vec<f64>;

/// A solver of a gradient grid at the given thicknesses and cos θ0.
type GridSolver = fn(&StackGrid, &[f64], &[f64]) -> irid::error::Result<GradientGrid>;

/// One output array of the colour gradients: its rows per layer.
type ColourColumn = fn(&ColorGradient) -> &Vec<[f64; 3]>;

/// About what a point's index derivatives cost against its thickness
/// derivatives (the scalar path against the lanes; docs/inverse.md): the
/// index gradient's tasks take this many times fewer points.
const INDEX_COST: usize = 16;

/// What `Stack.solve` differentiates: from its `gradient` and
/// `index_gradient` flags.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Derivatives {
    /// No derivative (gradient=False).
    None,
    /// By every layer's thickness (gradient=True).
    Thickness,
    /// By every layer's thickness, n and k (gradient=True,
    /// index_gradient=True).
    ThicknessAndIndex,
}

impl Derivatives {
    /// The derivatives `Stack.solve`'s flags ask for; ValueError naming the
    /// flag for index_gradient without gradient, or either with a
    /// `thickness_nm` sweep (`sweep`).
    pub fn from_flags(gradient: bool, index_gradient: bool, sweep: bool) -> PyResult<Derivatives> {
        if index_gradient && !gradient {
            return Err(invalid(
                "index_gradient",
                "adds to the thickness derivatives: it needs gradient=True",
            ));
        }
        if gradient && sweep {
            return Err(invalid(
                "gradient",
                "is the derivative at the stack's own thicknesses: not with a thickness_nm sweep",
            ));
        }
        Ok(match (gradient, index_gradient) {
            (false, _) => Derivatives::None,
            (true, false) => Derivatives::Thickness,
            (true, true) => Derivatives::ThicknessAndIndex,
        })
    }

    /// Raises MemoryError when the gradient solve of `layers` layers ×
    /// `wavelengths` × `angles` needs more than the budget: the solved
    /// chunks (R, T, amplitudes, 4 derivatives per layer, 8 more by n and
    /// k) and the arrays returned (6 per layer, 12 more by n and k).
    pub fn check_footprint(self, layers: usize, wavelengths: usize, angles: usize) -> PyResult<()> {
        let per_layer = match self {
            Derivatives::None => return Ok(()),
            Derivatives::Thickness => 0,
            Derivatives::ThicknessAndIndex => 20,
        };
        Footprint::new()
            .items(&[7, layers + 2, wavelengths, angles], 16)
            .items(&[per_layer, layers, wavelengths, angles], 8)
            .check(&format!(
                "the gradient of {layers} layers × {wavelengths} wavelengths × {angles} angles"
            ))
    }
}

/// Fewest points × layers of a gradient solve that go to the thread pool.
const PARALLEL_MIN_POINTS: usize = 2048;

/// Tasks a large gradient solve is cut into: a few per core of the pool,
/// so that a core slowed by other work leaves little for the others to
/// wait on, while each task still fills whole lanes.
const CHUNKS: usize = 8;

/// Fewest wavelengths per task when the pool solves a gradient.
const MIN_CHUNK_WAVELENGTHS: usize = 16;

/// Most points × layers per task (a few milliseconds of the lanes): Ctrl-C
/// is looked for between tasks, so a large solve is cut finer than
/// [`CHUNKS`].
const MAX_TASK_POINTS: usize = 1 << 18;

/// `Stack.solve(..., gradient=True)` over the grid's stack at its own
/// thicknesses: one sweep of the gradient lanes gives R and T, the
/// amplitudes (coherent stacks) and the derivatives, so nothing is solved
/// twice. The dict holds what `Stack.solve` returns (shape (wavelengths,
/// angles)) plus dRs_dd, dRp_dd, dTs_dd, dTp_dd, dR_dd and dT_dd, each of
/// shape (layers, wavelengths, angles), and with
/// [`Derivatives::ThicknessAndIndex`] the same six by n (dRs_dn, ...) and
/// by k (dRs_dk, ...). Raises ValueError where an incoherent layer lases.
pub fn solve_with_gradient<'py>(
    py: Python<'py>,
    grid: &StackGrid,
    cos_theta0: &[f64],
    derivatives: Derivatives,
) -> PyResult<Bound<'py, PyDict>> {
    let layers = grid.thicknesses_nm().len();
    let (wavelengths, angles) = (grid.wavelengths_nm().len(), cos_theta0.len());
    derivatives.check_footprint(layers, wavelengths, angles)?;
    let by_index = derivatives == Derivatives::ThicknessAndIndex;
    let chunks = solve_chunks(py, grid, cos_theta0, by_index)?;
    let result = PyDict::new(py);
    let shape = [wavelengths, angles];
    let responses = || chunks.iter().flat_map(|c| c.response.iter());
    let powers: [(&str, PowerColumn); 6] = [
        ("Rs", |r| r.rs),
        ("Rp", |r| r.rp),
        ("Ts", |r| r.ts),
        ("Tp", |r| r.tp),
        ("R", Response::r),
        ("T", Response::t),
    ];
    for (key, f) in powers {
        result.set_item(key, array(py, responses().map(f).collect(), &shape)?)?;
    }
    if grid.coherence().is_coherent() {
        let amplitudes = || chunks.iter().flat_map(|c| c.amplitudes.iter());
        let columns: [(&str, AmplitudeColumn); 4] = [
            ("rs", |a| a.rs),
            ("rp", |a| a.rp),
            ("ts", |a| a.ts),
            ("tp", |a| a.tp),
        ];
        for (key, f) in columns {
            result.set_item(key, array(py, amplitudes().map(f).collect(), &shape)?)?;
        }
    }
    add_derivatives(
        py,
        &result,
        &chunks,
        [layers, wavelengths, angles],
        by_index,
    )?;
    Ok(result)
}

/// The gradient grid of [`solve_with_gradient`] in runs of wavelengths,
/// each solved whole (the lanes take a coherent stack's points four or
/// eight at a time): on the thread pool, one run per task, when the grid is
/// large enough to pay for the handoff, else as one run on this thread.
/// `by_index`: with the derivatives by n and k (the scalar path, whose
/// points cost [`INDEX_COST`] times more and need no whole lanes).
fn solve_chunks(
    py: Python<'_>,
    grid: &StackGrid,
    cos_theta0: &[f64],
    by_index: bool,
) -> PyResult<Vec<GradientGrid>> {
    let (solver, cost, min_run): (GridSolver, usize, usize) = if by_index {
        (solve_stack_grid_with_index_gradient, INDEX_COST, 1)
    } else {
        (solve_stack_grid_with_gradient, 1, MIN_CHUNK_WAVELENGTHS)
    };
    let layers = grid.thicknesses_nm().len();
    let wavelengths = grid.wavelengths_nm().len();
    let per_wavelength = cos_theta0.len() * layers.max(1) * cost;
    if wavelengths * per_wavelength < PARALLEL_MIN_POINTS {
        return compute_cancellable(py, false, |_| {
            solver(grid, grid.thicknesses_nm(), cos_theta0)
        })?
        .map(|g| vec![g])
        .map_err(py_error);
    }
    let run = wavelengths
        .div_ceil(CHUNKS)
        .min((MAX_TASK_POINTS / per_wavelength).max(1))
        .max(min_run);
    let chunks = compute_cancellable(py, true, |cancel| {
        let chunk = |w0: usize| -> irid::error::Result<GradientGrid> {
            cancel.check()?;
            let w1 = (w0 + run).min(wavelengths);
            let media = layers + 2;
            let part = StackGrid::from_indices(
                grid.indices()[w0 * media..w1 * media].to_vec(),
                grid.thicknesses_nm().to_vec(),
                &grid.wavelengths_nm()[w0..w1],
            )
            .with_coherence(grid.coherence().clone());
            solver(&part, grid.thicknesses_nm(), cos_theta0)
        };
        let starts: Vec<usize> = (0..wavelengths).step_by(run).collect();
        starts.into_par_iter().map(chunk).collect::<Vec<_>>()
    })?;
    chunks
        .into_iter()
        .collect::<irid::error::Result<_>>()
        .map_err(py_error)
}

/// Adds the derivative arrays of `chunks` (runs of wavelengths, in order)
/// to `result`, each of `shape` (layers, wavelengths, angles): by the
/// thickness (dRs_dd, dRp_dd, dTs_dd, dTp_dd, dR_dd, dT_dd) and, when
/// `by_index`, the same six by n (`_dn`) and by k (`_dk`). All are views of
/// one array: one allocation whose pages the allocator keeps from call to
/// call, where six fresh ones of this size went back to the system on
/// every call and page-faulted in again, which cost more than the solve.
fn add_derivatives(
    py: Python<'_>,
    result: &Bound<'_, PyDict>,
    chunks: &[GradientGrid],
    shape: [usize; 3],
    by_index: bool,
) -> PyResult<()> {
    let [layers, wavelengths, angles] = shape;
    let size = layers * wavelengths * angles;
    // Layer l's rows of a chunk: its wavelengths × angles, contiguous.
    let rows =
        |c: &GradientGrid, l: usize| l * c.wavelengths * angles..(l + 1) * c.wavelengths * angles;
    let mut parameters: Vec<(&str, [DerivativeColumn; 4])> =
        vec![("dd", [|g| &g.d_rs, |g| &g.d_rp, |g| &g.d_ts, |g| &g.d_tp])];
    if by_index {
        parameters.push((
            "dn",
            [
                |g| &g.by_n[0],
                |g| &g.by_n[1],
                |g| &g.by_n[2],
                |g| &g.by_n[3],
            ],
        ));
        parameters.push((
            "dk",
            [
                |g| &g.by_k[0],
                |g| &g.by_k[1],
                |g| &g.by_k[2],
                |g| &g.by_k[3],
            ],
        ));
    }
    let mut all = Vec::with_capacity(6 * parameters.len() * size);
    for (_, polarized) in &parameters {
        let start = all.len();
        for f in polarized {
            for l in 0..layers {
                for c in chunks {
                    all.extend_from_slice(&f(c)[rows(c, l)]);
                }
            }
        }
        // dR and dT: the means of the s and p blocks just written.
        for (s, p) in [(0, 1), (2, 3)] {
            for i in 0..size {
                all.push(0.5 * (all[start + s * size + i] + all[start + p * size + i]));
            }
        }
    }
    let block = array(
        py,
        all,
        &[6 * parameters.len(), layers, wavelengths, angles],
    )?;
    let outputs = ["dRs", "dRp", "dTs", "dTp", "dR", "dT"];
    for (k, (suffix, _)) in parameters.iter().enumerate() {
        for (o, output) in outputs.into_iter().enumerate() {
            result.set_item(format!("{output}_{suffix}"), block.get_item(6 * k + o)?)?;
        }
    }
    Ok(())
}

/// The colours of `stack` at `angles` (degrees, checked by the caller) with
/// their derivatives: the per-angle colours as `Stack.color` reports them,
/// plus dreflectance_rgb_dd and dtransmittance_rgb_dd of shape
/// (layers, angles, 3) added to `result` by [`add_color_gradient`]. Runs
/// on the pool, where Ctrl-C stops it, when `on_pool`.
pub fn colors(
    py: Python<'_>,
    stack: &Stack,
    integrator: &SpectralIntegrator,
    angles: &[f64],
    on_pool: bool,
) -> PyResult<Vec<ColorGradient>> {
    let layers = stack.layers.len();
    Footprint::new()
        .items(&[2, integrator.wavelengths_nm().len(), layers.max(1), 4], 8)
        .items(&[angles.len(), layers.max(1), 4, 3], 8)
        .check(&format!(
            "the colour gradient of {layers} layers × {} angles",
            angles.len()
        ))?;
    compute_cancellable(py, on_pool, |cancel| {
        colors_with_gradient_cancellable(stack, integrator, angles, cancel)
    })?
    .map_err(py_error)
}

/// Adds `Stack.color`'s derivative arrays (see [`colors`]) to `result`.
pub fn add_color_gradient(
    py: Python<'_>,
    result: &Bound<'_, PyDict>,
    layers: usize,
    colours: &[ColorGradient],
) -> PyResult<()> {
    let keys: [(&str, ColourColumn); 4] = [
        ("dreflectance_rgb_dd", |c| &c.d_reflectance_rgb),
        ("dtransmittance_rgb_dd", |c| &c.d_transmittance_rgb),
        ("dreflectance_xyz_dd", |c| &c.d_reflectance_xyz),
        ("dtransmittance_xyz_dd", |c| &c.d_transmittance_xyz),
    ];
    for (key, f) in keys {
        let mut values = Vec::with_capacity(layers * colours.len() * 3);
        for l in 0..layers {
            for c in colours {
                values.extend_from_slice(&f(c)[l]);
            }
        }
        result.set_item(key, array(py, values, &[layers, colours.len(), 3])?)?;
    }
    Ok(())
}
