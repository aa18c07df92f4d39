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
    "incoherent",
    "material",
    "materials",
]
