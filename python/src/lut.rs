//! `irid.bake` and `irid.Lut`: lookup tables baked, saved, loaded, sampled
//! and validated.

use std::path::PathBuf;

use pyo3::prelude::*;
use pyo3::types::PyTuple;
use rayon::prelude::*;

use irid::color::Sampling;
use irid::lut::{validate, BakeSpec, Kind, Lut, Resolution, DEFAULT_COS_MIN, VALIDATION_SEED};

use crate::arrays::{array, broadcast_reals, json_to_py, real_list};
use crate::stack::{check_layer, PyStack};
use crate::{invalid, py_error};

/// The thickness range of `irid.bake` when none is given: interference
/// colours fade out within the first micrometre of a film.
const DEFAULT_THICKNESS_NM: (f64, f64) = (0.0, 1000.0);

/// A `(min, max)` pair from a number (both ends) or a two-element sequence.
fn range(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<(f64, f64)> {
    match real_list(obj, what)?.as_slice() {
        [x] => Ok((*x, *x)),
        [lo, hi] => Ok((*lo, *hi)),
        other => Err(invalid(
            what,
            format!(
                "expected a number or (min, max), got {} values",
                other.len()
            ),
        )),
    }
}

/// Bakes a lookup table of `stack` over the thickness of one layer and the
/// angle of incidence, as `irid bake` does.
///
/// thickness_nm: (min, max) in nm of layer `layer` (counted from 1 at the
/// ambient side), or one number for a single thickness; default (0, 1000).
/// max_error: the largest absolute error allowed in any channel (default
/// 1e-3 when no resolution is given); resolution: fixed node counts
/// (thickness, angle) or (thickness, angle, wavelength) instead.
/// cos_theta: (min, max) of cos θ in the ambient (default cos 89° to 1).
/// kind: "rgb" (linear sRGB under D65) or "spectral"; sampling: the rgb
/// kind's integration ("exact", "uniform:N", "rgb3"); wavelengths_nm: the
/// spectral kind's range. half: store f16. validation_points: random points
/// checked against the solver, recorded in the header (0: none). check:
/// with a fixed resolution, False skips the bake check.
#[pyfunction]
#[pyo3(signature = (
    stack, thickness_nm=None, layer=1, max_error=None, *, resolution=None, cos_theta=None,
    kind="rgb", sampling="exact", wavelengths_nm=None, half=false, validation_points=20_000,
    check=true
))]
#[allow(clippy::too_many_arguments)]
pub fn bake(
    py: Python<'_>,
    stack: &PyStack,
    thickness_nm: Option<&Bound<'_, PyAny>>,
    layer: usize,
    max_error: Option<f64>,
    resolution: Option<Vec<usize>>,
    cos_theta: Option<&Bound<'_, PyAny>>,
    kind: &str,
    sampling: &str,
    wavelengths_nm: Option<&Bound<'_, PyAny>>,
    half: bool,
    validation_points: usize,
    check: bool,
) -> PyResult<PyLut> {
    let mut spec = BakeSpec::new(stack.stack.clone());
    spec.layer = layer;
    if !spec.stack.layers.is_empty() {
        check_layer(&spec.stack, layer)?;
    }
    spec.thickness_nm = match thickness_nm {
        Some(t) => range(t, "thickness_nm")?,
        None => DEFAULT_THICKNESS_NM,
    };
    spec.cos_theta = match cos_theta {
        Some(c) => range(c, "cos_theta")?,
        None => (DEFAULT_COS_MIN, 1.0),
    };
    spec.kind = kind.parse::<Kind>().map_err(py_error)?;
    spec.sampling = sampling.parse::<Sampling>().map_err(py_error)?;
    if let Some(w) = wavelengths_nm {
        spec.wavelength_nm = range(w, "wavelengths_nm")?;
    }
    spec.half = half;
    spec.validation_points = validation_points;
    spec.check = check;
    spec.resolution = match (resolution, max_error) {
        (Some(_), Some(_)) => {
            return Err(invalid(
                "resolution",
                "give either resolution or max_error, not both",
            ))
        }
        (Some(r), None) => match r.as_slice() {
            [t, a] => Resolution::Nodes {
                thickness: *t,
                angle: *a,
                wavelength: 1,
            },
            [t, a, w] => Resolution::Nodes {
                thickness: *t,
                angle: *a,
                wavelength: *w,
            },
            _ => {
                return Err(invalid(
                    "resolution",
                    "expected (thickness, angle) or (thickness, angle, wavelength) node counts",
                ))
            }
        },
        (None, e) => Resolution::MaxError(e.unwrap_or(1e-3)),
    };
    spec.validate().map_err(py_error)?;
    let lut = py
        .allow_threads(|| {
            let mut lut = irid::lut::bake(&spec)?;
            if lut.header().error.validation.is_none() && spec.validation_points > 0 {
                let stats = validate(&lut, spec.validation_points, VALIDATION_SEED)?;
                lut.set_validation(stats);
            }
            Ok(lut)
        })
        .map_err(py_error)?;
    Ok(PyLut { lut })
}

/// A lookup table of a stack's response over a layer's thickness and cos θ
/// (and wavelength, for the spectral kind), as written by `irid bake`.
#[pyclass(name = "Lut", module = "irid", frozen)]
pub struct PyLut {
    lut: Lut,
}

