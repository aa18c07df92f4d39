#!/usr/bin/env python3
"""Times irid against independent TMM implementations on the same stacks and
the same wavelength x angle (x thickness) grids, checks that every peer agrees
with irid to 1e-9 in R and T, and writes the ratios to peers.md.

Peers: Byrnes' `tmm` (pure Python, one point per call), `colour-science`
(`colour.phenomena.multilayer_tmm`, numpy-vectorized over wavelengths and
angles) and `tmm-faster` (C++ with OpenMP, vectorized over wavelengths and
angles). irid and tmm-faster get the same number of threads (--threads,
default 2: this machine's core count); the two Python peers run on one core.

irid is driven through `irid bench --grid`, which reports its own wall time
for the computation and the complex indices it used at each wavelength; the
peers are fed exactly those indices, so every implementation solves the same
problem. Times are the best of --repeat runs; process start-up and I/O are
outside every timed region.

Usage: IRID_BIN=target/release/irid python tools/bench/bench_peers.py -o RUN_DIR [--quick]
RUN_DIR is the run's directory under benches/results/ (the one `irid bench`
just wrote, benches/results/DATE-MACHINE), so peers.md sits beside report.md.
Exits non-zero if a peer disagrees with irid by more than 1e-9.
"""

import argparse
import datetime
import json
import math
import os
import platform
import subprocess
import sys
import tempfile

THREADS_DEFAULT = 2
os.environ.setdefault("OMP_NUM_THREADS", str(THREADS_DEFAULT))

import numpy as np  # noqa: E402

import peer_calls  # noqa: E402
from peer_calls import best_of  # noqa: E402

TOLERANCE = 1e-9
STACKS = ["soap", "absorbing", "gain-on-gold", "two-layer", "mirror-front", "mirror-back"]
# Stacks with incoherent layers: irid against tmm-faster's calc_incoherent and
# Byrnes' inc_tmm.
INCOHERENT_STACKS = ["coated-sheet"]
# (bench stack, its file, thickness range) for the whole-process default bake.
PROCESS_BAKES = [("soap", "luts/soap-film.toml", "0:1000")]


def irid_bin():
    return os.environ.get("IRID_BIN", "target/release/irid")


def run_irid(stack, threads, repeat, *extra):
    """Runs `irid bench --grid` and returns its JSON document and R, T arrays
    shaped [angle][thickness][wavelength]."""
    with tempfile.TemporaryDirectory() as tmp:
        raw = os.path.join(tmp, "grid.raw")
        cmd = [
            irid_bin(), "bench", "--grid", stack,
            "--threads", str(threads), "--repeat", str(repeat), "--raw", raw, *extra,
        ]
        out = subprocess.run(cmd, check=True, capture_output=True, text=True)
        doc = json.loads(out.stdout)
        data = np.fromfile(raw, dtype="<f8")
    assert doc["layout"] == ["angle", "thickness", "wavelength"], doc["layout"]
    n_w, n_a = len(doc["wavelengths_nm"]), len(doc["angles_deg"])
    n_t = 1 if doc["thicknesses_nm"] is None else len(doc["thicknesses_nm"])
    half = data.size // 2
    shape = (n_a, n_t, n_w)
    return doc, data[:half].reshape(shape), data[half:].reshape(shape)


def indices(doc):
    """[wavelength][medium] complex indices, as irid used them."""
    return np.array(doc["indices_re"]) + 1j * np.array(doc["indices_im"])


def tmm_faster_grid(n_matrix, thicknesses_nm, angles_deg, wavelengths_nm):
    import tmm_faster

    d = [np.inf, *thicknesses_nm, np.inf]
    res = tmm_faster.calc_coherent(n_matrix, d, angles_deg, wavelengths_nm)
    # [wavelength][angle] -> [angle][wavelength]
    return res["R_avg"].T, res["T_avg"].T


def letters(coherent):
    """calc_incoherent's c from irid's per-layer flags."""
    return ["i", *("c" if flag else "i" for flag in coherent), "i"]


