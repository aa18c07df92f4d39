#!/usr/bin/env python3
"""Times Python `tmm` (tmm.coh_tmm) on the stacks of benches/tmm.rs and,
when criterion results exist (cargo bench --bench tmm), prints irid's time
beside it and the ratio: both as the least-disturbed time (the fastest of
many short runs: bench group solve_min here, timeit's best repeat there) and
as criterion's median of the plain bench group `solve`.

The stacks: ambient air, N films alternating n = 1.5 and n = 2.3 + 0.05i,
thicknesses 100, 107, 114, ... nm, a gold-like substrate n = 0.27 + 2.9i;
550 nm, cos θ0 = 0.8. One sample is unpolarized R and T: two coh_tmm calls
(s and p), as irid's solve computes both polarizations at once.

Usage: python3 tools/bench/time_tmm.py   (after: cargo bench --bench tmm)
The figure is the best of many short repeats (the machine is shared; the
minimum is the least disturbed run).
"""

import json
import math
import pathlib
import sys
import timeit

import tmm

ROOT = pathlib.Path(__file__).resolve().parents[2]
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
        # Short runs (well under a millisecond), many of them: the best is
        # the least disturbed by other work on a shared machine.
        number = max(1, 4 // (layers + 1))
        best = min(timeit.repeat(lambda: sample(n, d, th), number=number, repeat=300)) / number
        name = f"{layers} layers"
        rows.append((layers, best * 1e9, criterion_ns("solve_min", name), criterion_ns("solve", name)))
    print(f"{'layers':>6} {'tmm best (µs)':>14} {'irid min (ns)':>14} {'ratio':>7} {'irid median (ns)':>17}")
    for layers, tmm_ns, irid_min, irid_median in rows:
        fmt = lambda v, w: f"{v:{w}.0f}" if v else f"{'-':>{w}}"
        ratio = f"{tmm_ns / irid_min:6.0f}x" if irid_min else f"{'-':>7}"
        print(f"{layers:>6} {tmm_ns / 1e3:14.1f} {fmt(irid_min, 14)} {ratio} {fmt(irid_median, 17)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
