"""Shared set-up of the irid_film tests: Mitsuba variants, scenes, colour
differences (CIEDE2000 by colour-science, an implementation independent of
irid's). A module of its own name, not conftest.py, so that the tests can
import it by name even when pytest collects python/tests (which has its own
conftest) in the same run; conftest.py holds the fixtures."""

import warnings
from pathlib import Path

import numpy as np

with warnings.catch_warnings():
    warnings.simplefilter("ignore")
    import colour

import drjit as dr
import mitsuba as mi

import irid
import irid.mitsuba

REPO = Path(__file__).resolve().parents[2]
LUTS = REPO / "luts"
JIT = "llvm_ad_spectral"
SCALAR = "scalar_spectral"

#: A 300 nm film of n = 1.5 on gold: the opaque case (a film over a metal).
FILM_ON_GOLD = irid.Stack(ambient=1.0, layers=[(1.5, 300.0)], substrate="gold")
#: A quarter-wave MgF2 coating on glass (n = 1.5): lossless, transmissive, TIR from the glass side.
COATED_GLASS = irid.Stack(ambient=1.0, layers=[("MgF2", 250.0)], substrate=1.5)
#: A soap film in air: free-standing and lossless.
SOAP = irid.Stack.load(LUTS / "soap-film.toml")


def use(variant, symbolic=False):
    """Switches Mitsuba to ``variant`` with irid_film registered; in a JIT
    variant, symbolic loops and calls as asked."""
    mi.set_variant(variant)
    if variant != SCALAR:
        dr.set_flag(dr.JitFlag.SymbolicLoops, True)
        dr.set_flag(dr.JitFlag.SymbolicCalls, True)
    irid.mitsuba.register(symbolic=symbolic)


def orthographic_sphere(bsdf, size, max_depth=2, integrator="path"):
    """A unit sphere filling an orthographic view of [-1, 1]² under the
    constant emitter (CIE D65 at luminance 1), looked at along −z, with
    ``integrator`` (``direct``: emitter sampling only)."""
    if integrator == "direct":
        rendering = {"type": "direct", "emitter_samples": 1, "bsdf_samples": 0}
    else:
        rendering = {"type": integrator, "max_depth": max_depth}
    return mi.load_dict(
        {
            "type": "scene",
            "integrator": rendering,
            "emitter": {"type": "constant"},
            "sensor": {
                "type": "orthographic",
                "to_world": mi.ScalarTransform4f().look_at(origin=[0, 0, 4], target=[0, 0, 0], up=[0, 1, 0]),
                "sampler": {"type": "stratified"},
                "film": {"type": "hdrfilm", "width": size, "height": size, "rfilter": {"type": "box"}},
            },
            "sphere": {"type": "sphere", "bsdf": bsdf},
        }
    )


SRGB_TO_XYZ = np.array(
    [[0.4124564, 0.3575761, 0.1804375], [0.2126729, 0.7151522, 0.0721750], [0.0193339, 0.1191920, 0.9503041]]
)
D65_WHITE_XYZ = SRGB_TO_XYZ.sum(axis=1)


def delta_e(xyz_a, xyz_b):
    """CIEDE2000 between XYZ colours (Y = 1 for the white), white D65."""
    white = colour.XYZ_to_xy(D65_WHITE_XYZ)
    lab = [colour.XYZ_to_Lab(np.asarray(x), white) for x in (xyz_a, xyz_b)]
    return colour.delta_E(lab[0], lab[1], method="CIE 2000")


def rgb_to_xyz(rgb):
    return np.asarray(rgb) @ SRGB_TO_XYZ.T
