//! `irid.coherent`: the drop-in for tmm-faster's `calc_coherent`.

use num_complex::Complex64 as C64;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use rayon::prelude::*;

use irid::optics::{
    solve_incoherent, Coherence, Material, Response, StackGrid, MAX_THICKNESS_NM,
    WAVELENGTH_RANGE_NM,
};

use crate::arrays::{array, planned_len, real_list, values};
use crate::budget::{filled, room_for, Footprint};
use crate::invalid;
use crate::pool::{compute_cancellable, Cancel};

/// Checks everything the solver relies on, naming the entry at fault in
/// tmm-faster's terms (`n[i, j]`: wavelength i, medium j; `d[j]`).
fn check(
    indices: &[C64],
    media: usize,
    d: &[f64],
    angles_deg: &[f64],
    wavelengths_nm: &[f64],
) -> PyResult<()> {
    if media < 2 {
        return Err(invalid(
            "n",
            format!("needs at least 2 media (ambient and substrate), got {media}"),
        ));
    }
    if d.len() != media {
        return Err(invalid(
            "d",
            format!(
                "n has {media} media per wavelength but d has {} entries",
                d.len()
            ),
        ));
    }
    // tmm-faster ignores these two entries, and its examples write 0 there.
    let half_space = |t: f64| t == f64::INFINITY || t == 0.0;
    if !half_space(d[0]) || !half_space(d[media - 1]) {
        return Err(invalid(
            "d",
            format!(
                "the first and last entries (ambient and substrate) must be inf (or 0), got {} and {}",
                d[0],
                d[media - 1]
            ),
        ));
    }
    for (j, &t) in d.iter().enumerate().take(media - 1).skip(1) {
        if !(0.0..=MAX_THICKNESS_NM).contains(&t) {
            return Err(invalid(
                format!("d[{j}]"),
                format!(
                    "a layer thickness must be finite, ≥ 0 and ≤ {MAX_THICKNESS_NM:e} nm, got {t}"
                ),
            ));
        }
    }
    if let Some(a) = angles_deg.iter().find(|a| !(0.0..=90.0).contains(*a)) {
        return Err(invalid("angles", format!("{a} is outside [0, 90] degrees")));
    }
    check_wavelengths(wavelengths_nm, "wavelengths")?;
    for (i, row) in indices.chunks_exact(media).enumerate() {
        for (j, z) in row.iter().enumerate() {
            Material::constant(z.re, z.im)
                .check()
                .map_err(|e| invalid(format!("n[{i}, {j}]"), e.to_string()))?;
        }
        if row[0].im != 0.0 {
            return Err(invalid(
                format!("n[{i}, 0]"),
                format!(
                    "the ambient must be lossless (imaginary part 0), got {}",
                    row[0]
                ),
            ));
        }
        if row[media - 1].im < 0.0 {
            return Err(invalid(
                format!("n[{i}, {}]", media - 1),
                format!(
                    "gain (imaginary part < 0) is only allowed in finite layers, not in the substrate, got {}",
                    row[media - 1]
                ),
            ));
        }
    }
    Ok(())
}

/// Every wavelength (nm) lies in the library's range (NaN does not).
pub fn check_wavelengths(wavelengths_nm: &[f64], what: &str) -> PyResult<()> {
    let (lo, hi) = WAVELENGTH_RANGE_NM;
    match wavelengths_nm.iter().find(|w| !(lo..=hi).contains(*w)) {
        Some(w) => Err(invalid(what, format!("{w} nm is outside {lo:e}–{hi:e} nm"))),
        None => Ok(()),
    }
}

/// cos θ of an angle in degrees, exactly 0 at 90° (grazing incidence, where
/// no power enters the stack) rather than cos(π/2) ≈ 6e-17.
fn cos_deg(angle_deg: f64) -> f64 {
    if angle_deg == 90.0 {
        0.0
    } else {
        angle_deg.to_radians().cos()
    }
}

