"""EEVEE against Cycles on irid's material: no seam where the table switches
charts, no speckles at a sphere's rim.

A smooth sphere under an orthographic camera, its surface the emission of
the film group's Reflectance output (so lights, shadows and sampling do not
enter: both engines evaluate the same node graph, and what differs between
them is how they read the textures), rendered by EEVEE and by Cycles at one
sample a pixel with a pixel filter too narrow to blend neighbours. Each
pixel's cos θ (rendered the same way) names the chart the closed form reads
there (irid_blender.atlas_chart_for); pixels beside one of another chart
are the chart borders, pixels at cos θ below RIM_COS the rim. The check,
for a film on copper (smooth) and for coated glass at roughness 0.3 (the
rough table's slices): ΔE00 between EEVEE and Cycles is at most BOUND_MEAN
on average and BOUND_MAX anywhere in each region (the borders, the rim,
elsewhere), well inside an export's own stated error, and the borders'
mean is at most BORDER_FACTOR times the mean elsewhere (plus BORDER_SLACK):
no seam. What remains is the two engines' geometry (interpolated normals,
where in the pixel the sample falls), largest at the rim where the colour
changes fastest with the angle, and the tables' own small step between
two charts at their border, which a pixel straddles in one engine and
not the other.

Runs with Blender as a Python module, as tools/ci/blender.sh installs it:

    python blender/tests/test_eevee.py --irid target/release/irid [--image PNG]

--image writes EEVEE's and Cycles' renders of the first case side by side,
with a third panel of their ΔE00 (white = 1). Prints "N passed, N failed"
last and exits non-zero on any failure.
"""

import argparse
import math
import os
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import OpenEXR

import bpy

HERE = Path(__file__).resolve().parent
REPO = HERE.parents[1]
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(HERE.parent))
import irid_blender  # noqa: E402
from colour_exr import delta_e2000_rgb  # noqa: E402
from cycles_scene import Irid, emission_material, node_material, quiet_stdout  # noqa: E402

RESOLUTION = 160  # pixels a side; the sphere spans 145 of them
RIM_COS = 0.2  # below this cos θ a pixel is at the rim
BOUND_MEAN = 0.15
BOUND_MAX = 0.5
BORDER_FACTOR = 2.0
BORDER_SLACK = 0.01
CASES = [
    {"name": "film on copper", "stack": "tests/blender/film-on-copper.toml", "layer": 1,
     "range": (100.0, 500.0), "thickness_nm": 300.0, "roughness": 0.0},
    {"name": "coated glass, roughness 0.3", "stack": "tests/blender/film-on-glass.toml",
     "layer": 1, "range": (200.0, 500.0), "thickness_nm": 300.0, "roughness": 0.3},
]


def scene_setup(resolution):
    """An empty scene: a black transparent world, a smooth UV sphere of
    radius 1, an orthographic camera on +z framing it; EXR output."""
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    scene.render.resolution_x = scene.render.resolution_y = resolution
    scene.render.resolution_percentage = 100
    scene.render.film_transparent = True
    scene.view_settings.view_transform = "Standard"
    scene.view_settings.look = "None"
    settings = scene.render.image_settings
    settings.file_format = "OPEN_EXR"
    settings.color_depth = "32"
    settings.color_management = "OVERRIDE"
    settings.linear_colorspace_settings.name = "Linear Rec.709"
    world = bpy.data.worlds.new("black")
    scene.world = world
    if world.node_tree is None:
        world.use_nodes = True
    world.node_tree.nodes["Background"].inputs["Color"].default_value = (0, 0, 0, 1)
    # One sample at the pixel's centre in both engines: no neighbour blends in.
    scene.cycles.device = "CPU"
    scene.cycles.samples = 1
    scene.cycles.use_denoising = False
    scene.cycles.use_adaptive_sampling = False
    scene.cycles.filter_width = 0.01
    scene.eevee.taa_render_samples = 1
    scene.render.filter_size = 0.01
    scene.render.threads_mode = "FIXED"
    scene.render.threads = 2
    bpy.ops.mesh.primitive_uv_sphere_add(segments=128, ring_count=64, radius=1.0)
    sphere = bpy.context.active_object
    bpy.ops.object.shade_smooth()
    camera = bpy.data.cameras.new("camera")
    camera.type = "ORTHO"
    camera.ortho_scale = 2.2
    camera_object = bpy.data.objects.new("camera", camera)
    camera_object.location = (0.0, 0.0, 10.0)
    scene.collection.objects.link(camera_object)
    scene.camera = camera_object
    return scene, sphere