def tmm_faster_incoherent_grid(n_matrix, thicknesses_nm, c, angles_deg, wavelengths_nm):
    """tmm-faster's calc_incoherent, R and T as [angle][wavelength]."""
    import tmm_faster

    d = [np.inf, *thicknesses_nm, np.inf]
    res = tmm_faster.calc_incoherent(n_matrix, d, c, angles_deg, wavelengths_nm)
    return res["R_avg"].T, res["T_avg"].T


def colour_grid(n_matrix, thicknesses_nm, angles_deg, wavelengths_nm):
    """colour-science's R, T as [angle][wavelength], irid's layout."""
    r, t = peer_calls.colour_grid(n_matrix, thicknesses_nm, angles_deg, wavelengths_nm)
    return r.T, t.T


def byrnes_grid(n_matrix, thicknesses_nm, angles_deg, wavelengths_nm, coherence=None):
    """Byrnes' tmm's R, T as [angle][wavelength], irid's layout (inc_tmm
    with `coherence`, the letters of calc_incoherent's c)."""
    r, t = peer_calls.byrnes_grid(n_matrix, thicknesses_nm, angles_deg, wavelengths_nm, coherence)
    return r.T, t.T


def compare(r, t, pr, pt, grazing):
    """How a peer's R, T differ from irid's: max |dR| and |dT| away from
    grazing incidence, max of either at exactly 90 degrees (`grazing`: a mask
    broadcastable to r), and how many points the peer left NaN."""
    bad = ~(np.isfinite(pr) & np.isfinite(pt))
    pr, pt = np.where(bad, r, pr), np.where(bad, t, pt)
    dr, dt = np.abs(r - pr), np.abs(t - pt)
    grazing = np.broadcast_to(grazing, r.shape)
    away = ~grazing
    return {
        "R": float(dr[away].max(initial=0.0)),
        "T": float(dt[away].max(initial=0.0)),
        "grazing": float(np.maximum(dr, dt)[grazing].max(initial=0.0)),
        "nan": int(bad.sum()),
        "points": int(r.size),
    }


def agrees(c):
    return max(c["R"], c["T"], c["grazing"]) <= TOLERANCE and c["nan"] == 0


def finding(where, peer, c):
    parts = []
    if c["R"] > TOLERANCE:
        parts.append(f"R by up to {c['R']:.2e}")
    if c["T"] > TOLERANCE:
        parts.append(f"T by up to {c['T']:.2e}")
    if c["grazing"] > TOLERANCE:
        parts.append(f"R or T by {c['grazing']:.2e} at exactly 90°")
    if c["nan"]:
        parts.append(f"NaN at {c['nan']} of {c['points']} points")
    return f"{where}: {peer} differs from irid in " + ", ".join(parts)


def colour_dispersion_probe():
    """A one-film dispersive stack at 45°: does colour-science agree with
    Byrnes' tmm at every wavelength, or only at the first one given?"""
    import tmm

    w = np.array([400.0, 500.0, 600.0])
    n = np.array([[1.0, 1.0, 1.0], [2.7, 2.5, 2.4], [1.47, 1.46, 1.45]])
    r, _ = colour_grid(n.T, [60.0], np.array([45.0]), w)
    ref = []
    for i, wl in enumerate(w):
        sp = [tmm.coh_tmm(p, list(n[:, i]), [np.inf, 60.0, np.inf], math.radians(45), wl) for p in "sp"]
        ref.append(0.5 * (sp[0]["R"] + sp[1]["R"]))
    ok = np.abs(r[0] - np.array(ref)) <= TOLERANCE
    if ok.all():
        return None
    return (
        "colour-science probe (one dispersive film, 45°, 400/500/600 nm): agrees with Byrnes' tmm at "
        + ", ".join(f"{wl:.0f} nm" for wl, good in zip(w, ok) if good)
        + " and not at "
        + ", ".join(f"{wl:.0f} nm" for wl, good in zip(w, ok) if not good)
        + ": it appears to refract every wavelength with the indices of the first one"
        if ok[0] and not ok[1:].any()
        else f"colour-science probe: |ΔR| = {np.abs(r[0] - np.array(ref))} against Byrnes' tmm"
    )


