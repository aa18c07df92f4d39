//! Conversions between Python values and the flat vectors the library takes.
//!
//! Every array argument is measured before it is copied (a stride-0 view of
//! 10^13 elements costs nothing until it is made contiguous), and the
//! exception keeps numpy's verdict: `TypeError` for something that is not
//! numbers at all (`None`, an object), `ValueError` for numbers that are
//! wrong (a ragged list, a string that does not parse, an int beyond f64),
//! each naming the argument.

use std::ops::RangeInclusive;

use numpy::{Element, PyArray1, PyArrayDyn, PyArrayMethods, PyUntypedArray, PyUntypedArrayMethods};
use pyo3::exceptions::{PyMemoryError, PyOverflowError, PyTypeError};
use pyo3::prelude::*;
use pyo3::types::{IntoPyDict, PyBool, PyFloat, PyInt, PyList, PyTuple};

use crate::budget::{room_for, Footprint};
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

/// The values of `obj` (a number, a list, an array of any shape: anything
/// numpy turns into an array of `dtype`) in C order, with its shape. The
/// copies are checked against the memory budget before they are made.
pub fn values<'py, T: Element + Clone>(
    obj: &Bound<'py, PyAny>,
    dtype: &str,
    what: &str,
) -> PyResult<(Vec<T>, Vec<usize>)> {
    let item_bytes = std::mem::size_of::<T>() as u64;
    let measure = |size: usize, copies: usize| {
        Footprint::new()
            .items(&[size, copies], item_bytes)
            .check(&format!("{what}: {size} values"))
    };
    // An array of the dtype already (the usual case, and a stride-0 view's
    // only cheap form): read in place, in C order.
    if let Ok(array) = obj.downcast::<PyArrayDyn<T>>() {
        let array = array
            .try_readonly()
            .map_err(|e| invalid(what, format!("cannot be read ({e})")))?;
        measure(array.len(), 1)?;
        let shape = array.shape().to_vec();
        // as_slice is memory order, which a Fortran-ordered array does not
        // share with C order.
        let mut values = room_for(array.len(), what)?;
        match array.as_slice() {
            Ok(contiguous) if array.is_c_contiguous() => values.extend_from_slice(contiguous),
            _ => values.extend(array.as_array().iter().cloned()),
        }
        return Ok((values, shape));
    }
    if obj.is_none() {
        // numpy would make it NaN.
        return Err(wrong_type(what, "expected numbers, got None"));
    }
    let py = obj.py();
    let np = py.import("numpy")?;
    let not_numbers = "not an array of numbers";
    let as_dtype = |obj: &Bound<'py, PyAny>| -> PyResult<Bound<'py, PyAny>> {
        np.getattr("asarray")?
            .call((obj,), Some(&[("dtype", dtype)].into_py_dict(py)?))
            .map_err(|e| conversion_error(py, e, what, not_numbers))
    };
    let converted = if obj.is_instance_of::<PyList>() || obj.is_instance_of::<PyTuple>() {
        // The list's own objects take more memory than its array will.
        as_dtype(obj)?
    } else {
        // Measured before numpy copies it: an array of another dtype (a
        // stride-0 view of one included), or an object numpy converts.
        let as_is = np
            .getattr("asarray")?
            .call1((obj,))
            .map_err(|e| conversion_error(py, e, what, not_numbers))?;
        measure(as_is.getattr("size")?.extract()?, 2)?;
        as_dtype(&as_is)?
    };
    let array = converted.downcast::<PyArrayDyn<T>>()?.readonly();
    measure(array.len(), 1)?;
    let mut values = room_for(array.len(), what)?;
    values.extend(array.as_array().iter().cloned());
    Ok((values, array.shape().to_vec()))
}

