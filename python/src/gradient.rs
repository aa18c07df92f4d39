//! The `gradient=True` parts of `Stack.solve` and `Stack.color`: the
//! derivatives of R, T and the colour by every layer's thickness
//! (irid::optics::gradient, irid::color::gradient), as numpy arrays with
//! the layers first.

use pyo3::prelude::*;
use pyo3::types::PyDict;
use rayon::prelude::*;

use irid::color::gradient::{colors_with_gradient_cancellable, ColorGradient};
use irid::color::SpectralIntegrator;
use irid::optics::gradient::{solve_stack_grid_with_gradient, GradientGrid};
use irid::optics::{Stack, StackGrid};

use crate::arrays::array;
use crate::budget::Footprint;
use crate::pool::compute_cancellable;
use crate::py_error;

/// One output array of a gradient grid: its value at a point index.
type GridColumn = dyn Fn(&GradientGrid, usize) -> f64;

/// One output array of the colour gradients: its rows per layer.
type ColourColumn = fn(&ColorGradient) -> &Vec<[f64; 3]>;

/// Fewest points × layers of a gradient solve that go to the thread pool.
const PARALLEL_MIN_POINTS: usize = 2048;

/// Wavelengths per task when the pool solves a gradient.
const CHUNK_WAVELENGTHS: usize = 32;

/// Adds dRs_dd, dRp_dd, dTs_dd, dTp_dd, dR_dd and dT_dd, each of shape
/// (layers, wavelengths, angles), to `result`, for the grid's stack at its
/// own thicknesses. Raises ValueError where an incoherent layer lases. A
/// parallel solve runs on the pool, where Ctrl-C stops it between runs.
pub fn add_solve_gradient(
    py: Python<'_>,
    result: &Bound<'_, PyDict>,
    grid: &StackGrid,
    cos_theta0: &[f64],
) -> PyResult<()> {
    let layers = grid.thicknesses_nm().len();
    let (wavelengths, angles) = (grid.wavelengths_nm().len(), cos_theta0.len());
    Footprint::new()
        .items(&[6, layers, wavelengths, angles], 16)
        .check(&format!(
            "the gradient of {layers} layers × {wavelengths} wavelengths × {angles} angles"
        ))?;
    let points = wavelengths * angles;
    let parallel = points * layers.max(1) >= PARALLEL_MIN_POINTS;
    // Runs of wavelengths, each solved whole (the lanes take a coherent
    // stack's points four or eight at a time), one run per task.
    let run = if parallel {
        CHUNK_WAVELENGTHS
    } else {
        wavelengths.max(1)
    };
    let chunks = compute_cancellable(py, parallel, |cancel| {
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
            solve_stack_grid_with_gradient(&part, grid.thicknesses_nm(), cos_theta0)
        };
        let starts: Vec<usize> = (0..wavelengths).step_by(run).collect();
        if parallel {
            starts.into_par_iter().map(chunk).collect::<Vec<_>>()
        } else {
            starts.into_iter().map(chunk).collect()
        }
    })?;
    let chunks: Vec<GradientGrid> = chunks
        .into_iter()
        .collect::<irid::error::Result<_>>()
        .map_err(py_error)?;
    let shape = [layers, wavelengths, angles];
    let column = |f: &dyn Fn(&GradientGrid, usize) -> f64| -> Vec<f64> {
        let mut out = Vec::with_capacity(layers * points);
        for l in 0..layers {
            for c in &chunks {
                let span = l * c.wavelengths * angles..(l + 1) * c.wavelengths * angles;
                out.extend(span.map(|i| f(c, i)));
            }
        }
        out
    };
    let keys: [(&str, &GridColumn); 6] = [
        ("dRs_dd", &|g, i| g.d_rs[i]),
        ("dRp_dd", &|g, i| g.d_rp[i]),
        ("dTs_dd", &|g, i| g.d_ts[i]),
        ("dTp_dd", &|g, i| g.d_tp[i]),
        ("dR_dd", &|g, i| 0.5 * (g.d_rs[i] + g.d_rp[i])),
        ("dT_dd", &|g, i| 0.5 * (g.d_ts[i] + g.d_tp[i])),
    ];
    for (key, f) in keys {
        result.set_item(key, array(py, column(f), &shape)?)?;
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
