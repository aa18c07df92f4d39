//! Conversions between Python values and the flat vectors the library takes.

use numpy::{
    Element, PyArray1, PyArrayDyn, PyArrayMethods, PyReadonlyArrayDyn, PyUntypedArrayMethods,
};
use pyo3::prelude::*;
use pyo3::types::{IntoPyDict, PyTuple};

use crate::invalid;

/// A numpy array of `obj` with `dtype`, C-contiguous: numbers, lists and
/// arrays of any shape are accepted as numpy accepts them.
fn contiguous<'py>(
    obj: &Bound<'py, PyAny>,
    dtype: &str,
    what: &str,
) -> PyResult<Bound<'py, PyAny>> {
    let py = obj.py();
    let np = py.import("numpy")?;
    // asarray keeps a number 0-dimensional (ascontiguousarray makes it 1-D).
    let kwargs = [
        ("dtype", np.getattr(dtype)?),
        ("order", "C".into_pyobject(py)?.into_any()),
    ]
    .into_py_dict(py)?;
    np.getattr("asarray")?
        .call((obj,), Some(&kwargs))
        .map_err(|e| invalid(what, format!("not an array of numbers ({e})")))
}

/// The values of `obj` (anything numpy turns into an array) in C order, with
/// the array's shape.
pub fn values<T: Element + Clone>(
    obj: &Bound<'_, PyAny>,
    dtype: &str,
    what: &str,
) -> PyResult<(Vec<T>, Vec<usize>)> {
    let array = contiguous(obj, dtype, what)?;
    let array: PyReadonlyArrayDyn<'_, T> = array.extract()?;
    let shape = array.shape().to_vec();
    Ok((array.as_slice()?.to_vec(), shape))
}

/// Real values of `obj` as a flat list, with its shape.
pub fn reals(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<(Vec<f64>, Vec<usize>)> {
    values::<f64>(obj, "float64", what)
}

/// A one-dimensional list of reals: a number counts as a list of one.
pub fn real_list(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<Vec<f64>> {
    let (v, shape) = reals(obj, what)?;
    if shape.len() > 1 {
        return Err(invalid(
            what,
            format!("expected a number or a 1-D array, got shape {shape:?}"),
        ));
    }
    Ok(v)
}

/// numpy's broadcast of several arrays to one shape, each returned flat.
pub fn broadcast_reals(
    objs: &[&Bound<'_, PyAny>],
    what: &str,
) -> PyResult<(Vec<Vec<f64>>, Vec<usize>)> {
    let py = objs[0].py();
    let np = py.import("numpy")?;
    let arrays = np
        .getattr("broadcast_arrays")?
        .call1(PyTuple::new(py, objs)?)
        .map_err(|e| invalid(what, format!("the arrays do not broadcast together ({e})")))?;
    let mut out = Vec::with_capacity(objs.len());
    let mut shape = Vec::new();
    for a in arrays.try_iter()? {
        let (v, s) = reals(&a?, what)?;
        out.push(v);
        shape = s;
    }
    Ok((out, shape))
}

/// A new numpy array holding `data` with `shape` (no copy).
pub fn array<'py, T: Element>(
    py: Python<'py>,
    data: Vec<T>,
    shape: &[usize],
) -> PyResult<Bound<'py, PyArrayDyn<T>>> {
    PyArray1::from_vec(py, data).reshape(shape)
}

/// A JSON document as Python objects (dicts, lists, numbers, strings).
pub fn json_to_py<'py>(
    py: Python<'py>,
    value: &impl serde::Serialize,
) -> PyResult<Bound<'py, PyAny>> {
    let text = serde_json::to_string(value).map_err(|e| invalid("json", e.to_string()))?;
    py.import("json")?.getattr("loads")?.call1((text,))
}
