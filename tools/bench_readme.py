#!/usr/bin/env python3
"""Rewrites the README's "Speed against error" section from a real run's
benches/results/report.md and peers.md, so no figure in it is typed by hand.

Usage (after `irid bench -o benches/results` and `tools/bench_peers.py -o benches/results`):
    python3 tools/bench_readme.py [benches/results] [README.md]
"""
import os
import re
import sys

results = sys.argv[1] if len(sys.argv) > 1 else "benches/results"
readme_path = sys.argv[2] if len(sys.argv) > 2 else "README.md"
report = open(f"{results}/report.md").read() + "\n\n"
peers = open(f"{results}/peers.md").read()
def between(text, start, end):
    i = text.index(start); j = text.index(end, i + len(start))
    return text[i:j]
header = [l for l in report.splitlines() if l.startswith(("- Date:", "- Machine:", "- Threads:", "- Command:"))]
summary = between(report, "| method | ns / eval", "\n\n![speed vs error]")
renders = between(report, "| scene | film mode |", "\n\n") if "## Full renders" in report else ""
renders_intro = between(report, "One frame per film mode", "\n\n")
pheader = [l for l in peers.splitlines() if l.startswith("- Date:") or l.startswith("- Command:")]
general = between(peers, "| stack | points | irid (ms)", "\n\nTarget:")
gdesc = next(l for l in peers.splitlines() if l.startswith("Wavelengths `"))
bdesc = next(l for l in peers.splitlines() if l.startswith("`irid bench --grid STACK --bake-nodes"))
gtarget = re.search(r"Target: ≥ 5x.*", peers).group(0)
bake = between(peers, "| stack | points | irid table-only bake (s)", "\n\nTarget:")
btwo = next(l for l in peers.splitlines() if l.startswith("The baker is timed two ways."))
btarget = re.search(r"Target: baking.*", peers).group(0)
out = f"""## Speed against error: `irid bench`

`irid bench [--quick] [-o DIR] [--points N] [--threads N]` measures, for each fixed stack
(the example files in `luts/`: soap film, absorbing film, gain film on gold,
two layers on gold, and the 10-layer mirror seen from both sides) and each
method, the time of one shading evaluation (one thickness, one angle, to linear
sRGB reflectance; single thread, many evaluations in one loop divided by their
count) and its error against the 1 nm exact reference at 10000 random points:
max and 99th-percentile absolute reflectance error, mean and max CIEDE2000.
Methods: direct TMM with `rgb3`, `uniform:9/41/81` and `exact`; LUT sampling
(`irid::lut`, bilinear) at several resolutions in f32 and f16; and the
single-film analytic model renderers ship (`irid::analytic`: Belcour & Barla
2017 with exact Fresnel, and the glTF `KHR_materials_iridescence` reference
with Schlick Fresnel) on the one-film stacks. Table bakes and the full
renders run on `--threads` workers (default 2). It writes `report.md` (machine,
threads, date, command, a summary table and one table per stack), `results.csv`
and `speed-vs-error.png`. Default `-o` is `benches/results/`; the committed files
there come from the run below:

{chr(10).join(header)}

{summary}

![speed vs error](benches/results/speed-vs-error.png)

Each figure is the median over the stacks a method applies to; the per-stack
tables are in `benches/results/report.md` (with `results.csv` beside it). The
exact method's error is 0 by construction (it is the reference); the plot
draws it at 1e-4. The gain film on gold has resonances where reflectance
reaches the thousands, which dominate every method's absolute error on that
stack; where they exceed f16's range the baker refuses the f16 table, and
`report.md` lists it as not measured (a method marked "(5 stacks)" is a
median over the others). Timings on this shared 2-core machine move between
runs, so compare methods by their ratios within one run.

Full small renders (`irid::render`, in the same run). {renders_intro}

{renders}

### Against other TMM implementations

`tools/bench_peers.py` times Byrnes' `tmm`, `colour-science`
(`colour.phenomena.multilayer_tmm`) and `tmm-faster` (C++/OpenMP, same two
threads as irid) on the same stacks and grids, driving irid through
`irid bench --grid STACK` (JSON with the wall time and the exact complex
indices used, so every implementation solves the same problem), checks
agreement against irid to 1e-9 and writes `benches/results/peers.md`:

{chr(10).join(pheader)}

General evaluation. {gdesc}

{general}

{gtarget}

Baking a full table. {bdesc}

{btwo}

{bake}

{btarget}

Byrnes' `tmm` agrees with
irid everywhere compared (a disagreement with it fails the run). The other two
peers do not agree everywhere, and `peers.md` says where: tmm-faster's
p-polarized transmittance into an absorbing substrate (gold) differs, and
colour-science 0.4.7 refracts every wavelength with the first wavelength's
indices at oblique incidence and returns NaN beyond the critical angle.

To reproduce:

```sh
cargo build --release
target/release/irid bench -o benches/results
python3 -m venv .venv && .venv/bin/pip install -r tools/requirements.txt
OMP_NUM_THREADS=2 .venv/bin/python tools/bench_peers.py -o benches/results
python3 tools/bench_readme.py      # this section, from the two reports
```
"""
HEADING = "## Speed against error: `irid bench`"
readme = open(readme_path).read()
start = readme.find(HEADING)
if start < 0:
    readme = readme.rstrip("\n") + "\n\n" + out
else:
    # The section runs to the next level-2 heading (or the end).
    nxt = readme.find("\n## ", start + len(HEADING))
    readme = readme[:start] + out + (readme[nxt + 1:] if nxt >= 0 else "")
tmp = readme_path + ".tmp"
with open(tmp, "w") as f:
    f.write(readme)
os.replace(tmp, readme_path)
print(f"rewrote the section in {readme_path}")
