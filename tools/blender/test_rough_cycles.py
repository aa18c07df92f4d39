"""Headless Cycles check of irid's rough-film definition (docs/rough.md).

Cycles' Principled BSDF takes a single film's Fresnel per microfacet, at
v·h, on a GGX lobe: with base colour black, no metal and no transmission,
its specular layer is exactly the lobe of docs/rough.md for a film on glass
(single scattering when its distribution is "GGX", α = roughness²,
height-correlated Smith G2). On a large plane under a uniform white world,
seen by an orthographic camera at one angle, a pixel's value is that lobe's
directional albedo times the film's F_eff; divided by the same render of a
white GGX Glossy BSDF of the same roughness (the lobe's albedo alone) it is
F_eff, which `irid color --roughness R --white e --json` computes by
quadrature. Cycles' film is its own implementation (Belcour and Barla's
Airy sum in its own colour integration), so this is an independent check
for single dielectric films.

Runs with Blender as a Python module, as tools/ci/blender.sh installs it:

    python tools/blender/test_rough_cycles.py --irid target/release/irid

Both renders of a case use the same seed, so Cycles draws the same
microfacet normals for each and much of the noise cancels in the ratio. The
noise that remains is estimated from the spread of the per-pixel ratios
(its standard error per channel is printed and must stay below a fifth of
the bound's colour scale, NOISE_BOUND). Pass: CIEDE2000 between Cycles'
F_eff and irid's mean <= MEAN_BOUND and max <= MAX_BOUND over the cases.
Prints "N passed, N failed" last and exits non-zero on any failure.
"""

import argparse
import json
import math
import os
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

import bpy

HERE = Path(__file__).resolve().parent
REPO = HERE.parent.parent
sys.path.insert(0, str(HERE))
from colour_exr import delta_e2000_rgb  # noqa: E402
from cycles_scene import Bench, Irid  # noqa: E402

STACK = "tests/blender/film-on-glass.toml"  # 300 nm, n = 1.38, on n = 1.5
SUBSTRATE_IOR = 1.5
FILM_IOR = 1.38
FILM_NM = 300.0
ROUGHNESS = (0.0, 0.2, 0.35, 0.5)
ANGLES_DEG = (0.0, 30.0, 60.0)
RESOLUTION = 8  # pixels a side; every pixel sees the same angle
SAMPLES = 64  # per pixel
MEAN_BOUND = 0.1
MAX_BOUND = 0.15
NOISE_BOUND = 1e-3  # standard error of F_eff per channel


def bsdf_material(name, node_type, inputs):
    """A material of one GGX BSDF node with these input values."""
    material = bpy.data.materials.new(name)
    if material.node_tree is None:
        material.use_nodes = True
    tree = material.node_tree
    tree.nodes.clear()
    bsdf = tree.nodes.new(node_type)
    bsdf.distribution = "GGX"  # single scattering, not Multiscatter GGX
    for key, value in inputs.items():
        bsdf.inputs[key].default_value = value
    out = tree.nodes.new("ShaderNodeOutputMaterial")
    tree.links.new(bsdf.outputs[0], out.inputs["Surface"])
    return material


def principled_rough_film(roughness):
    """Cycles' thin film on glass, specular only (base colour black)."""
    return bsdf_material(f"Principled film r {roughness:g}", "ShaderNodeBsdfPrincipled", {
        "Base Color": (0.0, 0.0, 0.0, 1.0),
        "Metallic": 0.0,
        "Roughness": roughness,
        "IOR": SUBSTRATE_IOR,
        "Thin Film Thickness": FILM_NM,
        "Thin Film IOR": FILM_IOR,
    })


def white_glossy(roughness):
    """A white GGX lobe: its render is the lobe's directional albedo."""
    return bsdf_material(f"Glossy r {roughness:g}", "ShaderNodeBsdfGlossy", {
        "Color": (1.0, 1.0, 1.0, 1.0),
        "Roughness": roughness,
    })


