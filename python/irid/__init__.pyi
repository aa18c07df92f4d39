"""Type stubs of the irid module (the native extension irid._irid)."""

import os
from typing import Any, Dict, List, Mapping, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

__version__: str

ArrayLike = npt.ArrayLike
PathLike = Union[str, "os.PathLike[str]"]

#: Any medium form of a stack file: n, (n, k), n + kj, a built-in name, a dict
#: of stack-file keys (n, material, cauchy, sellmeier, table, name) or a Material.
MediumForm = Union[float, complex, Tuple[float, float], str, Mapping[str, Any], "Material"]
#: A layer: (form, thickness_nm), (form, thickness_nm, coherent) (False: an
#: incoherent, thick layer), or a dict of stack-file keys with thickness_nm.
LayerForm = Union[Tuple[MediumForm, float], Tuple[MediumForm, float, bool], Mapping[str, Any]]

def coherent(
    n: ArrayLike,
    d: ArrayLike,
    angles: ArrayLike,
    wavelengths: ArrayLike,
) -> Dict[str, npt.NDArray[np.float64]]:
    """R and T of a coherent multilayer at every wavelength and angle, with the
    arguments and result of tmm-faster's ``calc_coherent``.

    n: complex n + ik (k > 0 absorbs, k < 0 is gain), shape (wavelengths,
    media), ambient first; a 1-D n is the same at every wavelength.
    d: thicknesses in nm, inf for the ambient and the substrate.
    angles: degrees in [0, 90]; wavelengths: nm.
    Returns R_s, R_p, T_s, T_p, R_avg, T_avg, each (wavelengths, angles).
    """

def incoherent(
    n: ArrayLike,
    d: ArrayLike,
    c: Sequence[str],
    angles: ArrayLike,
    wavelengths: ArrayLike,
) -> Dict[str, npt.NDArray[np.float64]]:
    """R and T of a multilayer with coherent and incoherent (thick) layers at
    every wavelength and angle, with the arguments and result of tmm-faster's
    ``calc_incoherent`` (Byrnes' ``inc_tmm`` formulation).

    c: one letter per medium, 'c' (coherent) or 'i' (incoherent), the ambient
    and substrate 'i'. n, d, angles, wavelengths and the result as for
    ``coherent``. A point where an incoherent layer lases raises ValueError.
    """

def material(name: str) -> Material:
    """The built-in material called ``name`` (case-insensitive, aliases such as "Au")."""

def materials() -> List[str]:
    """The names of the built-in materials."""

class Material:
    """A refractive-index model: constant, built-in, Cauchy, Sellmeier or table."""

    def __init__(self, form: Optional[MediumForm] = None, **fields: Any) -> None: ...
    @property
    def name(self) -> str: ...
    @property
    def range_nm(self) -> Tuple[float, float]:
        """The wavelength range (nm) over which the index is defined."""
    def index(self, wavelengths_nm: ArrayLike) -> Any:
        """Complex n + ik at each wavelength (nm): an array of the input's
        shape, or a complex number for a number."""

class Stack:
    """A planar multilayer: lossless ambient, layers from the top down, substrate."""

    def __init__(
        self,
        ambient: Optional[MediumForm] = None,
        layers: Optional[Sequence[LayerForm]] = None,
        substrate: Optional[MediumForm] = None,
    ) -> None: ...
    @staticmethod
    def load(path: PathLike) -> Stack:
        """Reads a stack file (TOML); table paths are relative to its folder."""
    @staticmethod
    def from_toml(text: str, base_dir: PathLike = ".") -> Stack:
        """Parses stack-file text; table paths are relative to ``base_dir``."""
    @property
    def ambient(self) -> Material: ...
    @property
    def substrate(self) -> Material: ...
    @property
    def layers(self) -> List[Tuple[Material, float]]: ...
    @property
    def coherent(self) -> List[bool]:
        """Per layer, top down: False for an incoherent layer."""
    def solve(
        self,
        wavelengths_nm: ArrayLike,
        angles_deg: ArrayLike,
        thickness_nm: Optional[ArrayLike] = None,
        layer: int = 1,
        gradient: bool = False,
    ) -> Dict[str, npt.NDArray[Any]]:
        """Rs, Rp, Ts, Tp, R, T (float64) and rs, rp, ts, tp (complex128), each
        (wavelengths, angles), or (thicknesses, wavelengths, angles) with
        ``thickness_nm`` setting layer ``layer`` (1-based). A stack with
        incoherent layers has no amplitudes: R and T only. gradient=True
        (not with thickness_nm) adds dRs_dd, dRp_dd, dTs_dd, dTp_dd, dR_dd,
        dT_dd, each (layers, wavelengths, angles): the exact derivatives
        per nm of each layer's thickness, top layer first."""
    def response(
        self,
        cos_theta: ArrayLike,
        wavelength_nm: ArrayLike,
        thickness_nm: Optional[ArrayLike] = None,
        layer: int = 1,
        side: str = "ambient",
    ) -> Tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]:
        """Unpolarized (R, T) at broadcast points, each its own wavelength;
        side "ambient" or "substrate" (light from a lossless substrate)."""
    def to_json(self) -> str:
        """The stack as JSON (a table header's "stack")."""
    @staticmethod
    def from_json(text: str) -> Stack:
        """A stack from the JSON of ``to_json``."""
    def color(
        self,
        angles_deg: ArrayLike,
        sampling: str = "exact",
        white: str = "d65",
        roughness: Optional[float] = None,
        gradient: bool = False,
    ) -> Dict[str, npt.NDArray[np.float64]]:
        """angle_deg, reflectance_rgb, transmittance_rgb (linear sRGB),
        reflectance_xyz, transmittance_xyz, each (angles, 3) but angle_deg.
        With roughness in [0, 1]: angle_deg, reflectance_rgb and
        reflectance_xyz of F_eff (the reflectance pre-integrated over a GGX
        lobe, docs/rough.md) and lobe_albedo (angles,), single scattering,
        and reflectance_ms_rgb, reflectance_ms_xyz, transmittance_ms_rgb,
        transmittance_ms_xyz (angles, 3): compensated for multiple
        scattering, to be multiplied by the same lobe albedos. gradient=True (not
        with roughness) adds dreflectance_rgb_dd, dtransmittance_rgb_dd,
        dreflectance_xyz_dd, dtransmittance_xyz_dd, each (layers, angles, 3):
        the exact derivatives per nm of each layer's thickness."""

