#!/usr/bin/env python3
"""One-thread CPU time of `irid bench --grid STACK` and of tmm-faster's
`calc_coherent` on the same points (the indices irid reports), for every
stack of tools/bench/bench_peers.py. CPU time on one thread leaves out how each
side's threads fare on a loaded machine (OpenMP's waiting threads suffer far
more than rayon's from other processes), so it checks the ratios of
bench_peers.py, which are wall times on 2 threads.

irid's figure is the difference in process CPU time between a run of
2 × REPEAT evaluations and one of REPEAT, divided by REPEAT: start-up and
`irid bench`'s untimed warm-up cancel out. tmm-faster's is the best of 5
calls' thread CPU time.

Usage: IRID_BIN=target/release/irid python tools/bench/bench_single_thread.py [REPEAT]
"""

import json
import os
import resource
import subprocess
import sys
import tempfile
import time

os.environ["OMP_NUM_THREADS"] = "1"

import numpy as np  # noqa: E402
import tmm_faster  # noqa: E402

STACKS = ["soap", "absorbing", "gain-on-gold", "two-layer", "mirror-front", "mirror-back"]


def main():
    irid = os.environ.get("IRID_BIN", "target/release/irid")
    repeat = int(sys.argv[1]) if len(sys.argv) > 1 else 50
    for stack in STACKS:
        cpu = {}
        for count in (repeat, 2 * repeat):
            with tempfile.TemporaryDirectory() as tmp:
                raw = os.path.join(tmp, "grid.raw")
                before = resource.getrusage(resource.RUSAGE_CHILDREN)
                out = subprocess.run([irid, "bench", "--grid", stack, "--threads", "1",
                                      "--repeat", str(count), "--raw", raw],
                                     check=True, capture_output=True, text=True)
                after = resource.getrusage(resource.RUSAGE_CHILDREN)
            cpu[count] = after.ru_utime - before.ru_utime + after.ru_stime - before.ru_stime
        doc = json.loads(out.stdout)
        irid_cpu = (cpu[2 * repeat] - cpu[repeat]) / repeat
        n = np.array(doc["indices_re"]) + 1j * np.array(doc["indices_im"])
        d = [np.inf, *doc["layer_thicknesses_nm"], np.inf]
        a = np.array(doc["angles_deg"])
        w = np.array(doc["wavelengths_nm"])
        best = float("inf")
        for _ in range(5):
            start = time.thread_time()
            tmm_faster.calc_coherent(n, d, a, w)
            best = min(best, time.thread_time() - start)
        print(f"{stack:13s} irid {irid_cpu * 1e3:7.2f} ms CPU   tmm-faster {best * 1e3:8.2f} ms CPU   "
              f"ratio {best / irid_cpu:5.1f}x", flush=True)


if __name__ == "__main__":
    main()
