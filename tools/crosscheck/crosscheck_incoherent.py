#!/usr/bin/env python3
"""Cross-checks `irid eval --json` on stacks that mix coherent and incoherent
(`coherent = false`) layers against S. J. Byrnes' `tmm.inc_tmm` (PyPI tmm
0.2.0), and against the definition of an incoherent layer: the coherent
answer averaged over the layer's phase.

Random stacks draw 1-10 layers, each incoherent with probability 0.35 (at
least one): incoherent layers lossless, weakly or strongly absorbing or
metallic, 0 or 1e3-1e6 nm thick; coherent layers lossless, absorbing or with
weak gain, 0-1500 nm; an ambient of index 1-2 (some angles lie beyond a
layer's critical angle), a lossless, lossy or metal substrate; 1-3
wavelengths in 300-900 nm and 1-3 angles in [0, 90) including 0 and 89.999.
Pass: |dRs|, |dRp|, |dTs|, |dTp| <= 1e-9 (relative above 1).

Where irid deliberately differs from inc_tmm the reference is adjusted, not
skipped: a lossless incoherent layer beyond its critical angle carries no
propagating wave and irid takes it as opaque (it reflects as a half-space,
T = 0), so inc_tmm is given the stack cut there, that layer as its
substrate (inc_tmm's own answer there is not physical: its arcsin branch
makes the layer amplify, and R can come out negative).

The phase average: with every incoherent layer's one-way factor written
|phi| e^(i theta), the coherent R and T (characteristic matrices, numpy)
averaged over theta on 256 or more points (the trapezoid rule converges
geometrically for these periodic functions). It checks what inc_tmm cannot:
incoherent gain layers (inc_tmm refuses gain next to an incoherent medium),
on the branch that carries power forward, below their lasing threshold.

Then the limits: an opaque incoherent layer whose P underflows (T exactly
0), a zero-thickness incoherent layer (two interfaces added in power, the
closed form of a slab), near-grazing incidence, an
incoherent layer at its own critical angle and one beyond it, a lasing gain
layer and a coherence flag on the ambient or substrate (one line, exit 2).
Env: IRID_BIN (default target/release/irid), CROSSCHECK_STACKS (default 500).
"""

import json
import math
import os
import pathlib
import re
import subprocess
import sys
import tempfile
import warnings

import mpmath
import numpy as np
import tmm

from random_stacks import random_lists, stack_toml

TOL = 1e-9
PHASE_TOL = 1e-9
PHASES = 256
POOL = 24


def incoherent_layer(rng):
    kind = rng.random()
    if kind < 0.5:
        n = complex(rng.uniform(1.0, 3.0), 0.0)
    elif kind < 0.8:
        n = complex(rng.uniform(1.0, 3.0), rng.uniform(0.0, 1e-3))
    elif kind < 0.93:
        n = complex(rng.uniform(1.0, 3.0), rng.uniform(0.0, 0.5))
    else:
        n = complex(rng.uniform(0.05, 2.0), rng.uniform(1.0, 8.0))
    d = 0.0 if rng.random() < 0.08 else float(10 ** rng.uniform(3.0, 6.0))
    return n, d, False


def coherent_layer(rng):
    kind = rng.random()
    if kind < 0.5:
        k = 0.0
    elif kind < 0.88:
        k = float(rng.uniform(0.0, 1.0))
    else:
        k = -float(rng.uniform(0.0, 0.05))
    d = 0.0 if rng.random() < 0.05 else float(rng.uniform(0.0, 1500.0))
    return complex(rng.uniform(1.0, 3.0), k), d, True


