"""Headless Blender test of tools/blender/irid_blender.py.

Runs with Blender as a Python module (`pip install "bpy==5.0.*" "numpy<2"
OpenEXR`) and the irid binary:

    python tools/blender/test_blender.py --irid target/release/irid

Checks, each counted as one test:
  - orientation: Blender puts an EXR file's first row at v = 1 (the file is
    written with the OpenEXR package, not with Blender);
  - mapping: synthetic film tables whose texels hold their own (x, y)
    coordinates, rendered in Cycles through the node group, give back the
    export's closed-form (thickness, cos θ) -> (x, y) mapping, with and
    without a critical angle;
  - bad input: a missing file or damaged film.json raises ExportError with
    one message and leaves no image, node group or material behind;
  - add-on: register() and File > Import > irid film build and assign a material;
  - accuracy: `irid export --white e` of several stacks, the material in
    Cycles (CPU) on a large plane under a uniform white world, orthographic
    camera at 0, 30, 60 and 75 degrees to the normal (every pixel sees one
    angle), against `irid color --white e --json` at that angle and
    thickness: mean CIEDE2000 <= 0.3 and max <= 1 per stack, in the ACEScg
    working space and, for stacks whose exact colours lie inside Rec.709, in
    the Rec.709 one (Cycles clips negative BSDF colours);
  - Cycles' own Principled thin film on the one-film stacks (film on glass;
    films on silver and copper with the bare metal's irid colour as base
    colour), measured against the same exact colours and reported beside
    irid's, with no bound.

--table FILE writes the measured table (markdown); --docs rewrites the
table between the markers in docs/blender.md; --image PNG renders the
spheres picture of docs/blender.md. Prints "N passed, N failed" last and
exits non-zero on any failure.
"""

import argparse
import json
import math
import os
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import OpenEXR

import bpy

HERE = Path(__file__).resolve().parent
REPO = HERE.parent.parent
sys.path.insert(0, str(HERE))
import irid_blender  # noqa: E402

ANGLES_DEG = (0.0, 30.0, 60.0, 75.0)
MEAN_BOUND = 0.3
MAX_BOUND = 1.0
RESOLUTION = 4  # pixels a side: every pixel sees the same angle
SAMPLES = 2  # a mirror under a uniform world is noise-free; 2 checks that
DOC_MARKERS = ("<!-- blender-table:start -->", "<!-- blender-table:end -->")

# ---------------------------------------------------------------- colour

# Linear sRGB (IEC 61966-2-1 primaries, D65) to CIE XYZ; (1, 1, 1) is the
# reference white of Lab, as in irid's own delta_e2000_rgb.
SRGB_TO_XYZ = np.array(
    [[0.4124, 0.3576, 0.1805], [0.2126, 0.7152, 0.0722], [0.0193, 0.1192, 0.9505]]
)


def rgb_to_lab(rgb):
    xyz = np.asarray(rgb, float) @ SRGB_TO_XYZ.T
    t = xyz / SRGB_TO_XYZ.sum(axis=1)
    d = 6.0 / 29.0
    f = np.where(t > d**3, np.cbrt(t), t / (3 * d * d) + 4.0 / 29.0)
    return np.stack(
        [116 * f[..., 1] - 16, 500 * (f[..., 0] - f[..., 1]), 200 * (f[..., 1] - f[..., 2])], -1
    )


def delta_e2000(lab1, lab2):
    """CIEDE2000 (Sharma, Wu and Dalal 2005), elementwise over the last axis."""
    L1, a1, b1 = np.moveaxis(np.asarray(lab1, float), -1, 0)
    L2, a2, b2 = np.moveaxis(np.asarray(lab2, float), -1, 0)
    c_bar = 0.5 * (np.hypot(a1, b1) + np.hypot(a2, b2))
    g = 0.5 * (1 - np.sqrt(c_bar**7 / (c_bar**7 + 25.0**7)))
    a1p, a2p = (1 + g) * a1, (1 + g) * a2
    c1p, c2p = np.hypot(a1p, b1), np.hypot(a2p, b2)
    h1p = np.degrees(np.arctan2(b1, a1p)) % 360
    h2p = np.degrees(np.arctan2(b2, a2p)) % 360
    chroma_zero = c1p * c2p == 0
    dh = h2p - h1p
    dh = np.where(dh > 180, dh - 360, np.where(dh < -180, dh + 360, dh))
    dh = np.where(chroma_zero, 0.0, dh)
    d_big_h = 2 * np.sqrt(c1p * c2p) * np.sin(np.radians(dh / 2))
    l_bar = 0.5 * (L1 + L2)
    c_bar_p = 0.5 * (c1p + c2p)
    h_sum = h1p + h2p
    h_bar = np.where(
        np.abs(h1p - h2p) > 180, np.where(h_sum < 360, h_sum + 360, h_sum - 360), h_sum
    ) / 2
    h_bar = np.where(chroma_zero, h_sum, h_bar)
    t = (
        1
        - 0.17 * np.cos(np.radians(h_bar - 30))
        + 0.24 * np.cos(np.radians(2 * h_bar))
        + 0.32 * np.cos(np.radians(3 * h_bar + 6))
        - 0.20 * np.cos(np.radians(4 * h_bar - 63))
    )
    d_theta = 30 * np.exp(-(((h_bar - 275) / 25) ** 2))
    r_c = 2 * np.sqrt(c_bar_p**7 / (c_bar_p**7 + 25.0**7))
    s_l = 1 + 0.015 * (l_bar - 50) ** 2 / np.sqrt(20 + (l_bar - 50) ** 2)
    s_c = 1 + 0.045 * c_bar_p
    s_h = 1 + 0.015 * c_bar_p * t
    r_t = -np.sin(np.radians(2 * d_theta)) * r_c
    dl, dc, dhh = (L2 - L1) / s_l, (c2p - c1p) / s_c, d_big_h / s_h
    return np.sqrt(dl**2 + dc**2 + dhh**2 + r_t * dc * dhh)