def tmm_faster_absorbing_substrate_probe():
    """One film on an absorbing substrate at 45°: which of R_s, R_p, T_s, T_p
    does tmm-faster compute differently from Byrnes' tmm?"""
    import tmm
    import tmm_faster

    n = [1.0, 1.5, 0.4 + 2.4j]
    d = [np.inf, 250.0, np.inf]
    got = tmm_faster.calc_coherent(np.array([n], dtype=complex), d, np.array([45.0]), np.array([550.0]))
    sp = {p: tmm.coh_tmm(p, n, d, math.radians(45), 550.0) for p in "sp"}
    want = {"R_s": sp["s"]["R"], "R_p": sp["p"]["R"], "T_s": sp["s"]["T"], "T_p": sp["p"]["T"]}
    off = [k for k, v in want.items() if not abs(float(got[k][0, 0]) - v) <= TOLERANCE]
    if not off:
        return None
    return (
        "tmm-faster probe (film on a substrate with n = 0.4 + 2.4i, 45°, 550 nm): it differs from Byrnes' tmm in "
        + ", ".join(f"{k} ({float(got[k][0, 0]):.6f} vs {want[k]:.6f})" for k in off)
        + "; the other components agree, so the two define p-transmittance into an absorbing "
        "substrate differently (Byrnes and irid: Re(n conj(cos θ)) over the incident flux)"
    )


def cpu_model():
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown"


def peer_versions():
    from importlib.metadata import version

    return {p: version(p) for p in ("tmm", "colour-science", "tmm_faster", "numpy")}


def general_rows(args, failures, findings):
    """One wavelength x angle grid per stack, every implementation."""
    rows = []
    for stack in STACKS:
        doc, r, t = run_irid(stack, args.threads, args.repeat,
                             "--wavelengths", args.wavelengths, "--angles", args.angles)
        r, t = r[:, 0, :], t[:, 0, :]
        n = indices(doc)
        w = np.array(doc["wavelengths_nm"])
        a = np.array(doc["angles_deg"])
        d = doc["layer_thicknesses_nm"]
        points = r.size
        irid_s = doc["seconds"]
        row = {"stack": stack, "points": points, "irid": irid_s}

        grazing = (a >= 90.0)[:, None]
        secs, (pr, pt) = best_of(args.repeat, lambda: tmm_faster_grid(n, d, a, w))
        row["tmm-faster"] = secs
        row["tmm-faster cmp"] = compare(r, t, pr, pt, grazing)

        secs, (pr, pt) = best_of(args.repeat, lambda: colour_grid(n, d, a, w))
        row["colour"] = secs
        row["colour cmp"] = compare(r, t, pr, pt, grazing)

        # Byrnes' tmm is pure Python, one point per call: time it on every
        # step-th wavelength and scale per point.
        step = args.byrnes_step
        sub_w, sub_n = w[::step], n[::step]
        secs, (pr, pt) = best_of(1, lambda: byrnes_grid(sub_n, d, a, sub_w))
        row["tmm"] = secs * points / pr.size
        row["tmm cmp"] = compare(r[:, ::step], t[:, ::step], pr, pt, grazing)
        # Byrnes' tmm is the reference irid's solver was verified against: a
        # disagreement with it fails the run. The other peers' disagreements
        # are reported as findings about them, since tmm agrees with irid.
        if not agrees(row["tmm cmp"]):
            failures.append(finding(stack, "Byrnes' tmm", row["tmm cmp"]))
        for peer, label in (("tmm-faster", "tmm-faster"), ("colour", "colour-science")):
            if not agrees(row[f"{peer} cmp"]):
                findings.append(finding(stack, label, row[f"{peer} cmp"]))
        rows.append(row)
        print(
            f"  {stack:13s} irid {irid_s * 1e3:8.2f} ms   tmm-faster x{row['tmm-faster'] / irid_s:6.1f}"
            f"   colour x{row['colour'] / irid_s:7.1f}   tmm x{row['tmm'] / irid_s:8.0f}",
            flush=True,
        )
    return rows