def random_stack(rng, pool):
    count = int(rng.integers(1, 11))
    media = [incoherent_layer(rng) if rng.random() < 0.35 else coherent_layer(rng) for _ in range(count)]
    if all(c for _, _, c in media):
        media[int(rng.integers(0, count))] = incoherent_layer(rng)
    ambient = 1.0 if rng.random() < 0.5 else float(rng.uniform(1.0, 2.0))
    kind = rng.random()
    if kind < 0.4:
        substrate = complex(rng.uniform(1.0, 2.5), 0.0)
    elif kind < 0.7:
        substrate = complex(rng.uniform(1.0, 2.5), rng.uniform(0.0, 0.5))
    else:
        substrate = complex(rng.uniform(0.05, 2.0), rng.uniform(1.0, 8.0))
    wavelengths, angles = pool[int(rng.integers(0, len(pool)))]
    return ambient, media, substrate, wavelengths, angles


def evanescent(n, ambient, angle_deg):
    """A lossless medium beyond its critical angle (or at it), as irid
    decides it: (n^2 - n0^2) + (n0 cos)^2 <= 0."""
    q0 = ambient * math.cos(math.radians(angle_deg))
    return n.imag == 0.0 and (n.real * n.real - ambient * ambient) + q0 * q0 <= 0.0


def byrnes(ambient, media, substrate, wavelength, angle_deg):
    """tmm.inc_tmm's Rs, Rp, Ts, Tp; a stack with a lossless incoherent layer
    beyond its critical angle is cut there, that layer becoming the
    substrate (irid's opaque layer: R of what is above it, T = 0)."""
    cut = next((j for j, (n, _, c) in enumerate(media) if not c and evanescent(n, ambient, angle_deg)), None)
    if cut is not None:
        out = byrnes(ambient, media[:cut], media[cut][0], wavelength, angle_deg)
        return out and {**out, "Ts": 0.0, "Tp": 0.0}
    n_list = [complex(ambient)] + [n for n, _, _ in media] + [substrate]
    d_list = [math.inf] + [d for _, d, _ in media] + [math.inf]
    c_list = ["i"] + ["c" if c else "i" for _, _, c in media] + ["i"]
    th = math.radians(angle_deg)
    out = {}
    for pol in "sp":
        try:
            res = tmm.inc_tmm(pol, n_list, d_list, c_list, th, wavelength)
        except AssertionError:
            # tmm cannot tell the forward wave from the backward one in a
            # medium it sees at grazing incidence (n cos theta ~ 1e-12).
            return None
        out["R" + pol] = float(res["R"])
        out["T" + pol] = float(res["T"])
    return out


def phase_average(ambient, media, substrate, wavelength, angle_deg):
    """[`phase_average_on`] with the number of phases doubled from 256 until
    two agree to 1e-13 (near a lasing threshold the terms decay slowly)."""
    phases = PHASES
    last = phase_average_on(ambient, media, substrate, wavelength, angle_deg, phases)
    while phases < 65536:
        phases *= 2
        now = phase_average_on(ambient, media, substrate, wavelength, angle_deg, phases)
        if all(abs(now[k] - last[k]) <= 1e-13 * max(1.0, abs(now[k])) for k in now):
            return now
        last = now
    return last