def delta_e2000_rgb(a, b):
    return delta_e2000(rgb_to_lab(a), rgb_to_lab(b))


# Test pairs from G. Sharma, W. Wu, E. N. Dalal, "The CIEDE2000 color-difference
# formula: implementation notes, supplementary test data, and mathematical
# observations", Color Research & Application 30(1), 2005, Table 1 (pairs 1, 2,
# 3, 4, 7, 13, 17, 25, 34): (Lab 1, Lab 2, ΔE00).
SHARMA_PAIRS = [
    ((50.0, 2.6772, -79.7751), (50.0, 0.0, -82.7485), 2.0425),
    ((50.0, 3.1571, -77.2803), (50.0, 0.0, -82.7485), 2.8615),
    ((50.0, 2.8361, -74.0200), (50.0, 0.0, -82.7485), 3.4412),
    ((50.0, -1.3802, -84.2814), (50.0, 0.0, -82.7485), 1.0000),
    ((50.0, 0.0, 0.0), (50.0, -1.0, 2.0), 2.3669),
    ((50.0, 2.4900, -0.0010), (50.0, -2.4900, 0.0009), 7.1792),
    ((50.0, 2.5, 0.0), (73.0, 25.0, -18.0), 27.1492),
    ((60.2574, -34.0099, 36.2677), (60.4626, -34.1751, 39.4387), 1.2644),
    ((2.0776, 0.0795, -1.1350), (0.9033, -0.0636, -0.5514), 0.9082),
]

# ---------------------------------------------------------------- files


def write_exr(path, rgba_rows):
    """An RGBA half-float EXR whose first stored row is rgba_rows[0]."""
    pixels = np.ascontiguousarray(np.asarray(rgba_rows, np.float32).astype(np.float16))
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    with OpenEXR.File(header, {"RGBA": pixels}) as f:
        f.write(str(path))


def read_exr_rgb(path):
    with OpenEXR.File(str(path)) as f:
        channels = f.channels()
        if "RGBA" in channels:
            return np.asarray(channels["RGBA"].pixels, float)[..., :3]
        if "RGB" in channels:
            return np.asarray(channels["RGB"].pixels, float)
        return np.stack([np.asarray(channels[c].pixels, float) for c in "RGB"], -1)


def write_synthetic_export(
    directory, size_u, size_v, cos_range, cos_crit, y_crit, opaque, thickness_power=1
):
    """A film table for the mapping test: texel (i, j) holds reflectance
    (i / (N_u - 1), j / (N_v - 1), 0.25) and transmittance
    (1 - i / (N_u - 1), 1 - j / (N_v - 1), 0.75), so bilinear sampling gives
    back the continuous texel coordinates (x, y) the mapping produced."""
    directory.mkdir(parents=True, exist_ok=True)
    i = np.arange(size_u) / (size_u - 1)
    j = np.arange(size_v) / (size_v - 1)
    x, y = np.meshgrid(i, j)  # row r = j-th angle node: row 0 is y = 0
    one = np.ones_like(x)
    write_exr(directory / "reflectance.exr", np.stack([x, y, 0.25 * one, one], -1))
    write_exr(directory / "transmittance.exr", np.stack([1 - x, 1 - y, 0.75 * one, one], -1))
    film = {
        "format": "irid-film",
        "version": 1,
        "texture": {
            "width": size_u,
            "height": size_v,
            "format": "rgba16f",
            "files": {"reflectance": "reflectance.exr", "transmittance": "transmittance.exr"},
            "png": None,
        },
        "domain": {"thickness_nm": [100.0, 900.0], "cos_theta": list(cos_range)},
        "params": {
            "thickness_min_nm": 100.0,
            "thickness_max_nm": 900.0,
            "cos_min": cos_range[0],
            "cos_max": cos_range[1],
            "cos_crit": cos_crit,
            "y_crit": y_crit,
            "size_u": size_u,
            "size_v": size_v,
            "thickness_power": thickness_power,
        },
        "white": "e",
        "stack": {
            "ambient": {"name": "n=1", "dispersion": {"constant": {"n": 1.0, "k": 0.0}}},
            "layers": [],
            "substrate": {"name": "n=1.5", "dispersion": {"constant": {"n": 1.5, "k": 0.0}}},
        },
        "layer": 1,
        "sampling": "exact",
        "opaque": opaque,
    }
    (directory / "film.json").write_text(json.dumps(film, indent=1))


def expected_x(fraction, thickness_power):
    """The export's thickness warp (docs/gpu.md), written out directly."""
    x = min(max(fraction, 0.0), 1.0)
    return math.sqrt(x) if thickness_power == 2 else x