#[pymethods]
impl PyLut {
    /// Reads and checks a table (OpenEXR with irid's JSON header).
    #[staticmethod]
    fn load(py: Python<'_>, path: PathBuf) -> PyResult<Self> {
        let lut = py.allow_threads(|| Lut::load(&path)).map_err(py_error)?;
        Ok(PyLut { lut })
    }

    /// Writes the table atomically (a partial file is never left behind).
    fn save(&self, py: Python<'_>, path: PathBuf) -> PyResult<()> {
        py.allow_threads(|| self.lut.write(&path)).map_err(py_error)
    }

    /// The JSON header (axes, channels, stack, colour, error figures) as a dict.
    #[getter]
    fn header<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        json_to_py(py, self.lut.header())
    }

    /// "rgb" or "spectral".
    #[getter]
    fn kind(&self) -> String {
        self.lut.kind().to_string()
    }

    /// The stored values (float32), thickness fastest: rgb tables
    /// (cos θ, thickness, 6) with R r, g, b then T r, g, b; spectral tables
    /// (wavelength, cos θ, thickness, 2) with R, T. The node positions are
    /// in header["axes"].
    #[getter]
    fn data<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let sizes: Vec<usize> = self
            .lut
            .header()
            .axes
            .iter()
            .rev()
            .map(|a| a.nodes.len())
            .collect();
        let channels = if self.lut.kind() == Kind::Rgb { 6 } else { 2 };
        let mut shape = sizes;
        shape.push(channels);
        Ok(array(py, self.lut.data().to_vec(), &shape)?.into_any())
    }

    /// The table's R and T at each (thickness nm, cos θ) point, interpolated
    /// as a renderer does (outside the axes, clamped to the ends).
    ///
    /// The arguments broadcast together (numpy rules). An rgb table returns
    /// (R, T), each float32 of shape broadcast + (3,): linear sRGB. A
    /// spectral table needs wavelength_nm too and returns (R, T) of the
    /// broadcast shape.
    #[pyo3(signature = (thickness_nm, cos_theta, wavelength_nm=None))]
    fn sample<'py>(
        &self,
        py: Python<'py>,
        thickness_nm: &Bound<'py, PyAny>,
        cos_theta: &Bound<'py, PyAny>,
        wavelength_nm: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyTuple>> {
        let lut = &self.lut;
        match (lut.kind(), wavelength_nm) {
            (Kind::Rgb, None) => {
                let (v, shape) = broadcast_reals(&[thickness_nm, cos_theta], "sample")?;
                let (t, c) = (&v[0], &v[1]);
                let (r, tr) = py.allow_threads(|| {
                    let mut r = vec![0f32; 3 * t.len()];
                    let mut tr = vec![0f32; 3 * t.len()];
                    r.par_chunks_mut(3)
                        .zip(tr.par_chunks_mut(3))
                        .zip(t.par_iter().zip(c.par_iter()))
                        .with_min_len(4096)
                        .for_each(|((r, tr), (&t, &c))| {
                            let film = lut.sample_rgb(t as f32, c as f32);
                            r.copy_from_slice(&film.reflectance);
                            tr.copy_from_slice(&film.transmittance);
                        });
                    (r, tr)
                });
                let mut shape3 = shape;
                shape3.push(3);
                PyTuple::new(py, [array(py, r, &shape3)?, array(py, tr, &shape3)?])
            }
            (Kind::Spectral, Some(w)) => {
                let (v, shape) = broadcast_reals(&[thickness_nm, cos_theta, w], "sample")?;
                let (t, c, w) = (&v[0], &v[1], &v[2]);
                let (r, tr): (Vec<f32>, Vec<f32>) = py.allow_threads(|| {
                    t.par_iter()
                        .zip(c.par_iter())
                        .zip(w.par_iter())
                        .with_min_len(4096)
                        .map(|((&t, &c), &w)| lut.sample_spectral(t as f32, c as f32, w as f32))
                        .unzip()
                });
                PyTuple::new(py, [array(py, r, &shape)?, array(py, tr, &shape)?])
            }
            (Kind::Rgb, Some(_)) => Err(invalid(
                "wavelength_nm",
                "an rgb table has no wavelength axis",
            )),
            (Kind::Spectral, None) => Err(invalid(
                "wavelength_nm",
                "a spectral table needs the wavelength of each point",
            )),
        }
    }

    /// Compares the table with the solver at `points` random points (a
    /// PCG64 stream seeded with `seed`), as `irid validate --json`: a dict
    /// of per-channel max/mean/p99 absolute errors, CIEDE2000, the worst
    /// point and the hard regions.
    #[pyo3(signature = (points=20_000, seed=VALIDATION_SEED))]
    fn validate<'py>(
        &self,
        py: Python<'py>,
        points: usize,
        seed: u64,
    ) -> PyResult<Bound<'py, PyAny>> {
        let stats = py
            .allow_threads(|| validate(&self.lut, points, seed))
            .map_err(py_error)?;
        json_to_py(py, &stats)
    }

    fn __repr__(&self) -> String {
        let h = self.lut.header();
        let sizes: Vec<String> = h
            .axes
            .iter()
            .map(|a| format!("{} {}", a.nodes.len(), a.name))
            .collect();
        format!("irid.Lut({}, {})", h.kind, sizes.join(" × "))
    }
}
