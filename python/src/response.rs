//! `Stack.response`: R and T at arrays of points (thickness, cos θ,
//! wavelength), each point its own wavelength, from either side of the
//! stack. This is what a spectral renderer needs per path vertex: Mitsuba's
//! rays carry their own wavelengths, so no grid is shared between points.

use num_complex::Complex64 as C64;
use pyo3::prelude::*;
use pyo3::types::PyTuple;
use rayon::prelude::*;

use irid::optics::{solve, Stack, MAX_THICKNESS_NM};

use crate::arrays::{array, broadcast_reals};
use crate::pool::compute;
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

/// Unpolarized (R, T) at each point, the thickness of layer `layer` set per
/// point (or the stack's own where `thickness_nm` is None), in tasks on the
/// current thread pool when `parallel`, else on this thread. Fails on the
/// first point whose wavelength a material does not cover, or whose
/// thickness or cos θ is not a number in range.
fn solve_points(
    stack: &Stack,
    varying: Option<usize>,
    thickness_nm: Option<&[f64]>,
    cos_theta: &[f64],
    wavelength_nm: &[f64],
    parallel: bool,
) -> irid::Result<(Vec<f64>, Vec<f64>)> {
    let points = cos_theta.len();
    let mut reflectance = vec![0.0; points];
    let mut transmittance = vec![0.0; points];
    let solve_task = |(task, (r_out, t_out)): (usize, (&mut [f64], &mut [f64]))| {
        let mut n: Vec<C64> = Vec::with_capacity(stack.layers.len() + 2);
        let mut d = stack.thicknesses_nm();
        let start = task * POINTS_PER_TASK;
        for (k, (r, t)) in r_out.iter_mut().zip(t_out.iter_mut()).enumerate() {
            let i = start + k;
            let wl = wavelength_nm[i];
            stack.indices_at(wl, &mut n)?;
            if let (Some(layer), Some(thickness)) = (varying, thickness_nm) {
                d[layer] = thickness[i];
            }
            let response = solve(&n, &d, wl, cos_theta[i]);
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

fn check_points(thickness_nm: Option<&[f64]>, cos_theta: &[f64]) -> PyResult<()> {
    if let Some(c) = cos_theta.iter().find(|c| !(0.0..=1.0).contains(*c)) {
        return Err(invalid("cos_theta", format!("{c} is outside [0, 1]")));
    }
    if let Some(t) = thickness_nm
        .unwrap_or(&[])
        .iter()
        .find(|t| !(0.0..=MAX_THICKNESS_NM).contains(*t))
    {
        return Err(invalid(
            "thickness_nm",
            format!("must be finite, ≥ 0 and ≤ {MAX_THICKNESS_NM:e}, got {t}"),
        ));
    }
    Ok(())
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
    let thickness = columns.get(2).map(Vec::as_slice);
    check_points(thickness, &columns[0])?;
    let parallel = columns[0].len() > POINTS_PER_TASK;
    let (r, t) = compute(py, parallel, || {
        solve_points(
            &seen,
            varying,
            thickness,
            &columns[0],
            &columns[1],
            parallel,
        )
    })?
    .map_err(py_error)?;
    PyTuple::new(py, [array(py, r, &shape)?, array(py, t, &shape)?])
}
