//! `irid.incoherent`: the drop-in for tmm-faster's `calc_incoherent`.

use pyo3::prelude::*;
use pyo3::types::{PyDict, PyString};

use irid::optics::Coherence;

use crate::coherent::Grid;
use crate::{invalid, wrong_type};

/// The coherence list `c`, one 'c' (coherent) or 'i' (incoherent) per
/// medium of `media`, the ambient and substrate 'i' (they are incoherent
/// half-spaces, as Byrnes' `inc_tmm` requires).
fn coherence(c: &Bound<'_, PyAny>, media: usize) -> PyResult<Coherence> {
    let items = c
        .try_iter()
        .map_err(|_| wrong_type("c", "must be a sequence of 'c' and 'i', one per medium"))?;
    let mut flags = Vec::with_capacity(media);
    for (j, item) in items.enumerate() {
        let item = item?;
        let Ok(letter) = item.downcast::<PyString>() else {
            return Err(wrong_type(
                format!("c[{j}]"),
                format!("must be the string 'c' or 'i', got {}", item.repr()?),
            ));
        };
        flags.push(match letter.to_str()? {
            "c" => true,
            "i" => false,
            _ => {
                return Err(invalid(
                    format!("c[{j}]"),
                    format!(
                        "must be 'c' (coherent) or 'i' (incoherent), got {}",
                        item.repr()?
                    ),
                ))
            }
        });
        if flags.len() > media {
            break;
        }
    }
    if flags.len() != media {
        let count = c
            .len()
            .map_or_else(|_| flags.len().to_string(), |l| l.to_string());
        return Err(invalid(
            "c",
            format!(
                "has {count} entries but n has {media} media per wavelength (one letter per \
                 medium, the ambient and substrate included)"
            ),
        ));
    }
    for (j, what) in [(0, "ambient"), (media - 1, "substrate")] {
        if flags[j] {
            return Err(invalid(
                format!("c[{j}]"),
                format!("the {what} is an incoherent half-space: must be 'i', got 'c'"),
            ));
        }
    }
    Ok(Coherence::from_flags(flags[1..media - 1].iter().copied()))
}

/// R and T of a multilayer whose layers are coherent or incoherent, at every
/// wavelength and angle, with the arguments and result of tmm-faster's
/// `calc_incoherent` (Byrnes' `inc_tmm` formulation).
///
/// n, d, angles, wavelengths: as for `coherent`. c: one letter per medium,
/// 'c' for a coherent layer and 'i' for an incoherent one (thick: its inner
/// reflections add in power), the ambient and substrate 'i'; a list, tuple,
/// array or string of letters.
///
/// Returns a dict of float64 arrays of shape (wavelengths, angles): R_s,
/// R_p, T_s, T_p, R_avg, T_avg. A point where an incoherent layer lases (its
/// round trips gain power) raises ValueError naming it.
#[pyfunction]
#[pyo3(signature = (n, d, c, angles, wavelengths))]
pub fn incoherent<'py>(
    py: Python<'py>,
    n: &Bound<'py, PyAny>,
    d: &Bound<'py, PyAny>,
    c: &Bound<'py, PyAny>,
    angles: &Bound<'py, PyAny>,
    wavelengths: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyDict>> {
    let grid = Grid::new(n, d, angles, wavelengths)?;
    let coherence = coherence(c, grid.media)?;
    grid.solve(py, &coherence)
}