def incoherent_rows(args, failures, findings):
    """One wavelength x angle grid per stack with incoherent layers: irid
    against tmm-faster's calc_incoherent, and Byrnes' inc_tmm (the
    reference) on every byrnes_step-th wavelength."""
    rows = []
    for stack in INCOHERENT_STACKS:
        doc, r, t = run_irid(stack, args.threads, args.repeat,
                             "--wavelengths", args.wavelengths, "--angles", args.angles)
        r, t = r[:, 0, :], t[:, 0, :]
        n = indices(doc)
        w = np.array(doc["wavelengths_nm"])
        a = np.array(doc["angles_deg"])
        d, c = doc["layer_thicknesses_nm"], letters(doc["coherent"])
        # inc_tmm's Snell angles are taken at exactly 90 degrees too; keep
        # the comparison off grazing, as for the coherent peers.
        grazing = (a >= 90.0)[:, None]
        secs, (pr, pt) = best_of(args.repeat, lambda: tmm_faster_incoherent_grid(n, d, c, a, w))
        row = {"stack": stack, "points": r.size, "irid": doc["seconds"], "tmm-faster": secs,
               "tmm-faster cmp": compare(r, t, pr, pt, grazing)}
        step = args.byrnes_step
        secs, (pr, pt) = best_of(1, lambda: byrnes_grid(n[::step], d, a, w[::step], c))
        row["tmm"] = secs * r.size / pr.size
        row["tmm cmp"] = compare(r[:, ::step], t[:, ::step], pr, pt, grazing)
        if not agrees(row["tmm cmp"]):
            failures.append(finding(stack, "Byrnes' inc_tmm", row["tmm cmp"]))
        if not agrees(row["tmm-faster cmp"]):
            findings.append(finding(stack, "tmm-faster's calc_incoherent", row["tmm-faster cmp"]))
        rows.append(row)
        print(f"  {stack:13s} irid {row['irid'] * 1e3:8.2f} ms   calc_incoherent x{row['tmm-faster'] / row['irid']:6.1f}"
              f"   inc_tmm x{row['tmm'] / row['irid']:8.0f}", flush=True)
    return rows


