//! `irid.bake` and `irid.Lut`: lookup tables baked, saved, loaded, sampled
//! and validated.

use std::path::PathBuf;

use pyo3::prelude::*;
use pyo3::types::{PyString, PyTuple};
use rayon::prelude::*;

use irid::color::Sampling;
use irid::lut::{
    validate, BakeSpec, Kind, Layout, Lut, Resolution, DEFAULT_COS_MIN, VALIDATION_SEED,
};

use crate::arrays::{array, broadcast_reals, count, integer_in, json_to_py, position, real_list};
use crate::budget::Footprint;
use crate::pool::{compute, compute_cancellable, Cancel};
use crate::stack::{layer_number, PyStack};
use crate::{invalid, py_error, wrong_type};

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
/// instead, (thickness, angle) for an rgb table, (thickness, angle,
/// wavelength) for a spectral one.
/// cos_theta: (min, max) of cos θ in the ambient (default cos 89° to 1).
/// kind: "rgb" (linear sRGB under D65) or "spectral"; sampling: the rgb
/// kind's integration ("exact", "uniform:N", "rgb3"); wavelengths_nm: the
/// spectral kind's range (an rgb table refuses it). half: store f16.
/// validation_points: random points checked against the solver, recorded
/// in the header (0: none; default 20000). check: with a fixed resolution,
/// False skips the bake check. layout: "atlas" (charts in the layer's
/// optical thickness, format version 4, sized for an error target) or
/// "grid" (thickness × cos θ nodes, versions 2 and 3), as `irid bake
/// --layout`; default "atlas", "grid" with a resolution.
#[pyfunction]
#[pyo3(signature = (
    stack, thickness_nm=None, layer=None, max_error=None, *, resolution=None, cos_theta=None,
    kind="rgb", sampling="exact", wavelengths_nm=None, half=false, validation_points=None,
    check=true, layout=None
))]
#[allow(clippy::too_many_arguments)]
pub fn bake(
    py: Python<'_>,
    stack: &PyStack,
    thickness_nm: Option<&Bound<'_, PyAny>>,
    layer: Option<&Bound<'_, PyAny>>,
    max_error: Option<f64>,
    resolution: Option<&Bound<'_, PyAny>>,
    cos_theta: Option<&Bound<'_, PyAny>>,
    kind: &str,
    sampling: &str,
    wavelengths_nm: Option<&Bound<'_, PyAny>>,
    half: bool,
    validation_points: Option<&Bound<'_, PyAny>>,
    check: bool,
    layout: Option<&str>,
) -> PyResult<PyLut> {
    let mut spec = BakeSpec::new(stack.stack.clone());
    spec.layer = layer_number(&spec.stack, layer)?;
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
        if spec.kind == Kind::Rgb {
            // Silently ignored otherwise: an rgb table integrates its
            // sampling's wavelengths.
            return Err(invalid(
                "wavelengths_nm",
                "an rgb table has no wavelength axis (kind=\"spectral\" has one)",
            ));
        }
        spec.wavelength_nm = range(w, "wavelengths_nm")?;
    }
    spec.half = half;
    spec.validation_points = match validation_points {
        Some(v) => count(v, "validation_points")?,
        None => DEFAULT_VALIDATION_POINTS,
    };
    spec.check = check;
    spec.resolution = match (resolution, max_error) {
        (Some(_), Some(_)) => {
            return Err(invalid(
                "resolution",
                "give either resolution or max_error, not both",
            ))
        }
        (Some(r), None) => fixed_resolution(spec.kind, r)?,
        (None, e) => Resolution::MaxError(e.unwrap_or(1e-3)),
    };
    spec.layout = match layout {
        Some(l) => l.parse::<Layout>().map_err(py_error)?,
        None if resolution.is_some() => Layout::Grid,
        None => Layout::Atlas,
    };
    if resolution.is_some() && spec.layout == Layout::Atlas {
        return Err(invalid(
            "layout",
            "an atlas is sized for an error target, not a resolution (layout=\"grid\" takes one)",
        ));
    }
    // Checks the memory a fixed resolution needs (an error target's
    // refinement checks each round's as it goes).
    spec.validate().map_err(py_error)?;
    let lut = compute(py, true, || {
        let mut lut = irid::lut::bake(&spec)?;
        if lut.header().error.validation.is_none() && spec.validation_points > 0 {
            let stats = validate(&lut, spec.validation_points, VALIDATION_SEED)?;
            lut.set_validation(stats);
        }
        Ok(lut)
    })?
    .map_err(py_error)?;
    Ok(PyLut { lut })
}

/// The validation points of `irid.bake` when none are given, as `irid bake`.
const DEFAULT_VALIDATION_POINTS: usize = 20_000;