def cos_material():
    """Emission of cos θ = |Incoming · Normal| in all three channels."""
    material, tree = node_material("cos θ")
    geometry = tree.nodes.new("ShaderNodeNewGeometry")
    dot = tree.nodes.new("ShaderNodeVectorMath")
    dot.operation = "DOT_PRODUCT"
    tree.links.new(geometry.outputs["Incoming"], dot.inputs[0])
    tree.links.new(geometry.outputs["Normal"], dot.inputs[1])
    grey = tree.nodes.new("ShaderNodeCombineColor")
    for k in range(3):
        tree.links.new(dot.outputs["Value"], grey.inputs[k])
    emission = tree.nodes.new("ShaderNodeEmission")
    tree.links.new(grey.outputs[0], emission.inputs["Color"])
    out = tree.nodes.new("ShaderNodeOutputMaterial")
    tree.links.new(emission.outputs[0], out.inputs["Surface"])
    return material


def render(scene, sphere, material, engine, path):
    """RGBA of every pixel, rows top to bottom, shape (H, W, 4)."""
    scene.render.engine = engine
    sphere.data.materials.clear()
    sphere.data.materials.append(material)
    scene.render.filepath = str(path)
    with quiet_stdout():
        bpy.ops.render.render(write_still=True)
    with OpenEXR.File(str(path)) as f:
        return np.asarray(f.channels()["RGBA"].pixels, float)


def chart_map(export, cos, thickness_nm, roughness):
    """Per pixel, the number of the chart the lookup reads at cos θ `cos`
    (the rough atlas's when roughness > 0, at the thickness clamped to its
    range); -1 off the sphere."""
    if roughness > 0.0:
        rough = export.rough
        charts = rough.charts
        d = min(max(thickness_nm, rough.thickness_min_nm), rough.thickness_max_nm)
    else:
        charts, d = export.front, thickness_nm
    numbers = np.full(cos.shape, -1)
    for index in np.ndindex(cos.shape):
        if not math.isnan(cos[index]):
            chart = irid_blender.atlas_chart_for(charts, d, float(min(max(cos[index], 0.0), 1.0)))
            numbers[index] = charts.index(chart)
    return numbers


def regions(numbers, cos):
    """Masks of the chart borders (a pixel with a 4-neighbour on the sphere
    reading another chart), the rim (cos θ below RIM_COS, not a border) and
    the rest of the sphere."""
    on = numbers >= 0
    border = np.zeros_like(on)
    for axis in (0, 1):
        for shift in (1, -1):
            other = np.roll(numbers, shift, axis)
            border |= on & (other >= 0) & (other != numbers)
    rim = on & ~border & (np.nan_to_num(cos, nan=1.0) < RIM_COS)
    return {"chart borders": border, "rim": rim, "elsewhere": on & ~border & ~rim}


