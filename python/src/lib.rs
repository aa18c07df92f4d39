//! The `irid` Python module: the thin-film solver, colours and lookup tables
//! of the `irid` crate on numpy arrays.
//!
//! Every entry point converts its arguments while holding the GIL, then
//! releases it for the computation, which runs on rayon's threads
//! (`RAYON_NUM_THREADS` sets how many). Errors are the crate's own one-line
//! messages, the text the CLI prints after `irid: `, raised as `ValueError`
//! (bad input, malformed file) or `OSError` (a file that cannot be read or
//! written).

mod arrays;
mod coherent;
mod lut;
mod response;
mod stack;

use pyo3::exceptions::{PyFileNotFoundError, PyOSError, PyPermissionError, PyValueError};
use pyo3::prelude::*;

/// The Python exception for a library error, carrying its one-line message.
pub(crate) fn py_error(e: irid::Error) -> PyErr {
    let message = e.to_string();
    match &e {
        irid::Error::Io { source, .. } => match source.kind() {
            std::io::ErrorKind::NotFound => PyFileNotFoundError::new_err(message),
            std::io::ErrorKind::PermissionDenied => PyPermissionError::new_err(message),
            _ => PyOSError::new_err(message),
        },
        _ => PyValueError::new_err(message),
    }
}

/// A `ValueError` in the library's `what: why` form.
pub(crate) fn invalid(what: impl Into<String>, why: impl Into<String>) -> PyErr {
    py_error(irid::Error::invalid(what, why))
}

#[pymodule]
fn _irid(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add_function(wrap_pyfunction!(coherent::coherent, m)?)?;
    m.add_function(wrap_pyfunction!(stack::material, m)?)?;
    m.add_function(wrap_pyfunction!(stack::materials, m)?)?;
    m.add_function(wrap_pyfunction!(lut::bake, m)?)?;
    m.add_class::<stack::PyMaterial>()?;
    m.add_class::<stack::PyStack>()?;
    m.add_class::<lut::PyLut>()?;
    Ok(())
}
