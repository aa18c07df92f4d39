//! The memory check every entry point makes before it allocates.
//!
//! The convention (docs/python.md, "Memory"): an entry point whose
//! allocations grow with its input adds up what it will allocate, as items
//! times bytes per item, in a [`Footprint`], and calls
//! [`Footprint::check`] before allocating any of it. Everything is counted
//! with checked arithmetic (a product that overflows counts as too large), so
//! a request beyond the budget raises `MemoryError` in microseconds instead
//! of aborting the interpreter when the allocator fails. The budget is the
//! library's (`irid::limits`: `IRID_MEMORY_LIMIT`, else half the machine's
//! memory), the one the command line honours. Array arguments are checked
//! by `arrays` before they are copied.

use pyo3::exceptions::PyMemoryError;
use pyo3::prelude::*;

use crate::py_error;

/// What a call will allocate, in bytes; None once a figure overflows.
#[derive(Clone, Copy, Debug)]
#[must_use = "a footprint does nothing until it is checked"]
pub struct Footprint(Option<u64>);

impl Footprint {
    pub fn new() -> Self {
        Footprint(Some(0))
    }

    /// Adds the product of `counts` times `bytes_each`: for a buffer of
    /// shape (wavelengths, angles) of f64, `items(&[w, a], 8)`.
    pub fn items(self, counts: &[usize], bytes_each: u64) -> Self {
        let counts: Vec<u64> = counts.iter().map(|&c| c as u64).collect();
        let bytes = irid::limits::product(&counts, bytes_each);
        Footprint(self.0.zip(bytes).and_then(|(a, b)| a.checked_add(b)))
    }

    /// Raises `MemoryError` ("WHAT: needs about 48.0 GB, above the memory
    /// limit of 8.4 GB (set IRID_MEMORY_LIMIT to change it)") when the
    /// total is above the budget; `ValueError` when `IRID_MEMORY_LIMIT` is
    /// not a size.
    pub fn check(self, what: &str) -> PyResult<()> {
        irid::limits::check_allocation(what, self.0).map_err(py_error)
    }
}

/// An empty vector with room for `len` items, or `MemoryError` ("WHAT: the
/// system refused 7.2 GB") when the allocator cannot give it: under an
/// address-space limit (`ulimit -v`) the allocation can fail below the
/// budget, and Rust's allocation failure aborts the interpreter.
pub fn room_for<T>(len: usize, what: &str) -> PyResult<Vec<T>> {
    let mut v = Vec::new();
    v.try_reserve_exact(len).map_err(|_| {
        let bytes = (len as u64).saturating_mul(std::mem::size_of::<T>() as u64);
        PyMemoryError::new_err(format!(
            "{what}: the system refused {} of memory",
            irid::limits::human_bytes(bytes)
        ))
    })?;
    Ok(v)
}

/// `len` copies of `value` ([`room_for`]).
pub fn filled<T: Clone>(len: usize, value: T, what: &str) -> PyResult<Vec<T>> {
    let mut v = room_for(len, what)?;
    v.resize(len, value);
    Ok(v)
}