def expected_y(c, cos_min, cos_max, cos_crit, y_crit):
    """The export's angle warp (docs/gpu.md), written out directly."""
    c = min(max(c, cos_min), cos_max)
    if cos_crit < 0:
        return (c - cos_min) / (cos_max - cos_min)
    if c >= cos_crit:
        return y_crit + (1 - y_crit) * math.sqrt((c - cos_crit) / (cos_max - cos_crit))
    return y_crit - y_crit * math.sqrt((cos_crit - c) / (cos_crit - cos_min))


# ---------------------------------------------------------------- Blender scene


class Bench:
    """A Cycles scene: one large plane, an orthographic camera, a white world."""

    def __init__(self, workdir):
        self.workdir = Path(workdir)
        bpy.ops.wm.read_factory_settings(use_empty=True)
        scene = bpy.context.scene
        self.scene = scene
        scene.render.engine = "CYCLES"
        scene.cycles.device = "CPU"
        scene.cycles.samples = SAMPLES
        scene.cycles.use_adaptive_sampling = False
        scene.cycles.use_denoising = False
        scene.cycles.seed = 1
        scene.cycles.sample_clamp_direct = 0.0
        scene.cycles.sample_clamp_indirect = 0.0
        scene.cycles.blur_glossy = 0.0
        scene.render.threads_mode = "FIXED"
        scene.render.threads = 2
        scene.view_settings.view_transform = "Standard"
        scene.view_settings.look = "None"
        scene.render.resolution_x = RESOLUTION
        scene.render.resolution_y = RESOLUTION
        scene.render.resolution_percentage = 100
        settings = scene.render.image_settings
        settings.file_format = "OPEN_EXR"
        settings.color_depth = "32"
        settings.exr_codec = "ZIP"
        # Renders are written in linear Rec.709 (irid's linear sRGB) whatever
        # the working space.
        settings.color_management = "OVERRIDE"
        settings.linear_colorspace_settings.name = "Linear Rec.709"

        world = bpy.data.worlds.new("white")
        scene.world = world
        if world.node_tree is None:
            world.use_nodes = True
        self.world = world
        self.set_world("white")

        mesh = bpy.data.meshes.new("plane")
        half = 1.0e4
        mesh.from_pydata(
            [(-half, -half, 0), (half, -half, 0), (half, half, 0), (-half, half, 0)],
            [],
            [(0, 1, 2, 3)],
        )
        self.plane = bpy.data.objects.new("plane", mesh)
        # Keep the quad's diagonal edge away from the view: a refracted ray that
        # starts on the edge between its two triangles can hit the plane again.
        self.plane.location = (2000.0, 700.0, 0.0)
        scene.collection.objects.link(self.plane)

        camera = bpy.data.cameras.new("camera")
        camera.type = "ORTHO"
        camera.ortho_scale = 0.1
        camera.clip_start = 0.01
        camera.clip_end = 100.0
        self.camera = bpy.data.objects.new("camera", camera)
        scene.collection.objects.link(self.camera)
        scene.camera = self.camera
        self.renders = 0

    def set_world(self, mode):
        """white: uniform white for every ray. reflection: white except for rays
        that have refracted (so the plane shows R alone); transmission: white only
        for those (the plane shows T alone)."""
        tree = self.world.node_tree
        tree.nodes.clear()
        background = tree.nodes.new("ShaderNodeBackground")
        background.inputs["Color"].default_value = (1.0, 1.0, 1.0, 1.0)
        background.inputs["Strength"].default_value = 1.0
        out = tree.nodes.new("ShaderNodeOutputWorld")
        tree.links.new(background.outputs[0], out.inputs["Surface"])
        if mode == "white":
            return
        path = tree.nodes.new("ShaderNodeLightPath")
        strength = path.outputs["Is Transmission Ray"]
        if mode == "reflection":
            invert = tree.nodes.new("ShaderNodeMath")
            invert.operation = "SUBTRACT"
            invert.inputs[0].default_value = 1.0
            tree.links.new(strength, invert.inputs[1])
            strength = invert.outputs[0]
        elif mode != "transmission":
            raise ValueError(mode)
        tree.links.new(strength, background.inputs["Strength"])

    def set_working_space(self, name):
        """Blender 5.0's scene-linear working space: Linear Rec.709 (the default) or ACEScg."""
        done = bpy.ops.wm.set_working_color_space(working_space=name, convert_colors=False)
        if done != {"FINISHED"} or bpy.data.colorspace.working_space != name:
            raise RuntimeError(f"cannot set the working colour space to {name}")

    def render(self, material, angle_deg, samples=SAMPLES):
        """Linear Rec.709 RGB of every pixel, shape (H, W, 3)."""
        self.scene.cycles.samples = samples
        self.plane.data.materials.clear()
        self.plane.data.materials.append(material)
        theta = math.radians(angle_deg)
        distance = 10.0
        self.camera.location = (0.0, -distance * math.sin(theta), distance * math.cos(theta))
        self.camera.rotation_euler = (theta, 0.0, 0.0)
        path = self.workdir / f"render-{self.renders}.exr"
        self.renders += 1
        self.scene.render.filepath = str(path)
        with quiet_stdout():
            bpy.ops.render.render(write_still=True)
        return read_exr_rgb(path)


class quiet_stdout:
    """Silences Blender's per-render progress lines (written to file descriptor 1)."""

    def __enter__(self):
        sys.stdout.flush()
        self.saved = os.dup(1)
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, 1)
        os.close(devnull)

    def __exit__(self, *exc):
        os.dup2(self.saved, 1)
        os.close(self.saved)


