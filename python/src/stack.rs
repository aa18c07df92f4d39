//! `irid.Material`, `irid.material`, `irid.materials` and `irid.Stack`.

use std::path::{Path, PathBuf};

use num_complex::Complex64 as C64;
use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;
use pyo3::types::{IntoPyDict, PyComplex, PyDict, PyList, PyString, PyTuple};
use rayon::prelude::*;

use irid::color::{stack_colors_cancellable, FilmColor, Sampling, SpectralIntegrator, White};
use irid::optics::solver::power;
use irid::optics::spec::{IndexSpec, MediumSpec};
use irid::optics::{
    library, solve, solve_amplitudes, solve_mixed, Layer, Material, Response, Stack, StackGrid,
    MAX_THICKNESS_NM,
};
use irid::rough::{check_roughness, rough_colors_from_cancellable, seen_from, RoughColor};
use irid::sweep::Side as Seen;

use crate::arrays::{array, count, integer_in, planned_len, real, real_list, reals};
use crate::budget::Footprint;
use crate::coherent::check_wavelengths;
use crate::gradient::Derivatives;
use crate::pool::{compute_cancellable, compute_interruptible, Cancel};
use crate::{invalid, py_error, wrong_type};

/// A refractive-index model: a constant n + ik, a built-in material, a
/// Cauchy or Sellmeier formula, or a table.
///
/// Material(form) takes any medium form of a stack file: a number n, a pair
/// (n, k) or a complex n + kj (k > 0 absorbs, k < 0 is gain), a built-in
/// name ("gold"), or a dict with one of the keys n, material, cauchy
/// ([A, B] or [A, B, C], λ in µm), sellmeier ({"b": [...], "c": [...]},
/// optional "a"), table (a refractiveindex.info CSV path), and an optional
/// name. The same keys are accepted as keyword arguments:
/// Material(cauchy=[1.45, 0.0036]).
#[pyclass(name = "Material", module = "irid", frozen)]
#[derive(Clone)]
pub struct PyMaterial {
    pub material: Material,
}

#[pymethods]
impl PyMaterial {
    #[new]
    #[pyo3(signature = (form=None, **fields))]
    fn new(form: Option<&Bound<'_, PyAny>>, fields: Option<&Bound<'_, PyDict>>) -> PyResult<Self> {
        let material = match (form, fields) {
            (Some(form), None) => medium(form, "material", None)?,
            (None, Some(fields)) => medium(fields.as_any(), "material", None)?,
            (Some(_), Some(_)) => {
                return Err(invalid(
                    "material",
                    "give either one form or keyword fields, not both",
                ))
            }
            (None, None) => {
                return Err(invalid(
                    "material",
                    "give a form (a number, (n, k), a name or a dict) or keyword fields",
                ))
            }
        };
        Ok(PyMaterial { material })
    }

    /// The label used in messages and table headers.
    #[getter]
    fn name(&self) -> String {
        self.material.name.clone()
    }

    /// The wavelength range (nm) over which the index is defined.
    #[getter]
    fn range_nm(&self) -> (f64, f64) {
        self.material.range_nm()
    }

    /// The complex index n + ik at each wavelength (nm); same shape as the input.
    fn index<'py>(
        &self,
        py: Python<'py>,
        wavelengths_nm: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let (wavelengths, shape) = reals(wavelengths_nm, "wavelengths_nm")?;
        Footprint::new()
            .items(&[wavelengths.len()], 16)
            .check(&format!("wavelengths_nm: {} indices", wavelengths.len()))?;
        // A constant index would be returned at any "wavelength", NaN too.
        check_wavelengths(&wavelengths, "wavelengths_nm")?;
        let values = wavelengths
            .iter()
            .map(|&w| self.material.index_at(w))
            .collect::<irid::Result<Vec<C64>>>()
            .map_err(|e| invalid(self.material.name.clone(), e.to_string()))?;
        let out = array(py, values, &shape)?;
        if shape.is_empty() {
            // A number in, a number out.
            return out.get_item(PyTuple::empty(py));
        }
        Ok(out.into_any())
    }

    fn __repr__(&self) -> String {
        format!("irid.Material({:?})", self.material.name)
    }
}

/// The built-in material called `name` (case-insensitive, with aliases
/// such as "Au" or "SiO2"); ValueError names the built-ins if unknown.
#[pyfunction]
pub fn material(name: &str) -> PyResult<PyMaterial> {
    let material = library::builtin(name).ok_or_else(|| {
        invalid(
            "material",
            format!(
                "unknown material '{name}' (built-in: {})",
                library::names().join(", ")
            ),
        )
    })?;
    Ok(PyMaterial { material })
}

