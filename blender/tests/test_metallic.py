"""Blender 5.0's Metallic BSDF (Physical Conductor) with its thin film,
against exact colours: what docs/blender.md's comparison states.

The Physical Conductor takes a metal's complex index per RGB channel (IOR
and Extinction) and a thin film (Thin Film Thickness, Thin Film IOR) over
it. Rendered like test_blender.py's cases (Cycles CPU, a large plane under
a uniform white world, orthographic camera at 0°, 30°, 60° and 75°,
roughness 0), a film of n = 2.2, 250 nm, on

  - a metal of constant index 0.3 + 3.0i, given alike in the three
    channels: here the RGB description is the metal itself, and the check
    is ΔE00 mean ≤ CONSTANT_MEAN, max ≤ CONSTANT_MAX against `irid color`;
  - copper (irid's built-in, Johnson and Christy), given as its index at
    COPPER_RGB_NM (read from tools/gen/data/copper.csv, linearly between
    rows): reported, no bound (the RGB index cannot carry copper's
    dispersion across each channel's band).

irid's own material on the same copper film is test_blender.py's "film on
copper". Runs with Blender as a Python module, as tools/ci/blender.sh
installs it:

    python blender/tests/test_metallic.py --irid target/release/irid

Prints "N passed, N failed" last and exits non-zero on any failure.
"""

import argparse
import csv
import os
import sys
import tempfile
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
REPO = HERE.parents[1]
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(HERE.parent))
from colour_exr import delta_e2000_rgb  # noqa: E402
from cycles_scene import Bench, Irid, node_material  # noqa: E402

ANGLES_DEG = (0.0, 30.0, 60.0, 75.0)
FILM_IOR = 2.2
FILM_NM = 250.0
CONSTANT_INDEX = (0.3, 3.0)
CONSTANT_MEAN = 0.3
CONSTANT_MAX = 1.0
# Red, green and blue: the wavelengths of common RGB laser lines, one
# reading of "per channel" (Blender does not say which it means).
COPPER_RGB_NM = (630.0, 532.0, 465.0)


def metallic_material(name, ior_rgb, extinction_rgb):
    """Cycles' Metallic BSDF, Physical Conductor, GGX at roughness 0, with
    the thin film."""
    material, tree = node_material(name)
    bsdf = tree.nodes.new("ShaderNodeBsdfMetallic")
    bsdf.fresnel_type = "PHYSICAL_CONDUCTOR"
    bsdf.distribution = "GGX"
    bsdf.inputs["IOR"].default_value = tuple(ior_rgb)
    bsdf.inputs["Extinction"].default_value = tuple(extinction_rgb)
    bsdf.inputs["Roughness"].default_value = 0.0
    bsdf.inputs["Thin Film Thickness"].default_value = FILM_NM
    bsdf.inputs["Thin Film IOR"].default_value = FILM_IOR
    out = tree.nodes.new("ShaderNodeOutputMaterial")
    tree.links.new(bsdf.outputs["BSDF"], out.inputs["Surface"])
    return material


def copper_index(wavelengths_nm):
    """(n per wavelength, k per wavelength) of irid's copper table."""
    rows = []
    with open(REPO / "tools/gen/data/copper.csv") as f:
        for row in csv.reader(line for line in f if line[:1].isdigit()):
            rows.append([float(v) for v in row])
    table = np.array(rows)
    nm = table[:, 0] * 1000.0
    return (np.interp(wavelengths_nm, nm, table[:, 1]), np.interp(wavelengths_nm, nm, table[:, 2]))


def stack_text(substrate):
    return (f"ambient = {{ n = 1.0 }}\nsubstrate = {substrate}\n\n"
            f"[[layers]]\nn = {FILM_IOR}\nthickness_nm = {FILM_NM}\n")


def measure(bench, irid, workdir, name, substrate, ior_rgb, extinction_rgb):
    stack = workdir / f"{name.replace(' ', '-')}.toml"
    stack.write_text(stack_text(substrate))
    exact, _ = irid.colours(stack, ANGLES_DEG)
    material = metallic_material(name, ior_rgb, extinction_rgb)
    bench.set_world("white")
    errors = [delta_e2000_rgb(bench.render(material, a), exact[k]) for k, a in enumerate(ANGLES_DEG)]
    e = np.concatenate([np.ravel(x) for x in errors])
    return float(e.mean()), float(e.max())


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--irid", default=os.environ.get("IRID_BIN", REPO / "target/release/irid"))
    args = parser.parse_args()
    passed = failed = 0
    with tempfile.TemporaryDirectory(prefix="irid-metallic-") as tmp:
        workdir = Path(tmp)
        irid = Irid(args.irid, workdir)
        bench = Bench(workdir)
        n, k = CONSTANT_INDEX
        mean, worst = measure(bench, irid, workdir, "constant metal", f"{{ n = [{n}, {k}] }}",
                              (n,) * 3, (k,) * 3)
        ok = mean <= CONSTANT_MEAN and worst <= CONSTANT_MAX
        passed, failed = passed + ok, failed + (not ok)
        print(f"{'ok  ' if ok else 'FAIL'}  Metallic BSDF thin film on a metal of index {n} + {k}i "
              f"against exact (ΔE00 mean {mean:.3f}, max {worst:.3f})")
        n_rgb, k_rgb = copper_index(COPPER_RGB_NM)
        mean, worst = measure(bench, irid, workdir, "copper", '{ material = "copper" }', n_rgb, k_rgb)
        shown = ", ".join(f"{a:.3f} + {b:.3f}i" for a, b in zip(n_rgb, k_rgb))
        print(f"info  Metallic BSDF thin film on copper given as ({shown}) at "
              f"{', '.join(f'{w:g}' for w in COPPER_RGB_NM)} nm against exact "
              f"(ΔE00 mean {mean:.3f}, max {worst:.3f}; no bound)")
    print(f"{passed} passed, {failed} failed")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