def emission_material(name, group, output, thickness_fraction):
    """A material showing one of a film group's colour outputs as emission."""
    material = bpy.data.materials.new(name)
    if material.node_tree is None:
        material.use_nodes = True
    tree = material.node_tree
    tree.nodes.clear()
    film = tree.nodes.new("ShaderNodeGroup")
    film.node_tree = group
    film.inputs["Thickness"].default_value = thickness_fraction
    emission = tree.nodes.new("ShaderNodeEmission")
    emission.inputs["Strength"].default_value = 1.0
    out = tree.nodes.new("ShaderNodeOutputMaterial")
    tree.links.new(film.outputs[output], emission.inputs["Color"])
    tree.links.new(emission.outputs[0], out.inputs["Surface"])
    return material


def principled_material(name, base_color, metallic, ior, film_thickness_nm, film_ior, workdir):
    """Cycles' own thin film: a Principled BSDF with Thin Film inputs, no diffuse.
    The base colour (linear Rec.709) goes through a one-texel image tagged
    Linear Rec.709, so Blender converts it into the working space."""
    material = bpy.data.materials.new(name)
    if material.node_tree is None:
        material.use_nodes = True
    tree = material.node_tree
    tree.nodes.clear()
    bsdf = tree.nodes.new("ShaderNodeBsdfPrincipled")
    path = Path(workdir) / f"base-{len(bpy.data.images)}.exr"
    texel = np.array([[[*base_color, 1.0]]], np.float32)
    pixels = np.ascontiguousarray(texel)
    with OpenEXR.File({"compression": OpenEXR.NO_COMPRESSION}, {"RGBA": pixels}) as f:
        f.write(str(path))
    image = bpy.data.images.load(str(path), check_existing=False)
    image.colorspace_settings.name = "Linear Rec.709"
    texture = tree.nodes.new("ShaderNodeTexImage")
    texture.image = image
    texture.interpolation = "Closest"
    tree.links.new(texture.outputs["Color"], bsdf.inputs["Base Color"])
    bsdf.inputs["Metallic"].default_value = metallic
    bsdf.inputs["Roughness"].default_value = 0.0
    bsdf.inputs["IOR"].default_value = ior
    bsdf.inputs["Thin Film Thickness"].default_value = film_thickness_nm
    bsdf.inputs["Thin Film IOR"].default_value = film_ior
    out = tree.nodes.new("ShaderNodeOutputMaterial")
    tree.links.new(bsdf.outputs[0], out.inputs["Surface"])
    return material


# ---------------------------------------------------------------- irid


class Irid:
    def __init__(self, binary, workdir):
        self.binary = str(binary)
        self.workdir = Path(workdir)

    def run(self, *args):
        done = subprocess.run(
            [self.binary, *map(str, args)], capture_output=True, text=True, check=False
        )
        if done.returncode != 0:
            raise RuntimeError(f"irid {' '.join(map(str, args))}: {done.stderr.strip()}")
        return done.stdout

    def colours(self, stack_path, angles_deg):
        """Exact (reflectance, transmittance) linear RGB per angle, white E."""
        angles = ",".join(f"{a:g}" for a in angles_deg)
        rows = json.loads(
            self.run("color", stack_path, "--white", "e", "--angles", angles, "--json")
        )
        got = [row["angle_deg"] for row in rows]
        if not np.allclose(got, angles_deg):
            raise RuntimeError(f"irid color answered angles {got}, asked {list(angles_deg)}")
        return (
            np.array([row["reflectance_rgb"] for row in rows]),
            np.array([row["transmittance_rgb"] for row in rows]),
        )

    def export(self, stack_path, out_dir, layer, thickness_range):
        self.run(
            "export",
            stack_path,
            "-o",
            out_dir,
            "--white",
            "e",
            "--layer",
            layer,
            "--thickness",
            f"{thickness_range[0]:g}:{thickness_range[1]:g}",
        )
        return out_dir


def stack_with_thickness(source_text, layer, thickness_nm):
    """A stack file's text with the layer-th (from 1) layer's thickness replaced."""
    pattern = re.compile(r"^(\s*thickness_nm\s*=\s*)([0-9.eE+-]+)", re.M)
    matches = list(pattern.finditer(source_text))
    if len(matches) < layer:
        raise ValueError(f"the stack has fewer than {layer} layers with thickness_nm")
    m = matches[layer - 1]
    return source_text[: m.start(2)] + f"{thickness_nm!r}" + source_text[m.end(2) :]


# ---------------------------------------------------------------- the cases

# name, stack file, layer exported, its thickness range (nm), thickness of the
# second check (through the 0-1 socket), Cycles' Principled equivalent or None.
CASES = [
    {
        "name": "film on silver",
        "stack": "tests/blender/film-on-silver.toml",
        "layer": 1,
        "range": (200.0, 500.0),
        "cycles": {"metal": "silver", "film_ior": 1.38},
    },
    {
        "name": "film on copper",
        "stack": "tests/blender/film-on-copper.toml",
        "layer": 1,
        "range": (100.0, 500.0),
        "cycles": {"metal": "copper", "film_ior": 2.2},
    },
    {
        "name": "film on glass",
        "stack": "tests/blender/film-on-glass.toml",
        "layer": 1,
        "range": (200.0, 500.0),
        "cycles": {"substrate_ior": 1.5, "film_ior": 1.38},
    },
    {"name": "two layers on gold", "stack": "luts/two-layer.toml", "layer": 1, "range": (150.0, 450.0)},
    {
        "name": "absorbing film on fused silica",
        "stack": "luts/absorbing-film.toml",
        "layer": 1,
        "range": (150.0, 450.0),
    },
]
SOCKET_FRACTION = 0.3  # the second thickness: through the group's 0-1 socket


