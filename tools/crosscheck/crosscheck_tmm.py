#!/usr/bin/env python3
"""Cross-checks `irid eval --json` against S. J. Byrnes' Python `tmm`
(`tmm.coh_tmm`, PyPI tmm) on random stacks.

Each stack draws: 0-12 layers (one in ten has 13-60), constant complex indices
(lossless, absorbing, and weak gain in finite layers), thicknesses 0-1500 nm,
an ambient of index 1-2 (so that some angles lie beyond the critical angle), a
substrate that is a lossless or lossy dielectric or a metal, 1-2 wavelengths in
300-900 nm and 1-3 angles in [0, 90) including near-grazing ones. All stacks
are written to a temporary folder and evaluated by one `irid eval` call.

Pass: |dRs|, |dRp|, |dTs|, |dTp| <= 1e-9 (relative to the value when it
exceeds 1, as gain stacks can reflect more than they receive). The samples
where irid and tmm differ most are then recomputed with mpmath at 80 digits
(characteristic matrices, an independent formulation), which irid must match
to 1e-11: this says which side a residual difference comes from.
Env: IRID_BIN (default target/release/irid), CROSSCHECK_STACKS (default 1200).
"""

import json
import math
import os
import subprocess
import sys
import tempfile

import mpmath
import numpy as np
import tmm

from random_stacks import random_lists, stack_toml

TOL = 1e-9
MP_TOL = 1e-11
MP_SAMPLES = 20
# Stacks draw their (wavelengths, angles) lists from a pool, so that stacks
# sharing lists go to irid in one call.
POOL = 24


def random_stack(rng, pool):
    layers = int(rng.integers(0, 13)) if rng.random() < 0.9 else int(rng.integers(13, 61))
    ambient = 1.0 if rng.random() < 0.5 else float(rng.uniform(1.0, 2.0))
    media = []
    for _ in range(layers):
        n = float(rng.uniform(1.0, 3.0))
        kind = rng.random()
        if kind < 0.5:
            k = 0.0
        elif kind < 0.85:
            k = float(rng.uniform(0.0, 1.0))
        else:
            k = -float(rng.uniform(0.0, 0.05))  # gain
        d = 0.0 if rng.random() < 0.05 else float(rng.uniform(0.0, 1500.0))
        media.append((complex(n, k), d))
    kind = rng.random()
    if kind < 0.4:
        substrate = complex(rng.uniform(1.0, 2.5), 0.0)
    elif kind < 0.7:
        substrate = complex(rng.uniform(1.0, 2.5), rng.uniform(0.0, 0.5))
    else:
        substrate = complex(rng.uniform(0.05, 2.0), rng.uniform(1.0, 8.0))
    wavelengths, angles = pool[int(rng.integers(0, len(pool)))]
    return ambient, media, substrate, wavelengths, angles


def reference(ambient, media, substrate, wavelength, angle_deg):
    n_list = [complex(ambient)] + [n for n, _ in media] + [substrate]
    d_list = [math.inf] + [d for _, d in media] + [math.inf]
    th = math.radians(angle_deg)
    out = {}
    for pol in "sp":
        res = tmm.coh_tmm(pol, n_list, d_list, th, wavelength)
        out["R" + pol] = float(res["R"])
        out["T" + pol] = float(res["T"])
    return out


def high_precision(ambient, media, substrate, wavelength, angle_deg):
    """Rs, Rp, Ts, Tp from the product of characteristic matrices in mpmath,
    tilted admittances eta_s = q, eta_p = n^2/q, q on the decaying branch."""
    mpmath.mp.dps = 80
    n_all = [mpmath.mpc(ambient)] + [mpmath.mpc(n) for n, _ in media] + [mpmath.mpc(substrate)]
    theta = mpmath.radians(mpmath.mpf(repr(angle_deg)))
    beta = n_all[0] * mpmath.sin(theta)

    def q_of(n):
        q = mpmath.sqrt(n * n - beta * beta)
        return -q if (q.imag < 0 or (q.imag == 0 and q.real < 0)) else q

    qs = [n_all[0] * mpmath.cos(theta)] + [q_of(n) for n in n_all[1:]]
    k0 = 2 * mpmath.pi / mpmath.mpf(repr(wavelength))
    out = {}
    for pol in "sp":
        eta = [q if pol == "s" else n * n / q for n, q in zip(n_all, qs)]
        m = mpmath.eye(2)
        for j, (_, d) in enumerate(media):
            delta = k0 * qs[j + 1] * mpmath.mpf(repr(d))
            e = eta[j + 1]
            m = m * mpmath.matrix([[mpmath.cos(delta), -1j * mpmath.sin(delta) / e],
                                   [-1j * e * mpmath.sin(delta), mpmath.cos(delta)]])
        b = m[0, 0] + m[0, 1] * eta[-1]
        c = m[1, 0] + m[1, 1] * eta[-1]
        den = eta[0] * b + c
        out["R" + pol] = float(abs((eta[0] * b - c) / den) ** 2)
        out["T" + pol] = float(4 * mpmath.re(eta[0]) * mpmath.re(eta[-1]) / abs(den) ** 2)
    return out


