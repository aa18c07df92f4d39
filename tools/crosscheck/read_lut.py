#!/usr/bin/env python3
"""Reads irid lookup tables with the official OpenEXR bindings and checks them
against independent implementations.

For each table: opens it with PyPI `OpenEXR`, parses the JSON header in the
`irid` attribute (docs/lut-format.md), rebuilds the axes from the listed nodes,
checks the image size and channel set against them, then recomputes a few
nodes from the header's stack alone:
  - spectral tables: unpolarized R and T from Python `tmm` (coh_tmm, s and p),
  - rgb tables (exact sampling): the tmm spectrum at 1 nm over 360-830 nm
    integrated with colour-science's sd_to_XYZ (CIE 1931 2 degree, D65) and
    converted with its sRGB matrix (the same comparison as crosscheck_color).
Tolerances: f32 tables 1e-5 (spectral) / 2e-3 (rgb, colour-science
integrates slightly differently); f16 tables add the f16 rounding (1e-3).

Usage: read_lut.py [TABLE.exr ...]. Without arguments it bakes a small rgb
table (f16), a small spectral table and a small rgb table without the bake
check (--no-check) with $IRID_BIN (default
target/release/irid) into a temporary directory, and reads every luts/*.exr.
Exits non-zero on any failure.
"""

import json
import os
import subprocess
import sys
import tempfile
import warnings
from pathlib import Path

warnings.filterwarnings("ignore")  # colour warns about optional scipy/matplotlib

import colour  # noqa: E402
import numpy as np  # noqa: E402
import OpenEXR  # noqa: E402
import tmm  # noqa: E402

REPO = Path(__file__).resolve().parents[2]
NODES_CHECKED = 8


def index_at(material, wavelength_nm):
    """The complex index of a serialized irid Material (serde JSON form)."""
    disp = material["dispersion"]
    um = wavelength_nm * 1e-3
    if "constant" in disp:
        return complex(disp["constant"]["n"], disp["constant"]["k"])
    if "cauchy" in disp:
        c = disp["cauchy"]
        return complex(c["a"] + c["b"] / um**2 + c["c"] / um**4, 0.0)
    if "sellmeier" in disp:
        s = disp["sellmeier"]
        n2 = s.get("a", 1.0) + sum(b * um**2 / (um**2 - c) for b, c in zip(s["b"], s["c"]))
        return complex(np.sqrt(n2), 0.0)
    if "table" in disp:
        t = disp["table"]
        return complex(np.interp(wavelength_nm, t["wavelength_nm"], t["n"]),
                       np.interp(wavelength_nm, t["wavelength_nm"], t["k"]))
    raise ValueError(f"unknown dispersion {list(disp)}")


def response(stack, layer, thickness_nm, cos_theta, wavelength_nm):
    """Unpolarized (R, T) by Byrnes' tmm."""
    n = [index_at(stack["ambient"], wavelength_nm).real]
    n += [index_at(l["material"], wavelength_nm) for l in stack["layers"]]
    n += [index_at(stack["substrate"], wavelength_nm)]
    d = [l["thickness_nm"] for l in stack["layers"]]
    if layer > 0:
        d[layer - 1] = thickness_nm
    d = [np.inf] + d + [np.inf]
    if cos_theta <= 0.0:
        return 1.0, 0.0
    th0 = np.arccos(min(cos_theta, 1.0))
    s = tmm.coh_tmm("s", n, d, th0, wavelength_nm)
    p = tmm.coh_tmm("p", n, d, th0, wavelength_nm)
    return 0.5 * (s["R"] + p["R"]), 0.5 * (s["T"] + p["T"])


def rgb_exact(stack, layer, t, c):
    wl = np.arange(360.0, 831.0, 1.0)
    spectra = np.array([response(stack, layer, t, c, w) for w in wl])
    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"]
    d65 = colour.SDS_ILLUMINANTS["D65"]
    m = colour.RGB_COLOURSPACES["sRGB"].matrix_XYZ_to_RGB
    out = []
    for k in range(2):
        sd = colour.SpectralDistribution(spectra[:, k], wl)
        out.append(m @ (colour.sd_to_XYZ(sd, cmfs, d65) / 100.0))
    return out


