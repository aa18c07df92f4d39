//! Conversions between Python values and the flat vectors the library takes.
//!
//! Every array argument is measured before it is copied (a stride-0 view of
//! 10^13 elements costs nothing until numpy makes it contiguous), and the
//! exception keeps numpy's verdict: `TypeError` for something that is not
//! numbers at all (`None`, an object), `ValueError` for numbers that are
//! wrong (a ragged list, a string that does not parse, an int beyond f64),
//! each naming the argument.

use std::ops::RangeInclusive;

use numpy::{
    Element, PyArray1, PyArrayDyn, PyArrayMethods, PyReadonlyArrayDyn, PyUntypedArrayMethods,
};
use pyo3::exceptions::{PyMemoryError, PyOverflowError, PyTypeError};
use pyo3::prelude::*;
use pyo3::types::{IntoPyDict, PyBool, PyTuple};

use crate::budget::Footprint;
use crate::{invalid, wrong_type};

/// numpy's error converting argument `what`, as the exception the package
/// raises for it: the same type for TypeError and MemoryError, ValueError
/// for the rest (ValueError, OverflowError).
fn conversion_error(py: Python<'_>, e: PyErr, what: &str, doing: &str) -> PyErr {
    if e.is_instance_of::<PyTypeError>(py) {
        wrong_type(what, format!("{doing} ({e})"))
    } else if e.is_instance_of::<PyMemoryError>(py) {
        PyMemoryError::new_err(format!("{what}: {e}"))
    } else {
        invalid(what, format!("{doing} ({e})"))
    }
}

/// A numpy array of `obj` with `dtype`, C-contiguous: numbers, lists and
/// arrays of any shape are accepted as numpy accepts them. The copy is
/// checked against the memory budget first.
fn contiguous<'py>(
    obj: &Bound<'py, PyAny>,
    dtype: &str,
    what: &str,
) -> PyResult<Bound<'py, PyAny>> {
    let py = obj.py();
    if obj.is_none() {
        // numpy would make it NaN.
        return Err(wrong_type(what, "expected numbers, got None"));
    }
    let np = py.import("numpy")?;
    let not_numbers = "not an array of numbers";
    // No copy of an array; a list becomes the array it describes, smaller
    // than the list itself.
    let as_is = np
        .getattr("asarray")?
        .call1((obj,))
        .map_err(|e| conversion_error(py, e, what, not_numbers))?;
    let size: usize = as_is.getattr("size")?.extract()?;
    let item_bytes: u64 = np
        .getattr("dtype")?
        .call1((dtype,))?
        .getattr("itemsize")?
        .extract()?;
    // numpy's contiguous copy, then the library's own.
    Footprint::new()
        .items(&[size, 2], item_bytes)
        .check(&format!("{what}: {size} values"))?;
    // asarray keeps a number 0-dimensional (ascontiguousarray makes it 1-D).
    let kwargs = [
        ("dtype", np.getattr(dtype)?),
        ("order", "C".into_pyobject(py)?.into_any()),
    ]
    .into_py_dict(py)?;
    np.getattr("asarray")?
        .call((as_is,), Some(&kwargs))
        .map_err(|e| conversion_error(py, e, what, not_numbers))
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

/// Named arrays broadcast together (numpy's rules), each returned flat,
/// with the broadcast shape. The copies, and the caller's
/// `output_bytes_per_point` at every broadcast point, are checked against
/// the memory budget (as `what`) before anything of the broadcast size is
/// allocated.
pub fn broadcast_reals(
    named: &[(&Bound<'_, PyAny>, &str)],
    what: &str,
    output_bytes_per_point: u64,
) -> PyResult<(Vec<Vec<f64>>, Vec<usize>)> {
    let py = named[0].0.py();
    let np = py.import("numpy")?;
    let arrays = named
        .iter()
        .map(|&(obj, name)| contiguous(obj, "float64", name))
        .collect::<PyResult<Vec<_>>>()?;
    let shapes = arrays
        .iter()
        .map(|a| a.getattr("shape"))
        .collect::<PyResult<Vec<_>>>()?;
    let shape: Vec<usize> = np
        .getattr("broadcast_shapes")?
        .call1(PyTuple::new(py, shapes)?)
        .map_err(|e| invalid(what, format!("the arrays do not broadcast together ({e})")))?
        .extract()?;
    let points = shape.iter().try_fold(1usize, |n, &s| n.checked_mul(s));
    // Each argument's broadcast copy in numpy and in the library (f64 each).
    let copy_bytes = 16 * named.len() as u64;
    Footprint::new()
        .items(
            &[points.unwrap_or(usize::MAX)],
            copy_bytes + output_bytes_per_point,
        )
        .check(&format!("{what}: {shape:?} points"))?;
    let mut out = Vec::with_capacity(arrays.len());
    for (a, &(_, name)) in arrays.iter().zip(named) {
        let view = np
            .getattr("broadcast_to")?
            .call1((a, PyTuple::new(py, &shape)?))?;
        out.push(reals(&view, name)?.0);
    }
    Ok((out, shape))
}

/// The position of element `flat` of a C-ordered array of `shape`, as numpy
/// prints an index: `[2, 0]`, or nothing for a 0-d array.
pub fn position(mut flat: usize, shape: &[usize]) -> String {
    if shape.is_empty() {
        return String::new();
    }
    let mut index = vec![0; shape.len()];
    for (i, &n) in shape.iter().enumerate().rev() {
        if n > 0 {
            index[i] = flat % n;
            flat /= n;
        }
    }
    let parts: Vec<String> = index.iter().map(|i| i.to_string()).collect();
    format!("[{}]", parts.join(", "))
}

/// A Python integer (int, numpy integers: anything with `__index__`) in
/// `range`: `TypeError` for anything else (a float included), `ValueError`
/// naming the range for an integer outside it, however large (never an
/// `OverflowError`).
pub fn integer_in(
    obj: &Bound<'_, PyAny>,
    what: &str,
    range: RangeInclusive<i128>,
) -> PyResult<i128> {
    let py = obj.py();
    let index = py
        .import("operator")?
        .getattr("index")?
        .call1((obj,))
        .map_err(|_| {
            let type_name = obj
                .get_type()
                .name()
                .map_or_else(|_| "?".to_string(), |n| n.to_string());
            wrong_type(what, format!("expected an integer, got {type_name}"))
        })?;
    let value = index.extract::<i128>().ok().filter(|v| range.contains(v));
    value.ok_or_else(|| {
        invalid(
            what,
            format!(
                "must be between {} and {}, got {}",
                range.start(),
                range.end(),
                index
                    .str()
                    .map_or_else(|_| "?".to_string(), |s| s.to_string())
            ),
        )
    })
}

/// A real number (an int, a float, a numpy scalar): `TypeError` for
/// anything else (a bool, a string), `ValueError` for an int beyond f64.
pub fn real(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<f64> {
    let repr = || {
        obj.repr()
            .map_or_else(|_| "?".to_string(), |r| r.to_string())
    };
    if obj.is_instance_of::<PyBool>() {
        return Err(wrong_type(
            what,
            format!("expected a number, got {}", repr()),
        ));
    }
    obj.extract::<f64>().map_err(|e| {
        if e.is_instance_of::<PyOverflowError>(obj.py()) {
            invalid(what, format!("{} is beyond the range of a float", repr()))
        } else {
            wrong_type(what, format!("expected a number, got {}", repr()))
        }
    })
}

/// A count or size: an integer from 0 to `usize::MAX`.
pub fn count(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<usize> {
    Ok(integer_in(obj, what, 0..=usize::MAX as i128)? as usize)
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