def bake_rows(args, failures, findings):
    """A full table: irid's baker (an rgb table with 1 nm integration, so
    R at every thickness x angle node and every wavelength 360-830 nm) against
    tmm-faster computing R at the same points, one call per thickness node.
    The baker is timed without its error check (the table's points only, the
    like-for-like figure) and with it (about 4x the points).
    The values are compared through irid's grid sweep over the same nodes,
    which splits the stack around the varying layer the way the baker does."""
    rows = []
    for stack in args.bake_stacks:
        doc, r, t = run_irid(stack, args.threads, args.repeat, "--bake-nodes", args.bake_nodes)
        n = indices(doc)
        w = np.array(doc["wavelengths_nm"])
        a = np.array(doc["angles_deg"])
        base = list(doc["layer_thicknesses_nm"])
        v = doc["varying_layer"]

        def peer():
            out_r = np.empty_like(r)
            out_t = np.empty_like(t)
            for k, th in enumerate(doc["thicknesses_nm"]):
                d = list(base)
                d[v] = th
                out_r[:, k, :], out_t[:, k, :] = tmm_faster_grid(n, d, a, w)
            return out_r, out_t

        secs, (pr, pt) = best_of(1, peer)
        grazing = (a >= 90.0)[:, None, None]
        cmp = compare(r, t, pr, pt, grazing)
        if not agrees(cmp):
            findings.append(finding(f"bake {stack}", "tmm-faster", cmp))
        # Byrnes' tmm at random points off grazing anchors irid's values.
        import tmm

        rng = np.random.default_rng(1)
        worst = 0.0
        off = np.flatnonzero(a < 90.0)
        for _ in range(args.byrnes_samples):
            ai, k, wi = rng.choice(off), rng.integers(r.shape[1]), rng.integers(r.shape[2])
            d = [np.inf, *base, np.inf]
            d[v + 1] = doc["thicknesses_nm"][k]
            n_list = list(n[wi])
            th = math.radians(a[ai])
            sp = [tmm.coh_tmm(pol, n_list, d, th, w[wi]) for pol in ("s", "p")]
            worst = max(worst, abs(r[ai, k, wi] - 0.5 * (sp[0]["R"] + sp[1]["R"])),
                        abs(t[ai, k, wi] - 0.5 * (sp[0]["T"] + sp[1]["T"])))
        if not worst <= TOLERANCE:
            failures.append(f"bake {stack}: Byrnes' tmm differs from irid by {worst:.2e}")
        if doc["bake_table_points"] != r.size:
            failures.append(f"bake {stack}: the table-only bake evaluated {doc['bake_table_points']} "
                            f"points, tmm-faster {r.size}")
        rows.append({"stack": stack, "points": r.size, "table": doc["bake_table_seconds"],
                     "checked": doc["bake_seconds"], "checked points": doc["bake_points"],
                     "sweep": doc["seconds"], "tmm-faster": secs,
                     "diff": max(cmp["R"], cmp["T"]), "tmm": worst})
        print(f"  bake {stack:13s} irid table-only bake {doc['bake_table_seconds']:.3f} s, "
              f"checked bake {doc['bake_seconds']:.3f} s, sweep {doc['seconds']:.3f} s   "
              f"tmm-faster {secs:.2f} s: x{secs / doc['bake_table_seconds']:.1f} / "
              f"x{secs / doc['bake_seconds']:.1f} / x{secs / doc['seconds']:.1f}",
              flush=True)
    return rows


def process_bake_rows(args, failures):
    """The default `irid bake` as a whole process (start-up, the bake check,
    the 20 000-point validation through the solver and the file write all
    included) against tmm-faster computing R and T at the table's nodes: every
    thickness x angle node of the written table at every wavelength of the
    exact 1 nm integration, one call per thickness node."""
    import OpenEXR

    rows = []
    for stack, stack_file, thickness in PROCESS_BAKES:
        with tempfile.TemporaryDirectory() as tmp:
            out = os.path.join(tmp, "table.exr")
            cmd = [irid_bin(), "bake", stack_file, "-o", out, "--thickness", thickness,
                   "--resolution", args.process_bake]
            env = dict(os.environ, RAYON_NUM_THREADS=str(args.threads))
            secs, _ = best_of(args.repeat, lambda: subprocess.run(cmd, check=True, capture_output=True, env=env))
            with OpenEXR.File(out) as f:
                h = json.loads(f.header()["irid"])
        axes = {a["name"]: np.array(a["nodes"]) for a in h["axes"]}
        validation = (h["error"].get("validation") or {}).get("points", 0)
        check = (h["error"].get("bake_check") or {}).get("points", 0)
        # The indices irid uses at the integration's wavelengths (360-830 nm, 1 nm).
        doc, _, _ = run_irid(stack, args.threads, 1, "--bake-nodes", "2,2")
        n = indices(doc)
        w = np.array(doc["wavelengths_nm"])
        a = np.degrees(np.arccos(np.clip(axes["cos_theta"], 0.0, 1.0)))
        base = list(doc["layer_thicknesses_nm"])
        v = doc["varying_layer"]

        def peer():
            for th in axes["thickness_nm"]:
                d = list(base)
                d[v] = th
                tmm_faster_grid(n, d, a, w)

        peer_s, _ = best_of(min(args.repeat, 3), peer)
        points = len(axes["thickness_nm"]) * len(a) * len(w)
        if validation != 20000:
            failures.append(f"process bake {stack}: the table records {validation} validation points, not 20000")
        rows.append({"stack": stack, "command": " ".join(["irid", *cmd[1:3], "-o", "table.exr", *cmd[5:]]),
                     "points": points, "irid": secs, "tmm-faster": peer_s,
                     "validation": validation, "check": check})
        print(f"  process bake {stack:13s} irid {secs:.3f} s (validation {validation} points, "
              f"check {check}), tmm-faster {peer_s:.2f} s: x{peer_s / secs:.1f}", flush=True)
    return rows