def bake(
    stack: Stack,
    thickness_nm: Optional[Union[float, Tuple[float, float]]] = None,  # None: (0, 1000)
    layer: int = 1,
    max_error: Optional[float] = None,  # None: 1e-3 unless resolution is given
    *,
    resolution: Optional[Sequence[int]] = None,
    cos_theta: Optional[Union[float, Tuple[float, float]]] = None,
    kind: str = "rgb",
    sampling: str = "exact",
    wavelengths_nm: Optional[Tuple[float, float]] = None,
    half: bool = False,
    validation_points: int = 20000,
    check: bool = True,
    layout: Optional[str] = None,  # "atlas" or "grid"; None: atlas, grid with a resolution
) -> Lut:
    """Bakes a lookup table over a layer's thickness and cos θ, as ``irid bake``."""

class Lut:
    """A baked lookup table (OpenEXR with irid's JSON header)."""

    @staticmethod
    def load(path: PathLike) -> Lut: ...
    def save(self, path: PathLike) -> None: ...
    @property
    def header(self) -> Dict[str, Any]: ...
    @property
    def kind(self) -> str: ...
    @property
    def data(self) -> npt.NDArray[np.float32]: ...
    def sample(
        self,
        thickness_nm: ArrayLike,
        cos_theta: ArrayLike,
        wavelength_nm: Optional[ArrayLike] = None,
    ) -> Tuple[npt.NDArray[np.float32], npt.NDArray[np.float32]]:
        """(R, T) at broadcast points: rgb tables give (..., 3) linear sRGB.
        Coordinates beyond an axis (±inf included) take its end's value;
        NaN raises ValueError."""
    def validate(self, points: int = 20000, seed: int = 1) -> Dict[str, Any]:
        """The table against the solver at random points, as ``irid validate --json``."""

class RoughLut:
    """A rough table of ``irid bake --rough``: F_eff over thickness, cos θ
    and GGX roughness (OpenEXR with irid's "irid-rough" JSON header)."""

    @staticmethod
    def load(path: PathLike) -> RoughLut: ...
    @property
    def header(self) -> Dict[str, Any]: ...
    def sample(
        self,
        thickness_nm: ArrayLike,
        cos_theta: ArrayLike,
        roughness: ArrayLike,
    ) -> npt.NDArray[np.float32]:
        """F_eff at broadcast points, (..., 3) linear sRGB. Thickness and
        cos θ beyond the table take its end's value; NaN or a roughness
        outside [0, 1] raises ValueError."""

class Fit:
    """The result of ``fit``; array shapes lead with the batch shape (...),
    () for one spectrum."""

    stack: Optional[Stack]  # None for a batch
    layers: List[int]
    thickness_nm: npt.NDArray[np.float64]  # (..., layers)
    sigma_nm: npt.NDArray[np.float64]  # (..., layers)
    chi2: npt.NDArray[np.float64]  # (...)
    residual: npt.NDArray[np.float64]  # (...): rms of model - measured
    residual_R: Optional[npt.NDArray[np.float64]]  # (..., wavelengths, angles)
    residual_T: Optional[npt.NDArray[np.float64]]
    threshold: npt.NDArray[np.float64]  # (...)
    ambiguous: npt.NDArray[np.bool_]  # (...)
    alternatives: List[List[Tuple[List[float], float]]]
    degrees_of_freedom: int

class ColorFit:
    """The result of ``fit_color``."""

    stack: Stack
    layers: List[int]
    thickness_nm: npt.NDArray[np.float64]
    angle_deg: npt.NDArray[np.float64]
    delta_e2000: npt.NDArray[np.float64]
    rgb: npt.NDArray[np.float64]  # (angles, 3)
    ambiguous: bool
    tolerance_de2000: float
    alternatives: List[Tuple[List[float], List[float]]]  # (thicknesses, ΔE00 per angle)

def fit(
    stack: Stack,
    vary: Sequence[int],
    wavelengths_nm: ArrayLike,
    angles_deg: ArrayLike,
    R: Optional[ArrayLike] = None,
    T: Optional[ArrayLike] = None,
    sigma: Optional[ArrayLike] = None,
    bounds: Optional[Sequence[Tuple[float, float]]] = None,
) -> Fit:
    """Weighted least squares of the varied layers' thicknesses (1-based from
    the top) to R and/or T shaped (..., wavelengths, angles)."""

def fit_color(
    stack: Stack,
    vary: Sequence[int],
    angles_deg: ArrayLike,
    target_rgb: ArrayLike,
    white: str = "d65",
    roughness: Optional[float] = None,
    bounds: Optional[Sequence[Tuple[float, float]]] = None,
) -> ColorFit:
    """The thicknesses whose reflected colours come closest in CIEDE2000 to
    ``target_rgb`` (angles, 3) at ``angles_deg``."""