/// The names of the built-in materials.
#[pyfunction]
pub fn materials() -> Vec<&'static str> {
    library::names().to_vec()
}

/// One medium of a stack from any of its Python forms. `thickness_nm` is a
/// layer's thickness given beside the form (`(form, thickness)`).
fn medium(obj: &Bound<'_, PyAny>, field: &str, layer_thickness: Option<f64>) -> PyResult<Material> {
    let finite = field.starts_with("layers");
    if let Ok(m) = obj.downcast::<PyMaterial>() {
        return Ok(m.get().material.clone());
    }
    let mut spec = if let Ok(dict) = obj.downcast::<PyDict>() {
        let py = obj.py();
        // allow_nan=False: NaN is refused here, naming the field, rather
        // than written as JSON that does not parse.
        let json: String = py
            .import("json")?
            .getattr("dumps")?
            .call((dict,), Some(&[("allow_nan", false)].into_py_dict(py)?))
            .and_then(|j| j.extract())
            .map_err(|e| {
                let why = format!("not a stack-file medium ({e})");
                if e.is_instance_of::<PyTypeError>(py) {
                    wrong_type(field, why)
                } else {
                    invalid(field, why)
                }
            })?;
        let spec: MediumSpec =
            serde_json::from_str(&json).map_err(|e| invalid(field, e.to_string()))?;
        if layer_thickness.is_some() && spec.thickness_nm.is_some() {
            return Err(invalid(
                format!("{field}.thickness_nm"),
                "given twice (in the dict and beside it)",
            ));
        }
        spec
    } else if let Ok(name) = obj.downcast::<PyString>() {
        MediumSpec {
            material: Some(name.to_str()?.to_string()),
            ..MediumSpec::default()
        }
    } else if let Ok(z) = obj.downcast::<PyComplex>() {
        index_spec(z.real(), z.imag())
    } else if obj.is_instance_of::<pyo3::types::PyBool>() {
        return Err(wrong_type(field, "a bool is not a refractive index"));
    } else if let Ok(n) = obj.extract::<f64>() {
        index_spec(n, 0.0)
    } else if let Ok((n, k)) = obj.extract::<(f64, f64)>() {
        index_spec(n, k)
    } else {
        return Err(wrong_type(
            field,
            format!(
                "expected a number n, a pair (n, k), a complex n + kj, a material name, \
                 a dict of stack-file keys or an irid.Material, got {}",
                obj.repr()?
            ),
        ));
    };
    if finite && spec.thickness_nm.is_none() {
        spec.thickness_nm = layer_thickness;
    }
    spec.resolve(field, Path::new(""), finite).map_err(py_error)
}

fn index_spec(n: f64, k: f64) -> MediumSpec {
    MediumSpec {
        n: Some(IndexSpec { n, k }),
        ..MediumSpec::default()
    }
}

/// One layer: `(form, thickness_nm)`, `(form, thickness_nm, coherent)`, or
/// a dict of stack-file keys carrying its `thickness_nm` (and optionally
/// `coherent`).
fn layer(obj: &Bound<'_, PyAny>, field: &str) -> PyResult<Layer> {
    if obj.is_instance_of::<PyDict>() {
        let thickness_nm = obj
            .get_item("thickness_nm")
            .ok()
            .and_then(|t| t.extract::<f64>().ok())
            .unwrap_or(f64::NAN);
        let material = medium(obj, field, None)?;
        // The stack-file parse behind `medium` has checked it is a bool.
        let coherent = obj
            .get_item("coherent")
            .ok()
            .and_then(|c| c.extract::<bool>().ok())
            .unwrap_or(true);
        return Ok(Layer {
            coherent,
            ..Layer::new(material, thickness_nm)
        });
    }
    let tuple = obj
        .downcast::<PyTuple>()
        .map(|t| t.as_any().clone())
        .or_else(|_| obj.downcast::<PyList>().map(|l| l.as_any().clone()));
    let expected = "expected (material, thickness_nm), (material, thickness_nm, coherent) \
                    or a dict with thickness_nm";
    let Ok(tuple) = tuple else {
        return Err(wrong_type(
            field,
            format!("{expected}, got {}", obj.repr()?),
        ));
    };
    let coherent = match tuple.len()? {
        2 => true,
        3 => {
            let flag = tuple.get_item(2)?;
            if !flag.is_instance_of::<pyo3::types::PyBool>() {
                return Err(wrong_type(
                    format!("{field}.coherent"),
                    format!(
                        "must be True or False (False: an incoherent, thick layer), got {}",
                        flag.repr()?
                    ),
                ));
            }
            flag.extract()?
        }
        _ => return Err(invalid(field, format!("{expected}, got {}", obj.repr()?))),
    };
    let thickness_nm = real(&tuple.get_item(1)?, &format!("{field}.thickness_nm"))?;
    let material = medium(&tuple.get_item(0)?, field, Some(thickness_nm))?;
    Ok(Layer {
        coherent,
        ..Layer::new(material, thickness_nm)
    })
}