def phase_average_on(ambient, media, substrate, wavelength, angle_deg, phases):
    """R and T averaged over every incoherent layer's phase: the coherent
    answer from characteristic matrices (admittances q for s, n^2/q for p),
    each incoherent layer's delta = theta + i k0 Im(q) d, q on the branch
    that carries power forward. Vectorized over the grid of phases."""
    n_all = [complex(ambient)] + [n for n, _, _ in media] + [substrate]
    theta0 = math.radians(angle_deg)
    beta_sq = (ambient * math.sin(theta0)) ** 2
    k0 = 2 * math.pi / wavelength

    def q_decaying(n):
        q = np.sqrt(complex(n * n - beta_sq))
        return -q if (q.imag < 0 or (q.imag == 0 and q.real < 0)) else q

    q_all = [complex(ambient * math.cos(theta0))] + [q_decaying(n) for n in n_all[1:]]
    incoherent = [j for j, (_, _, c) in enumerate(media, start=1) if not c]
    grids = np.meshgrid(*[np.arange(phases) * (2 * math.pi / phases)] * len(incoherent), indexing="ij")
    theta = {j: g.ravel() for j, g in zip(incoherent, grids)}
    size = phases ** len(incoherent)
    out = {}
    for pol in "sp":
        eta = [q if pol == "s" else n * n / q for n, q in zip(n_all, q_all)]
        m = np.broadcast_to(np.eye(2, dtype=complex), (size, 2, 2)).copy()
        for j, (n, d, coherent) in enumerate(media, start=1):
            q = q_all[j]
            if coherent:
                delta = np.full(size, k0 * q * d)
            else:
                if q.real < 0:  # gain: the wave that carries power forward
                    q = -q
                delta = theta[j] + 1j * k0 * q.imag * d
            e = q if pol == "s" else n * n / q
            c, s = np.cos(delta), np.sin(delta)
            layer = np.empty((size, 2, 2), dtype=complex)
            layer[:, 0, 0] = c
            layer[:, 0, 1] = -1j * s / e
            layer[:, 1, 0] = -1j * e * s
            layer[:, 1, 1] = c
            m = m @ layer
        b = m[:, 0, 0] + m[:, 0, 1] * eta[-1]
        cc = m[:, 1, 0] + m[:, 1, 1] * eta[-1]
        den = eta[0] * b + cc
        out["R" + pol] = float(np.mean(np.abs((eta[0] * b - cc) / den) ** 2))
        out["T" + pol] = float(np.mean(4 * eta[0].real * eta[-1].real / np.abs(den) ** 2))
    return out


LASES = re.compile(r"^irid: (\S+\.toml): layers\[(\d+)\]: this incoherent layer lases at (\S+) nm, (\S+)°")


def run_irid(binary, cases, tmp, tag):
    """irid eval --json on every case, in one call per (wavelengths, angles)
    list; returns per case its list of rows, or for a stack irid refuses
    because an incoherent layer lases, (layer, wavelength, angle) of the
    point it names (the call is then repeated without that stack)."""
    groups = {}
    for i, (ambient, media, substrate, wls, angles) in enumerate(cases):
        path = pathlib.Path(tmp) / f"{tag}{i:05d}.toml"
        path.write_text(stack_toml(ambient, media, substrate))
        key = (",".join(map(repr, wls)), ",".join(map(repr, angles)))
        groups.setdefault(key, []).append((i, str(path)))
    rows = [None] * len(cases)
    for (wls, angles), members in groups.items():
        while members:
            cmd = [binary, "eval", "--json", "--wavelengths", wls, "--angles", angles] + [p for _, p in members]
            run = subprocess.run(cmd, capture_output=True, text=True)
            lases = LASES.match(run.stderr)
            if run.returncode == 2 and lases:
                i = next(i for i, p in members if p == lases.group(1))
                rows[i] = (int(lases.group(2)), float(lases.group(3)), float(lases.group(4)))
                members = [(j, p) for j, p in members if j != i]
                continue
            if run.returncode != 0:
                raise SystemExit(f"irid failed ({run.returncode}): {run.stderr.strip()}")
            for (i, _), line in zip(members, run.stdout.splitlines()):
                rows[i] = json.loads(line)
            break
    return rows


def compare(got, want, tol):
    return max(abs(got[k] - v) / max(1.0, abs(v)) if math.isfinite(got[k]) else math.inf for k, v in want.items())