def main():
    import pathlib

    binary = os.environ.get("IRID_BIN", "target/release/irid")
    count = int(os.environ.get("CROSSCHECK_STACKS", "1200"))
    rng = np.random.default_rng(20261122)
    pool = [random_lists(rng, grazing_share=0.2) for _ in range(POOL)]
    stacks = [random_stack(rng, pool) for _ in range(count)]
    worst = 0.0
    worst_at = None
    differences = []  # (|d|, stack index, row) for the mpmath pass
    failures = []
    samples = 0
    with tempfile.TemporaryDirectory() as tmp:
        groups = {}
        for i, (ambient, media, substrate, wls, angles) in enumerate(stacks):
            path = pathlib.Path(tmp) / f"s{i:05d}.toml"
            path.write_text(stack_toml(ambient, media, substrate))
            key = (",".join(map(repr, wls)), ",".join(map(repr, angles)))
            groups.setdefault(key, []).append((i, path))
        for (wls, angles), members in groups.items():
            cmd = [binary, "eval", "--json", "--wavelengths", wls, "--angles", angles]
            cmd += [str(p) for _, p in members]
            run = subprocess.run(cmd, capture_output=True, text=True)
            if run.returncode != 0:
                print(f"irid failed ({run.returncode}): {run.stderr.strip()}")
                return 1
            outputs = run.stdout.splitlines()
            assert len(outputs) == len(members), "one JSON array per stack"
            for (i, _), line in zip(members, outputs):
                ambient, media, substrate, _, _ = stacks[i]
                for row in json.loads(line):
                    ref = reference(ambient, media, substrate, row["wavelength_nm"], row["angle_deg"])
                    samples += 1
                    differences.append((max(abs(row[k] - v) / max(1.0, abs(v)) for k, v in ref.items()), i, row, ref))
                    for key, want in ref.items():
                        got = row[key]
                        err = abs(got - want) / max(1.0, abs(want))
                        if not math.isfinite(got) or err > TOL:
                            failures.append((i, row["wavelength_nm"], row["angle_deg"], key, got, want))
                        elif err > worst:
                            worst = err
                            worst_at = (i, row["wavelength_nm"], row["angle_deg"], key, got, want)
                    if abs(row["R"] - (row["Rs"] + row["Rp"]) / 2) > 1e-15 or abs(row["T"] - (row["Ts"] + row["Tp"]) / 2) > 1e-15:
                        failures.append((i, row["wavelength_nm"], row["angle_deg"], "R/T mean", row["R"], row["T"]))
    print(f"crosscheck_tmm: {count} stacks, {samples} (wavelength, angle) samples, "
          f"worst |d| = {worst:.2e} (tolerance {TOL:.0e})")
    differences.sort(key=lambda x: x[0], reverse=True)
    mp_irid = mp_tmm = 0.0
    for _, i, row, ref in differences[:MP_SAMPLES]:
        ambient, media, substrate, _, _ = stacks[i]
        exact = high_precision(ambient, media, substrate, row["wavelength_nm"], row["angle_deg"])
        for key, want in exact.items():
            scale = max(1.0, abs(want))
            err = abs(row[key] - want) / scale
            mp_irid = max(mp_irid, err)
            mp_tmm = max(mp_tmm, abs(ref[key] - want) / scale)
            if err > MP_TOL:
                failures.append((i, row["wavelength_nm"], row["angle_deg"], key + " vs mpmath", row[key], want))
    print(f"  on the {MP_SAMPLES} samples where they differ most, against mpmath at 80 digits: "
          f"irid within {mp_irid:.1e}, tmm within {mp_tmm:.1e} (irid tolerance {MP_TOL:.0e})")
    if os.environ.get("CROSSCHECK_VERBOSE") and worst_at:
        i = worst_at[0]
        print("  worst at stack %d, %.3f nm, %.4f deg, %s: irid %r tmm %r" % worst_at)
        print("  ", stacks[i][:3])
    if failures:
        for f in failures[:10]:
            print("  FAIL stack %d at %.3f nm, %.4f deg: %s irid %r reference %r" % f)
        print(f"{len(failures)} failed, {max(0, samples * 4 - len(failures))} passed")
        return 1
    print(f"{samples * 4} passed, 0 failed")
    return 0


if __name__ == "__main__":
    sys.exit(main())