/// A planar multilayer: a lossless ambient, layers from the top (ambient
/// side) down, and a semi-infinite substrate.
///
/// Stack(ambient=1.0, layers=[(material, thickness_nm), ...], substrate=1.0)
/// takes every medium form irid.Material takes; a layer given as
/// (material, thickness_nm, False) is incoherent (thick: its inner
/// reflections add in power). Stack.load(path) reads a stack file (TOML).
#[pyclass(name = "Stack", module = "irid", frozen)]
#[derive(Clone)]
pub struct PyStack {
    pub stack: Stack,
}

#[pymethods]
impl PyStack {
    #[new]
    #[pyo3(signature = (ambient=None, layers=None, substrate=None))]
    fn new(
        ambient: Option<&Bound<'_, PyAny>>,
        layers: Option<&Bound<'_, PyAny>>,
        substrate: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Self> {
        let vacuum = || Material::constant(1.0, 0.0);
        let ambient = ambient.map_or_else(|| Ok(vacuum()), |a| medium(a, "ambient", None))?;
        let substrate = substrate.map_or_else(|| Ok(vacuum()), |s| medium(s, "substrate", None))?;
        let mut list = Vec::new();
        if let Some(layers) = layers {
            for (i, item) in layers
                .try_iter()
                .map_err(|_| wrong_type("layers", "must be a list of (material, thickness_nm)"))?
                .enumerate()
            {
                list.push(layer(&item?, &format!("layers[{}]", i + 1))?);
            }
        }
        let stack = Stack {
            ambient,
            layers: list,
            substrate,
        };
        stack.validate().map_err(py_error)?;
        Ok(PyStack { stack })
    }

    /// Reads a stack file (TOML); table paths in it are relative to its folder.
    #[staticmethod]
    fn load(path: PathBuf) -> PyResult<Self> {
        Ok(PyStack {
            stack: Stack::load(&path).map_err(py_error)?,
        })
    }

    /// Parses stack-file text; table paths are relative to `base_dir`.
    #[staticmethod]
    #[pyo3(signature = (text, base_dir=PathBuf::from(".")))]
    fn from_toml(text: &str, base_dir: PathBuf) -> PyResult<Self> {
        Ok(PyStack {
            stack: Stack::from_toml_str(text, &base_dir, "stack").map_err(py_error)?,
        })
    }

    /// The stack as JSON text (the form a table's header records under
    /// "stack": every material with its dispersion data), for hosts whose
    /// scene descriptions hold only text.
    fn to_json(&self) -> PyResult<String> {
        serde_json::to_string(&self.stack).map_err(|e| invalid("stack", e.to_string()))
    }

    /// Reads the JSON of `to_json` (or a table header's "stack") back.
    #[staticmethod]
    fn from_json(text: &str) -> PyResult<Self> {
        let stack: Stack = serde_json::from_str(text)
            .map_err(|e| invalid("stack", format!("not a stack's JSON ({e})")))?;
        stack.validate().map_err(py_error)?;
        Ok(PyStack { stack })
    }

    #[getter]
    fn ambient(&self) -> PyMaterial {
        PyMaterial {
            material: self.stack.ambient.clone(),
        }
    }

    #[getter]
    fn substrate(&self) -> PyMaterial {
        PyMaterial {
            material: self.stack.substrate.clone(),
        }
    }

    /// The layers as (Material, thickness_nm), from the top down.
    #[getter]
    fn layers(&self) -> Vec<(PyMaterial, f64)> {
        self.stack
            .layers
            .iter()
            .map(|l| {
                (
                    PyMaterial {
                        material: l.material.clone(),
                    },
                    l.thickness_nm,
                )
            })
            .collect()
    }

    /// Per layer, top down: False for an incoherent layer.
    #[getter]
    fn coherent(&self) -> Vec<bool> {
        self.stack.layers.iter().map(|l| l.coherent).collect()
    }

    /// R, T and the complex amplitudes at every wavelength (nm) and angle of
    /// incidence (degrees in [0, 90)), for unpolarized light from the ambient.
    /// A stack with incoherent layers has no amplitudes (their phase is
    /// averaged out): its dict holds R and T only, and a point where an
    /// incoherent layer lases raises ValueError naming it.
    ///
    /// Returns a dict of arrays of shape (wavelengths, angles), or
    /// (thicknesses, wavelengths, angles) when `thickness_nm` lists
    /// thicknesses for layer `layer` (counted from 1 at the ambient side):
    /// Rs, Rp, Ts, Tp, R, T (float64; R and T the unpolarized means) and
    /// rs, rp, ts, tp (complex128; r referred to the top interface, t the
    /// ratio of the forward amplitude at the substrate's interface to the
    /// incident one, in Byrnes' tmm's convention).
    ///
    /// gradient=True adds the exact derivatives by every layer's thickness
    /// (per nm, layers top down; docs/inverse.md): dRs_dd, dRp_dd, dTs_dd,
    /// dTp_dd, dR_dd, dT_dd, each of shape (layers, wavelengths, angles)
    /// (views of one array), from the same single solve as R, T and the
    /// amplitudes. Not with a `thickness_nm` sweep. index_gradient=True
    /// (with gradient=True; about 14× its cost) adds the same six by each
    /// layer's n and k (dRs_dn, ..., dT_dn; dRs_dk, ..., dT_dk).
    #[pyo3(signature = (wavelengths_nm, angles_deg, thickness_nm=None, layer=None, gradient=false, index_gradient=false))]
    #[allow(clippy::too_many_arguments)]
    fn solve<'py>(
        &self,
        py: Python<'py>,
        wavelengths_nm: &Bound<'py, PyAny>,
        angles_deg: &Bound<'py, PyAny>,
        thickness_nm: Option<&Bound<'py, PyAny>>,
        layer: Option<&Bound<'py, PyAny>>,
        gradient: bool,
        index_gradient: bool,
    ) -> PyResult<Bound<'py, PyDict>> {
        let derivatives =
            Derivatives::from_flags(gradient, index_gradient, thickness_nm.is_some())?;
        // From the arguments' sizes before they are copied, then from the copies.
        if let (Some(w), Some(a)) = (planned_len(wavelengths_nm), planned_len(angles_deg)) {
            derivatives.check_footprint(self.stack.layers.len(), w, a)?;
            let thicknesses = thickness_nm.map(|t| planned_len(t).unwrap_or(0));
            self.solve_footprint(w, a, thicknesses)?;
        }
        let wavelengths = real_list(wavelengths_nm, "wavelengths_nm")?;
        let angles = real_list(angles_deg, "angles_deg")?;
        if let Some(a) = angles.iter().find(|a| !(**a >= 0.0 && **a < 90.0)) {
            return Err(invalid(
                "angles_deg",
                format!("{a} is outside [0, 90) degrees"),
            ));
        }
        let layer = layer_number(&self.stack, layer)?;
        let sweep = match thickness_nm {
            None => None,
            Some(_) if self.stack.layers.is_empty() => {
                return Err(invalid("thickness_nm", "the stack has no layer to vary"))
            }
            Some(t) => {
                let list = real_list(t, "thickness_nm")?;
                if let Some(t) = list.iter().find(|t| !(0.0..=MAX_THICKNESS_NM).contains(*t)) {
                    return Err(invalid(
                        "thickness_nm",
                        format!("must be finite, ≥ 0 and ≤ {MAX_THICKNESS_NM:e}, got {t}"),
                    ));
                }
                Some(Sweep {
                    layer,
                    thicknesses_nm: list,
                })
            }
        };
        let shape: Vec<usize> = match &sweep {
            Some(s) => vec![s.thicknesses_nm.len(), wavelengths.len(), angles.len()],
            None => vec![wavelengths.len(), angles.len()],
        };
        self.solve_footprint(
            wavelengths.len(),
            angles.len(),
            sweep.as_ref().map(|s| s.thicknesses_nm.len()),
        )?;
        let grid = StackGrid::new(&self.stack, &wavelengths).map_err(py_error)?;
        let cos_theta0: Vec<f64> = angles.iter().map(|a| a.to_radians().cos()).collect();
        if derivatives != Derivatives::None {
            return crate::gradient::solve_with_gradient(py, &grid, &cos_theta0, derivatives);
        }
        let parallel = shape.iter().product::<usize>() >= SOLVE_PARALLEL_MIN_POINTS;
        let solve =
            |cancel: &Cancel| solve_points(&grid, &cos_theta0, sweep.as_ref(), parallel, cancel);
        let points = compute_cancellable(py, parallel, solve)?;
        if let Some(k) = points.iter().position(|p| !p.power[0].is_finite()) {
            lasing_at(&grid, &cos_theta0, sweep.as_ref(), k)?;
        }
        let result = PyDict::new(py);
        for (k, key) in ["Rs", "Rp", "Ts", "Tp", "R", "T"].into_iter().enumerate() {
            let column = points.iter().map(|p| p.power[k]).collect();
            result.set_item(key, array(py, column, &shape)?)?;
        }
        if !self.stack.is_coherent() {
            return Ok(result);
        }
        for (k, key) in ["rs", "rp", "ts", "tp"].into_iter().enumerate() {
            let column: Vec<C64> = points.iter().map(|p| p.amplitudes[k]).collect();
            result.set_item(key, array(py, column, &shape)?)?;
        }
        Ok(result)
    }

    /// The reflected and transmitted colour at each angle (degrees in
    /// [0, 90)) for unpolarized light from the ambient, as `irid color`.
    ///
    /// sampling: "exact" (1 nm over 360–830 nm), "uniform:N" (380–780 nm)
    /// or "rgb3". white: "d65" (irid's default: the spectrum under D65, a
    /// perfect reflector is (1, 1, 1)) or "e" (the equal-energy white that
    /// Blender Cycles and the glTF viewer assume: a flat spectrum is
    /// (1, 1, 1)), as `irid color --white`.
    /// Returns a dict: angle_deg (A,), reflectance_rgb, transmittance_rgb
    /// (linear sRGB, (A, 3)), reflectance_xyz, transmittance_xyz (CIE XYZ,
    /// Y = 1 for a perfect reflector, (A, 3)).
    ///
    /// roughness (a number in [0, 1], as `irid color --roughness`): the
    /// reflectance and transmittance pre-integrated over GGX reflection and
    /// refraction lobes of that roughness, F_eff and T_eff (docs/rough.md),
    /// per view angle instead. Returns a dict: angle_deg, reflectance_rgb,
    /// reflectance_xyz, transmittance_rgb, transmittance_xyz (as above),
    /// lobe_albedo and transmission_lobe_albedo (A,), the white lobes'
    /// directional albedos (single scattering), and reflectance_ms_rgb,
    /// reflectance_ms_xyz, transmittance_ms_rgb, transmittance_ms_xyz
    /// ((A, 3)): F_eff and T_eff compensated for multiple scattering, to be
    /// multiplied by the same lobe albedos (a lossless film's
    /// lobe_albedo × reflectance_ms + transmission_lobe_albedo ×
    /// transmittance_ms is 1). Roughness 0 gives the smooth colours exactly.
    ///
    /// side: "front" (the view in the ambient, the default; "ambient" says
    /// the same) or "substrate" (the view in a lossless substrate, angles
    /// in it), as `irid color --side`.
    ///
    /// gradient=True (smooth films only) adds the exact derivatives of the
    /// colours by every layer's thickness (per nm, layers top down):
    /// dreflectance_rgb_dd, dtransmittance_rgb_dd, dreflectance_xyz_dd and
    /// dtransmittance_xyz_dd, each of shape (layers, angles, 3).
    #[pyo3(signature = (angles_deg, sampling="exact", white="d65", roughness=None, gradient=false, side="front"))]
    #[allow(clippy::too_many_arguments)]
    fn color<'py>(
        &self,
        py: Python<'py>,
        angles_deg: &Bound<'py, PyAny>,
        sampling: &str,
        white: &str,
        roughness: Option<&Bound<'py, PyAny>>,
        gradient: bool,
        side: &str,
    ) -> PyResult<Bound<'py, PyDict>> {
        let side = match side {
            "front" | "ambient" => Seen::Front,
            "substrate" => Seen::Back,
            other => {
                return Err(invalid(
                    "side",
                    format!("expected \"front\" or \"substrate\", got {other:?}"),
                ))
            }
        };
        let sampling: Sampling = sampling.parse().map_err(py_error)?;
        let white: White = white.parse().map_err(py_error)?;
        let integrator = SpectralIntegrator::with_white(sampling, white);
        // From the argument's size before it is copied, then from the copy.
        let rough = roughness.is_some();
        if let Some(n) = planned_len(angles_deg) {
            self.color_footprint(&integrator, n, rough)?;
        }
        let angles = real_list(angles_deg, "angles_deg")?;
        self.color_footprint(&integrator, angles.len(), rough)?;
        if gradient {
            if roughness.is_some() {
                return Err(invalid(
                    "gradient",
                    "is given for smooth films only: not with roughness",
                ));
            }
            if side != Seen::Front {
                return Err(invalid(
                    "gradient",
                    "is given for the front side only: not with side=\"substrate\"",
                ));
            }
            return self.color_gradient(py, &integrator, angles);
        }
        if let Some(roughness) = roughness {
            return self.rough_color(py, &integrator, angles, roughness, side);
        }
        let (seen, _) = seen_from(&self.stack, 1, side, &integrator).map_err(py_error)?;
        let on_pool = self.color_work(&integrator, angles.len()) >= INTERRUPTIBLE_MIN_WORK;
        let colours = compute_cancellable(py, on_pool, |cancel| {
            stack_colors_cancellable(&seen, &integrator, &angles, cancel)
        })?
        .map_err(py_error)?;
        colour_dict(
            py,
            angles,
            &colours,
            &[
                ("reflectance_rgb", |c| c.reflectance_rgb),
                ("transmittance_rgb", |c| c.transmittance_rgb),
                ("reflectance_xyz", |c| c.reflectance_xyz),
                ("transmittance_xyz", |c| c.transmittance_xyz),
            ],
        )
    }

    /// Unpolarized (R, T) at arrays of points, each with its own wavelength:
    /// what a spectral renderer asks per path vertex.
    ///
    /// cos_theta: cosine of the incidence angle in the medium the light
    /// arrives through, in [0, 1]; wavelength_nm: vacuum wavelengths;
    /// thickness_nm: the thickness of layer `layer` (1-based from the
    /// ambient side) per point, or None for the stack's own. The arrays
    /// broadcast together (numpy rules). side: "ambient" (light from the
    /// ambient) or "substrate" (from a lossless substrate: the reversed
    /// stack; past its critical angle T is 0). Returns (R, T), float64 of the
    /// broadcast shape.
    #[pyo3(signature = (cos_theta, wavelength_nm, thickness_nm=None, layer=None, side="ambient"))]
    fn response<'py>(
        &self,
        py: Python<'py>,
        cos_theta: &Bound<'py, PyAny>,
        wavelength_nm: &Bound<'py, PyAny>,
        thickness_nm: Option<&Bound<'py, PyAny>>,
        layer: Option<&Bound<'py, PyAny>>,
        side: &str,
    ) -> PyResult<Bound<'py, PyTuple>> {
        crate::response::response(
            py,
            &self.stack,
            thickness_nm,
            cos_theta,
            wavelength_nm,
            layer,
            side,
        )
    }

    fn __repr__(&self) -> String {
        let layers: Vec<String> = self
            .stack
            .layers
            .iter()
            .map(|l| {
                let incoherent = if l.coherent { "" } else { ", False" };
                format!("({:?}, {}{incoherent})", l.material.name, l.thickness_nm)
            })
            .collect();
        format!(
            "irid.Stack(ambient={:?}, layers=[{}], substrate={:?})",
            self.stack.ambient.name,
            layers.join(", "),
            self.stack.substrate.name
        )
    }
}