def write_report(path, args, general, bake, failures, findings, command, process_bake=(), incoherent=()):
    lines = _report_header(args, command)
    lines += _general_section(args, general)
    if incoherent:
        lines += _incoherent_section(args, incoherent)
    lines += _bake_section(args, bake)
    if process_bake:
        lines += _process_bake_section(args, process_bake)
    lines += _agreement_section(args, failures, findings)
    tmp = path + ".tmp"
    with open(tmp, "w") as f:
        f.write("\n".join(lines) + "\n")
    os.replace(tmp, path)


def _report_header(args, command):
    return [
        "# irid against other TMM implementations",
        "",
        f"- Date: {datetime.datetime.now(datetime.timezone.utc):%Y-%m-%d %H:%M} UTC",
        f"- Machine: {os.cpu_count()} logical cores, CPU {cpu_model()}",
        f"- Threads: irid {args.threads}, tmm-faster {os.environ['OMP_NUM_THREADS']} (OpenMP); tmm and colour-science run on one core",
        "- Peers: " + ", ".join(f"{k} {v}" for k, v in peer_versions().items()),
        f"- Command: `{command}`",
        f"- Agreement required: max |ΔR|, |ΔT| ≤ {TOLERANCE:g} against irid at every point",
        "",
        "Every figure below comes from the run that wrote this file. A ratio is peer time / irid time",
        "(higher means irid is faster). Times are the best of "
        f"{args.repeat} runs, without process start-up or I/O.",
        "",
    ]