/// The six results of [`solve_grid`], in the order of their keys.
const KEYS: [&str; 6] = ["R_s", "R_p", "T_s", "T_p", "R_avg", "T_avg"];

/// Solves every (wavelength, angle) pair into one buffer laid out
/// [angle][key][wavelength] (keys as [`KEYS`]), so that each key is a
/// strided (wavelengths, angles) view of it and nothing is transposed.
/// Each task solves one angle over a run of wavelengths through
/// `StackGrid::solve_spectrum` (eight or four wavelengths per vector; a run
/// whose indices do not change with wavelength takes the non-dispersive
/// kernel). With `parallel`, the tasks run on the current thread pool, and
/// the wavelengths are cut into runs when there are too few angles to keep
/// every thread busy, or when a run would take longer than a signal may
/// wait ([`MAX_RUN`]); without, on the calling thread, one run per angle.
/// The tasks stop once `cancel` is set (what they leave is discarded).
/// `out` is the buffer, one value per (angle, key, wavelength), allocated
/// by the caller so that a refusal is a `MemoryError`.
#[allow(clippy::too_many_arguments)]
pub fn solve_grid(
    indices: &[C64],
    thicknesses_nm: &[f64],
    coherence: &Coherence,
    wavelengths_nm: &[f64],
    cos_theta0: &[f64],
    parallel: bool,
    cancel: &Cancel,
    mut out: Vec<f64>,
) -> Vec<f64> {
    let media = thicknesses_nm.len() + 2;
    let (n_w, n_a) = (wavelengths_nm.len(), cos_theta0.len());
    debug_assert_eq!(out.len(), n_a * KEYS.len() * n_w);
    if out.is_empty() {
        return out;
    }
    let runs = if parallel {
        let tasks_wanted = 4 * rayon::current_num_threads();
        tasks_wanted
            .div_ceil(n_a)
            .clamp(1, n_w.div_ceil(MIN_RUN))
            .max(n_w.div_ceil(MAX_RUN))
    } else {
        1
    };
    let run_len = n_w.div_ceil(runs);
    let grids: Vec<StackGrid> = (0..n_w)
        .step_by(run_len)
        .map(|start| {
            let end = (start + run_len).min(n_w);
            StackGrid::from_indices(
                indices[start * media..end * media].to_vec(),
                thicknesses_nm.to_vec(),
                &wavelengths_nm[start..end],
            )
            .with_coherence(coherence.clone())
        })
        .collect();
    // One task per (angle, run): the run's slice of each key's row.
    let mut tasks = Vec::with_capacity(n_a * grids.len());
    for (block, &cos) in out.chunks_mut(KEYS.len() * n_w).zip(cos_theta0) {
        let mut rows: Vec<_> = block
            .chunks_mut(n_w)
            .map(|r| r.chunks_mut(run_len))
            .collect();
        for grid in &grids {
            let slices: [&mut [f64]; 6] = std::array::from_fn(|k| rows[k].next().unwrap());
            tasks.push((cos, grid, slices));
        }
    }
    let solve_task =
        |spectrum: &mut Vec<Response>,
         (cos, grid, [rs, rp, ts, tp, r, t]): (f64, &StackGrid, [&mut [f64]; 6])| {
            if cancel.is_set() {
                return;
            }
            spectrum.clear();
            spectrum.resize(grid.wavelengths_nm().len(), Response::default());
            grid.solve_spectrum(thicknesses_nm, cos, spectrum);
            for (w, x) in spectrum.iter().enumerate() {
                rs[w] = x.rs;
                rp[w] = x.rp;
                ts[w] = x.ts;
                tp[w] = x.tp;
                r[w] = x.r();
                t[w] = x.t();
            }
        };
    if parallel {
        tasks
            .into_par_iter()
            .for_each_init(|| Vec::with_capacity(run_len), solve_task);
    } else {
        let mut spectrum = Vec::with_capacity(run_len);
        for task in tasks {
            solve_task(&mut spectrum, task);
        }
    }
    out
}