/// Work of a `Stack.color` call (wavelengths × angles × media) from which
/// it runs on the pool, where Ctrl-C stops it: about a millisecond.
const INTERRUPTIBLE_MIN_WORK: usize = 1 << 16;

impl PyStack {
    /// Checks what `Stack.solve` allocates for `wavelengths` × `angles`
    /// points (× `thicknesses`, a sweep's): the points, then their columns
    /// as arrays; the grid's indices; the arguments' copies.
    fn solve_footprint(
        &self,
        wavelengths: usize,
        angles: usize,
        thicknesses: Option<usize>,
    ) -> PyResult<()> {
        let shape: Vec<usize> = match thicknesses {
            Some(t) => vec![t, wavelengths, angles],
            None => vec![wavelengths, angles],
        };
        Footprint::new()
            .items(&shape, 2 * std::mem::size_of::<Point>() as u64)
            .items(&[wavelengths, self.stack.layers.len() + 2], 64)
            .items(&[wavelengths + angles + thicknesses.unwrap_or(0)], 8)
            .check(&format!(
                "{}{wavelengths} wavelengths × {angles} angles",
                thicknesses.map_or(String::new(), |t| format!("{t} thicknesses × "))
            ))
    }

    /// The size of `Stack.color`'s solve at `angles` angles: wavelengths ×
    /// angles × media.
    fn color_work(&self, integrator: &SpectralIntegrator, angles: usize) -> usize {
        let media = self.stack.layers.len() + 2;
        integrator
            .wavelengths_nm()
            .len()
            .saturating_mul(angles)
            .saturating_mul(media)
    }

