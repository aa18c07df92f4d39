//! `irid.RoughLut`: the rough table of `irid bake --rough` loaded and
//! sampled (docs/lut-format.md, "Rough tables").

use std::path::PathBuf;

use pyo3::prelude::*;
use rayon::prelude::*;

use irid::lut::RoughLut;
use irid::rough::check_roughness;

use crate::arrays::{array, broadcast_reals, json_to_py, position};
use crate::lut::SAMPLE_BLOCK;
use crate::pool::{compute, compute_cancellable, Cancel};
use crate::{invalid, py_error};

/// A rough table: the front side's reflectance F_eff over a layer's
/// thickness, cos θ and GGX roughness, as written by `irid bake --rough`.
#[pyclass(name = "RoughLut", module = "irid", frozen)]
pub struct PyRoughLut {
    lut: RoughLut,
}

#[pymethods]
impl PyRoughLut {
    /// Reads and checks a rough table (OpenEXR with irid's JSON header,
    /// format "irid-rough").
    #[staticmethod]
    fn load(py: Python<'_>, path: PathBuf) -> PyResult<Self> {
        let lut = compute(py, true, || RoughLut::load(&path))?.map_err(py_error)?;
        Ok(PyRoughLut { lut })
    }

    /// The JSON header (charts, slices, stack, colour, error figures) as a dict.
    #[getter]
    fn header<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        json_to_py(py, self.lut.header())
    }

    /// The table's F_eff (linear sRGB, float32 of shape broadcast + (3,))
    /// at each (thickness nm, cos θ, roughness) point, as `RoughLut::sample`
    /// (thickness and cos θ clamped to the table's range). The arguments
    /// broadcast together (numpy rules); NaN, or a roughness outside
    /// [0, 1], is a ValueError naming the argument and its position.
    fn sample<'py>(
        &self,
        py: Python<'py>,
        thickness_nm: &Bound<'py, PyAny>,
        cos_theta: &Bound<'py, PyAny>,
        roughness: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let named = [
            (thickness_nm, "thickness_nm"),
            (cos_theta, "cos_theta"),
            (roughness, "roughness"),
        ];
        let (coordinates, shape) = broadcast_reals(&named, "sample", 3 * 4)?;
        for (values, (_, name)) in coordinates.iter().zip(&named) {
            if let Some(i) = values.iter().position(|x| x.is_nan()) {
                return Err(invalid(
                    format!("{name}{}", position(i, &shape)),
                    "NaN is not a coordinate",
                ));
            }
        }
        if let Some(i) = coordinates[2]
            .iter()
            .position(|&r| check_roughness("roughness", r).is_err())
        {
            let what = format!("roughness{}", position(i, &shape));
            check_roughness(&what, coordinates[2][i]).map_err(py_error)?;
        }
        let lut = &self.lut;
        let parallel = coordinates[0].len() > SAMPLE_BLOCK;
        let rgb = compute_cancellable(py, parallel, |cancel| {
            sample_rough(lut, &coordinates, parallel, cancel)
        })?;
        let mut shape3 = shape;
        shape3.push(3);
        Ok(array(py, rgb, &shape3)?.into_any())
    }

    fn __repr__(&self) -> String {
        let h = self.lut.header();
        format!(
            "irid.RoughLut({} slices, {}-{} nm)",
            h.slices, h.atlas.thickness_nm.0, h.atlas.thickness_nm.1
        )
    }
}

/// F_eff (RGB, f32) at every (thickness, cos θ, roughness) of
/// `coordinates`: in blocks on the current thread pool when `parallel`
/// (none once `cancel` is set), else on this thread.
fn sample_rough(
    lut: &RoughLut,
    coordinates: &[Vec<f64>],
    parallel: bool,
    cancel: &Cancel,
) -> Vec<f32> {
    let [thickness, cos, rough] = coordinates else {
        unreachable!("a rough table is sampled at three coordinates")
    };
    let mut rgb = vec![0f32; 3 * thickness.len()];
    let fill = |out: &mut [f32], points: [&[f64]; 3]| {
        let [thickness, cos, rough] = points;
        let points = thickness.iter().zip(cos).zip(rough);
        for (out, ((&d, &c), &r)) in out.chunks_exact_mut(3).zip(points) {
            for (o, x) in out.iter_mut().zip(lut.sample(d, c, r)) {
                *o = x as f32;
            }
        }
    };
    if parallel {
        rgb.par_chunks_mut(3 * SAMPLE_BLOCK)
            .zip(
                thickness
                    .par_chunks(SAMPLE_BLOCK)
                    .zip(cos.par_chunks(SAMPLE_BLOCK))
                    .zip(rough.par_chunks(SAMPLE_BLOCK)),
            )
            .for_each(|(out, ((d, c), r))| {
                if !cancel.is_set() {
                    fill(out, [d, c, r])
                }
            });
    } else {
        fill(&mut rgb, [thickness, cos, rough]);
    }
    rgb
}
