#!/usr/bin/env python3
"""Cross-checks the built-in material library.

1. src/optics/library_data.rs regenerates byte-identically from
   tools/gen/data/*.csv (tools/gen/gen_materials.py).
2. Each built-in material, put under an ambient of n = 1.5 as a substrate,
   reflects what Fresnel's equations give for the index computed here
   independently: the dielectrics from each publication's formula in its
   own form (Ciddor's n − 1 for air, Malitson's and Dodge's resonance
   wavelengths), the metals and TiO2 by linear interpolation of the CSV.
   Checked at 0° and 30°, 300-850 nm, through `irid eval --json`.

Pass: |dRs|, |dRp| <= 1e-12 (5e-9 for air, which irid evaluates in a
Sellmeier form that matches Ciddor's n to 4e-9 over 300-850 nm). Env: IRID_BIN (default
target/release/irid).
"""

import cmath
import csv
import json
import math
import os
import pathlib
import subprocess
import sys
import tempfile

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "tools" / "gen"))
import gen_materials  # noqa: E402

N_AMBIENT = 1.5
ANGLES = (0.0, 30.0)


def sellmeier_resonances(terms):
    """n² = 1 + Σ B λ² / (λ² − λᵢ²), λᵢ in µm."""
    return lambda um: math.sqrt(1 + sum(b * um**2 / (um**2 - l**2) for b, l in terms))


def daimon_water(um):
    """Daimon & Masumura 2007, 20.0 °C: n² − 1 = Σ B λ² / (λ² − C), C in µm²."""
    terms = [(5.684027565e-1, 5.101829712e-3), (1.726177391e-1, 1.821153936e-2),
             (2.086189578e-2, 2.620722293e-2), (1.130748688e-1, 1.069792721e1)]
    return math.sqrt(1 + sum(b * um**2 / (um**2 - c) for b, c in terms))


def ciddor_air(um):
    s2 = 1 / um**2
    return 1 + 0.05792105 / (238.0185 - s2) + 0.00167917 / (57.362 - s2)


def table(stem):
    rows = [r for r in csv.reader(l for l in (ROOT / "tools" / "gen" / "data" / f"{stem}.csv").read_text().splitlines()
                                  if l and l[0].isdigit())]
    wl_nm = np.array([float(r[0]) * 1000 for r in rows])
    n = np.array([float(r[1]) for r in rows])
    k = np.array([float(r[2]) for r in rows])
    return lambda um: complex(np.interp(um * 1000, wl_nm, n), np.interp(um * 1000, wl_nm, k))


MATERIALS = {
    "air": (ciddor_air, 5e-9),
    "water": (daimon_water, 1e-12),
    "soap": (daimon_water, 1e-12),
    "fused-silica": (sellmeier_resonances([(0.6961663, 0.0684043), (0.4079426, 0.1162414), (0.8974794, 9.896161)]), 1e-12),
    "TiO2": (table("tio2"), 1e-12),
    "MgF2": (sellmeier_resonances([(0.48755108, 0.04338408), (0.39875031, 0.09461442), (2.3120353, 23.793604)]), 1e-12),
    "sapphire": (sellmeier_resonances([(1.4313493, 0.0726631), (0.65054713, 0.1193242), (5.3414021, 18.028251)]), 1e-12),
    "gold": (table("gold"), 1e-12),
    "silver": (table("silver"), 1e-12),
    "aluminium": (table("aluminium"), 1e-12),
    "copper": (table("copper"), 1e-12),
}


def fresnel(n, angle_deg):
    c = math.cos(math.radians(angle_deg))
    beta2 = N_AMBIENT**2 * (1 - c * c)
    q0 = N_AMBIENT * c
    q = cmath.sqrt(complex(n) ** 2 - beta2)
    if q.imag < 0 or (q.imag == 0 and q.real < 0):
        q = -q
    rs = (q0 - q) / (q0 + q)
    rp = (n * n * q0 - N_AMBIENT**2 * q) / (n * n * q0 + N_AMBIENT**2 * q)
    return abs(rs) ** 2, abs(rp) ** 2


def main():
    failures = []
    with tempfile.TemporaryDirectory() as tmp:
        regenerated = pathlib.Path(tmp) / "library_data.rs"
        gen_materials.main(regenerated)
        committed = ROOT / "src" / "optics" / "library_data.rs"
        if regenerated.read_bytes() != committed.read_bytes():
            failures.append("src/optics/library_data.rs differs from what tools/gen/gen_materials.py generates")

        binary = os.environ.get("IRID_BIN", "target/release/irid")
        wavelengths = sorted(set([300.0 + 25.0 * i for i in range(23)] + [381.5, 548.6, 659.5, 821.1, 333.3]))
        paths = []
        for name in MATERIALS:
            path = pathlib.Path(tmp) / f"{name}.toml"
            path.write_text(f'ambient = {{ n = {N_AMBIENT} }}\nsubstrate = {{ material = "{name}" }}\n')
            paths.append(path)
        run = subprocess.run(
            [binary, "eval", "--json", "--wavelengths", ",".join(map(repr, wavelengths)),
             "--angles", ",".join(map(repr, ANGLES))] + [str(p) for p in paths],
            capture_output=True, text=True)
        if run.returncode != 0:
            print(f"irid failed ({run.returncode}): {run.stderr.strip()}")
            return 1
        checked = 0
        worst = {}
        for (name, (index, tol)), line in zip(MATERIALS.items(), run.stdout.splitlines()):
            for row in json.loads(line):
                want = fresnel(index(row["wavelength_nm"] / 1000), row["angle_deg"])
                for key, w in zip(("Rs", "Rp"), want):
                    err = abs(row[key] - w)
                    worst[name] = max(worst.get(name, 0.0), err)
                    checked += 1
                    if not err <= tol:
                        failures.append(f"{name} at {row['wavelength_nm']} nm, {row['angle_deg']}°: "
                                        f"{key} irid {row[key]!r}, expected {w!r}")
    print(f"crosscheck_materials: {len(MATERIALS)} materials, {checked} reflectances; worst |dR|: "
          + ", ".join(f"{k} {v:.0e}" for k, v in worst.items()))
    for f in failures[:10]:
        print("  FAIL", f)
    print(f"{checked + 1 - len(failures)} passed, {len(failures)} failed")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