def check_random(binary, rng, count, tmp, failures):
    pool = [random_lists(rng, grazing_share=0.15) for _ in range(POOL)]
    cases = [random_stack(rng, pool) for _ in range(count)]
    results = run_irid(binary, cases, tmp, "r")
    worst, samples, adjusted, unanswered = 0.0, 0, 0, 0
    phase_worst, phase_samples = 0.0, 0
    lasing = []
    for i, rows in enumerate(results):
        ambient, media, substrate, _, _ = cases[i]
        if isinstance(rows, tuple):
            lasing.append((i, rows))
            continue
        for row in rows:
            w, a = row["wavelength_nm"], row["angle_deg"]
            adjusted += any(not c and evanescent(n, ambient, a) for n, _, c in media)
            want = byrnes(ambient, media, substrate, w, a)
            if want is None:
                unanswered += 1
            else:
                err = compare(row, want, TOL)
                samples += 1
                worst = max(worst, err)
                if err > TOL:
                    failures.append(f"stack {i} at {w} nm, {a} deg: {err:.2e} from inc_tmm: {cases[i][:3]}")
            # The phase average, with one incoherent layer (see the module's
            # text), not evanescent, and matrices that stay finite.
            inc = [(n, d) for n, d, c in media if not c]
            thin = all(d * 2 * math.pi / w * abs(n.imag) < 5 for n, d, _ in media)
            if len(inc) == 1 and thin and not any(evanescent(n, ambient, a) for n, _ in inc) and a < 89:
                err = compare(row, phase_average(ambient, media, substrate, w, a), TOL)
                phase_samples += 1
                if err > phase_worst and os.environ.get("CROSSCHECK_VERBOSE"):
                    print("phase", err, (ambient, media, substrate, w, a), row)
                phase_worst = max(phase_worst, err)
    print(f"crosscheck_incoherent: {count} random mixed stacks, {samples} (wavelength, angle) samples "
          f"({adjusted} with an evanescent incoherent layer), worst |d| from tmm.inc_tmm = {worst:.2e} "
          f"(tolerance {TOL:.0e}); tmm asserted on {unanswered} near-grazing samples")
    print(f"  phase average of the coherent answer on {phase_samples} of them, with one incoherent layer: "
          f"worst |d| = {phase_worst:.2e} (tolerance {PHASE_TOL:.0e})")
    if phase_worst > PHASE_TOL:
        failures.append(f"phase average differs by {phase_worst:.2e}")
    # A divergent sum shows in inc_tmm's power matrices as a negative power
    # (a negative 1 - |r'|^2 P^2 rho): the independent sign of a refusal.
    for i, (layer, w, a) in lasing:
        ambient, media, substrate, _, _ = cases[i]
        want = byrnes(ambient, media, substrate, w, a)
        if want is not None and all(math.isfinite(v) and v >= 0 for v in want.values()):
            failures.append(f"stack {i} refused at {w} nm, {a} deg (layer {layer}), but inc_tmm finds {want}")
    print(f"  {len(lasing)} stacks refused because an incoherent layer lases (coherent gain films beside it); "
          f"inc_tmm gives a negative power at each point named")


def gain_cases(rng, count):
    """Stacks with one incoherent gain layer below its lasing threshold:
    weak gain over a moderate thickness."""
    cases = []
    while len(cases) < count:
        pool = [random_lists(rng, grazing_share=0.15)]
        ambient, media, substrate, wls, angles = random_stack(rng, pool)
        media = [m for m in media if m[2]][:3]
        gain = (complex(rng.uniform(1.3, 2.5), -rng.uniform(1e-5, 3e-4)), float(rng.uniform(100.0, 3000.0)), False)
        media.insert(int(rng.integers(0, len(media) + 1)), gain)
        angles = [a for a in angles if a < 89] or [0.0]
        cases.append((ambient, media, substrate, wls, angles))
    return cases


def check_gain(binary, rng, tmp, failures):
    cases = gain_cases(rng, 40)
    results = run_irid(binary, cases, tmp, "g")
    worst, samples, refused = 0.0, 0, 0
    for i, rows in enumerate(results):
        ambient, media, substrate, _, _ = cases[i]
        if isinstance(rows, tuple):
            refused += 1
            continue
        for row in rows:
            w, a = row["wavelength_nm"], row["angle_deg"]
            want = phase_average(ambient, media, substrate, w, a)
            err = compare(row, want, PHASE_TOL)
            worst = max(worst, err)
            samples += 1
            if err > PHASE_TOL:
                failures.append(f"gain stack {i} at {w} nm, {a} deg: {err:.2e} from the phase average: {cases[i][:3]}")
    print(f"  {len(cases)} stacks with an incoherent gain layer ({refused} refused as lasing), {samples} samples: "
          f"worst |d| from the phase average ({PHASES} phases) = {worst:.2e} (tolerance {PHASE_TOL:.0e}; "
          f"inc_tmm refuses gain)")