def measure_case(results, scene, sphere, irid, workdir, case):
    directory = irid.export(REPO / case["stack"], workdir / case["name"].replace(" ", "-"),
                            case["layer"], case["range"], rough=True)
    export = irid_blender.Export(directory)
    group = irid_blender.make_node_group(export, name=f"{case['name']} film")
    fraction = (case["thickness_nm"] - case["range"][0]) / (case["range"][1] - case["range"][0])
    material = emission_material(f"R {case['name']}", group, "Reflectance", fraction,
                                 Roughness=case["roughness"])
    tag = case["name"].split(",")[0].replace(" ", "-")
    cos = render(scene, sphere, cos_material(), "CYCLES", workdir / f"cos-{tag}.exr")
    images = {engine: render(scene, sphere, material, engine, workdir / f"{engine}-{tag}.exr")
              for engine in ("BLENDER_EEVEE", "CYCLES")}
    covered = (images["CYCLES"][..., 3] > 0.999) & (images["BLENDER_EEVEE"][..., 3] > 0.999)
    covered &= cos[..., 3] > 0.999
    c = np.where(covered, cos[..., 0], np.nan)
    numbers = chart_map(export, c, case["thickness_nm"], case["roughness"])
    delta = delta_e2000_rgb(images["BLENDER_EEVEE"][..., :3], images["CYCLES"][..., :3])
    figures = {}
    for name, mask in regions(numbers, c).items():
        e = delta[mask]
        figures[name] = (float(e.mean()), float(e.max()), int(mask.sum())) if e.size else None
    shown = "; ".join(f"{name} {f[0]:.3f} / {f[1]:.3f} ({f[2]} px)" for name, f in figures.items()
                      if f)
    ok = all(f is not None and f[0] <= BOUND_MEAN and f[1] <= BOUND_MAX for f in figures.values())
    ok = ok and figures["chart borders"][0] <= (
        BORDER_FACTOR * figures["elsewhere"][0] + BORDER_SLACK)
    results.check(f"{case['name']}: EEVEE against Cycles, ΔE00 mean / max at the chart borders, "
                  "the rim and elsewhere", ok, f"({shown})")
    return images, delta


def write_picture(images, delta, png_path):
    """EEVEE, Cycles and their ΔE00 (white = 1) side by side, as an sRGB PNG."""
    panels = [images["BLENDER_EEVEE"][..., :3], images["CYCLES"][..., :3],
              np.repeat(np.minimum(delta, 1.0)[..., None], 3, -1)]
    strip = np.concatenate(panels, axis=1)
    srgb = np.where(strip <= 0.0031308, 12.92 * strip, 1.055 * np.abs(strip) ** (1 / 2.4) - 0.055)
    height, width = strip.shape[:2]
    image = bpy.data.images.new("eevee against cycles", width, height, alpha=False)
    rgba = np.concatenate([np.clip(srgb, 0, 1), np.ones((height, width, 1))], -1)
    image.pixels[:] = rgba[::-1].ravel()  # Blender's rows run bottom to top
    image.filepath_raw = str(png_path)
    image.file_format = "PNG"
    image.save()
    print(f"wrote {png_path}")


class Results:
    def __init__(self):
        self.passed = self.failed = 0

    def check(self, name, ok, detail=""):
        print(f"{'ok  ' if ok else 'FAIL'}  {name} {detail}")
        if ok:
            self.passed += 1
        else:
            self.failed += 1


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--irid", default=os.environ.get("IRID_BIN", REPO / "target/release/irid"))
    parser.add_argument("--resolution", type=int, default=RESOLUTION)
    parser.add_argument("--image", help="write EEVEE | Cycles | ΔE00 of the first case to this PNG")
    args = parser.parse_args()
    started = time.monotonic()
    results = Results()
    with tempfile.TemporaryDirectory(prefix="irid-eevee-") as tmp:
        workdir = Path(tmp)
        irid = Irid(args.irid, workdir)
        scene, sphere = scene_setup(args.resolution)
        for k, case in enumerate(CASES):
            images, delta = measure_case(results, scene, sphere, irid, workdir, case)
            if k == 0 and args.image:
                write_picture(images, delta, Path(args.image))
        try:  # which OpenGL EEVEE drew with (headless: EGL, often Mesa's llvmpipe)
            import gpu
            print(f"info  EEVEE drew on {gpu.platform.vendor_get()} {gpu.platform.renderer_get()} "
                  f"{gpu.platform.version_get()}")
        except Exception as e:  # the figures above stand without it
            print(f"info  EEVEE's GPU platform is not readable here ({e})")
    print(f"{time.monotonic() - started:.0f} s")
    print(f"{results.passed} passed, {results.failed} failed")
    return 1 if results.failed else 0


if __name__ == "__main__":
    sys.exit(main())
