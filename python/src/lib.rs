//! The `irid` Python module: the thin-film solver, colours and lookup tables
//! of the `irid` crate on numpy arrays.
//!
//! Every entry point converts its arguments while holding the GIL, checks
//! what it will allocate against the memory budget ([`budget`]), then
//! releases the GIL for the computation, which runs on the package's own
//! thread pool ([`pool`]: `RAYON_NUM_THREADS` sets its size; it is rebuilt
//! in a forked child).
//!
//! Errors carry the crate's own one-line messages, the text the CLI prints
//! after `irid: `, and follow one rule (docs/python.md, "Errors"):
//! `TypeError` for an argument of a type its parameter never takes,
//! `ValueError` for a value or content irid refuses, `OSError` (the subclass
//! the system's error names) when a file cannot be opened, read or written,
//! `MemoryError` above the memory budget.

mod arrays;
mod budget;
mod coherent;
mod fit;
mod gradient;
mod incoherent;
mod lut;
mod pool;
mod response;
mod rough_lut;
mod stack;

use std::io::ErrorKind;

use pyo3::exceptions::{
    PyFileExistsError, PyFileNotFoundError, PyInterruptedError, PyIsADirectoryError,
    PyKeyboardInterrupt, PyMemoryError, PyNotADirectoryError, PyOSError, PyPermissionError,
    PyTypeError, PyValueError,
};
use pyo3::prelude::*;

/// The Python exception for a library error, carrying its one-line message.
pub(crate) fn py_error(e: irid::Error) -> PyErr {
    let message = e.to_string();
    match &e {
        irid::Error::Io { source, .. } => {
            let error = match source.kind() {
                ErrorKind::NotFound => PyFileNotFoundError::new_err(message),
                ErrorKind::PermissionDenied => PyPermissionError::new_err(message),
                ErrorKind::AlreadyExists => PyFileExistsError::new_err(message),
                ErrorKind::IsADirectory => PyIsADirectoryError::new_err(message),
                ErrorKind::NotADirectory => PyNotADirectoryError::new_err(message),
                ErrorKind::Interrupted => PyInterruptedError::new_err(message),
                _ => PyOSError::new_err(message),
            };
            if let Some(errno) = source.raw_os_error() {
                // As Python's own OSError: `e.errno` is the system's number
                // (str(e) stays the one-line message).
                Python::with_gil(|py| {
                    let _ = error.value(py).setattr("errno", errno);
                });
            }
            error
        }
        irid::Error::OverBudget { .. } => PyMemoryError::new_err(message),
        // Only an interrupted call sets its flag, and it raises the
        // interrupt itself; this is for a flag set some other way.
        irid::Error::Cancelled => PyKeyboardInterrupt::new_err(message),
        _ => PyValueError::new_err(message),
    }
}

/// A `ValueError` in the library's `what: why` form.
pub(crate) fn invalid(what: impl Into<String>, why: impl Into<String>) -> PyErr {
    py_error(irid::Error::invalid(what, why))
}

/// A `TypeError` in the same `what: why` form: an argument of a type its
/// parameter never takes.
pub(crate) fn wrong_type(what: impl AsRef<str>, why: impl AsRef<str>) -> PyErr {
    PyTypeError::new_err(format!("{}: {}", what.as_ref(), why.as_ref()))
}

#[pymodule]
fn _irid(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add_function(wrap_pyfunction!(coherent::coherent, m)?)?;
    m.add_function(wrap_pyfunction!(incoherent::incoherent, m)?)?;
    m.add_function(wrap_pyfunction!(stack::material, m)?)?;
    m.add_function(wrap_pyfunction!(stack::materials, m)?)?;
    m.add_function(wrap_pyfunction!(lut::bake, m)?)?;
    m.add_function(wrap_pyfunction!(fit::fit, m)?)?;
    m.add_function(wrap_pyfunction!(fit::fit_color, m)?)?;
    m.add_class::<stack::PyMaterial>()?;
    m.add_class::<stack::PyStack>()?;
    m.add_class::<lut::PyLut>()?;
    m.add_class::<rough_lut::PyRoughLut>()?;
    Ok(())
}