def eval_one(binary, tmp, name, text, wavelengths, angles):
    path = pathlib.Path(tmp) / f"{name}.toml"
    path.write_text(text)
    cmd = [binary, "eval", "--json", "--wavelengths", wavelengths, "--angles", angles, str(path)]
    return subprocess.run(cmd, capture_output=True, text=True)


def slab_near_grazing(n, angle_deg):
    """A lossless incoherent slab of index n in vacuum, in mpmath at 50
    digits: R = 2 R1 / (1 + R1), T = 1 - R, R1 each face's Fresnel power."""
    mpmath.mp.dps = 50
    th = mpmath.radians(mpmath.mpf(repr(angle_deg)))
    c, q = mpmath.cos(th), mpmath.sqrt(n * n - mpmath.sin(th) ** 2)
    out = {}
    for pol, r in (("s", (c - q) / (c + q)), ("p", (n * n * c - q) / (n * n * c + q))):
        r1 = r * r
        out["R" + pol] = float(2 * r1 / (1 + r1))
        out["T" + pol] = float(1 - 2 * r1 / (1 + r1))
    return out


def check_limits(binary, tmp, failures):
    def expect(name, cond, detail):
        if not cond:
            failures.append(f"limit '{name}': {detail}")

    def rows_of(name, ambient, media, substrate, wavelengths, angles):
        run = eval_one(binary, tmp, name, stack_toml(ambient, media, substrate), wavelengths, angles)
        expect(name, run.returncode == 0, run.stderr.strip())
        return json.loads(run.stdout) if run.returncode == 0 else []

    def against_tmm(name, ambient, media, substrate, wavelengths="450,633", angles="0,40,75,89.999"):
        rows = rows_of(name, ambient, media, substrate, wavelengths, angles)
        for row in rows:
            err = compare(row, byrnes(ambient, media, substrate, row["wavelength_nm"], row["angle_deg"]), TOL)
            expect(name, err <= TOL, f"{err:.2e} from inc_tmm at {row['wavelength_nm']} nm, {row['angle_deg']} deg")
        return rows

    coating = [(complex(1.38, 0.0), 100.0, True)]
    # An opaque incoherent layer: e^(-2 k0 k d) underflows; nothing crosses.
    rows = against_tmm("opaque", 1.0, coating + [(complex(1.5, 0.5), 1e7, False)] + coating, complex(1.5, 0))
    expect("opaque", all(r["Ts"] == 0.0 and r["Tp"] == 0.0 for r in rows), "T is not exactly 0")
    # A zero-thickness incoherent layer: a lossless slab's two interfaces in
    # power, R = 2 R1 / (1 + R1) at normal incidence.
    rows = against_tmm("zero thickness", 1.0, [(complex(1.5, 0.0), 0.0, False)], complex(1.0, 0))
    r1 = (0.5 / 2.5) ** 2
    expect("zero thickness", abs(rows[0]["Rs"] - 2 * r1 / (1 + r1)) < 1e-15, f"R = {rows[0]['Rs']!r}")
    # Several incoherent layers with metals between them, and near grazing.
    against_tmm("several", 1.0, [(complex(1.52, 0), 1e6, False), (complex(0.2, 3.4), 20.0, True),
                                 (complex(1.33, 1e-6), 5e5, False), (complex(2.1, 0.0), 80.0, True),
                                 (complex(1.45, 0), 2e6, False)], complex(0.05, 4.0))
    # Near grazing incidence a glass sheet in air: tmm's cos(arcsin) loses
    # digits there, so the reference is the slab's closed form in mpmath,
    # R = 2 R1 / (1 + R1) (exactly 90 degrees, where R = 1 and T = 0, is
    # the Python interface's test: irid eval takes angles below 90).
    rows = rows_of("grazing", 1.0, [(complex(1.5, 0), 1e6, False)], complex(1.0, 0), "550", "89.9,89.999999")
    for row in rows:
        want = slab_near_grazing(1.5, row["angle_deg"])
        err = max(abs(row[k] - v) for k, v in want.items())
        expect("grazing", err < 1e-13, f"{err:.2e} from the closed form at {row['angle_deg']} deg")
    # From glass (n = 1.5) an incoherent water layer is at its own critical
    # angle near 62.46 deg and evanescent beyond it, where it reflects
    # everything; R and T are continuous across (inc_tmm given the cut stack).
    crit = math.degrees(math.asin(1.33 / 1.5))
    water = [(complex(1.38, 0), 120.0, True), (complex(1.33, 0), 2e4, False), (complex(1.38, 0), 120.0, True)]
    against_tmm("critical", 1.5, water, complex(1.5, 0), "500", f"{crit - 1e-3!r},70,80")
    # Within 1e-7 deg of it q is ~1e-4 and set by rounding in beta (no two
    # codes agree to 1e-9 there): R and T must only run on continuously.
    near = [crit - 1e-3, crit - 1e-7, crit, crit + 1e-7, 70.0, 80.0]
    rows = rows_of("critical", 1.5, water, complex(1.5, 0), "500", ",".join(map(repr, near)))
    expect("critical", all(abs(r["R"] - 1) < 1e-3 and r["T"] < 1e-3 for r in rows[1:]), f"{rows}")
    expect("critical", all(abs(r["R"] - 1) < 1e-15 and r["T"] == 0.0 for r in rows[-3:]), f"{rows}")
    # Bad input: a lasing gain layer; the flag on a half-space.
    lasing = stack_toml(1.0, [(complex(1.5, -0.01), 1e6, False)], complex(1.5, 0))
    for name, text, needle in [
        ("lasing", lasing, "layers[1]: this incoherent layer lases"),
        ("ambient flag", "ambient = { n = 1.0, coherent = false }\nsubstrate = { n = 1.5 }\n", "ambient.coherent: not allowed"),
        ("substrate flag", "ambient = { n = 1.0 }\nsubstrate = { n = 1.5, coherent = true }\n", "substrate.coherent: not allowed"),
    ]:
        run = eval_one(binary, tmp, name.replace(" ", "-"), text, "550", "0")
        lines = run.stderr.strip().splitlines()
        expect(name, run.returncode == 2 and len(lines) == 1 and needle in lines[0] and not run.stdout,
               f"exit {run.returncode}, stderr {run.stderr!r}")


def main():
    # tmm overflows and divides by zero on the way to its (finite) answers,
    # as the phase average does for its far-off phases.
    np.seterr(all="ignore")
    warnings.simplefilter("ignore", RuntimeWarning)
    binary = os.environ.get("IRID_BIN", "target/release/irid")
    count = int(os.environ.get("CROSSCHECK_STACKS", "500"))
    rng = np.random.default_rng(20261203)
    failures = []
    with tempfile.TemporaryDirectory() as tmp:
        check_random(binary, rng, count, tmp, failures)
        check_gain(binary, rng, tmp, failures)
        check_limits(binary, tmp, failures)
    if failures:
        for f in failures[:10]:
            print("  FAIL", f)
        print(f"{len(failures)} failed")
        return 1
    print("  limits (opaque, zero thickness, several incoherent layers, grazing, critical and "
          "evanescent incoherent layers, lasing and misplaced flags): passed")
    return 0


if __name__ == "__main__":
    sys.exit(main())
