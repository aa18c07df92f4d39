//! `Stack.response`: R and T at arrays of points (thickness, cos θ,
//! wavelength), each point its own wavelength, from either side of the
//! stack. This is what a spectral renderer needs per path vertex: Mitsuba's
//! rays carry their own wavelengths, so no grid is shared between points,
//! and the library's `PointSolver` solves them several to a vector.

use pyo3::prelude::*;
use pyo3::types::PyTuple;
use rayon::prelude::*;

use irid::optics::{LayerThickness, PointSolver, Response, Stack};

use crate::arrays::{array, broadcast_reals};
use crate::pool::{compute_cancellable, Cancel};
use crate::stack::layer_number;
use crate::{invalid, py_error};

/// Points handed to one rayon task: enough to amortize the task, few enough
/// to spread a render's bounce over both cores. A call of fewer points runs
/// on the calling thread.
const POINTS_PER_TASK: usize = 2048;

/// Which side of the stack the light arrives from.
#[derive(Clone, Copy, PartialEq, Eq)]
pub enum Side {
    /// Through the ambient, as everywhere else in irid.
    Ambient,
    /// Through the substrate (which must then be lossless): the reversed stack.
    Substrate,
}

impl Side {
    pub fn parse(side: &str) -> PyResult<Side> {
        match side {
            "ambient" => Ok(Side::Ambient),
            "substrate" => Ok(Side::Substrate),
            other => Err(invalid(
                "side",
                format!("expected \"ambient\" or \"substrate\", got {other:?}"),
            )),
        }
    }
}

/// The stack as seen from `side`, and the index (0-based) that layer
/// `layer` (1-based, counted from the ambient side) has in it.
fn oriented(stack: &Stack, layer: usize, side: Side) -> PyResult<(Stack, usize)> {
    match side {
        Side::Ambient => Ok((stack.clone(), layer - 1)),
        Side::Substrate => {
            if !stack.substrate.is_lossless() {
                return Err(invalid(
                    "side",
                    format!(
                        "light cannot arrive through the substrate {}: it absorbs (k > 0)",
                        stack.substrate.name
                    ),
                ));
            }
            Ok((stack.reversed(), stack.layers.len().saturating_sub(layer)))
        }
    }
}

/// Unpolarized (R, T) at each point, the thickness of layer `varying` set
/// per point (or the stack's own where it is None), through `solver` in
/// tasks on the current thread pool when `parallel`, else on this thread;
/// each task looks at `cancel` first ([`irid::Error::Cancelled`] once set).
/// Each task solves its points into a buffer of its own of at most
/// [`POINTS_PER_TASK`] responses (64 KB), so what grows with the call is
/// only R and T. Fails on a point whose wavelength a material does not
/// cover or where an incoherent layer lases (the caller has checked
/// the angles and thicknesses).
fn solve_points(
    solver: &PointSolver<'_>,
    varying: Option<LayerThickness<'_>>,
    cos_theta: &[f64],
    wavelength_nm: &[f64],
    parallel: bool,
    cancel: &Cancel,
) -> irid::Result<(Vec<f64>, Vec<f64>)> {
    let points = cos_theta.len();
    let mut reflectance = vec![0.0; points];
    let mut transmittance = vec![0.0; points];
    let solve_task = |(task, (r_out, t_out)): (usize, (&mut [f64], &mut [f64]))| {
        cancel.check()?;
        let start = task * POINTS_PER_TASK;
        let range = start..start + r_out.len();
        let varying = varying.map(|v| LayerThickness {
            layer: v.layer,
            thickness_nm: &v.thickness_nm[range.clone()],
        });
        let mut responses = vec![Response::default(); range.len()];
        solver.solve(
            varying,
            &wavelength_nm[range.clone()],
            &cos_theta[range],
            &mut responses,
        )?;
        for ((r, t), response) in r_out.iter_mut().zip(t_out.iter_mut()).zip(&responses) {
            *r = response.r();
            *t = response.t();
        }
        Ok(())
    };
    if parallel {
        reflectance
            .par_chunks_mut(POINTS_PER_TASK)
            .zip(transmittance.par_chunks_mut(POINTS_PER_TASK))
            .enumerate()
            .try_for_each(solve_task)?;
    } else {
        reflectance
            .chunks_mut(POINTS_PER_TASK)
            .zip(transmittance.chunks_mut(POINTS_PER_TASK))
            .enumerate()
            .try_for_each(solve_task)?;
    }
    Ok((reflectance, transmittance))
}

/// The body of `Stack.response` (see its docstring in stack.rs).
pub fn response<'py>(
    py: Python<'py>,
    stack: &Stack,
    thickness_nm: Option<&Bound<'py, PyAny>>,
    cos_theta: &Bound<'py, PyAny>,
    wavelength_nm: &Bound<'py, PyAny>,
    layer: Option<&Bound<'py, PyAny>>,
    side: &str,
) -> PyResult<Bound<'py, PyTuple>> {
    let side = Side::parse(side)?;
    let layer = layer_number(stack, layer)?;
    if thickness_nm.is_some() && stack.layers.is_empty() {
        return Err(invalid("thickness_nm", "the stack has no layer to vary"));
    }
    // Without layers `layer` names none; the index is then unused.
    let (seen, index) = oriented(stack, layer.clamp(1, stack.layers.len().max(1)), side)?;
    let varying = thickness_nm.map(|_| index);
    let mut arrays = vec![(cos_theta, "cos_theta"), (wavelength_nm, "wavelength_nm")];
    if let Some(t) = thickness_nm {
        arrays.push((t, "thickness_nm"));
    }
    // R and T (f64 each) per point; the arrays returned are those buffers.
    let (columns, shape) = broadcast_reals(&arrays, "response", 16)?;
    let varying = varying
        .zip(columns.get(2))
        .map(|(layer, t)| LayerThickness {
            layer,
            thickness_nm: t,
        });
    let solver = PointSolver::new(&seen).map_err(py_error)?;
    solver.check(varying, &columns[0]).map_err(py_error)?;
    let parallel = columns[0].len() > POINTS_PER_TASK;
    let (r, t) = compute_cancellable(py, parallel, |cancel| {
        solve_points(&solver, varying, &columns[0], &columns[1], parallel, cancel)
    })?
    .map_err(py_error)?;
    PyTuple::new(py, [array(py, r, &shape)?, array(py, t, &shape)?])
}
