#!/usr/bin/env python3
"""Times irid's Python package (`irid.coherent`) against tmm-faster,
colour-science and Byrnes' tmm in one process, on the same numpy arrays, and
writes the figures into peers.md as its own section; and `irid.incoherent`
against tmm-faster's `calc_incoherent` and Byrnes' `inc_tmm` on stacks with
incoherent (thick) layers.

The stacks are bench_peers.py's six (the example stack files in luts/, the
mirror also seen from its substrate), at their files' thicknesses; the grid is
wavelengths 380:780:1 nm x angles 0:89:1 degrees. The complex indices come
from irid's materials (`Material.index`), so every implementation solves the
same problem. irid (rayon) and tmm-faster (OpenMP) get the same number of
threads (--threads, default 2); colour-science and tmm run on one core. Times
are the best of --repeat calls; Byrnes' tmm is timed on every 20th
wavelength and scaled per point. A disagreement with Byrnes' tmm beyond 1e-9
fails the run.

Usage: python tools/bench/bench_python.py [-o benches/results] [--quick]
(with the package installed: pip install ./python)
"""

import argparse
import datetime
import math
import os
import re
import sys
from pathlib import Path

import peer_calls
from peer_calls import best_of

THREADS_DEFAULT = 2
REPO = Path(__file__).resolve().parents[2]
STACKS = [
    ("soap", "soap-film.toml", False),
    ("absorbing", "absorbing-film.toml", False),
    ("gain-on-gold", "gain-on-gold.toml", False),
    ("two-layer", "two-layer.toml", False),
    ("mirror-front", "mirror-10.toml", False),
    ("mirror-back", "mirror-10.toml", True),
]
# Stacks with incoherent layers (irid.incoherent against calc_incoherent).
INCOHERENT_STACKS = [("coated-sheet", "coated-sheet.toml")]
TOLERANCE = 1e-9
BEGIN, END = "<!-- bench_python.py: begin -->", "<!-- bench_python.py: end -->"


def arrays(irid, file, reversed_, wavelengths):
    """n (wavelengths, media) and d (with inf ends) of a stack file."""
    import numpy as np

    stack = irid.Stack.load(REPO / "luts" / file)
    media = [stack.ambient, *[m for m, _ in stack.layers], stack.substrate]
    d = [math.inf, *[t for _, t in stack.layers], math.inf]
    if reversed_:
        media, d = media[::-1], d[::-1]
    n = np.stack([np.asarray(m.index(wavelengths), dtype=complex) for m in media], axis=1)
    return np.ascontiguousarray(n), d


def byrnes(n, d, angles, wavelengths):
    return peer_calls.byrnes_grid(n, d[1:-1], angles, wavelengths)


def coherence(irid, file):
    """calc_incoherent's c of a stack file: 'i' for the ambient, the
    substrate and every incoherent layer."""
    stack = irid.Stack.load(REPO / "luts" / file)
    return ["i", *("c" if flag else "i" for flag in stack.coherent), "i"]


def incoherent_rows(irid, args, wavelengths, angles, step, failures, findings):
    """irid.incoherent against calc_incoherent (timed) and inc_tmm (on every
    step-th wavelength, scaled per point) on INCOHERENT_STACKS."""
    import numpy as np
    import tmm_faster

    rows = []
    for name, file in INCOHERENT_STACKS:
        n, d = arrays(irid, file, False, wavelengths)
        c = coherence(irid, file)
        mine_s, mine = best_of(args.repeat, lambda: irid.incoherent(n, d, c, angles, wavelengths))
        tf_s, tf = best_of(args.repeat, lambda: tmm_faster.calc_incoherent(n, d, c, angles, wavelengths))
        sub = slice(None, None, step)
        by_s, (br, bt) = best_of(1, lambda: peer_calls.byrnes_grid(n[sub], d[1:-1], angles, wavelengths[sub], c))
        by_s *= mine["R_avg"].size / br.size
        diff = max(np.abs(mine["R_avg"][sub] - br).max(), np.abs(mine["T_avg"][sub] - bt).max())
        if not diff <= TOLERANCE:
            failures.append(f"{name}: irid.incoherent differs from Byrnes' inc_tmm by {diff:.2e}")
        tf_diff = max(np.abs(mine[k] - tf[k]).max() for k in ("R_avg", "T_avg"))
        if tf_diff > TOLERANCE:
            findings.append(f"{name}: calc_incoherent differs from irid (and inc_tmm) by up to {tf_diff:.1e}")
        rows.append((name, mine["R_avg"].size, mine_s, tf_s, by_s, diff, tf_diff))
        print(f"  {name:13s} irid.incoherent {mine_s * 1e3:7.2f} ms   calc_incoherent x{tf_s / mine_s:5.1f}   "
              f"inc_tmm x{by_s / mine_s:7.0f}", flush=True)
    return rows