/// How many values converting `obj` gives, read without copying anything:
/// an array's size, a number's 1, a list's or tuple's length (its rows, for
/// a nested one: the list itself holds more memory than that). None for
/// anything else, which the conversion measures itself. An entry point
/// checks its whole footprint with these counts before it converts any
/// argument, so that a huge argument is refused before it is copied.
pub fn planned_len(obj: &Bound<'_, PyAny>) -> Option<usize> {
    if let Ok(array) = obj.downcast::<PyUntypedArray>() {
        return Some(array.len());
    }
    if obj.is_instance_of::<PyFloat>() || obj.is_instance_of::<PyInt>() {
        return Some(1);
    }
    if obj.is_instance_of::<PyList>() || obj.is_instance_of::<PyTuple>() {
        return obj.len().ok();
    }
    None
}

/// Real values of `obj` as a flat list, with its shape.
pub fn reals(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<(Vec<f64>, Vec<usize>)> {
    if let Ok(x) = obj.downcast_exact::<PyFloat>() {
        return Ok((vec![x.value()], Vec::new()));
    }
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
/// with the broadcast shape. The expanded copies, and the caller's
/// `output_bytes_per_point` at every broadcast point, are checked against
/// the memory budget (as `what`) before anything of the broadcast size is
/// allocated.
pub fn broadcast_reals(
    named: &[(&Bound<'_, PyAny>, &str)],
    what: &str,
    output_bytes_per_point: u64,
) -> PyResult<(Vec<Vec<f64>>, Vec<usize>)> {
    let arrays = named
        .iter()
        .map(|&(obj, name)| reals(obj, name))
        .collect::<PyResult<Vec<_>>>()?;
    let shapes: Vec<&[usize]> = arrays.iter().map(|(_, s)| s.as_slice()).collect();
    let shape = broadcast_shape(&shapes).ok_or_else(|| {
        invalid(
            what,
            format!("the arrays do not broadcast together (shapes {shapes:?})"),
        )
    })?;
    let points = shape.iter().try_fold(1usize, |n, &s| n.checked_mul(s));
    Footprint::new()
        .items(
            &[points.unwrap_or(usize::MAX)],
            8 * named.len() as u64 + output_bytes_per_point,
        )
        .check(&format!("{what}: {shape:?} points"))?;
    let flat = arrays
        .into_iter()
        .map(|(values, s)| expand(values, &s, &shape))
        .collect();
    Ok((flat, shape))
}

/// numpy's broadcast of `shapes`: aligned at the last axis, each axis's
/// sizes equal or 1; None when they do not broadcast.
fn broadcast_shape(shapes: &[&[usize]]) -> Option<Vec<usize>> {
    let ndim = shapes.iter().map(|s| s.len()).max().unwrap_or(0);
    let mut out = vec![1; ndim];
    for shape in shapes {
        for (size, axis) in shape.iter().rev().zip(out.iter_mut().rev()) {
            match (*axis, *size) {
                (_, 1) => {}
                (1, n) => *axis = n,
                (a, n) if a == n => {}
                _ => return None,
            }
        }
    }
    Some(out)
}

/// `values` of `shape` repeated along the axes it broadcasts over, to
/// `target` (a broadcast of `shape`), in C order.
fn expand(values: Vec<f64>, shape: &[usize], target: &[usize]) -> Vec<f64> {
    if shape == target {
        return values;
    }
    // Each target axis's step in `values`: 0 where it is broadcast.
    let mut steps = vec![0; target.len()];
    let mut step = 1;
    for (size, axis_step) in shape.iter().rev().zip(steps.iter_mut().rev()) {
        if *size != 1 {
            *axis_step = step;
        }
        step *= size;
    }
    let total: usize = target.iter().product();
    let mut out = Vec::with_capacity(total);
    let (mut index, mut at) = (vec![0; target.len()], 0);
    for _ in 0..total {
        out.push(values[at]);
        // The next index in C order, carrying into the axes before.
        for axis in (0..target.len()).rev() {
            index[axis] += 1;
            at += steps[axis];
            if index[axis] < target[axis] {
                break;
            }
            at -= steps[axis] * index[axis];
            index[axis] = 0;
        }
    }
    out
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