/// Fewest points of a `coherent` call that go to the thread pool: below,
/// the solve (about 10 ns a point) takes less than the handoff.
const PARALLEL_MIN_POINTS: usize = 4096;

/// What `coherent` allocates beyond its converted arguments: the indices
/// (a 1-D n repeated per wavelength, each run's copy, the grid's lane
/// layout of n and n², 64 bytes per wavelength and medium in all), each
/// wavelength's k0 and copy, and per angle cos θ and its tasks; the result
/// (six f64 per point).
fn grid_footprint(wavelengths: usize, angles: usize, media: usize) -> Footprint {
    Footprint::new()
        .items(&[wavelengths, media], 64)
        .items(&[wavelengths], 16)
        .items(&[angles], 8 + 256)
        .items(&[angles, KEYS.len(), wavelengths], 8)
}

/// Fewest wavelengths in a run of [`solve_grid`]: enough groups of four to
/// amortize laying the run's indices out.
const MIN_RUN: usize = 64;

/// Most wavelengths in a run of [`solve_grid`]: a few milliseconds of work
/// between two looks at the cancel flag, however few the angles.
const MAX_RUN: usize = 1 << 16;

/// R and T of a coherent multilayer at every wavelength and angle, with the
/// arguments and result of tmm-faster's `calc_coherent`.
///
/// n: complex indices n + ik (k > 0 absorbs, k < 0 is gain), shape
/// (wavelengths, media), ambient first; a 1-D n is the same at every
/// wavelength. d: thicknesses in nm, inf (or 0, as tmm-faster's examples
/// write it) for the ambient and the substrate.
/// angles: incidence in the ambient, degrees in [0, 90]. wavelengths: vacuum
/// wavelengths in nm.
///
/// Returns a dict of float64 arrays of shape (wavelengths, angles): R_s, R_p,
/// T_s, T_p, R_avg, T_avg (the unpolarized means). T is the power flux into
/// the substrate, Re(n cos θ) for s and Re(n conj(cos θ)) for p over the
/// incident flux, as in Byrnes' tmm: right for absorbing substrates too.
#[pyfunction]
#[pyo3(signature = (n, d, angles, wavelengths))]
pub fn coherent<'py>(
    py: Python<'py>,
    n: &Bound<'py, PyAny>,
    d: &Bound<'py, PyAny>,
    angles: &Bound<'py, PyAny>,
    wavelengths: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyDict>> {
    Grid::new(n, d, angles, wavelengths)?.solve(py, &Coherence::coherent())
}

/// [`grid_footprint`] and the arguments' copies, from their sizes as given
/// (numpy's arrays, lists: [`planned_len`]) before any is converted, so
/// that a call far above the budget is refused before it copies gigabytes.
/// The media are counted from `d`, which has one entry per medium.
fn planned_footprint(
    n: &Bound<'_, PyAny>,
    d: &Bound<'_, PyAny>,
    angles: &Bound<'_, PyAny>,
    wavelengths: &Bound<'_, PyAny>,
) -> PyResult<()> {
    let [Some(w), Some(a), Some(media)] = [wavelengths, angles, d].map(planned_len) else {
        return Ok(());
    };
    let indices = planned_len(n).unwrap_or(0);
    grid_footprint(w, a, media)
        .items(&[w + a + media], 8)
        .items(&[indices], 16)
        .check(&format!("{w} wavelengths × {a} angles × {media} media"))
}

/// A wavelength × angle grid of one stack as tmm-faster's functions take
/// it, converted and checked.
pub struct Grid {
    pub indices: Vec<C64>,
    pub media: usize,
    d: Vec<f64>,
    angles_deg: Vec<f64>,
    wavelengths_nm: Vec<f64>,
}

