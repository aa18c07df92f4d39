"""irid: exact thin-film optics (the transfer-matrix method) on numpy arrays.

- ``coherent(n, d, angles, wavelengths)``: R and T over a wavelength x angle
  grid with the arguments and result of tmm-faster's ``calc_coherent``.
- ``incoherent(n, d, c, angles, wavelengths)``: the same with thick
  (incoherent) layers, the arguments and result of tmm-faster's
  ``calc_incoherent`` (c: 'c' or 'i' per medium).
- ``Stack``: a multilayer from any stack-file material form (or
  ``Stack.load(path)``); ``solve`` gives R, T and the complex amplitudes,
  ``color`` the reflected and transmitted colour.
- ``Material`` / ``material(name)``: refractive-index models and the
  built-in library; ``.index(wavelengths_nm)``.
- ``bake(stack, ...) -> Lut``: a lookup table over a layer's thickness and
  the angle, saved as OpenEXR; ``Lut.sample`` interpolates it as a renderer does.
- ``RoughLut.load(path)``: the rough table of ``irid bake --rough``;
  ``RoughLut.sample(thickness_nm, cos_theta, roughness)`` gives F_eff (RGB).
- ``fit(stack, vary, wavelengths_nm, angles_deg, R=..., T=..., sigma=...,
  bounds=...)``: layer thicknesses from measured spectra (one, or a batch
  shaped (..., wavelengths, angles)), with σ, χ² and an ambiguity report;
  ``fit_color(stack, vary, angles_deg, target_rgb)``: thicknesses from
  colours seen at angles (docs/inverse.md).
- ``irid.mitsuba`` (imported on its own, needs the ``mitsuba`` package): the
  ``irid_film`` BSDF for Mitsuba 3's spectral variants.

Computation runs on the package's thread pool with the GIL released
(``RAYON_NUM_THREADS`` sets its size); a fork()ed child builds its own.
Errors carry the one-line message the ``irid`` command prints: ``TypeError``
for an argument of a type its parameter never takes, ``ValueError`` for a
value or content irid refuses, ``OSError`` (its subclass) for a file the
system cannot open, read or write, ``MemoryError`` for a call above the
memory budget (``IRID_MEMORY_LIMIT``, else half the machine's memory).
"""

from ._irid import (
    Lut,
    Material,
    RoughLut,
    Stack,
    __version__,
    bake,
    coherent,
    fit as _fit,
    fit_color as _fit_color,
    incoherent,
    material,
    materials,
)

__all__ = [
    "Lut",
    "Material",
    "RoughLut",
    "Stack",
    "__version__",
    "bake",
    "coherent",
    "fit",
    "fit_color",
    "incoherent",
    "material",
    "materials",
]


class Fit:
    """The result of ``fit``: ``stack`` (the fitted stack; None for a batch),
    ``layers`` (the varied layers, 1-based), ``thickness_nm`` and
    ``sigma_nm`` (..., layers), ``chi2``, ``residual`` (the rms of model -
    measured), ``threshold`` and ``ambiguous`` (...), ``residual_R`` and
    ``residual_T`` (..., wavelengths, angles, or None),
    ``degrees_of_freedom``, and ``alternatives``: per spectrum, a list of
    (thicknesses, chi2) of other minima the data cannot tell from the best.
    ``...`` is the batch shape, () for one spectrum."""

    def __init__(self, fields):
        self.__dict__.update(fields)

    def __repr__(self):
        return "irid.Fit(thickness_nm={!r}, sigma_nm={!r}, chi2={!r})".format(
            self.thickness_nm, self.sigma_nm, self.chi2
        )


class ColorFit:
    """The result of ``fit_color``: ``stack``, ``layers``, ``thickness_nm``,
    ``angle_deg``, ``delta_e2000`` (per angle), ``rgb`` (the fitted
    colours, (angles, 3)), ``ambiguous``, ``tolerance_de2000`` and
    ``alternatives``: a list of (thicknesses, ΔE00 per angle) of other
    minima, more than 10 nm away, whose largest ΔE00 over the angles is
    within ``tolerance_de2000`` of the best's: the colours at these angles
    cannot tell them apart (add angles to decide)."""

    def __init__(self, fields):
        self.__dict__.update(fields)

    def __repr__(self):
        return "irid.ColorFit(thickness_nm={!r}, delta_e2000={!r})".format(
            self.thickness_nm, self.delta_e2000
        )


def fit(stack, vary, wavelengths_nm, angles_deg, R=None, T=None, sigma=None, bounds=None):
    """Weighted least squares of the thicknesses of layers ``vary`` (1-based
    from the top) to measured R and/or T, each (wavelengths, angles) or a
    batch (..., wavelengths, angles) fitted in parallel; ``sigma`` a number,
    (wavelengths, angles) or R's shape (None: unknown, sigma_nm scaled by the
    fit's scatter); ``bounds`` one (lo, hi) in nm per varied layer (None:
    +-50 % around the stack's thicknesses, which start the fit). The search
    is global within the bounds (docs/inverse.md)."""
    return Fit(_fit(stack, vary, wavelengths_nm, angles_deg, R, T, sigma, bounds))


def fit_color(stack, vary, angles_deg, target_rgb, white="d65", roughness=None, bounds=None):
    """The thicknesses of layers ``vary`` whose reflected colours (linear sRGB
    under ``white``) come closest in CIEDE2000 to ``target_rgb`` (angles, 3)
    at ``angles_deg``; with ``roughness``, the rough film's colours of
    ``Stack.color(roughness=)``. A target no passive film can reflect is a
    ValueError naming it."""
    return ColorFit(_fit_color(stack, vary, angles_deg, target_rgb, white, roughness, bounds))
