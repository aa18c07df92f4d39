//! `irid.fit` and `irid.fit_color` (their Python wrappers are in
//! `irid/__init__.py`): thin shells over the crate's `fit` module.

use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use rayon::prelude::*;

use irid::color::White;
use irid::fit::{self as fitting, ColorTarget, Measurement, SpectrumFit, SpectrumFitter, Vary};

use crate::arrays::{array, integer_in, planned_len, real, reals};
use crate::budget::Footprint;
use crate::coherent::check_wavelengths;
use crate::pool::{compute, compute_interruptible};
use crate::stack::PyStack;
use crate::{invalid, py_error};

/// `vary`: layer numbers, 1-based from the top.
fn layers(vary: &Bound<'_, PyAny>) -> PyResult<Vec<usize>> {
    let items: Vec<Bound<'_, PyAny>> = if let Ok(list) = vary.extract::<Vec<Bound<'_, PyAny>>>() {
        list
    } else {
        vec![vary.clone()]
    };
    items
        .iter()
        .enumerate()
        .map(|(i, v)| Ok(integer_in(v, &format!("vary[{i}]"), 0..=u32::MAX as i128)? as usize))
        .collect()
}

/// `angles_deg`: each in [0, 90).
fn check_angles(angles: &[f64]) -> PyResult<()> {
    match angles.iter().find(|a| !(0.0..90.0).contains(*a)) {
        Some(a) => Err(invalid(
            "angles_deg",
            format!("{a} is outside [0, 90) degrees"),
        )),
        None => Ok(()),
    }
}

/// `bounds`: one (lo, hi) per varied layer.
fn bounds(obj: Option<&Bound<'_, PyAny>>) -> PyResult<Option<Vec<(f64, f64)>>> {
    let Some(obj) = obj else { return Ok(None) };
    let pairs: Vec<Bound<'_, PyAny>> = obj.extract()?;
    pairs
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let what = format!("bounds[{i}]");
            let pair: Vec<Bound<'_, PyAny>> = p.extract()?;
            let [lo, hi] = &pair[..] else {
                return Err(invalid(what, "expected a pair (lo, hi) in nm"));
            };
            Ok((real(lo, &what)?, real(hi, &what)?))
        })
        .collect::<PyResult<Vec<_>>>()
        .map(Some)
}

/// A measured channel shaped (..., wavelengths, angles): its values and the
/// leading (batch) shape.
fn channel(
    obj: Option<&Bound<'_, PyAny>>,
    what: &str,
    grid: (usize, usize),
) -> PyResult<Option<(Vec<f64>, Vec<usize>)>> {
    let Some(obj) = obj else { return Ok(None) };
    let (values, shape) = reals(obj, what)?;
    let n = shape.len();
    if n < 2 || (shape[n - 2], shape[n - 1]) != grid {
        return Err(invalid(
            what,
            format!(
                "shape {shape:?}: expected (..., {}, {}), (wavelengths, angles) after any batch axes",
                grid.0, grid.1
            ),
        ));
    }
    Ok(Some((values, shape[..n - 2].to_vec())))
}