    /// Checks what `Stack.color` allocates for `angles` angles. Smooth: the
    /// responses at every (wavelength, angle), the grid's indices, and per
    /// angle its colour and the four (angles, 3) results. Rough: the
    /// colours and the seven results (the library checks its own sweep and
    /// kernels).
    fn color_footprint(
        &self,
        integrator: &SpectralIntegrator,
        angles: usize,
        rough: bool,
    ) -> PyResult<()> {
        if rough {
            return Footprint::new()
                .items(&[angles], std::mem::size_of::<RoughColor>() as u64 + 15 * 8)
                .check(&format!("{angles} angles"));
        }
        let samples = integrator.wavelengths_nm().len();
        Footprint::new()
            .items(&[samples, angles], std::mem::size_of::<Response>() as u64)
            .items(&[samples, self.stack.layers.len() + 2], 64)
            .items(
                &[angles],
                std::mem::size_of::<FilmColor>() as u64 + 4 * 3 * 8 + 8,
            )
            .check(&format!("{angles} angles × {samples} wavelengths"))
    }

    /// `Stack.color(..., roughness=R, side=...)`: F_eff and T_eff per angle
    /// (docs/rough.md).
    fn rough_color<'py>(
        &self,
        py: Python<'py>,
        integrator: &SpectralIntegrator,
        angles: Vec<f64>,
        roughness: &Bound<'py, PyAny>,
        side: Seen,
    ) -> PyResult<Bound<'py, PyDict>> {
        let roughness = real(roughness, "roughness")?;
        check_roughness("roughness", roughness).map_err(py_error)?;
        let colours = compute_interruptible(py, |cancel| {
            rough_colors_from_cancellable(&self.stack, integrator, &angles, roughness, side, cancel)
        })?
        .map_err(py_error)?;
        let albedo = colours.iter().map(|c| c.lobe_albedo).collect();
        let through = colours.iter().map(|c| c.transmission_lobe_albedo).collect();
        let result = colour_dict(
            py,
            angles,
            &colours,
            &[
                ("reflectance_rgb", |c| c.reflectance_rgb),
                ("reflectance_xyz", |c| c.reflectance_xyz),
                ("transmittance_rgb", |c| c.transmittance_rgb),
                ("transmittance_xyz", |c| c.transmittance_xyz),
                ("reflectance_ms_rgb", |c| c.reflectance_ms_rgb),
                ("reflectance_ms_xyz", |c| c.reflectance_ms_xyz),
                ("transmittance_ms_rgb", |c| c.transmittance_ms_rgb),
                ("transmittance_ms_xyz", |c| c.transmittance_ms_xyz),
            ],
        )?;
        let n = colours.len();
        result.set_item("lobe_albedo", array(py, albedo, &[n])?)?;
        result.set_item("transmission_lobe_albedo", array(py, through, &[n])?)?;
        Ok(result)
    }
}