class Results:
    def __init__(self):
        self.passed = 0
        self.failed = 0
        self.rows = []

    def check(self, name, ok, detail=""):
        if ok:
            self.passed += 1
            print(f"ok    {name} {detail}")
        else:
            self.failed += 1
            print(f"FAIL  {name} {detail}")


def test_delta_e(results):
    worst = max(abs(float(delta_e2000(a, b)) - e) for a, b, e in SHARMA_PAIRS)
    symmetric = max(
        abs(float(delta_e2000(a, b)) - float(delta_e2000(b, a))) for a, b, _ in SHARMA_PAIRS
    )
    results.check("CIEDE2000 on Sharma's pairs", worst < 1e-4 and symmetric < 1e-9,
                  f"(largest difference {worst:.1e})")


def test_orientation(results, workdir):
    rows = np.zeros((4, 2, 4))
    rows[:, :, 0] = np.arange(4)[:, None]
    rows[:, :, 3] = 1.0
    path = workdir / "rows.exr"
    write_exr(path, rows)
    image = bpy.data.images.load(str(path), check_existing=False)
    image.colorspace_settings.name = "Non-Color"
    width, height = image.size
    pixels = np.array(image.pixels[:]).reshape(height, width, 4)
    bpy.data.images.remove(image)
    # Blender's pixel rows run from v = 0 (bottom) up: the file's first row is the last.
    results.check("file's first row at v = 1", list(pixels[:, 0, 0]) == [3.0, 2.0, 1.0, 0.0],
                  f"(Blender rows bottom-up hold file rows {list(pixels[:, 0, 0])})")


def test_mapping(results, bench, workdir):
    cos_range = (math.cos(math.radians(89.0)), 1.0)
    variants = [
        ("linear", 9, 7, -1.0, 0.0, 1),
        # Critical angle at cos 0.6, on the texel row k = 3 of 7: y_crit = 3 / 6.
        ("critical", 9, 7, 0.6, 0.5, 1),
        # Nodes crowding towards grazing incidence and towards the thinnest film.
        ("grazing, square-root thickness", 9, 7, cos_range[0], 0.0, 2),
    ]
    for label, size_u, size_v, cos_crit, y_crit, power in variants:
        directory = workdir / f"synthetic-{label.replace(' ', '').replace(',', '-')}"
        write_synthetic_export(
            directory, size_u, size_v, cos_range, cos_crit, y_crit, False, power
        )
        group = irid_blender.make_node_group(directory, name=f"synthetic {label}")
        worst = 0.0
        for fraction in (0.0, 0.37, 1.0):
            reflect = emission_material(f"R {label} {fraction}", group, "Reflectance", fraction)
            transmit = emission_material(f"T {label} {fraction}", group, "Transmittance", fraction)
            for angle in ANGLES_DEG + (89.5,):
                y = expected_y(math.cos(math.radians(angle)), *cos_range, cos_crit, y_crit)
                r = bench.render(reflect, angle)
                t = bench.render(transmit, angle)
                x = expected_x(fraction, power)
                want_r = np.array([x, y, 0.25])
                want_t = np.array([1 - x, 1 - y, 0.75])
                worst = max(worst, np.abs(r - want_r).max(), np.abs(t - want_t).max())
        # Half-float texels hold 1/1024 steps near 1; float math nodes add ~1e-6.
        results.check(f"mapping, {label} warp", worst < 2e-3,
                      f"(largest |rendered - closed form| {worst:.1e})")