def check_table(path, rng):
    with OpenEXR.File(str(path), separate_channels=True) as f:
        # The header is a view of the open file: read what is needed inside.
        text = f.header().get("irid")
        channels = {name: np.array(ch.pixels) for name, ch in f.channels().items()}
    if text is None:
        sys.exit(f"FAIL: {path}: no 'irid' header attribute")
    h = json.loads(text)
    fail = lambda why: sys.exit(f"FAIL: {path}: {why}")  # noqa: E731
    # Version 2 differs from 1 only in allowing a null bake check.
    if h.get("format") != "irid-lut" or h.get("version") not in (1, 2, 3):
        fail(f"format {h.get('format')} version {h.get('version')}")
    axes = {a["name"]: np.array(a["nodes"]) for a in h["axes"]}
    t_nodes, c_nodes = axes["thickness_nm"], axes["cos_theta"]
    spectral = h["kind"] == "spectral"
    w_nodes = axes.get("wavelength_nm", np.array([0.0]))
    names = [c["name"] for c in h["channels"]]
    if set(names) != set(channels):
        fail(f"channels {sorted(channels)} vs header {names}")
    height = len(c_nodes) * (len(w_nodes) if spectral else 1)
    for name, px in channels.items():
        if px.shape != (height, len(t_nodes)):
            fail(f"channel {name} is {px.shape}, axes give {(height, len(t_nodes))}")
    half = h["precision"] == "f16"
    if any(px.dtype != (np.float16 if half else np.float32) for px in channels.values()):
        fail("sample type differs from the header's precision")
    if not spectral and h["color"]["sampling"] != "exact":
        print(f"  {path.name}: rgb with {h['color']['sampling']} sampling; "
              "only the layout is checked")
        return 0.0, 0
    worst = 0.0
    for _ in range(NODES_CHECKED):
        i, j = rng.integers(len(t_nodes)), rng.integers(len(c_nodes))
        t, c = t_nodes[i], c_nodes[j]
        if spectral:
            k = rng.integers(len(w_nodes))
            row = k * len(c_nodes) + j
            want = response(h["stack"], h["layer"], t, c, w_nodes[k])
            got = [channels["reflectance"][row, i], channels["transmittance"][row, i]]
            tol = 1e-3 if half else 1e-5
        else:
            r, tr = rgb_exact(h["stack"], h["layer"], t, c)
            want = list(r) + list(tr)
            got = [channels[n][j, i] for n in names]
            tol = 3e-3 if half else 2e-3
        err = float(np.max(np.abs(np.array(got, dtype=float) - np.array(want))))
        worst = max(worst, err)
        if err > tol:
            fail(f"node t={t} cos={c}: table {got} vs independent {want} (|d| {err:.2e} > {tol})")
    check = h["error"]["bake_check"]
    check = "not made" if check is None else f"{check['max_abs_all']:.2e}"
    print(f"  {path.name}: v{h['version']} {h['kind']} {h['precision']}, "
          f"{'x'.join(str(len(a)) for a in axes.values())} nodes, bake check {check}; "
          f"{NODES_CHECKED} nodes vs tmm{'' if spectral else ' + colour-science'}: "
          f"max |d| {worst:.2e}")
    return worst, NODES_CHECKED


def bake(irid, stack, out, *extra):
    cmd = [irid, "bake", str(REPO / "luts" / stack), "-o", str(out), "--validate-points", "200",
           *extra]
    proc = subprocess.run(cmd, capture_output=True, text=True)
    if proc.returncode != 0:
        sys.exit(f"FAIL: {' '.join(cmd)}: {proc.stderr.strip()}")
    return out


def main():
    rng = np.random.default_rng(12)
    tables = [Path(p) for p in sys.argv[1:]]
    with tempfile.TemporaryDirectory() as tmp:
        if not tables:
            irid = os.environ.get("IRID_BIN", "target/release/irid")
            tables.append(bake(irid, "two-layer.toml", Path(tmp) / "two-layer.exr",
                               "--thickness", "0:400", "--resolution", "9,5", "--half"))
            tables.append(bake(irid, "oil-on-water.toml", Path(tmp) / "oil.exr",
                               "--kind", "spectral", "--thickness", "100:600",
                               "--resolution", "11,7,9"))
            tables.append(bake(irid, "soap-film.toml", Path(tmp) / "soap-unchecked.exr",
                               "--thickness", "0:800", "--resolution", "17,9", "--no-check"))
            tables += sorted((REPO / "luts").glob("*.exr"))
        checked = 0
        for path in tables:
            checked += check_table(path, rng)[1]
    print(f"read_lut: {len(tables)} tables read with OpenEXR {OpenEXR.__version__}, "
          f"{checked} nodes agree with tmm {getattr(tmm, '__version__', '')}")


if __name__ == "__main__":
    main()