impl Grid {
    /// `n`, `d`, `angles` and `wavelengths` as [`coherent`] takes them,
    /// checked against the memory budget before anything is allocated.
    pub fn new(
        n: &Bound<'_, PyAny>,
        d: &Bound<'_, PyAny>,
        angles: &Bound<'_, PyAny>,
        wavelengths: &Bound<'_, PyAny>,
    ) -> PyResult<Grid> {
        planned_footprint(n, d, angles, wavelengths)?;
        let wavelengths_nm = real_list(wavelengths, "wavelengths")?;
        let angles_deg = real_list(angles, "angles")?;
        let d = real_list(d, "d")?;
        let (mut indices, shape) = values::<C64>(n, "complex128", "n")?;
        let media = match shape.as_slice() {
            [m] => *m,
            [w, m] if *w == wavelengths_nm.len() => *m,
            _ => {
                return Err(invalid(
                    "n",
                    format!(
                        "expected shape (wavelengths, media) = ({}, {}), got {shape:?}",
                        wavelengths_nm.len(),
                        d.len()
                    ),
                ))
            }
        };
        grid_footprint(wavelengths_nm.len(), angles_deg.len(), media).check(&format!(
            "{} wavelengths × {} angles × {media} media",
            wavelengths_nm.len(),
            angles_deg.len()
        ))?;
        if shape.len() == 1 {
            // One set of media for every wavelength.
            let mut repeated = room_for(indices.len() * wavelengths_nm.len(), "n")?;
            for _ in 0..wavelengths_nm.len() {
                repeated.extend_from_slice(&indices);
            }
            indices = repeated;
        }
        check(&indices, media, &d, &angles_deg, &wavelengths_nm)?;
        Ok(Grid {
            indices,
            media,
            d,
            angles_deg,
            wavelengths_nm,
        })
    }

    /// R and T at every point as tmm-faster returns them, the layers
    /// coherent or not as `coherence` says. A point where an incoherent
    /// layer lases is a `ValueError` naming it (`n[i, j]`: wavelength i,
    /// medium j).
    pub fn solve<'py>(
        &self,
        py: Python<'py>,
        coherence: &Coherence,
    ) -> PyResult<Bound<'py, PyDict>> {
        let (n_w, n_a) = (self.wavelengths_nm.len(), self.angles_deg.len());
        let thicknesses_nm = &self.d[1..self.media - 1];
        let cos_theta0: Vec<f64> = self.angles_deg.iter().map(|&a| cos_deg(a)).collect();
        let parallel = n_w * n_a >= PARALLEL_MIN_POINTS;
        let out = filled(n_a * KEYS.len() * n_w, 0.0, "the result")?;
        let solve = |cancel: &Cancel| {
            solve_grid(
                &self.indices,
                thicknesses_nm,
                coherence,
                &self.wavelengths_nm,
                &cos_theta0,
                parallel,
                cancel,
                out,
            )
        };
        let values = compute_cancellable(py, parallel, solve)?;
        if let Some(k) = values.iter().position(|v| !v.is_finite()) {
            let (a, w) = (k / (KEYS.len() * n_w), k % n_w);
            let row = &self.indices[w * self.media..(w + 1) * self.media];
            if let Err(diverged) = solve_incoherent(
                row,
                thicknesses_nm,
                coherence,
                self.wavelengths_nm[w],
                cos_theta0[a],
            ) {
                return Err(invalid(
                    format!("n[{w}, {}]", diverged.layer),
                    diverged.reason(self.wavelengths_nm[w], cos_theta0[a]),
                ));
            }
        }
        // One (angles, keys, wavelengths) array; each key is its (wavelengths,
        // angles) transposed slice, a view with no copy.
        let all = array(py, values, &[n_a, KEYS.len(), n_w])?;
        let result = PyDict::new(py);
        for (k, key) in KEYS.into_iter().enumerate() {
            let view = all
                .as_any()
                .get_item((pyo3::types::PySlice::full(py), k))?
                .getattr("T")?;
            result.set_item(key, view)?;
        }
        Ok(result)
    }
}