/// `resolution`: a sequence of node counts, one per axis of the table's
/// kind as `irid bake --resolution` takes them: (thickness, angle) for rgb,
/// (thickness, angle, wavelength) for spectral. A str is refused though it
/// is a sequence (of characters).
fn fixed_resolution(kind: Kind, obj: &Bound<'_, PyAny>) -> PyResult<Resolution> {
    let expected = match kind {
        Kind::Rgb => "an rgb table takes (thickness, angle) node counts",
        Kind::Spectral => "a spectral table takes (thickness, angle, wavelength) node counts",
    };
    let items = obj
        .downcast::<PyString>()
        .err()
        .and_then(|_| obj.try_iter().ok())
        .ok_or_else(|| wrong_type("resolution", expected))?;
    let counts = items
        .enumerate()
        .map(|(i, item)| count(&item?, &format!("resolution[{i}]")))
        .collect::<PyResult<Vec<usize>>>()?;
    match (kind, counts.as_slice()) {
        (Kind::Rgb, &[thickness, angle]) => Ok(Resolution::Nodes {
            thickness,
            angle,
            wavelength: 1,
        }),
        (Kind::Spectral, &[thickness, angle, wavelength]) => Ok(Resolution::Nodes {
            thickness,
            angle,
            wavelength,
        }),
        _ => Err(invalid("resolution", expected)),
    }
}

/// Points in one task of the samplers, and the fewest a call hands to the
/// thread pool: below, sampling (nanoseconds a point) takes less than the
/// handoff.
pub(crate) const SAMPLE_BLOCK: usize = 4096;

/// An rgb table's R and T (three f32 each, interleaved) at every
/// (thickness, cos θ): in blocks on the current thread pool when
/// `parallel` (none once `cancel` is set), else on this thread.
fn sample_rgb(
    lut: &Lut,
    thickness_nm: &[f64],
    cos_theta: &[f64],
    parallel: bool,
    cancel: &Cancel,
) -> (Vec<f32>, Vec<f32>) {
    let mut r = vec![0f32; 3 * thickness_nm.len()];
    let mut t = vec![0f32; 3 * thickness_nm.len()];
    let fill = |r: &mut [f32], t: &mut [f32], thickness_nm: &[f64], cos_theta: &[f64]| {
        let films = thickness_nm
            .iter()
            .zip(cos_theta)
            .map(|(&thickness, &cos)| lut.sample_rgb(thickness as f32, cos as f32));
        for ((r, t), film) in r.chunks_exact_mut(3).zip(t.chunks_exact_mut(3)).zip(films) {
            r.copy_from_slice(&film.reflectance);
            t.copy_from_slice(&film.transmittance);
        }
    };
    if parallel {
        r.par_chunks_mut(3 * SAMPLE_BLOCK)
            .zip(t.par_chunks_mut(3 * SAMPLE_BLOCK))
            .zip(
                thickness_nm
                    .par_chunks(SAMPLE_BLOCK)
                    .zip(cos_theta.par_chunks(SAMPLE_BLOCK)),
            )
            .for_each(|((r, t), (thickness_nm, cos_theta))| {
                if !cancel.is_set() {
                    fill(r, t, thickness_nm, cos_theta)
                }
            });
    } else {
        fill(&mut r, &mut t, thickness_nm, cos_theta);
    }
    (r, t)
}

