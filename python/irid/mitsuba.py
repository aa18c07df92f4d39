"""irid's exact thin films in Mitsuba 3: the ``irid_film`` BSDF.

``register()`` adds the BSDF ``irid_film`` to the current Mitsuba variant
(``scalar_spectral`` or ``llvm_ad_spectral``; other spectral, unpolarized
variants are accepted but untested). Its parameters:

- ``stack``: an ``irid.Stack`` (``register()`` lets ``mi.load_dict`` take
  one), a stack file path, or a stack's JSON (``stack.to_json()``);
- ``layer``: the layer whose thickness varies, 1-based from the ambient side
  (default 1);
- ``thickness_nm``: a number, or any Mitsuba texture (a bitmap with
  ``raw: True``, noise, a checkerboard...) whose value is the thickness in nm;
- ``table`` (optional): the path of an irid spectral table baked for this
  stack and layer over 360–830 nm (``irid.bake(stack, kind="spectral",
  wavelengths_nm=(360, 830), thickness_nm=(lo, hi)).save(path)``), looked
  up in Dr.Jit instead of solving;
- ``roughness`` (optional, default 0): 0 is a mirror-smooth film; above 0 a
  GGX lobe (alpha = roughness², height-correlated Smith G2, the film's
  Fresnel per microfacet at v·h); a texture gives a roughness per point
  (a rough lobe everywhere, roughness below 0.01 taken as 0.01).

``mi.traverse(scene)`` lists each film's ``thickness_nm`` (its value, or
its texture's parameters) and ``roughness``; both are differentiable in
the AD variants (docs/mitsuba.md, "Inverse rendering").

Light from the ambient side (the side the shape's normal points to) is
reflected with the film's R; a lossless substrate transmits the film's T,
refracted by the substrate's index relative to the ambient's (with total
internal reflection from the dense side); an absorbing substrate transmits
nothing and its back side is black, as Mitsuba's ``conductor``. See
docs/mitsuba.md.
"""

import json
import os

import numpy as np

from . import Lut, Stack

#: The wavelengths Mitsuba's spectral variants sample (MI_CIE_MIN, MI_CIE_MAX).
SPECTRAL_RANGE_NM = (360.0, 830.0)
#: Where the direction of refraction is taken for a dispersive ambient or
#: substrate (the sodium D line, where glass indices are quoted).
REFRACTION_WAVELENGTH_NM = 589.3
#: irid's thickest accepted layer (irid::optics::MAX_THICKNESS_NM).
MAX_THICKNESS_NM = 1e12

_PLUGIN = "irid_film"


class FilmError(ValueError):
    """Bad input to ``irid_film``: one line, ``irid_film: <what>: <why>``."""

    def __init__(self, what, why):
        super().__init__(f"{_PLUGIN}: {what}: {why}")


def register(symbolic=False):
    """Adds the BSDF ``irid_film`` to the current Mitsuba variant.

    The plugin accepts unpolarized spectral variants; in any other (RGB,
    mono, polarized) loading an ``irid_film`` raises at ``load_dict`` time.

    In the JIT variants a film without a table calls irid's solver on the
    CPU between Dr.Jit kernels, which symbolic loops and calls cannot do:
    ``register()`` therefore turns ``dr.JitFlag.SymbolicLoops`` and
    ``SymbolicCalls`` off in the calling thread (Dr.Jit's flags are per
    thread: render in this one). ``register(symbolic=True)`` leaves them on,
    for scenes whose films all have tables; loading a film without a table
    then raises.
    """
    import mitsuba as mi

    variant = mi.variant()
    if variant is None:
        raise RuntimeError(f"{_PLUGIN}: no Mitsuba variant set: call mi.set_variant('llvm_ad_spectral') first")
    if not symbolic and variant.startswith(("llvm_", "cuda_")):
        import drjit as dr

        dr.set_flag(dr.JitFlag.SymbolicLoops, False)
        dr.set_flag(dr.JitFlag.SymbolicCalls, False)
    mi.register_bsdf(_PLUGIN, lambda props: _film_class(variant, symbolic)(props))
    _accept_stacks_in_load_dict(mi)


def _stacks_as_json(value):
    """``value`` (a scene dict or any part of it) with every ``irid.Stack``
    given as an ``irid_film``'s ``stack`` written as its JSON."""
    if not isinstance(value, dict):
        return value
    out = {key: _stacks_as_json(item) for key, item in value.items()}
    if out.get("type") == _PLUGIN and isinstance(out.get("stack"), Stack):
        out["stack"] = out["stack"].to_json()
    return out


