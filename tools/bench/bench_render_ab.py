#!/usr/bin/env python3
"""Times two irid binaries on the same direct-film render, interleaved, and
prints the best wall and CPU time of each and their ratio. Interleaving puts
both under the same load, so the ratio holds on a shared machine.

Usage: python tools/bench/bench_render_ab.py OLD_IRID NEW_IRID [REPEAT]
Renders `two-layer-noise --film direct --sampling uniform:41` at 500x500 on
2 threads into a temporary PNG.
"""

import os
import resource
import subprocess
import sys
import tempfile
import time


def run(cmd):
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = after.ru_utime - before.ru_utime + after.ru_stime - before.ru_stime
    return wall, cpu


def main():
    old, new = sys.argv[1], sys.argv[2]
    repeat = int(sys.argv[3]) if len(sys.argv) > 3 else 3
    times = {old: [], new: []}
    with tempfile.TemporaryDirectory() as tmp:
        png = os.path.join(tmp, "render.png")
        for i in range(repeat):
            for binary in (old, new):
                wall, cpu = run([binary, "render", "two-layer-noise", "--film", "direct",
                                 "--sampling", "uniform:41", "--width", "500", "--height", "500",
                                 "--threads", "2", "-o", png])
                times[binary].append((wall, cpu))
                print(f"{i} {binary}: wall {wall:.3f} s, CPU {cpu:.3f} s", flush=True)
    wall_old, wall_new = (min(w for w, _ in times[b]) for b in (old, new))
    cpu_old, cpu_new = (min(c for _, c in times[b]) for b in (old, new))
    print(f"best wall: old {wall_old:.3f} s, new {wall_new:.3f} s, ratio {wall_old / wall_new:.2f}x; "
          f"best CPU: old {cpu_old:.3f} s, new {cpu_new:.3f} s, ratio {cpu_old / cpu_new:.2f}x")


if __name__ == "__main__":
    main()