def ratio_and_noise(film, white):
    """F_eff = mean(film) / mean(white) per channel over the pixels, and its
    standard error (delta method over the pixels, which are independent)."""
    film = film.reshape(-1, 3)
    white = white.reshape(-1, 3)
    ratio = film.mean(0) / white.mean(0)
    residual = film - ratio * white
    noise = residual.std(0, ddof=1) / math.sqrt(len(film)) / white.mean(0)
    return ratio, noise


def irid_colours(irid, stack, roughness=None):
    """`irid color --white e` per angle: F_eff with a roughness, else the
    smooth reflectance at the view angle."""
    angles = ",".join(f"{a:g}" for a in ANGLES_DEG)
    rough = [] if roughness is None else ["--roughness", f"{roughness:g}"]
    rows = json.loads(irid.run("color", stack, *rough, "--white", "e", "--angles", angles, "--json"))
    return np.array([row["reflectance_rgb"] for row in rows])


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--irid", default=os.environ.get("IRID_BIN", REPO / "target/release/irid"))
    parser.add_argument("--samples", type=int, default=SAMPLES, help="samples per pixel")
    parser.add_argument("--resolution", type=int, default=RESOLUTION, help="pixels a side")
    args = parser.parse_args()

    started = time.monotonic()
    passed = failed = 0
    errors = []
    at_view = []  # Cycles' rough F_eff against the smooth film at the view angle
    worst_noise = 0.0
    with tempfile.TemporaryDirectory(prefix="irid-rough-cycles-") as tmp:
        workdir = Path(tmp)
        irid = Irid(args.irid, workdir)
        bench = Bench(workdir)
        bench.scene.render.resolution_x = args.resolution
        bench.scene.render.resolution_y = args.resolution
        bench.set_world("white")
        smooth = irid_colours(irid, REPO / STACK)
        for roughness in ROUGHNESS:
            expected = irid_colours(irid, REPO / STACK, roughness)
            film = principled_rough_film(roughness)
            white = white_glossy(roughness)
            for k, angle in enumerate(ANGLES_DEG):
                got, noise = ratio_and_noise(
                    bench.render(film, angle, args.samples), bench.render(white, angle, args.samples)
                )
                de = float(delta_e2000_rgb(got, expected[k]))
                errors.append(de)
                if roughness > 0:
                    at_view.append(float(delta_e2000_rgb(got, smooth[k])))
                worst_noise = max(worst_noise, float(noise.max()))
                print(f"info  roughness {roughness:g}, {angle:g} deg: Cycles F_eff "
                      f"{np.round(got, 5).tolist()} ± {noise.max():.1e}, irid "
                      f"{np.round(expected[k], 5).tolist()}, dE00 {de:.3f}")
    mean, worst = float(np.mean(errors)), float(np.max(errors))
    print(f"info  the smooth film's colour at the view angle instead of F_eff: dE00 mean "
          f"{np.mean(at_view):.2f}, max {np.max(at_view):.2f} against Cycles at roughness > 0")
    for name, ok, detail in (
        ("Cycles' rough film against irid color --roughness, mean dE00", mean <= MEAN_BOUND,
         f"{mean:.3f} (bound {MEAN_BOUND:g})"),
        ("Cycles' rough film against irid color --roughness, max dE00", worst <= MAX_BOUND,
         f"{worst:.3f} (bound {MAX_BOUND:g})"),
        ("Cycles' noise in F_eff (standard error per channel)", worst_noise <= NOISE_BOUND,
         f"{worst_noise:.1e} (bound {NOISE_BOUND:g})"),
        # The check can tell: the view-angle colour misses Cycles by far more.
        ("the smooth colour at the view angle fails the same bound", np.mean(at_view) > MEAN_BOUND * 5,
         f"mean dE00 {np.mean(at_view):.2f}"),
    ):
        print(f"{'ok   ' if ok else 'FAIL '} {name}: {detail}")
        passed, failed = passed + ok, failed + (not ok)
    print(f"{len(errors)} cases ({len(ROUGHNESS)} roughnesses x {len(ANGLES_DEG)} angles), "
          f"{args.resolution}x{args.resolution} pixels x {args.samples} samples, "
          f"{bench.renders} renders in {time.monotonic() - started:.0f} s")
    print(f"{passed} passed, {failed} failed")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
