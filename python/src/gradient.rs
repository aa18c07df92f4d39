//! The `gradient=True` parts of `Stack.solve` and `Stack.color`: the
//! derivatives of R, T and the colour by every layer's thickness
//! (irid::optics::gradient, irid::color::gradient), as numpy arrays with
//! the layers first.

use pyo3::prelude::*;
use pyo3::types::PyDict;
use rayon::prelude::*;

use irid::color::gradient::{colors_with_gradient, ColorGradient};
use irid::color::SpectralIntegrator;
use irid::optics::gradient::{solve_grid_point_with_gradient, ResponseGradient, Workspace};
use irid::optics::{Response, Stack, StackGrid};

use crate::arrays::array;
use crate::budget::Footprint;
use crate::pool::compute;
use crate::py_error;

/// Fewest points of a gradient solve that go to the thread pool (each costs
/// about as much as a few forward points).
const PARALLEL_MIN_POINTS: usize = 128;

/// Adds dRs_dd, dRp_dd, dTs_dd, dTp_dd, dR_dd and dT_dd, each of shape
/// (layers, wavelengths, angles), to `result`, for the grid's stack at its
/// own thicknesses. Raises ValueError where an incoherent layer lases.
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
    // One row of angles per wavelength, each with its own scratch.
    let rows = compute(py, parallel, || {
        let row = |w: usize| -> irid::error::Result<Vec<(Response, ResponseGradient)>> {
            let mut work = Workspace::default();
            cos_theta0
                .iter()
                .map(|&c| {
                    solve_grid_point_with_gradient(grid, w, grid.thicknesses_nm(), c, &mut work)
                })
                .collect()
        };
        if parallel {
            (0..wavelengths).into_par_iter().map(row).collect::<Vec<_>>()
        } else {
            (0..wavelengths).map(row).collect()
        }
    })?;
    let rows: Vec<Vec<(Response, ResponseGradient)>> = rows
        .into_iter()
        .collect::<irid::error::Result<_>>()
        .map_err(py_error)?;
    let shape = [layers, wavelengths, angles];
    let column = |f: &dyn Fn(&ResponseGradient, usize) -> f64| -> Vec<f64> {
        let mut out = Vec::with_capacity(layers * points);
        for l in 0..layers {
            for row in &rows {
                out.extend(row.iter().map(|(_, g)| f(g, l)));
            }
        }
        out
    };
    let keys: [(&str, &dyn Fn(&ResponseGradient, usize) -> f64); 6] = [
        ("dRs_dd", &|g, l| g.rs[l]),
        ("dRp_dd", &|g, l| g.rp[l]),
        ("dTs_dd", &|g, l| g.ts[l]),
        ("dTp_dd", &|g, l| g.tp[l]),
        ("dR_dd", &|g, l| g.r(l)),
        ("dT_dd", &|g, l| g.t(l)),
    ];
    for (key, f) in keys {
        result.set_item(key, array(py, column(f), &shape)?)?;
    }
    Ok(())
}

/// The colours of `stack` at `angles` (degrees, checked by the caller) with
/// their derivatives: the per-angle colours as `Stack.color` reports them,
/// plus dreflectance_rgb_dd and dtransmittance_rgb_dd of shape
/// (layers, angles, 3) added to `result` by [`add_color_gradient`].
pub fn colors(
    py: Python<'_>,
    stack: &Stack,
    integrator: &SpectralIntegrator,
    angles: &[f64],
) -> PyResult<Vec<ColorGradient>> {
    let layers = stack.layers.len();
    Footprint::new()
        .items(
            &[2, integrator.wavelengths_nm().len(), layers.max(1), 4],
            8,
        )
        .items(&[angles.len(), layers.max(1), 4, 3], 8)
        .check(&format!(
            "the colour gradient of {layers} layers × {} angles",
            angles.len()
        ))?;
    compute(py, false, || colors_with_gradient(stack, integrator, angles))?.map_err(py_error)
}

/// Adds `Stack.color`'s derivative arrays (see [`colors`]) to `result`.
pub fn add_color_gradient(
    py: Python<'_>,
    result: &Bound<'_, PyDict>,
    layers: usize,
    colours: &[ColorGradient],
) -> PyResult<()> {
    let keys: [(&str, fn(&ColorGradient) -> &Vec<[f64; 3]>); 4] = [
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