def _accept_stacks_in_load_dict(mi):
    """Mitsuba's scene dicts hold only its own types (an ``irid.Stack`` makes
    ``load_dict`` raise nanobind's type error); ``register()`` therefore
    wraps ``mi.load_dict`` once so that an ``irid_film``'s ``stack`` may be
    an ``irid.Stack``. (Mitsuba's ``load_dict`` is one function for every
    variant: it loads in the current one, so the wrapper holds across
    ``mi.set_variant``.)"""
    original = mi.load_dict
    if getattr(original, "_irid_wrapper", False):
        return

    def load_dict(scene, *args, **kwargs):
        return original(_stacks_as_json(scene), *args, **kwargs)

    load_dict._irid_wrapper = True
    load_dict.__doc__ = mi.load_dict.__doc__
    mi.load_dict = load_dict


def bsdf(stack, thickness_nm, layer=1, table=None, roughness=0.0):
    """The scene-dict entry of an ``irid_film``, checked when made.

    ``stack`` may be an ``irid.Stack`` (written as its JSON) or a stack file
    path; ``thickness_nm`` a number or a texture dict. Raises ``FilmError``
    (a ``ValueError``) for bad input, as loading the dict would.
    """
    entry = {"type": _PLUGIN, "stack": stack.to_json() if isinstance(stack, Stack) else os.fspath(stack)}
    entry.update(layer=layer, thickness_nm=thickness_nm, roughness=roughness)
    if table is not None:
        entry["table"] = os.fspath(table)
    _FilmSetup.from_values(entry)
    return entry


# ---------------------------------------------------------------------------
# Parameters, checked once when the plugin is loaded.


class _FilmSetup:
    """Everything ``irid_film`` needs that does not depend on the variant:
    the stack, the layer, the table, the roughness, the refraction indices."""

    def __init__(self, stack, layer, thickness, table, roughness):
        self.stack = stack
        self.layer = layer
        self.thickness = thickness  # a float, or the caller's texture
        self.table = table
        self.roughness = roughness  # a float, or the caller's texture
        self.textured_roughness = _is_texture(roughness)
        #: Whether the film is a rough lobe (a textured roughness always is).
        self.rough = self.textured_roughness or roughness > 0.0
        wavelengths = np.linspace(*SPECTRAL_RANGE_NM, 471)
        indices = _media_indices(stack, wavelengths)
        self.transmissive = not np.any(indices[-1].imag != 0.0)
        ambient, substrate = (
            complex(m.index(REFRACTION_WAVELENGTH_NM)).real for m in (stack.ambient, stack.substrate)
        )
        #: n_substrate / n_ambient: the relative index light from the ambient sees.
        self.eta = substrate / ambient
        #: n_substrate / n_ambient at every nm of SPECTRAL_RANGE_NM, for the
        #: angle in the ambient that light from the substrate corresponds to.
        self.eta_per_nm = (indices[-1].real / indices[0].real).astype(np.float32)
        if self.rough and self.transmissive and abs(self.eta - 1.0) < 1e-6:
            raise FilmError(
                "roughness",
                "a rough film with the same index on both sides refracts nothing (its transmission is "
                "straight through, not a microfacet lobe); give roughness 0",
            )
        if table is not None:
            _check_table(table, stack, layer, thickness)
            if self.transmissive and not all(np.all(i.imag == 0.0) for i in indices[1:-1]):
                raise FilmError(
                    "table",
                    "a table holds the ambient side only; light from a lossless substrate through "
                    "absorbing layers needs the solver (drop 'table')",
                )

    @staticmethod
    def from_values(values):
        """Checks a dict of parameter values (numbers, strings, textures)."""
        known = {"type", "stack", "layer", "thickness_nm", "table", "roughness", "id"}
        unknown = sorted(set(values) - known)
        if unknown:
            raise FilmError(unknown[0], "unknown parameter (irid_film takes stack, layer, thickness_nm, table, roughness)")
        if "stack" not in values:
            raise FilmError("stack", "missing: give a stack file path or an irid.Stack's to_json()")
        stack = _load_stack(values["stack"])
        layer = values.get("layer", 1)
        if isinstance(layer, bool) or not isinstance(layer, (int, float)) or not float(layer).is_integer():
            raise FilmError("layer", f"must be a whole number, got {layer!r}")
        layer = int(layer)
        count = len(stack.layers)
        if count == 0:
            raise FilmError("stack", "has no layers: there is no film for thickness_nm to set")
        if not 1 <= layer <= count:
            raise FilmError("layer", f"must be between 1 and {count} (the stack's layers), got {layer}")
        if "thickness_nm" not in values:
            raise FilmError("thickness_nm", "missing: give a number (nm) or a texture")
        thickness = values["thickness_nm"]
        if isinstance(thickness, (int, float)) and not isinstance(thickness, bool):
            thickness = float(thickness)
            if not 0.0 <= thickness <= MAX_THICKNESS_NM:
                raise FilmError("thickness_nm", f"must be finite, ≥ 0 and ≤ {MAX_THICKNESS_NM:g}, got {thickness}")
        roughness = values.get("roughness", 0.0)
        if not _is_texture(roughness):
            if isinstance(roughness, bool) or not isinstance(roughness, (int, float)) or not 0.0 <= float(roughness) <= 1.0:
                # A short value as written; anything else by its type (a repr can run to pages).
                shown = repr(roughness) if isinstance(roughness, (str, int, float)) and len(repr(roughness)) <= 40 else type(roughness).__name__
                raise FilmError("roughness", f"must be a number in [0, 1] or a texture, got {shown}")
            roughness = float(roughness)
        table = None
        if values.get("table") is not None:
            path = values["table"]
            try:
                table = Lut.load(path)
            except (OSError, ValueError) as e:
                raise FilmError("table", str(e)) from None
        return _FilmSetup(stack, layer, thickness, table, roughness)