def _general_section(args, general):
    lines = [
        "## General evaluation: wavelength × angle grid",
        "",
        f"Wavelengths `{args.wavelengths}` nm × angles `{args.angles}` °. Byrnes' `tmm` is timed on every "
        f"{args.byrnes_step}th wavelength and scaled per point.",
        "",
        "| stack | points | irid (ms) | tmm-faster (ms) | ratio | colour-science (ms) | ratio | tmm (ms, scaled) | ratio | max diff vs tmm | vs tmm-faster (R, T) |",
        "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for r in general:
        tc, fc = r["tmm cmp"], r["tmm-faster cmp"]
        diff = max(tc["R"], tc["T"])
        lines.append(
            f"| {r['stack']} | {r['points']} | {r['irid'] * 1e3:.2f} | {r['tmm-faster'] * 1e3:.2f} | "
            f"{r['tmm-faster'] / r['irid']:.1f}x | {r['colour'] * 1e3:.1f} | {r['colour'] / r['irid']:.0f}x | "
            f"{r['tmm'] * 1e3:.0f} | {r['tmm'] / r['irid']:.0f}x | {diff:.1e} | {fc['R']:.1e}, {fc['T']:.1e} |"
        )
    worst = min(r["tmm-faster"] / r["irid"] for r in general)
    lines += [
        "",
        f"Target: ≥ 20x tmm-faster on the same {args.threads} threads. Lowest ratio in this run: "
        f"**{worst:.1f}x** ({'met' if worst >= 20 else 'NOT met'}).",
        "",
    ]
    return lines


def _incoherent_section(args, incoherent):
    lines = [
        "## Incoherent layers: wavelength × angle grid",
        "",
        f"The same grid on stacks with incoherent (thick) layers, against tmm-faster's `calc_incoherent` "
        f"and Byrnes' `inc_tmm` (timed on every {args.byrnes_step}th wavelength and scaled per point). "
        "coated-sheet is `luts/coated-sheet.toml`: a TiO2 film on a 1 mm incoherent fused-silica sheet "
        "with MgF2 behind, in air.",
        "",
        "| stack | points | irid (ms) | calc_incoherent (ms) | ratio | inc_tmm (ms, scaled) | ratio "
        "| max diff vs inc_tmm | vs calc_incoherent (R, T) |",
        "|---|---:|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for r in incoherent:
        tc, fc = r["tmm cmp"], r["tmm-faster cmp"]
        lines.append(
            f"| {r['stack']} | {r['points']} | {r['irid'] * 1e3:.2f} | {r['tmm-faster'] * 1e3:.2f} | "
            f"{r['tmm-faster'] / r['irid']:.1f}x | {r['tmm'] * 1e3:.0f} | {r['tmm'] / r['irid']:.0f}x | "
            f"{max(tc['R'], tc['T']):.1e} | {fc['R']:.1e}, {fc['T']:.1e} |"
        )
    worst = min(r["tmm-faster"] / r["irid"] for r in incoherent)
    lines += [
        "",
        f"Target: ≥ 10x calc_incoherent on the same {args.threads} threads. Lowest ratio in this run: "
        f"**{worst:.1f}x** ({'met' if worst >= 10 else 'NOT met'}).",
        "",
    ]
    return lines


def _bake_section(args, bake):
    lines = [
        "## Baking a full table: thickness × angle × wavelength",
        "",
        f"`irid bench --grid STACK --bake-nodes {args.bake_nodes}`: irid's baker (`lut::bake`) builds an rgb table of "
        f"{args.bake_nodes.replace(',', ' × ')} (thickness × angle) nodes with 1 nm integration, i.e. R at every node and "
        "every wavelength 360–830 nm, then integrates to colour. tmm-faster computes R at the same "
        "thickness × angle × wavelength points, one call per thickness node (no colour integration: "
        "that is irid's extra work). irid's grid sweep evaluates the same points (the baker's "
        "split-stack method, f64 output) and is the one compared for agreement.",
        "",
        "The baker is timed two ways. The **table-only bake** (`irid bake --resolution T,A --no-check`) "
        "evaluates exactly the table's nodes: the same points as tmm-faster, so it is the like-for-like "
        "comparison. The **checked bake** (the default) evaluates the grid with every interval halved, "
        "about 4x the table's points, i.e. ~3x more points than tmm-faster computes (the column gives "
        "the count), to measure the table's own interpolation error for its header; its even nodes are "
        "the table.",
        "",
        "| stack | points | irid table-only bake (s) | ratio | irid checked bake (s) | points it evaluates | ratio "
        "| irid sweep (s) | ratio | tmm-faster (s) | max diff vs tmm (sampled) | vs tmm-faster |",
        "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for r in bake:
        lines.append(
            f"| {r['stack']} | {r['points']} | {r['table']:.3f} | {r['tmm-faster'] / r['table']:.1f}x | "
            f"{r['checked']:.3f} | {r['checked points']} | {r['tmm-faster'] / r['checked']:.1f}x | "
            f"{r['sweep']:.3f} | {r['tmm-faster'] / r['sweep']:.1f}x | {r['tmm-faster']:.2f} | "
            f"{r['tmm']:.1e} | {r['diff']:.1e} |"
        )
    if bake:
        worst = min(r["tmm-faster"] / r["table"] for r in bake)
        worst_checked = min(r["tmm-faster"] / r["checked"] for r in bake)
        lines += ["", "Target: baking ≥ 50x faster than tmm-faster computing the same points. It compares the "
                  "table-only bake, which computes the same points as tmm-faster. Lowest ratio in this run: "
                  f"**{worst:.1f}x** ({'met' if worst >= 50 else 'NOT met'}). The checked bake, which also "
                  f"measures its own error, reaches {worst_checked:.1f}x at its lowest."]
    return lines


def _process_bake_section(args, process_bake):
    lines = [
        "",
        "## The default bake as a whole process",
        "",
        f"`irid bake STACK -o table.exr --thickness T0:T1 --resolution {args.process_bake}` as a whole process "
        f"(best of {args.repeat}, RAYON_NUM_THREADS={args.threads}): start-up, the table's nodes, the bake check "
        "(about 4x the table's points), the validation (each of its points a full 1 nm spectrum through "
        "the general solver) and the file write. tmm-faster computes R and T at the written table's "
        "thickness x angle nodes at every wavelength of the 1 nm integration, one call per thickness node.",
        "",
        "| stack | command | table points | validation points | bake check points | irid (s) | tmm-faster (s) | ratio |",
        "|---|---|---:|---:|---:|---:|---:|---:|",
    ]
    for r in process_bake:
        lines.append(
            f"| {r['stack']} | `{r['command']}` | {r['points']} | {r['validation']} | {r['check']} | "
            f"{r['irid']:.3f} | {r['tmm-faster']:.2f} | {r['tmm-faster'] / r['irid']:.1f}x |"
        )
    worst = min(r["tmm-faster"] / r["irid"] for r in process_bake)
    lines += ["", f"Target: the default bake ≥ 20x tmm-faster. Lowest ratio in this run: **{worst:.1f}x** "
              f"({'met' if worst >= 20 else 'NOT met'})."]
    return lines


def _agreement_section(args, failures, findings):
    lines = ["", "## Agreement", ""]
    lines += [
        "Byrnes' `tmm` is the reference: irid's solver was verified against it, a disagreement with it "
        "beyond the tolerance fails this run. In the bake, it is evaluated at "
        f"{args.byrnes_samples} random points off grazing incidence.",
        "",
    ]
    lines += [f"- FAILED: {f}" for f in failures] or [
        "- irid agrees with Byrnes' tmm to within the tolerance at every point compared."
    ]
    if findings:
        lines += ["", "Where the other peers disagree with irid (and so with Byrnes' tmm); their timings are still shown:", ""]
        lines += [f"- {f}" for f in findings]
    return lines


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("-o", "--out", required=True, help="directory for peers.md: the run's benches/results/DATE-MACHINE")
    ap.add_argument("--quick", action="store_true", help="small grids (a smoke test, not a measurement)")
    ap.add_argument("--threads", type=int, default=THREADS_DEFAULT)
    ap.add_argument("--repeat", type=int, default=5)
    args = ap.parse_args()
    if args.threads != int(os.environ["OMP_NUM_THREADS"]):
        sys.exit("set OMP_NUM_THREADS to --threads before starting (OpenMP reads it once)")
    if args.quick:
        args.wavelengths, args.angles, args.byrnes_step = "380:780:20", "0:80:10", 4
        args.bake_nodes, args.bake_stacks, args.repeat = "16,8", ["soap"], 1
        args.process_bake = "16,8"
        args.byrnes_samples = 50
    else:
        args.wavelengths, args.angles, args.byrnes_step = "380:780:1", "0:89:1", 20
        args.bake_nodes, args.bake_stacks = "256,64", ["soap", "mirror-front"]
        args.process_bake = "128,64"
        args.byrnes_samples = 500
    # The binary as the reader would name it from the repository's root.
    shown_bin = os.path.relpath(irid_bin()) if os.path.isabs(irid_bin()) else irid_bin()
    command = "IRID_BIN=" + shown_bin + " python tools/bench/bench_peers.py " + " ".join(sys.argv[1:])
    failures = []
    print("general evaluation:", flush=True)
    findings = []
    general = general_rows(args, failures, findings)
    print("incoherent layers:", flush=True)
    incoherent = incoherent_rows(args, failures, findings)
    for probe in (colour_dispersion_probe(), tmm_faster_absorbing_substrate_probe()):
        if probe:
            findings.append(probe)
    print("baking:", flush=True)
    bake = bake_rows(args, failures, findings)
    print("the default bake as a whole process:", flush=True)
    process_bake = process_bake_rows(args, failures)
    os.makedirs(args.out, exist_ok=True)
    path = os.path.join(args.out, "peers.md")
    write_report(path, args, general, bake, failures, findings, command, process_bake, incoherent)
    print(f"wrote {path}")
    for f in failures:
        print("FAILED:", f)
    sys.exit(1 if failures else 0)


if __name__ == "__main__":
    main()