/// A spectral table's R and T at every (thickness, cos θ, wavelength) of
/// `coordinates`: in blocks on the current thread pool when `parallel`
/// (none once `cancel` is set), else on this thread.
fn sample_spectral(
    lut: &Lut,
    coordinates: &[Vec<f64>],
    parallel: bool,
    cancel: &Cancel,
) -> (Vec<f32>, Vec<f32>) {
    let [thickness_nm, cos_theta, wavelength_nm] = coordinates else {
        unreachable!("a spectral table is sampled at three coordinates")
    };
    let mut r = vec![0f32; thickness_nm.len()];
    let mut t = vec![0f32; thickness_nm.len()];
    let fill = |r: &mut [f32], t: &mut [f32], points: [&[f64]; 3]| {
        let [thickness_nm, cos_theta, wavelength_nm] = points;
        let points = thickness_nm.iter().zip(cos_theta).zip(wavelength_nm);
        for ((r, t), ((&thickness, &cos), &wavelength)) in r.iter_mut().zip(t).zip(points) {
            (*r, *t) = lut.sample_spectral(thickness as f32, cos as f32, wavelength as f32);
        }
    };
    if parallel {
        r.par_chunks_mut(SAMPLE_BLOCK)
            .zip(t.par_chunks_mut(SAMPLE_BLOCK))
            .zip(
                thickness_nm
                    .par_chunks(SAMPLE_BLOCK)
                    .zip(cos_theta.par_chunks(SAMPLE_BLOCK))
                    .zip(wavelength_nm.par_chunks(SAMPLE_BLOCK)),
            )
            .for_each(|((r, t), ((thickness, cos), wavelength))| {
                if !cancel.is_set() {
                    fill(r, t, [thickness, cos, wavelength])
                }
            });
    } else {
        fill(&mut r, &mut t, [thickness_nm, cos_theta, wavelength_nm]);
    }
    (r, t)
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
    /// Its memory is checked against the budget from the file's headers
    /// before a pixel is read.
    #[staticmethod]
    fn load(py: Python<'_>, path: PathBuf) -> PyResult<Self> {
        if irid::lut::rough::is_rough_table(&path) {
            return Err(invalid(
                path.display().to_string(),
                "a rough table (irid bake --rough): irid.RoughLut.load reads it",
            ));
        }
        let lut = compute(py, true, || Lut::load(&path))?.map_err(py_error)?;
        Ok(PyLut { lut })
    }

    /// Writes the table atomically (a partial file is never left behind).
    fn save(&self, py: Python<'_>, path: PathBuf) -> PyResult<()> {
        compute(py, true, || self.lut.write(&path))?.map_err(py_error)
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

    /// The stored values (float32), thickness fastest: rgb grid tables
    /// (cos θ, thickness, 6) with R r, g, b then T r, g, b; spectral grid
    /// tables (wavelength, cos θ, thickness, 2) with R, T. The node
    /// positions are in header["axes"]. Atlas tables (format version 4):
    /// (rows, columns, channels) of the atlas image, per wavelength node
    /// for a spectral one (header["atlas"] says where each chart is).
    #[getter]
    fn data<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let header = self.lut.header();
        let mut shape: Vec<usize> = match &header.atlas {
            Some(t) => header
                .axes
                .get(2)
                .map(|w| w.nodes.len())
                .into_iter()
                .chain([t.atlas.height, t.atlas.width])
                .collect(),
            None => header.axes.iter().rev().map(|a| a.nodes.len()).collect(),
        };
        shape.push(header.channel_names().len());
        let data = self.lut.data();
        Footprint::new()
            .items(&[data.len()], 4)
            .check(&format!("data: a copy of {} values", data.len()))?;
        Ok(array(py, data.to_vec(), &shape)?.into_any())
    }

    /// The table's R and T at each (thickness nm, cos θ) point, interpolated
    /// as a renderer does (outside the axes, ±inf included, clamped to the
    /// ends). NaN is a ValueError naming the argument and its position.
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
        let spectral = lut.kind() == Kind::Spectral;
        let mut named = vec![(thickness_nm, "thickness_nm"), (cos_theta, "cos_theta")];
        match (spectral, wavelength_nm) {
            (false, Some(_)) => {
                return Err(invalid(
                    "wavelength_nm",
                    "an rgb table has no wavelength axis",
                ))
            }
            (true, None) => {
                return Err(invalid(
                    "wavelength_nm",
                    "a spectral table needs the wavelength of each point",
                ))
            }
            (_, w) => named.extend(w.map(|w| (w, "wavelength_nm"))),
        }
        // R and T per point: three f32 each for rgb, one for spectral.
        let output_bytes = if spectral { 2 * 4 } else { 2 * 3 * 4 };
        let (coordinates, shape) = broadcast_reals(&named, "sample", output_bytes)?;
        for (values, (_, name)) in coordinates.iter().zip(&named) {
            if let Some(i) = values.iter().position(|x| x.is_nan()) {
                return Err(invalid(
                    format!("{name}{}", position(i, &shape)),
                    "NaN is not a coordinate",
                ));
            }
        }
        let parallel = coordinates[0].len() > SAMPLE_BLOCK;
        if spectral {
            let (r, t) = compute_cancellable(py, parallel, |cancel| {
                sample_spectral(lut, &coordinates, parallel, cancel)
            })?;
            PyTuple::new(py, [array(py, r, &shape)?, array(py, t, &shape)?])
        } else {
            let (r, t) = compute_cancellable(py, parallel, |cancel| {
                sample_rgb(lut, &coordinates[0], &coordinates[1], parallel, cancel)
            })?;
            let mut shape3 = shape;
            shape3.push(3);
            PyTuple::new(py, [array(py, r, &shape3)?, array(py, t, &shape3)?])
        }
    }

    /// Compares the table with the solver at `points` random points (a
    /// PCG64 stream seeded with `seed`), as `irid validate --json`: a dict
    /// of per-channel max/mean/p99 absolute errors, CIEDE2000, the worst
    /// point and the hard regions.
    /// Memory does not grow with the count (points are folded into running
    /// figures), which the library bounds.
    #[pyo3(signature = (points=None, seed=None))]
    fn validate<'py>(
        &self,
        py: Python<'py>,
        points: Option<&Bound<'py, PyAny>>,
        seed: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let points = match points {
            Some(p) => count(p, "points")?,
            None => DEFAULT_VALIDATION_POINTS,
        };
        let seed = match seed {
            Some(s) => integer_in(s, "seed", 0..=u64::MAX as i128)? as u64,
            None => VALIDATION_SEED,
        };
        let stats = compute(py, true, || validate(&self.lut, points, seed))?.map_err(py_error)?;
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
