#!/usr/bin/env python3
"""Times Python `tmm` (tmm.coh_tmm) on the stacks of benches/tmm.rs and,
when criterion results exist (cargo bench --bench tmm), prints irid's time
beside it and the ratio.

The stacks: ambient air, N films alternating n = 1.5 and n = 2.3 + 0.05i,
thicknesses 100, 107, 114, ... nm, a gold-like substrate n = 0.27 + 2.9i;
550 nm, cos θ0 = 0.8. One sample is unpolarized R and T: two coh_tmm calls
(s and p), as irid's solve computes both polarizations at once.

Usage: python3 tools/time_tmm.py   (after: cargo bench --bench tmm)
The figure is the best of several repeats (the machine is shared; the
minimum is the least disturbed run).
"""

import json
import math
import pathlib
import sys
import timeit

import tmm

ROOT = pathlib.Path(__file__).resolve().parent.parent
CRITERION = ROOT / "target" / "criterion"


def stack(layers):
    n = [1.0]
    d = [math.inf]
    for i in range(layers):
        n.append(1.5 if i % 2 == 0 else complex(2.3, 0.05))
        d.append(100.0 + 7.0 * i)
    n.append(complex(0.27, 2.9))
    d.append(math.inf)
    return n, d


def sample(n, d, th):
    s = tmm.coh_tmm("s", n, d, th, 550.0)
    p = tmm.coh_tmm("p", n, d, th, 550.0)
    return (s["R"] + p["R"]) / 2, (s["T"] + p["T"]) / 2


def criterion_ns(group, name):
    """Criterion's median estimate for one benchmark, in ns, or None."""
    path = CRITERION / group / name / "new" / "estimates.json"
    if not path.exists():
        return None
    return json.loads(path.read_text())["median"]["point_estimate"]


def main():
    th = math.acos(0.8)
    rows = []
    for layers in (1, 2, 10, 100):
        n, d = stack(layers)
        number = max(20, 2000 // (layers + 1))
        best = min(timeit.repeat(lambda: sample(n, d, th), number=number, repeat=7)) / number
        rows.append((layers, best * 1e9, criterion_ns("solve", f"{layers} layers")))
    print(f"{'layers':>6} {'tmm (µs)':>10} {'irid (ns)':>10} {'ratio':>8}")
    for layers, tmm_ns, irid_ns in rows:
        irid = f"{irid_ns:10.0f}" if irid_ns else f"{'-':>10}"
        ratio = f"{tmm_ns / irid_ns:7.0f}x" if irid_ns else f"{'-':>8}"
        print(f"{layers:>6} {tmm_ns / 1e3:10.1f} {irid} {ratio}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