/// The weighted least-squares fit of `vary`'s thicknesses to R and/or T.
#[pyfunction]
#[pyo3(signature = (stack, vary, wavelengths_nm, angles_deg, r=None, t=None, sigma=None, bounds=None))]
#[allow(clippy::too_many_arguments)]
pub fn fit<'py>(
    py: Python<'py>,
    stack: &PyStack,
    vary: &Bound<'py, PyAny>,
    wavelengths_nm: &Bound<'py, PyAny>,
    angles_deg: &Bound<'py, PyAny>,
    r: Option<&Bound<'py, PyAny>>,
    t: Option<&Bound<'py, PyAny>>,
    sigma: Option<&Bound<'py, PyAny>>,
    bounds: Option<&Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    let stack = &stack.stack;
    let layers = layers(vary)?;
    let bounds = self::bounds(bounds)?;
    let vary = Vary::new(stack, &layers, bounds.as_deref(), "vary", "bounds").map_err(py_error)?;
    // From the arguments' sizes before any is copied: per measured value
    // its copy and its measurement's, with σ, the wavelength and the angle
    // beside it (eight f64 at most).
    let measured = [r, t, sigma]
        .into_iter()
        .flatten()
        .map(|a| planned_len(a).unwrap_or(0))
        .chain([wavelengths_nm, angles_deg].map(|a| planned_len(a).unwrap_or(0)))
        .max()
        .unwrap_or(0);
    Footprint::new()
        .items(&[measured], 8 * 8)
        .check(&format!("{measured} measured values"))?;
    let (wavelengths, _) = reals(wavelengths_nm, "wavelengths_nm")?;
    let (angles, _) = reals(angles_deg, "angles_deg")?;
    check_wavelengths(&wavelengths, "wavelengths_nm")?;
    check_angles(&angles)?;
    let grid = (wavelengths.len(), angles.len());
    let r = channel(r, "R", grid)?;
    let t = channel(t, "T", grid)?;
    let batch = match (&r, &t) {
        (Some((_, a)), Some((_, b))) if a != b => {
            return Err(invalid(
                "T",
                format!("batch shape {b:?} differs from R's {a:?}"),
            ))
        }
        (Some((_, a)), _) | (None, Some((_, a))) => a.clone(),
        (None, None) => return Err(invalid("R", "neither R nor T is given")),
    };
    let spectra: usize = batch.iter().product();
    let points = grid.0 * grid.1;
    let sigma = match sigma {
        None => None,
        Some(s) => {
            let (values, shape) = reals(s, "sigma")?;
            let full: Vec<usize> = batch.iter().copied().chain([grid.0, grid.1]).collect();
            if shape.is_empty() {
                Some(vec![values[0]; spectra * points])
            } else if shape == [grid.0, grid.1] {
                Some(values.repeat(spectra))
            } else if shape == full {
                Some(values)
            } else {
                return Err(invalid(
                    "sigma",
                    format!("shape {shape:?}: expected a number, (wavelengths, angles) or R's shape {full:?}"),
                ));
            }
        }
    };
    let rows = |s: usize| -> Measurement {
        let slice = |v: &Vec<f64>| v[s * points..(s + 1) * points].to_vec();
        Measurement {
            wavelength_nm: (0..points).map(|i| wavelengths[i / grid.1]).collect(),
            angle_deg: (0..points).map(|i| angles[i % grid.1]).collect(),
            reflectance: r.as_ref().map(|(v, _)| slice(v)),
            transmittance: t.as_ref().map(|(v, _)| slice(v)),
            sigma: sigma.as_ref().map(slice),
        }
    };
    let measured: Vec<Measurement> = (0..spectra).map(rows).collect();
    for m in &measured {
        m.check("", layers.len()).map_err(py_error)?;
    }
    // SpectrumFitter::fit_many's loop, with a look at the flag before each
    // spectrum: Ctrl-C stops a batch between two fits.
    let fits = compute_interruptible(py, |cancel| -> irid::Result<Vec<SpectrumFit>> {
        let fitter = SpectrumFitter::new(stack, &vary, &measured[0])?;
        measured
            .par_iter()
            .map(|m| {
                cancel.check()?;
                fitter.fit(m)
            })
            .collect()
    })?
    .map_err(py_error)?;
    let out = results(py, &fits, &batch, grid)?;
    if batch.is_empty() {
        let fitted = vary.apply(stack, &fits[0].thickness_nm);
        out.set_item("stack", PyStack { stack: fitted })?;
    } else {
        out.set_item("stack", py.None())?;
    }
    Ok(out)
}

/// The fits as arrays over the batch shape.
fn results<'py>(
    py: Python<'py>,
    fits: &[SpectrumFit],
    batch: &[usize],
    grid: (usize, usize),
) -> PyResult<Bound<'py, PyDict>> {
    let k = fits[0].layers.len();
    let with = |extra: &[usize]| -> Vec<usize> { batch.iter().chain(extra).copied().collect() };
    let out = PyDict::new(py);
    let column =
        |f: &dyn Fn(&SpectrumFit) -> Vec<f64>| -> Vec<f64> { fits.iter().flat_map(f).collect() };
    out.set_item("layers", fits[0].layers.clone())?;
    out.set_item(
        "thickness_nm",
        array(py, column(&|f| f.thickness_nm.clone()), &with(&[k]))?,
    )?;
    out.set_item(
        "sigma_nm",
        array(py, column(&|f| f.sigma_nm.clone()), &with(&[k]))?,
    )?;
    out.set_item("chi2", array(py, column(&|f| vec![f.chi2]), &with(&[]))?)?;
    out.set_item(
        "residual",
        array(py, column(&|f| vec![f.rms_residual]), &with(&[]))?,
    )?;
    out.set_item(
        "threshold",
        array(py, column(&|f| vec![f.threshold]), &with(&[]))?,
    )?;
    out.set_item("degrees_of_freedom", fits[0].degrees_of_freedom)?;
    let ambiguous: Vec<bool> = fits.iter().map(SpectrumFit::is_ambiguous).collect();
    out.set_item("ambiguous", array(py, ambiguous, &with(&[]))?)?;
    let grid_shape = with(&[grid.0, grid.1]);
    for (key, values) in [
        (
            "residual_R",
            fits.iter()
                .map(|f| f.residual_r.clone())
                .collect::<Option<Vec<_>>>(),
        ),
        (
            "residual_T",
            fits.iter()
                .map(|f| f.residual_t.clone())
                .collect::<Option<Vec<_>>>(),
        ),
    ] {
        match values {
            Some(v) => out.set_item(key, array(py, v.concat(), &grid_shape)?)?,
            None => out.set_item(key, py.None())?,
        }
    }
    let alternatives = PyList::empty(py);
    for f in fits {
        let list = PyList::empty(py);
        for a in &f.alternatives {
            list.append((a.thickness_nm.clone(), a.chi2))?;
        }
        alternatives.append(list)?;
    }
    out.set_item("alternatives", alternatives)?;
    Ok(out)
}