def test_bad_input(results, workdir):
    good = workdir / "synthetic-linear"
    before = (len(bpy.data.images), len(bpy.data.node_groups), len(bpy.data.materials))
    cases = {}
    missing = workdir / "bad-missing"
    write_synthetic_export(missing, 3, 3, (0.1, 1.0), -1.0, 0.0, True)
    (missing / "transmittance.exr").unlink()
    cases["a missing transmittance.exr"] = (missing, "transmittance.exr is missing")
    damaged = workdir / "bad-json"
    write_synthetic_export(damaged, 3, 3, (0.1, 1.0), -1.0, 0.0, True)
    (damaged / "film.json").write_text('{"format": "irid-film", "version": 1, "params": {')
    cases["a truncated film.json"] = (damaged, "not readable JSON")
    wrong = workdir / "bad-params"
    write_synthetic_export(wrong, 3, 3, (0.1, 1.0), -1.0, 0.0, True)
    film = json.loads((wrong / "film.json").read_text())
    film["params"]["cos_max"] = "one"
    (wrong / "film.json").write_text(json.dumps(film))
    cases["a non-numeric parameter"] = (wrong, "params.cos_max")
    broken = workdir / "bad-exr"
    write_synthetic_export(broken, 3, 3, (0.1, 1.0), -1.0, 0.0, True)
    data = (broken / "reflectance.exr").read_bytes()
    (broken / "reflectance.exr").write_bytes(data[: len(data) // 3])
    cases["a truncated reflectance.exr"] = (broken, "reflectance.exr: Blender cannot read it")
    for what, (directory, needle) in cases.items():
        try:
            irid_blender.make_material(directory, thickness_nm=300.0)
            ok, detail = False, "(no exception)"
        except irid_blender.ExportError as e:
            message = str(e)
            ok = needle in message and "\n" not in message
            detail = f"({message})"
        after = (len(bpy.data.images), len(bpy.data.node_groups), len(bpy.data.materials))
        results.check(f"bad input: {what}", ok and after == before,
                      detail + ("" if after == before else f" left {after} vs {before}"))
    try:
        irid_blender.make_material(good, thickness_nm=50.0)
        ok = False
    except ValueError as e:
        ok = "outside the export's range" in str(e)
    after = (len(bpy.data.images), len(bpy.data.node_groups), len(bpy.data.materials))
    results.check("bad input: a thickness outside the range", ok and after == before)


def test_addon(results, workdir):
    """The add-on registers, and its import operator builds and assigns a material."""
    directory = workdir / "synthetic-linear"
    irid_blender.register()
    try:
        mesh = bpy.data.meshes.new("addon mesh")
        mesh.from_pydata([(0, 0, 0), (1, 0, 0), (0, 1, 0)], [], [(0, 1, 2)])
        obj = bpy.data.objects.new("addon object", mesh)
        bpy.context.scene.collection.objects.link(obj)
        bpy.context.view_layer.objects.active = obj
        obj.select_set(True)
        done = bpy.ops.import_scene.irid_film(
            filepath=str(directory / "film.json"), thickness_nm=500.0
        )
        material = mesh.materials[0] if mesh.materials else None
        film = material and next(
            (n for n in material.node_tree.nodes if n.bl_idname == "ShaderNodeGroup"), None
        )
        fraction = film.inputs["Thickness"].default_value if film else None
        ok = done == {"FINISHED"} and fraction is not None and abs(fraction - 0.5) < 1e-6
        results.check("add-on: File > Import > irid film assigns the material", ok,
                      f"(operator {done}, thickness socket {fraction})")
        bpy.data.objects.remove(obj)
        bpy.data.meshes.remove(mesh)
    finally:
        irid_blender.unregister()


WORKING_SPACES = ("ACEScg", "Linear Rec.709")
# A transmitting film's material adds a Refraction lobe to the Glossy one;
# Cycles picks one of them per sample, so those renders take many samples.
TRANSMITTING_SAMPLES = 16384


def measure(results, bench, irid, workdir):
    """Every case in every working space: irid's material and, on the one-film
    cases, Cycles' Principled thin film, against irid color."""
    table = []
    exports = {}
    for space in WORKING_SPACES:
        bench.set_working_space(space)
        for n, case in enumerate(CASES):
            stack = REPO / case["stack"]
            if n not in exports:
                exports[n] = irid.export(stack, workdir / f"export-{n}", case["layer"], case["range"])
            row = measure_case(results, bench, irid, workdir, case, n, exports[n], space)
            table.append(row)
    return table


def measure_case(results, bench, irid, workdir, case, n, directory, space):
    stack = REPO / case["stack"]
    export = irid_blender.Export(directory)
    text = stack.read_text()
    nominal = float(
        re.findall(r"^\s*thickness_nm\s*=\s*([0-9.eE+-]+)", text, re.M)[case["layer"] - 1]
    )
    t_min, t_max = case["range"]
    checks = [("constant", nominal, None)]
    checks.append(("socket", t_min + SOCKET_FRACTION * (t_max - t_min), SOCKET_FRACTION))
    transmits = export.transmits()
    samples = TRANSMITTING_SAMPLES if transmits else SAMPLES
    errors = {"R": [], "T": []}
    in_gamut = True
    for how, thickness, fraction in checks:
        stack_file = workdir / f"stack-{n}-{how}.toml"
        stack_file.write_text(stack_with_thickness(text, case["layer"], thickness))
        exact = dict(zip("RT", irid.colours(stack_file, ANGLES_DEG)))
        if fraction is None:
            material = irid_blender.make_material(directory, thickness_nm=thickness)
        else:
            material = irid_blender.make_material(directory)
            film = next(n for n in material.node_tree.nodes if n.bl_idname == "ShaderNodeGroup")
            film.inputs["Thickness"].default_value = fraction
        # An opaque film is lit by the whole white world; a transmitting one is
        # rendered twice, lit only through reflection and only through refraction.
        modes = (("reflection", "R"), ("transmission", "T")) if transmits else (("white", "R"),)
        for mode, channel in modes:
            bench.set_world(mode)
            in_gamut = in_gamut and bool((exact[channel] >= 0).all())
            for k, angle in enumerate(ANGLES_DEG):
                rendered = bench.render(material, angle, samples)
                errors[channel].append(delta_e2000_rgb(rendered, exact[channel][k]))
    # Cycles clips negative BSDF colours: in the Rec.709 working space a film
    # colour outside Rec.709 cannot be rendered, so the bound applies there only
    # to stacks whose exact colours are inside it.
    bounded = space != "Linear Rec.709" or in_gamut
    row = {"case": case["name"], "space": space, "bounded": bounded}
    for channel, values in errors.items():
        if not values:
            continue
        e = np.concatenate([np.ravel(x) for x in values])
        row[f"irid_{channel}"] = (float(e.mean()), float(e.max()))
        name = f"{case['name']}, {space} working space: irid {channel} vs exact"
        figures = f"(ΔE00 mean {e.mean():.3f}, max {e.max():.3f})"
        if bounded:
            results.check(name, e.mean() <= MEAN_BOUND and e.max() <= MAX_BOUND, figures)
        else:
            print(f"info  {name} {figures}: exact colours outside Rec.709, reported only")
    if case.get("cycles"):
        row["cycles_R"] = cycles_figures(bench, irid, workdir, case, nominal, stack)
        print(f"info  {case['name']}, {space} working space: Cycles' Principled thin film R "
              f"ΔE00 mean {row['cycles_R'][0]:.3f}, max {row['cycles_R'][1]:.3f} (no bound)")
    return row


def cycles_figures(bench, irid, workdir, case, nominal, stack):
    """Cycles' Principled thin film against exact reflectance at the nominal thickness."""
    spec = case["cycles"]
    exact_r, _ = irid.colours(stack, ANGLES_DEG)
    if "metal" in spec:
        bare = workdir / f"bare-{spec['metal']}.toml"
        bare.write_text(f'ambient = {{ n = 1.0 }}\nsubstrate = {{ material = "{spec["metal"]}" }}\n')
        base, _ = irid.colours(bare, (0.0,))
        material = principled_material(
            f"Cycles {case['name']}", tuple(base[0]), 1.0, 1.5, nominal, spec["film_ior"], workdir
        )
    else:
        material = principled_material(
            f"Cycles {case['name']}", (0.0, 0.0, 0.0), 0.0, spec["substrate_ior"], nominal,
            spec["film_ior"], workdir,
        )
    bench.set_world("white")
    errors = [delta_e2000_rgb(bench.render(material, a), exact_r[k]) for k, a in enumerate(ANGLES_DEG)]
    e = np.concatenate([np.ravel(x) for x in errors])
    return float(e.mean()), float(e.max())


def render_picture(irid, workdir, png_path):
    """Two mirror spheres under a white world, film on copper with a noise
    thickness: irid's material on the left, Cycles' Principled thin film on the
    right (copper as its base colour), the same thickness texture driving both."""
    case = next(c for c in CASES if c["name"] == "film on copper")
    t_min, t_max = case["range"]
    directory = irid.export(REPO / case["stack"], workdir / "export-picture", 1, (t_min, t_max))
    bare = workdir / "bare-picture.toml"
    bare.write_text(f'ambient = {{ n = 1.0 }}\nsubstrate = {{ material = "{case["cycles"]["metal"]}" }}\n')
    base, _ = irid.colours(bare, (0.0,))

    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = 32
    scene.cycles.use_denoising = False
    scene.view_settings.view_transform = "Standard"
    scene.render.resolution_x, scene.render.resolution_y = 560, 320
    scene.render.image_settings.file_format = "PNG"
    scene.render.image_settings.color_mode = "RGB"
    scene.render.image_settings.compression = 100
    world = bpy.data.worlds.new("white")
    scene.world = world
    if world.node_tree is None:
        world.use_nodes = True
    tree = world.node_tree
    tree.nodes.clear()
    # White light on the spheres; a grey backdrop for the camera only.
    background = tree.nodes.new("ShaderNodeBackground")
    mix = tree.nodes.new("ShaderNodeMix")
    mix.data_type = "RGBA"
    mix.inputs["A"].default_value = (1.0, 1.0, 1.0, 1.0)
    mix.inputs["B"].default_value = (0.45, 0.45, 0.45, 1.0)
    path = tree.nodes.new("ShaderNodeLightPath")
    tree.links.new(path.outputs["Is Camera Ray"], mix.inputs["Factor"])
    tree.links.new(mix.outputs["Result"], background.inputs["Color"])
    out = tree.nodes.new("ShaderNodeOutputWorld")
    tree.links.new(background.outputs[0], out.inputs["Surface"])

    def noise_fraction(tree):
        """A 0-1 thickness pattern over the sphere's own coordinates."""
        coords = tree.nodes.new("ShaderNodeTexCoord")
        noise = tree.nodes.new("ShaderNodeTexNoise")
        noise.inputs["Scale"].default_value = 1.5
        noise.inputs["Detail"].default_value = 1.0
        tree.links.new(coords.outputs["Object"], noise.inputs["Vector"])
        remap = tree.nodes.new("ShaderNodeMapRange")
        remap.inputs["From Min"].default_value = 0.3
        remap.inputs["From Max"].default_value = 0.7
        remap.clamp = True
        tree.links.new(noise.outputs["Fac"], remap.inputs["Value"])
        return remap.outputs["Result"]

    irid_material = irid_blender.make_material(directory, name="irid film on copper")
    tree = irid_material.node_tree
    film = next(n for n in tree.nodes if n.bl_idname == "ShaderNodeGroup")
    tree.links.new(noise_fraction(tree), film.inputs["Thickness"])

    spec = case["cycles"]
    cycles_material = principled_material(
        "Cycles thin film on copper", tuple(base[0]), 1.0, 1.5, t_min, spec["film_ior"], workdir
    )
    tree = cycles_material.node_tree
    to_nm = tree.nodes.new("ShaderNodeMath")
    to_nm.operation = "MULTIPLY_ADD"
    tree.links.new(noise_fraction(tree), to_nm.inputs[0])
    to_nm.inputs[1].default_value = t_max - t_min
    to_nm.inputs[2].default_value = t_min
    bsdf = next(n for n in tree.nodes if n.bl_idname == "ShaderNodeBsdfPrincipled")
    tree.links.new(to_nm.outputs[0], bsdf.inputs["Thin Film Thickness"])

    label_material = bpy.data.materials.new("label")
    if label_material.node_tree is None:
        label_material.use_nodes = True
    tree = label_material.node_tree
    tree.nodes.clear()
    emission = tree.nodes.new("ShaderNodeEmission")
    emission.inputs["Color"].default_value = (0.0, 0.0, 0.0, 1.0)
    out = tree.nodes.new("ShaderNodeOutputMaterial")
    tree.links.new(emission.outputs[0], out.inputs["Surface"])

    for x, material, label in (
        (-1.15, irid_material, "irid export"),
        (1.15, cycles_material, "Cycles thin film"),
    ):
        bpy.ops.mesh.primitive_uv_sphere_add(segments=96, ring_count=48, location=(x, 0, 0.15))
        sphere = bpy.context.active_object
        bpy.ops.object.shade_smooth()
        sphere.data.materials.append(material)
        sphere.visible_glossy = False  # each sphere shows the white world only
        sphere.visible_transmission = False
        curve = bpy.data.curves.new(label, "FONT")
        curve.body = label
        curve.size = 0.2
        curve.align_x = "CENTER"
        text = bpy.data.objects.new(label, curve)
        text.location = (x, 0, -1.2)
        text.rotation_euler = (math.radians(90), 0, 0)
        text.data.materials.append(label_material)
        text.visible_glossy = False
        scene.collection.objects.link(text)

    camera = bpy.data.cameras.new("camera")
    camera.type = "ORTHO"
    camera.ortho_scale = 4.9
    camera_object = bpy.data.objects.new("camera", camera)
    camera_object.location = (0, -10, 0)
    camera_object.rotation_euler = (math.radians(90), 0, 0)
    scene.collection.objects.link(camera_object)
    scene.camera = camera_object
    png_path.parent.mkdir(parents=True, exist_ok=True)
    scene.render.filepath = str(png_path)
    bpy.ops.render.render(write_still=True)
    print(f"wrote {png_path}")


def format_table(table):
    angles = ", ".join(f"{a:g}°" for a in ANGLES_DEG)
    lines = [
        f"ΔE00 (CIEDE2000) against `irid color --white e`, at {angles}, at the stack's "
        f"thickness and at {SOCKET_FRACTION:g} of the exported range through the Thickness "
        f"socket; Cycles CPU, roughness 0, {SAMPLES} samples ({TRANSMITTING_SAMPLES} for a "
        f"transmitting film), {RESOLUTION}×{RESOLUTION} pixels. Bound on irid: mean ≤ "
        f"{MEAN_BOUND:g}, max ≤ {MAX_BOUND:g} (* where the exact colours fall outside Rec.709 "
        "and the Rec.709 working space clips them: reported, not bounded).",
        "",
        "| stack | working space | irid R mean / max | irid T mean / max | Cycles thin film R mean / max |",
        "| --- | --- | --- | --- | --- |",
    ]
    fmt = lambda pair: "–" if pair is None else f"{pair[0]:.3f} / {pair[1]:.3f}"  # noqa: E731
    for row in table:
        mark = "" if row["bounded"] else " *"
        lines.append(
            f"| {row['case']} | {row['space']} | {fmt(row.get('irid_R'))}{mark} | "
            f"{fmt(row.get('irid_T'))}{mark if row.get('irid_T') else ''} | "
            f"{fmt(row.get('cycles_R'))} |"
        )
    return "\n".join(lines) + "\n"


def update_docs(table_text):
    doc = REPO / "docs" / "blender.md"
    text = doc.read_text()
    start, end = DOC_MARKERS
    if start not in text or end not in text:
        raise RuntimeError(f"{doc}: the table markers are missing")
    head, rest = text.split(start, 1)
    _, tail = rest.split(end, 1)
    doc.write_text(f"{head}{start}\n{table_text}{end}{tail}")


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--irid", default=os.environ.get("IRID_BIN", REPO / "target/release/irid"))
    parser.add_argument("--table", help="write the measured table (markdown) here")
    parser.add_argument("--docs", action="store_true", help="rewrite the table in docs/blender.md")
    parser.add_argument("--image", help="render the docs' spheres picture to this PNG")
    parser.add_argument("--keep", help="keep renders and exports in this directory")
    args = parser.parse_args()

    started = time.monotonic()
    results = Results()
    with tempfile.TemporaryDirectory(prefix="irid-blender-") as tmp:
        workdir = Path(args.keep or tmp)
        workdir.mkdir(parents=True, exist_ok=True)
        irid = Irid(args.irid, workdir)
        bench = Bench(workdir)
        test_delta_e(results)
        test_orientation(results, workdir)
        test_mapping(results, bench, workdir)
        test_bad_input(results, workdir)
        test_addon(results, workdir)
        table = measure(results, bench, irid, workdir)
        table_text = format_table(table)
        print()
        print(table_text)
        if args.table:
            Path(args.table).write_text(table_text)
        if args.docs:
            update_docs(table_text)
        if args.image:
            render_picture(irid, workdir, Path(args.image))
    print(f"{bench.renders} renders in {time.monotonic() - started:.0f} s")
    print(f"{results.passed} passed, {results.failed} failed")
    return 1 if results.failed else 0


if __name__ == "__main__":
    sys.exit(main())