def incoherent_lines(rows, args):
    worst = min(r[3] / r[2] for r in rows)
    lines = [
        "",
        "`irid.incoherent(n, d, c, angles, wavelengths)` and `tmm_faster.calc_incoherent` with the same "
        "arguments on the same grid, in the same process; Byrnes' `inc_tmm` on the same sampled wavelengths "
        "as `tmm` above. coated-sheet is `luts/coated-sheet.toml`: a TiO2 film on a 1 mm incoherent "
        "fused-silica sheet with MgF2 behind, in air.",
        "",
        "| stack | points | irid.incoherent (ms) | calc_incoherent (ms) | ratio | inc_tmm (ms, scaled) | ratio "
        "| max diff vs inc_tmm | max diff vs calc_incoherent |",
        "|---|---:|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for name, points, mine_s, tf_s, by_s, diff, tf_diff in rows:
        lines.append(
            f"| {name} | {points} | {mine_s * 1e3:.2f} | {tf_s * 1e3:.2f} | {tf_s / mine_s:.1f}x | "
            f"{by_s * 1e3:.0f} | {by_s / mine_s:.0f}x | {diff:.1e} | {tf_diff:.1e} |"
        )
    lines += [
        "",
        f"Target: ≥ 10x calc_incoherent on the same {args.threads} threads, lowest ratio in this run "
        f"**{worst:.1f}x** ({'met' if worst >= 10 else 'NOT met'}).",
    ]
    return lines


def colour_grid(n, d, angles, wavelengths):
    return peer_calls.colour_grid(n, d[1:-1], angles, wavelengths)


def coherent_rows(irid, args, wavelengths, angles, step, failures, findings):
    """irid.coherent against tmm-faster, colour-science (timed) and Byrnes'
    tmm (on every step-th wavelength, scaled per point) on STACKS."""
    import numpy as np
    import tmm_faster

    rows = []
    for name, file, reversed_ in STACKS:
        n, d = arrays(irid, file, reversed_, wavelengths)
        mine_s, mine = best_of(args.repeat, lambda: irid.coherent(n, d, angles, wavelengths))
        tf_s, tf = best_of(args.repeat, lambda: tmm_faster.calc_coherent(n, d, angles, wavelengths))
        col_s, _ = best_of(max(1, args.repeat // 3), lambda: colour_grid(n, d, angles, wavelengths))
        sub = slice(None, None, step)
        by_s, (br, bt) = best_of(1, lambda: byrnes(n[sub], d, angles, wavelengths[sub]))
        by_s *= mine["R_avg"].size / br.size
        diff = max(np.abs(mine["R_avg"][sub] - br).max(), np.abs(mine["T_avg"][sub] - bt).max())
        if not diff <= TOLERANCE:
            failures.append(f"{name}: irid.coherent differs from Byrnes' tmm by {diff:.2e}")
        tf_diff = max(np.abs(mine[k] - tf[k]).max() for k in ("R_avg", "T_avg"))
        if tf_diff > TOLERANCE:
            findings.append(f"{name}: tmm-faster differs from irid (and Byrnes' tmm) by up to {tf_diff:.1e}")
        rows.append((name, mine["R_avg"].size, mine_s, tf_s, col_s, by_s, diff, tf_diff))
        print(f"  {name:13s} irid {mine_s * 1e3:7.2f} ms   tmm-faster x{tf_s / mine_s:5.1f}   "
              f"colour x{col_s / mine_s:6.1f}   tmm x{by_s / mine_s:7.0f}", flush=True)
    return rows


def coherent_lines(rows, args, wavelengths, angles, step, load):
    """The section's heading, the run's conditions and the irid.coherent
    table, from coherent_rows' rows."""
    from importlib.metadata import version

    cpu = "unknown"
    try:
        cpu = next(l.split(":", 1)[1].strip() for l in open("/proc/cpuinfo") if l.startswith("model name"))
    except (OSError, StopIteration):
        pass
    peers = ", ".join(f"{p} {version(p)}" for p in ("irid", "tmm", "tmm_faster", "colour-science", "numpy"))
    worst_tf = min(r[3] / r[2] for r in rows)
    worst_tmm = min(r[5] / r[2] for r in rows)
    lines = [
        BEGIN,
        "## In process: irid's Python package",
        "",
        f"- Date: {datetime.datetime.now(datetime.timezone.utc):%Y-%m-%d %H:%M} UTC; "
        f"{os.cpu_count()} logical cores, CPU {cpu}",
        f"- Threads: irid {args.threads} (rayon), tmm-faster {args.threads} (OpenMP); tmm and colour-science one core",
        f"- Load average when the run started: {load[0]:.1f} (other work on the machine slows every peer)"
        + ("; other work slows the peers unequally (tmm-faster's OpenMP threads spin while they wait), "
           "so an idle machine gives the fairer ratio" if load[0] > args.threads else ""),
        f"- Versions: {peers}",
        f"- Command: `python tools/bench/bench_python.py {' '.join(sys.argv[1:])}`",
        "",
        "`irid.coherent(n, d, angles, wavelengths)` and `tmm_faster.calc_coherent` with the same "
        f"arguments, in one Python process: wavelengths {wavelengths[0]:g}:{wavelengths[-1]:g}:"
        f"{wavelengths[1] - wavelengths[0]:g} nm × angles {angles[0]:g}:{angles[-1]:g}:{angles[1] - angles[0]:g} °, "
        "each stack at its file's thicknesses. colour-science's `multilayer_tmm` and Byrnes' `tmm` get the "
        f"same arrays (tmm on every {step}th wavelength, scaled per point). Times include converting the "
        f"arguments and building the result dict; best of {args.repeat} calls. A ratio is peer time / irid time.",
        "",
        "| stack | points | irid.coherent (ms) | tmm-faster (ms) | ratio | colour-science (ms) | ratio "
        "| tmm (ms, scaled) | ratio | max diff vs tmm | max diff vs tmm-faster |",
        "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for name, points, mine_s, tf_s, col_s, by_s, diff, tf_diff in rows:
        lines.append(
            f"| {name} | {points} | {mine_s * 1e3:.2f} | {tf_s * 1e3:.2f} | {tf_s / mine_s:.1f}x | "
            f"{col_s * 1e3:.1f} | {col_s / mine_s:.0f}x | {by_s * 1e3:.0f} | {by_s / mine_s:.0f}x | "
            f"{diff:.1e} | {tf_diff:.1e} |"
        )
    lines += [
        "",
        f"Targets: ≥ 10x tmm-faster on the same {args.threads} threads, lowest ratio in this run "
        f"**{worst_tf:.1f}x** ({'met' if worst_tf >= 10 else 'NOT met'}); ≥ 1000x Byrnes' tmm, lowest "
        f"**{worst_tmm:.0f}x** ({'met' if worst_tmm >= 1000 else 'NOT met'}).",
    ]
    return lines


def write_section(path, section):
    """Puts ``section`` into peers.md at ``path`` in place of this script's
    previous section, or appends it; returns the path."""
    path.parent.mkdir(parents=True, exist_ok=True)
    text = path.read_text() if path.exists() else "# irid against other TMM implementations\n"
    pattern = re.compile(re.escape(BEGIN) + ".*?" + re.escape(END) + "\n?", re.S)
    text = pattern.sub(lambda _: section, text) if pattern.search(text) else text.rstrip("\n") + "\n\n" + section
    tmp = path.with_suffix(".md.tmp")
    tmp.write_text(text)
    os.replace(tmp, path)
    return path


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("-o", "--out", default="benches/results", help="directory of peers.md")
    ap.add_argument("--threads", type=int, default=THREADS_DEFAULT)
    ap.add_argument("--repeat", type=int, default=7)
    ap.add_argument("--quick", action="store_true", help="small grids (a smoke test, not a measurement)")
    args = ap.parse_args()
    # Both thread pools read these once, at first use.
    os.environ["OMP_NUM_THREADS"] = os.environ["RAYON_NUM_THREADS"] = str(args.threads)

    import numpy as np

    import irid

    load = os.getloadavg()
    step = 4 if args.quick else 20
    wavelengths = np.arange(380.0, 781.0, 20.0 if args.quick else 1.0)
    angles = np.arange(0.0, 90.0, 10.0 if args.quick else 1.0)
    failures, findings = [], []
    rows = coherent_rows(irid, args, wavelengths, angles, step, failures, findings)
    incoherent = incoherent_rows(irid, args, wavelengths, angles, step, failures, findings)
    lines = coherent_lines(rows, args, wavelengths, angles, step, load)
    lines += incoherent_lines(incoherent, args)
    lines += [""]
    lines += [f"- FAILED: {f}" for f in failures] or [
        "- irid.coherent agrees with Byrnes' tmm, and irid.incoherent with Byrnes' inc_tmm, to 1e-9 at every "
        "point compared."]
    lines += [f"- {f}" for f in findings]
    lines.append(END)
    path = write_section(Path(args.out) / "peers.md", "\n".join(lines) + "\n")
    print(f"wrote {path}")
    for f in failures:
        print("FAILED:", f)
    sys.exit(1 if failures else 0)


if __name__ == "__main__":
    main()