impl PyStack {
    /// `Stack.color(..., gradient=True)`: the colours and their derivatives.
    fn color_gradient<'py>(
        &self,
        py: Python<'py>,
        integrator: &SpectralIntegrator,
        angles: Vec<f64>,
    ) -> PyResult<Bound<'py, PyDict>> {
        let on_pool = self.color_work(integrator, angles.len()) >= INTERRUPTIBLE_MIN_WORK;
        let colours = crate::gradient::colors(py, &self.stack, integrator, &angles, on_pool)?;
        let result = colour_dict(
            py,
            angles,
            &colours,
            &[
                ("reflectance_rgb", |c| c.reflectance_rgb),
                ("transmittance_rgb", |c| c.transmittance_rgb),
                ("reflectance_xyz", |c| c.reflectance_xyz),
                ("transmittance_xyz", |c| c.transmittance_xyz),
            ],
        )?;
        crate::gradient::add_color_gradient(py, &result, self.stack.layers.len(), &colours)?;
        Ok(result)
    }
}

/// A named colour of one angle's result, as `Stack.color` returns it.
type ColourKey<C> = (&'static str, fn(&C) -> [f64; 3]);

/// `Stack.color`'s dict: angle_deg (A,) and each named colour (A, 3).
fn colour_dict<'py, C>(
    py: Python<'py>,
    angles: Vec<f64>,
    colours: &[C],
    keys: &[ColourKey<C>],
) -> PyResult<Bound<'py, PyDict>> {
    let result = PyDict::new(py);
    let n = angles.len();
    result.set_item("angle_deg", array(py, angles, &[n])?)?;
    for (key, f) in keys {
        let values: Vec<f64> = colours.iter().flat_map(f).collect();
        result.set_item(*key, array(py, values, &[colours.len(), 3])?)?;
    }
    Ok(result)
}

