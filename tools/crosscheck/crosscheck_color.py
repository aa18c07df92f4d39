#!/usr/bin/env python3
"""Cross-checks `irid color` against colour-science.

For a few stacks (soap films, a dispersive coating on glass, an absorbing
film, built-in TiO2 on gold, a bare interface), takes the reflectance and
transmittance spectra from `irid eval --json` at 1 nm over 360-830 nm,
integrates them with `colour.sd_to_XYZ` (CIE 1931 2 degree observer, CIE D65)
and converts to linear sRGB with colour-science's sRGB matrix. Compares with
`irid color --sampling exact --json` on the same stacks and angles:
|d linear sRGB| <= 2e-3 and |d XYZ| <= 2e-3.

The two sides differ on purpose in details that must not matter at that
tolerance: colour-science interpolates D65 (5 nm) with its own method and
extrapolates it beyond 780 nm; its sRGB matrix uses the rounded white
xy = (0.3127, 0.3290) while irid derives it from the tables' D65 white.

Also regenerates src/color/cie_tables.rs with tools/gen/gen_cie_tables.py and
checks it is byte-identical to the committed file (nobody edited it by hand).

Env: IRID_BIN (default target/release/irid). Exits non-zero on failure.
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

TOLERANCE = 2e-3
ANGLES_DEG = [0, 20, 45, 70, 85]


def soap_film(thickness_nm):
    return f"""
ambient = {{ n = 1.0 }}
substrate = {{ n = 1.0 }}
[[layers]]
n = 1.33
thickness_nm = {thickness_nm}
"""


STACKS = {
    **{f"soap-{d:g}nm": soap_film(d) for d in (120.0, 450.0, 950.0)},
    "dispersive-coating-on-glass": """
ambient = { n = 1.0 }
substrate = { cauchy = [1.5046, 0.0042, 0.0] }
[[layers]]
cauchy = [2.2, 0.03, 0.001]
thickness_nm = 210.0
[[layers]]
n = 1.38
thickness_nm = 95.0
""",
    "absorbing-film-on-glass": """
ambient = { n = 1.0 }
substrate = { n = 1.52 }
[[layers]]
n = [2.0, 0.4]
thickness_nm = 35.0
""",
    "tio2-on-gold": """
ambient = { n = 1.0 }
substrate = { material = "gold" }
[[layers]]
material = "TiO2"
thickness_nm = 140.0
""",
    "bare-glass": """
ambient = { n = 1.0 }
substrate = { n = 1.5 }
""",
}


def run_json(cmd):
    proc = subprocess.run(cmd, capture_output=True, text=True)
    if proc.returncode != 0:
        sys.exit(f"FAIL: {' '.join(cmd)} exited {proc.returncode}: {proc.stderr.strip()}")
    return json.loads(proc.stdout)


def tables_are_generated():
    repo = Path(__file__).resolve().parents[2]
    committed = repo / "src/color/cie_tables.rs"
    with tempfile.TemporaryDirectory() as tmp:
        fresh = Path(tmp) / "cie_tables.rs"
        subprocess.run([sys.executable, str(repo / "tools/gen/gen_cie_tables.py"), str(fresh)],
                       check=True, capture_output=True)
        if fresh.read_bytes() != committed.read_bytes():
            sys.exit(f"FAIL: {committed} differs from what tools/gen/gen_cie_tables.py writes")
    print(f"  {committed.relative_to(repo)} matches tools/gen/gen_cie_tables.py output")


def main():
    irid = os.environ.get("IRID_BIN", "target/release/irid")
    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"]
    d65 = colour.SDS_ILLUMINANTS["D65"]
    xyz_to_rgb = colour.RGB_COLOURSPACES["sRGB"].matrix_XYZ_to_RGB
    angles = ",".join(str(a) for a in ANGLES_DEG)

    worst_rgb = worst_xyz = 0.0
    worst_where = ""
    checked = 0
    failures = []
    with tempfile.TemporaryDirectory() as tmp:
        for name, text in STACKS.items():
            path = Path(tmp) / f"{name}.toml"
            path.write_text(text)
            spectra = run_json([irid, "eval", str(path), "--wavelengths", "360:830:1",
                                "--angles", angles, "--json"])
            colours = run_json([irid, "color", str(path), "--angles", angles,
                                "--sampling", "exact", "--json"])
            if len(colours) != len(ANGLES_DEG):
                sys.exit(f"FAIL: {name}: {len(colours)} colours for {len(ANGLES_DEG)} angles")
            for got in colours:
                angle = got["angle_deg"]
                rows = sorted((r for r in spectra if abs(r["angle_deg"] - angle) < 1e-9),
                              key=lambda r: r["wavelength_nm"])
                wl = np.array([r["wavelength_nm"] for r in rows])
                if len(wl) != 471:
                    sys.exit(f"FAIL: {name} {angle} deg: {len(wl)} wavelengths from eval")
                for key in ("R", "T"):
                    sd = colour.SpectralDistribution(np.array([r[key] for r in rows]), wl)
                    xyz = colour.sd_to_XYZ(sd, cmfs, d65) / 100.0
                    rgb = xyz_to_rgb @ xyz
                    kind = "reflectance" if key == "R" else "transmittance"
                    d_rgb = np.abs(rgb - np.array(got[f"{kind}_rgb"])).max()
                    d_xyz = np.abs(xyz - np.array(got[f"{kind}_xyz"])).max()
                    checked += 1
                    if max(d_rgb, d_xyz) > max(worst_rgb, worst_xyz):
                        worst_where = f"{name} {angle} deg {kind}"
                    worst_rgb = max(worst_rgb, d_rgb)
                    worst_xyz = max(worst_xyz, d_xyz)
                    if d_rgb > TOLERANCE or d_xyz > TOLERANCE:
                        failures.append(f"{name} {angle} deg {kind}: irid rgb "
                                        f"{got[kind + '_rgb']} vs colour {rgb.tolist()}")

    print(f"crosscheck_color: {checked} colours ({len(STACKS)} stacks x {len(ANGLES_DEG)} "
          f"angles x R,T) vs colour-science {colour.__version__} sd_to_XYZ")
    print(f"  max |d linear sRGB| = {worst_rgb:.2e}, max |d XYZ| = {worst_xyz:.2e} "
          f"(tolerance {TOLERANCE:g}; worst at {worst_where})")
    tables_are_generated()
    if failures:
        print("FAIL:\n  " + "\n  ".join(failures[:10]))
        sys.exit(1)
    print("OK")


if __name__ == "__main__":
    main()