/// The thicknesses whose reflected colours are closest in ΔE00 to targets.
#[pyfunction]
#[pyo3(signature = (stack, vary, angles_deg, target_rgb, white="d65", roughness=None, bounds=None))]
#[allow(clippy::too_many_arguments)] // Python's keyword arguments, one each
pub fn fit_color<'py>(
    py: Python<'py>,
    stack: &PyStack,
    vary: &Bound<'py, PyAny>,
    angles_deg: &Bound<'py, PyAny>,
    target_rgb: &Bound<'py, PyAny>,
    white: &str,
    roughness: Option<&Bound<'py, PyAny>>,
    bounds: Option<&Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    let stack = &stack.stack;
    let layers = layers(vary)?;
    let bounds = self::bounds(bounds)?;
    let vary = Vary::new(stack, &layers, bounds.as_deref(), "vary", "bounds").map_err(py_error)?;
    let white: White = white.parse().map_err(py_error)?;
    // From the arguments' sizes before they are copied: per angle its
    // target colour (three values), the fit's colour and ΔE00, a few dozen
    // f64 at most.
    let planned = planned_len(angles_deg)
        .unwrap_or(0)
        .max(planned_len(target_rgb).unwrap_or(0).div_ceil(3));
    Footprint::new()
        .items(&[planned], 32 * 8)
        .check(&format!("{planned} angles"))?;
    let (angles, _) = reals(angles_deg, "angles_deg")?;
    check_angles(&angles)?;
    let (rgb, shape) = reals(target_rgb, "target_rgb")?;
    if shape != [angles.len(), 3] {
        return Err(invalid(
            "target_rgb",
            format!(
                "shape {shape:?}: expected ({}, 3), one colour per angle",
                angles.len()
            ),
        ));
    }
    let roughness = roughness.map(|r| real(r, "roughness")).transpose()?;
    let targets: Vec<ColorTarget> = angles
        .iter()
        .enumerate()
        .map(|(j, &angle_deg)| ColorTarget {
            angle_deg,
            rgb: [rgb[3 * j], rgb[3 * j + 1], rgb[3 * j + 2]],
        })
        .collect();
    let fit = compute(py, true, || {
        fitting::fit_color(stack, &vary, &targets, white, roughness)
    })?
    .map_err(py_error)?;
    let out = PyDict::new(py);
    out.set_item(
        "stack",
        PyStack {
            stack: vary.apply(stack, &fit.thickness_nm),
        },
    )?;
    out.set_item("layers", fit.layers.clone())?;
    out.set_item(
        "thickness_nm",
        array(py, fit.thickness_nm.clone(), &[layers.len()])?,
    )?;
    out.set_item(
        "angle_deg",
        array(py, fit.angle_deg.clone(), &[angles.len()])?,
    )?;
    out.set_item(
        "delta_e2000",
        array(py, fit.delta_e2000.clone(), &[angles.len()])?,
    )?;
    out.set_item("rgb", array(py, fit.rgb.concat(), &[angles.len(), 3])?)?;
    out.set_item("ambiguous", fit.is_ambiguous())?;
    out.set_item("tolerance_de2000", fit.tolerance_de2000)?;
    let alternatives = PyList::empty(py);
    for a in &fit.alternatives {
        alternatives.append((a.thickness_nm.clone(), a.delta_e2000.clone()))?;
    }
    out.set_item("alternatives", alternatives)?;
    Ok(out)
}