/// The `layer` argument (1 when not given): for a stack with layers, one
/// of them, counted from 1 at the ambient side; any integer ≥ 0 for a stack
/// without (the library ignores it).
pub fn layer_number(stack: &Stack, layer: Option<&Bound<'_, PyAny>>) -> PyResult<usize> {
    let n = stack.layers.len();
    let Some(obj) = layer else { return Ok(1) };
    if n == 0 {
        return count(obj, "layer");
    }
    // Any integer, however large or negative, then the library's words for
    // one that is not a layer.
    let layer = integer_in(obj, "layer", i128::MIN..=i128::MAX)?;
    if !(1..=n as i128).contains(&layer) {
        return Err(invalid(
            "layer",
            format!("must be between 1 and {n} (the stack's layers), got {layer}"),
        ));
    }
    Ok(layer as usize)
}

/// Thicknesses (nm) swept over one layer (1-based).
struct Sweep {
    layer: usize,
    thicknesses_nm: Vec<f64>,
}

/// Fewest points of a `Stack.solve` call that go to the thread pool:
/// below, the solve (about 0.2 µs a point) takes less than the handoff.
const SOLVE_PARALLEL_MIN_POINTS: usize = 256;

/// R, T and the amplitudes at every (thickness of the sweep, wavelength of
/// the grid, angle) point, angles fastest: a row of angles per task on the
/// current thread pool when `parallel`, else on this thread. Rows stop once
/// `cancel` is set (the points are then discarded).
fn solve_points(
    grid: &StackGrid,
    cos_theta0: &[f64],
    sweep: Option<&Sweep>,
    parallel: bool,
    cancel: &Cancel,
) -> Vec<Point> {
    let wavelengths = grid.wavelengths_nm();
    let runs = sweep.map_or(1, |s| s.thicknesses_nm.len());
    let mut points = vec![Point::default(); runs * wavelengths.len() * cos_theta0.len()];
    let fill_row = |(row, out): (usize, &mut [Point])| {
        if cancel.is_set() {
            return;
        }
        let (run, i) = (row / wavelengths.len(), row % wavelengths.len());
        let mut d = grid.thicknesses_nm().to_vec();
        if let Some(s) = sweep {
            d[s.layer - 1] = s.thicknesses_nm[run];
        }
        let n = grid.indices_at(i);
        let coherence = grid.coherence();
        for (p, &c) in out.iter_mut().zip(cos_theta0) {
            if !coherence.is_coherent() {
                // +∞ where a layer lases: `lasing_at` names it afterwards.
                let r = solve_mixed(n, &d, coherence, wavelengths[i], c);
                p.power = [r.rs, r.rp, r.ts, r.tp, r.r(), r.t()];
                continue;
            }
            // One recursion gives both: the power from the amplitudes is
            // what `solve` computes (it differs only at grazing, cos θ = 0).
            let a = solve_amplitudes(n, &d, wavelengths[i], c);
            let r = if c > 0.0 {
                power(n, c, &a)
            } else {
                solve(n, &d, wavelengths[i], c)
            };
            p.power = [r.rs, r.rp, r.ts, r.tp, r.r(), r.t()];
            p.amplitudes = [a.rs, a.rp, a.ts, a.tp];
        }
    };
    let row_len = cos_theta0.len().max(1);
    if parallel {
        points
            .par_chunks_mut(row_len)
            .enumerate()
            .for_each(fill_row);
    } else {
        points.chunks_mut(row_len).enumerate().for_each(fill_row);
    }
    points
}

/// The error for point `k` of [`solve_points`]' output, where an incoherent
/// layer lases (Ok if it does not).
fn lasing_at(
    grid: &StackGrid,
    cos_theta0: &[f64],
    sweep: Option<&Sweep>,
    k: usize,
) -> PyResult<()> {
    let (angles, wavelengths) = (cos_theta0.len(), grid.wavelengths_nm().len());
    let (row, a) = (k / angles, k % angles);
    let (run, i) = (row / wavelengths, row % wavelengths);
    let mut d = grid.thicknesses_nm().to_vec();
    if let Some(s) = sweep {
        d[s.layer - 1] = s.thicknesses_nm[run];
    }
    match grid.diverged(i, &d, cos_theta0[a]) {
        Some(lasing) => Err(py_error(
            lasing.error(grid.wavelengths_nm()[i], cos_theta0[a]),
        )),
        None => Ok(()),
    }
}

#[derive(Clone, Copy, Default)]
struct Point {
    power: [f64; 6],
    amplitudes: [C64; 4],
}