def _is_texture(value):
    """A texture's scene-dict entry, or the Mitsuba texture made of one."""
    return isinstance(value, dict) or hasattr(value, "eval_1")


def _load_stack(value):
    if not isinstance(value, str):
        raise FilmError("stack", f"expected a stack file path or a stack's JSON, got {type(value).__name__}")
    try:
        if value.lstrip().startswith("{"):
            return Stack.from_json(value)
        return Stack.load(value)
    except (OSError, ValueError) as e:
        raise FilmError("stack", str(e)) from None


def _media_indices(stack, wavelengths):
    """Every medium's complex index over ``wavelengths``, ambient first; a
    material that does not cover Mitsuba's spectral range is refused here
    rather than in the middle of a render."""
    media = [("ambient", stack.ambient)]
    media += [(f"layers[{i + 1}]", m) for i, (m, _) in enumerate(stack.layers)]
    media.append(("substrate", stack.substrate))
    out = []
    for field, material in media:
        lo, hi = material.range_nm
        if lo > SPECTRAL_RANGE_NM[0] or hi < SPECTRAL_RANGE_NM[1]:
            raise FilmError(
                f"stack: {field}",
                f"{material.name} is defined over {lo:g}–{hi:g} nm; Mitsuba samples "
                f"{SPECTRAL_RANGE_NM[0]:g}–{SPECTRAL_RANGE_NM[1]:g} nm",
            )
        out.append(np.asarray(material.index(wavelengths)))
    return out


def _check_table(table, stack, layer, thickness):
    header = table.header
    if table.kind != "spectral":
        raise FilmError("table", f"an {table.kind} table; irid_film needs a spectral one (irid bake --kind spectral)")
    if header["stack"] != json.loads(stack.to_json()) or header["layer"] != layer:
        raise FilmError("table", "baked for another stack or layer than the one given")
    nodes = {a["name"]: a["nodes"] for a in header["axes"]}
    w = nodes["wavelength_nm"]
    if w[0] > SPECTRAL_RANGE_NM[0] or w[-1] < SPECTRAL_RANGE_NM[1]:
        raise FilmError(
            "table",
            f"covers {w[0]:g}–{w[-1]:g} nm; Mitsuba samples {SPECTRAL_RANGE_NM[0]:g}–"
            f"{SPECTRAL_RANGE_NM[1]:g} nm (bake with --wavelengths 360:830)",
        )
    t = nodes["thickness_nm"]
    if isinstance(thickness, float) and not t[0] <= thickness <= t[-1]:
        raise FilmError("thickness_nm", f"{thickness:g} nm is outside the table's {t[0]:g}–{t[-1]:g} nm")


# ---------------------------------------------------------------------------
# The BSDF, made once per variant (its base class is the variant's mi.BSDF).

_classes = {}


def _film_class(variant, symbolic):
    key = (variant, symbolic)
    if key not in _classes:
        from . import _mitsuba_bsdf

        _classes[key] = _mitsuba_bsdf.make_class(variant, symbolic)
    return _classes[key]


def ggx_lambda(alpha, cos_theta):
    """Smith's Λ of GGX for a direction at ``cos_theta`` from the normal
    (numpy or Dr.Jit arrays): (−1 + √(1 + α² tan²θ)) / 2."""
    cos2 = cos_theta * cos_theta
    tan2 = (1.0 - cos2) / cos2
    return 0.5 * (-1.0 + (1.0 + alpha * alpha * tan2) ** 0.5)


__all__ = ["FilmError", "SPECTRAL_RANGE_NM", "bsdf", "register"]
