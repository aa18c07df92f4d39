"""Headless Blender test of the irid_blender add-on (blender/irid_blender).

Runs with Blender as a Python module (`pip install "bpy==5.0.*" "numpy<2"
OpenEXR`) and the irid binary:

    python blender/tests/test_blender.py --irid target/release/irid

Checks, each counted as one test:
  - orientation: Blender puts an EXR file's first row at v = 1 (the file is
    written with the OpenEXR package, not with Blender);
  - mapping: a synthetic atlas whose texels hold their own (x, y)
    coordinates, rendered in Cycles through the node group, gives back the
    chart the closed form picks and its (x, y), front and back faces;
  - rough table: synthetic slices, each an atlas of the front side's charts
    holding their own coordinates, give back at roughness r > 0 the rough
    chart the closed form picks, its (x, y) and √r (two slices blended),
    and at roughness 0 the smooth chart; malformed rough tables are refused;
  - inputs: the Normal input sets the film's angle; Thickness nm, when 0 or
    more, sets the thickness in nanometres;
  - bad input: a missing file or damaged film.json raises ExportError with
    one message and leaves no image, node group or material behind; so does
    an export for another white than Blender's, naming `--white e`;
  - add-on: register() and File > Import > irid film put the material in the
    active slot of the selected meshes, keeping their other slots, and cancel
    with a message when no mesh is selected; given no thickness, it takes
    the middle of the export's range;
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
    irid's, with no bound;
  - the glass side: coated glass seen from inside the glass (a back face) at
    20, 30, 40 and 60 degrees (past the critical angle), R and T against
    `irid color` of the reversed stack, the same bounds;
  - layering: add_film_layer over a diffuse Principled base and as the coat
    of a white metal one, in the white world, against R + albedo T;
  - white furnace: a coated glass cube, every bounce followed, averages 1
    within 1 % (Cycles' Principled glass beside it).

--table FILE writes the measured table (markdown); --docs rewrites the
table between the markers in docs/blender.md; --image PNG renders the
spheres picture of docs/blender.md. Prints "N passed, N failed" last and
exits non-zero on any failure.

The helpers live beside this file: colour_exr.py (CIEDE2000, EXR files, the
export's closed-form mapping) and cycles_scene.py (the Cycles scene, the
materials, the irid command line, the spheres picture).
"""

import argparse
import json
import math
import os
import re
import sys
import tempfile
import time
import tomllib
from pathlib import Path

import numpy as np

import bpy

HERE = Path(__file__).resolve().parent
REPO = HERE.parents[1]
# Python puts the script's directory on sys.path, Blender's --python does
# not; the package sits one folder up.
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(HERE.parent))
import irid_blender  # noqa: E402
from colour_exr import (  # noqa: E402
    delta_e2000,
    delta_e2000_rgb,
    write_exr,
    write_linear_band,
    write_synthetic_atlas,
)
from cycles_scene import (  # noqa: E402
    RESOLUTION,
    SAMPLES,
    Bench,
    Irid,
    emission_material,
    glass_material,
    principled_material,
    render_picture,
    stack_with_thickness,
)

ANGLES_DEG = (0.0, 30.0, 60.0, 75.0)
MEAN_BOUND = 0.3
MAX_BOUND = 1.0
DOC_MARKERS = ("<!-- blender-table:start -->", "<!-- blender-table:end -->")

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


def test_bad_input(results, workdir):
    good = workdir / "synthetic-linear"
    write_linear_band(good)
    before = (len(bpy.data.images), len(bpy.data.node_groups), len(bpy.data.materials))
    cases = {}
    missing = workdir / "bad-missing"
    write_linear_band(missing, (3, 3), opaque=True)
    (missing / "transmittance.exr").unlink()
    cases["a missing transmittance.exr"] = (missing, "transmittance.exr is missing")
    damaged = workdir / "bad-json"
    write_linear_band(damaged, (3, 3), opaque=True)
    (damaged / "film.json").write_text('{"format": "irid-film", "version": 3, "params": {')
    cases["a truncated film.json"] = (damaged, "not readable JSON")
    wrong = workdir / "bad-params"
    write_linear_band(wrong, (3, 3), opaque=True)
    film = json.loads((wrong / "film.json").read_text())
    film["charts"][0]["params"]["cos_hi"] = "one"
    (wrong / "film.json").write_text(json.dumps(film))
    cases["a non-numeric parameter"] = (wrong, "params.cos_hi")
    broken = workdir / "bad-exr"
    write_linear_band(broken, (3, 3), opaque=True)
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
    """The add-on registers; its import operator puts the material in the
    active slot of the selected meshes, keeping their other slots, and says
    so when no mesh is selected (building nothing)."""
    directory = workdir / "synthetic-linear"
    irid_blender.register()
    try:
        mesh = bpy.data.meshes.new("addon mesh")
        mesh.from_pydata([(0, 0, 0), (1, 0, 0), (0, 1, 0)], [], [(0, 1, 2)])
        kept = [bpy.data.materials.new(f"kept {k}") for k in range(2)]
        for material in kept:
            mesh.materials.append(material)
        obj = bpy.data.objects.new("addon object", mesh)
        bpy.context.scene.collection.objects.link(obj)
        bpy.context.view_layer.objects.active = obj
        obj.active_material_index = 1
        for other in bpy.context.view_layer.objects:
            other.select_set(False)
        count = len(bpy.data.materials)
        # An operator's error report reaches a script as a RuntimeError.
        try:
            done = bpy.ops.import_scene.irid_film(
                filepath=str(directory / "film.json"), thickness_nm=500.0
            )
        except RuntimeError as e:
            done = str(e)
        results.check("add-on: with no mesh selected, the operator says so and builds nothing",
                      "No mesh is selected" in str(done) and len(bpy.data.materials) == count,
                      f"(operator: {done}; materials {count} -> {len(bpy.data.materials)})")
        obj.select_set(True)
        try:
            done = bpy.ops.import_scene.irid_film(
                filepath=str(directory / "film.json"), thickness_nm=500.0, roughness=0.3
            )
        except RuntimeError as e:
            done = str(e)
        results.check("add-on: a roughness above 0 with an export without the rough table is "
                      "refused, naming --rough",
                      "--rough" in str(done) and len(bpy.data.materials) == count,
                      f"(operator: {done}; materials {count} -> {len(bpy.data.materials)})")
        done = bpy.ops.import_scene.irid_film(
            filepath=str(directory / "film.json"), thickness_nm=500.0
        )
        slots = [m.name if m else None for m in mesh.materials]
        material = mesh.materials[1]
        film = material and next(
            (n for n in material.node_tree.nodes if n.bl_idname == "ShaderNodeGroup"), None
        )
        nm = film.inputs["Thickness nm"].default_value if film else None
        ok = (done == {"FINISHED"} and len(slots) == 2 and slots[0] == "kept 0"
              and material is not kept[1] and nm == 500.0)
        results.check("add-on: File > Import > irid film fills the active slot, keeps the others",
                      ok, f"(operator {done}, slots {slots}, thickness {nm} nm)")
        # No thickness given: the middle of this export's range, not a
        # fixed number that may lie outside it.
        ranged = workdir / "synthetic-400-800"
        write_linear_band(ranged, thickness_range=(400.0, 800.0))
        try:
            done = bpy.ops.import_scene.irid_film(filepath=str(ranged / "film.json"))
        except RuntimeError as e:
            done = str(e)
        material = mesh.materials[1]
        film = material and next(
            (n for n in material.node_tree.nodes if n.bl_idname == "ShaderNodeGroup"), None
        )
        nm = film.inputs["Thickness nm"].default_value if film else None
        results.check("add-on: without a thickness, the middle of the export's range (400-800 nm)",
                      done == {"FINISHED"} and nm == 600.0, f"(operator {done}, thickness {nm} nm)")
        bpy.data.objects.remove(obj)
        bpy.data.meshes.remove(mesh)
    finally:
        irid_blender.unregister()


# A synthetic version 3 atlas: on the front, a polar corner, a band near
# grazing incidence (log cos θ axis about 0, log p axis) and a band above it
# (square-root cos θ axis about its own minimum, uniform p); on the back,
# one band of another optical factor with a uniform cos θ axis.
A_SOAP = (1.0 / 1.33) ** 2
SYNTHETIC_ATLAS = [
    {"side": 0, "kind": 1, "a": A_SOAP, "floor": 0.2, "scale_nm": 40.0, "radius": 0.25,
     "size": (9, 7)},
    {"side": 0, "kind": 0, "a": A_SOAP, "floor": 0.2, "p0_nm": 150.0, "p_lo_nm": 0.0,
     "p_hi_nm": 600.0, "cos_lo": 0.0, "cos_hi": 0.35, "anchor": 0.0, "offset": 0.02,
     "size": (11, 8)},
    {"side": 0, "kind": 0, "a": A_SOAP, "floor": 0.2, "p0_nm": 0.0, "p_lo_nm": 100.0,
     "p_hi_nm": 600.0, "cos_lo": 0.35, "cos_hi": 1.0, "anchor": 0.35, "offset": 0.0,
     "size": (10, 9)},
    {"side": 1, "kind": 0, "a": 0.5, "floor": 0.3, "p0_nm": 80.0, "p_lo_nm": 0.0,
     "p_hi_nm": 600.0, "cos_lo": 0.0, "cos_hi": 1.0, "anchor": 0.0, "offset": -1.0,
     "size": (8, 6)},
]


def test_atlas_mapping(results, bench, workdir):
    """Version 3: a synthetic atlas whose texels hold their own chart
    coordinates and chart number, rendered through the node group, gives
    back the chart the closed-form choice picks and its (x, y), at
    thicknesses and angles that reach every chart, front and back faces."""
    directory = workdir / "synthetic-atlas"
    write_synthetic_atlas(directory, SYNTHETIC_ATLAS, {"front": [0, 1, 2], "back": [3]},
                          (0.0, 600.0), False)
    export = irid_blender.Export(directory)
    group = irid_blender.make_node_group(export, name="synthetic atlas")
    worst, picked = 0.0, set()
    for fraction in (0.0, 0.01, 0.05, 0.3, 0.8, 1.0):
        material = emission_material(f"R atlas {fraction}", group, "Reflectance", fraction)
        d = 600.0 * fraction
        for angle in (0.0, 30.0, 60.0, 75.0, 82.0, 87.0, 89.5):
            c = math.cos(math.radians(angle))
            for below, charts in ((False, export.front), (True, export.back)):
                chart = irid_blender.atlas_chart_for(charts, d, c)
                k = export.charts.index(chart)
                picked.add(k)
                x, y = chart.xy(d, c)
                got = bench.render(material, angle, below=below)
                worst = max(worst, np.abs(got - np.array([x, y, (k + 1) / 16])).max())
    results.check("version 3 atlas: the chart chosen in closed form and its (x, y), both sides",
                  worst < 2e-3 and picked == {0, 1, 2, 3},
                  f"(largest |rendered - closed form| {worst:.1e}; charts read {sorted(picked)})")


def test_inputs(results, bench, workdir):
    """The Normal input sets the angle (a constant normal 60° from the
    surface's, seen at 0°, gives the film at 60°); Thickness nm, when 0 or
    more, wins over the 0-1 Thickness."""
    directory = workdir / "synthetic-linear"
    group = irid_blender.make_node_group(directory, name="synthetic inputs")
    tilted = (0.0, math.sin(math.radians(60.0)), math.cos(math.radians(60.0)))
    worst = 0.0
    for normal, angle, want in ((tilted, 0.0, 60.0), (None, 30.0, 30.0)):
        material = emission_material(f"R normal {want}", group, "Reflectance", 0.2, normal=normal)
        y = math.cos(math.radians(want))  # the band's uniform cos θ axis
        got = bench.render(material, angle)
        worst = max(worst, np.abs(got - np.array([0.2, y, 1 / 16])).max())
    results.check("the Normal input sets the film's angle", worst < 2e-3,
                  f"(largest |rendered - closed form| {worst:.1e})")
    worst = 0.0
    for nm, x in ((700.0, 0.75), (100.0, 0.0), (2000.0, 1.0), (-1.0, 0.2)):
        material = emission_material(f"R nm {nm}", group, "Reflectance", 0.2, Thickness_nm=nm)
        got = bench.render(material, 0.0)
        worst = max(worst, abs(float(got[..., 0].mean()) - x))
    results.check("Thickness nm sets the thickness (clamped; below 0 the 0-1 input does)",
                  worst < 2e-3, f"(largest |rendered x - expected| {worst:.1e})")


# A synthetic rough table: 5 slices in rows of 2 (so slices 2-4 sit in later
# rows), each an atlas of the front side's charts of its own (a corner of
# another radius, the bands split at another cos θ, other sizes), unlike the
# smooth atlas's, so the test sees which one is read.
SYNTHETIC_ROUGH = {"slices": 5, "columns": 2, "charts": [
    {"side": 0, "kind": 1, "a": A_SOAP, "floor": 0.2, "scale_nm": 30.0, "radius": 0.2,
     "size": (7, 6)},
    {"side": 0, "kind": 0, "a": A_SOAP, "floor": 0.2, "p0_nm": 100.0, "p_lo_nm": 0.0,
     "p_hi_nm": 600.0, "cos_lo": 0.0, "cos_hi": 0.6, "anchor": 0.0, "offset": 0.05,
     "size": (9, 7)},
    {"side": 0, "kind": 0, "a": A_SOAP, "floor": 0.2, "p0_nm": 0.0, "p_lo_nm": 50.0,
     "p_hi_nm": 600.0, "cos_lo": 0.6, "cos_hi": 1.0, "anchor": 0.6, "offset": 0.0,
     "size": (8, 10)},
]}


def rough_expected(export, d, c, r):
    """What the group's Reflectance gives on a front face of a synthetic
    export at thickness d nm, cos θ c, roughness r: at 0 the smooth atlas's
    chart (x, y, (k + 1) / 16); above 0 the rough atlas's chart chosen by
    the same closed form at d clamped to the rough atlas's range, (x, y,
    (k + 1) / 16 + √min(r, 1) / 2). Returns it and which (table, chart) it
    read."""
    if r == 0.0:
        chart = irid_blender.atlas_chart_for(export.front, d, c)
        k, blue = export.charts.index(chart), 0.0
    else:
        rough = export.rough
        d = min(max(d, rough.thickness_min_nm), rough.thickness_max_nm)
        chart = irid_blender.atlas_chart_for(rough.charts, d, c)
        k, blue = export.rough.charts.index(chart), math.sqrt(min(r, 1.0)) / 2
    x, y = chart.xy(d, c)
    return np.array([x, y, (k + 1) / 16 + blue]), ("rough" if r else "smooth", k)


def test_rough_mapping(results, bench, workdir):
    """The group's Reflectance through the rough table: at roughness r > 0
    the rough atlas's chart chosen in closed form, moved into the two slices
    around √r (clamped to 1) and blended, gives back its (x, y) and √r; at
    roughness 0 exactly the smooth atlas's chart. A back face of a film with
    its own back side keeps the back chart's smooth reflectance; a film
    whose back faces read the front side (no back side) reads the rough
    table there too; a rough atlas of a narrower thickness range than the
    export's is read at the thickness clamped to its range."""
    directory = workdir / "synthetic-rough"
    write_synthetic_atlas(directory, SYNTHETIC_ATLAS, {"front": [0, 1, 2], "back": [3]},
                          (0.0, 600.0), False, rough=SYNTHETIC_ROUGH)
    export = irid_blender.Export(directory)
    group = irid_blender.make_node_group(export, name="synthetic rough")
    worst, read = 0.0, set()
    for fraction in (0.01, 0.37):
        d = 600.0 * fraction
        for r in (0.0, 0.01, 0.3, 0.5, 0.8, 1.0, 1.5):
            material = emission_material(f"R rough {r} {fraction}", group, "Reflectance", fraction,
                                         Roughness=r)
            for angle in (0.0, 40.0, 75.0, 89.5):
                want, which = rough_expected(export, d, math.cos(math.radians(angle)), r)
                read.add(which)
                worst = max(worst, np.abs(bench.render(material, angle) - want).max())
    every = {("rough", k) for k in range(3)} | {("smooth", k) for k in range(3)}
    results.check("rough table: the rough atlas's chart, in the two slices around √roughness, "
                  "blended; roughness 0 the smooth atlas", worst < 2e-3 and read == every,
                  f"(largest |rendered - closed form| {worst:.1e}; charts read {sorted(read)})")
    material = emission_material("R rough back", group, "Reflectance", 0.37, Roughness=0.5)
    worst = 0.0
    for angle in (0.0, 30.0, 60.0):
        c = math.cos(math.radians(angle))
        x, y = export.back[0].xy(222.0, c)
        got = bench.render(material, angle, below=True)
        worst = max(worst, np.abs(got - np.array([x, y, 4 / 16])).max())
    results.check("rough table: a back face with its own back side keeps the smooth back chart",
                  worst < 2e-3, f"(largest |rendered - closed form| {worst:.1e})")
    one = workdir / "synthetic-rough-front-only"
    write_synthetic_atlas(one, SYNTHETIC_ATLAS[:3], {"front": [0, 1, 2], "back": None},
                          (0.0, 600.0), True, rough=dict(SYNTHETIC_ROUGH, thickness_nm=(0.0, 300.0)))
    export = irid_blender.Export(one)
    group = irid_blender.make_node_group(export)
    worst = {False: 0.0, True: 0.0}
    for fraction in (0.37, 0.8):  # 222 nm, and 480 nm: read at 300 nm
        material = emission_material(f"R rough opaque {fraction}", group, "Reflectance", fraction,
                                     Roughness=0.5)
        for below in (False, True):
            for angle in (0.0, 60.0):
                want, _ = rough_expected(export, 600.0 * fraction, math.cos(math.radians(angle)), 0.5)
                got = bench.render(material, angle, below=below)
                worst[below] = max(worst[below], np.abs(got - want).max())
    results.check("rough table: a back face of a film with no back side reads it too",
                  worst[True] < 2e-3, f"(largest |rendered - closed form| {worst[True]:.1e})")
    results.check("rough table: the thickness clamped to the rough atlas's own range",
                  worst[False] < 2e-3, f"(largest |rendered - closed form| {worst[False]:.1e})")


def test_rough_refused(results, workdir):
    """Without the rough table a roughness above 0, a node-driven one
    (roughness=None) and a rough Principled base under add_film_layer are
    each one ExportError naming --rough, leaving nothing behind; the group
    of such an export has no Roughness input. A rough table whose slices do
    not lie (or hold the roughness) where the closed form puts them, whose
    chart leaves its slice, or of the layout before the rough atlas is
    refused with one line."""
    smooth = workdir / "synthetic-linear"
    before = (len(bpy.data.images), len(bpy.data.node_groups), len(bpy.data.materials))
    for roughness in (0.3, None):
        try:
            irid_blender.make_material(smooth, roughness=roughness)
            ok, detail = False, "(accepted)"
        except irid_blender.ExportError as e:
            ok = "--rough" in str(e) and "\n" not in str(e)
            detail = f"({e})"
        after = (len(bpy.data.images), len(bpy.data.node_groups), len(bpy.data.materials))
        results.check(f"no rough table: make_material(roughness={roughness}) raises",
                      ok and after == before, detail)
    material = bpy.data.materials.new("rough base")
    if material.node_tree is None:
        material.use_nodes = True
    nodes = len(material.node_tree.nodes)
    try:
        irid_blender.add_film_layer(material, smooth)  # a new Principled has roughness 0.5
        ok, detail = False, "(accepted)"
    except irid_blender.ExportError as e:
        ok, detail = "--rough" in str(e) and "Roughness is 0.5" in str(e), f"({e})"
    results.check("no rough table: add_film_layer over a rough Principled raises, material unchanged",
                  ok and len(material.node_tree.nodes) == nodes, detail)
    bpy.data.materials.remove(material)
    group = irid_blender.make_node_group(smooth, name="no rough")
    names = [s.name for s in group.interface.items_tree if getattr(s, "in_out", "") == "INPUT"]
    results.check("no rough table: the group has no Roughness input", "Roughness" not in names,
                  f"(inputs {names})")
    bpy.data.node_groups.remove(group)
    bad = workdir / "bad-rough"
    write_synthetic_atlas(bad, SYNTHETIC_ATLAS[:3], {"front": [0, 1, 2], "back": None},
                          (0.0, 600.0), True, rough=SYNTHETIC_ROUGH)
    good = json.loads((bad / "film.json").read_text())
    for what, change, needle in (
        ("a rough tiling that disagrees with its slice rectangles",
         lambda rough: rough["tiling"].update(columns=3), "closed form"),
        ("a rough table whose slices are not at roughness (s / (S - 1))²",
         lambda rough: rough["nodes"].update(roughness=[0.0, 0.25, 0.5, 0.75, 1.0]), "nodes.roughness"),
        ("a rough chart outside its slice",
         lambda rough: rough["charts"][2]["params"].update(y0=40), "does not lie in"),
        ("a rough table of the old form (one mapping, no charts)",
         lambda rough: rough.update(layout=rough.pop("tiling")), "export it again"),
    ):
        film = json.loads(json.dumps(good))
        change(film["rough"])
        (bad / "film.json").write_text(json.dumps(film))
        try:
            irid_blender.Export(bad)
            ok, detail = False, "(accepted)"
        except irid_blender.ExportError as e:
            ok, detail = needle in str(e) and "\n" not in str(e), f"({e})"
        results.check(f"{what} is refused", ok, detail)


def test_white(results, irid, workdir):
    """An export for another white than Blender's is refused, naming --white e."""
    synthetic = workdir / "synthetic-d65"
    write_linear_band(synthetic, (3, 3), opaque=True)
    film = json.loads((synthetic / "film.json").read_text())
    film["white"] = "d65"
    (synthetic / "film.json").write_text(json.dumps(film))
    d65 = irid.export(REPO / "tests/blender/film-on-copper.toml", workdir / "export-d65", 1,
                      (200.0, 300.0), white="d65")
    before = (len(bpy.data.images), len(bpy.data.node_groups), len(bpy.data.materials))
    for what, directory in (("a synthetic", synthetic), ("irid export's default", d65)):
        try:
            irid_blender.make_material(directory, thickness_nm=250.0)
            ok, detail = False, "(accepted)"
        except irid_blender.ExportError as e:
            ok, detail = "--white e" in str(e) and "'d65'" in str(e), f"({e})"
        after = (len(bpy.data.images), len(bpy.data.node_groups), len(bpy.data.materials))
        results.check(f"a --white d65 export ({what}) is refused, naming --white e",
                      ok and after == before, detail)


def reversed_stack(path, out):
    """A stack file's reversal (seen from its substrate): written to `out`.
    Handles the forms the test's stacks use (n, [n, k], material, cauchy)."""
    stack = tomllib.loads(Path(path).read_text())

    def medium(m):
        return "{ " + ", ".join(f"{k} = {json.dumps(v)}" for k, v in m.items()) + " }"

    lines = [f"ambient = {medium(stack['substrate'])}", f"substrate = {medium(stack['ambient'])}"]
    for layer in reversed(stack.get("layers", [])):
        lines.append("[[layers]]")
        lines += [f"{k} = {json.dumps(v)}" for k, v in layer.items()]
    out.write_text("\n".join(lines) + "\n")
    return out


GLASS_SIDE_ANGLES = (20.0, 30.0, 40.0, 60.0)


def test_glass_side(results, bench, irid, workdir):
    """Coated glass seen from inside the glass (a back face) against the
    reversed stack: 20°, 30°, 40° below the critical angle (41.8°), 60° past
    it (R = 1, T = 0)."""
    case = next(c for c in CASES if c["name"] == "film on glass")
    stack = REPO / case["stack"]
    directory = irid.export(stack, workdir / "export-glass", case["layer"], case["range"])
    material = irid_blender.make_material(directory, thickness_nm=300.0)
    back = reversed_stack(stack, workdir / "glass-reversed.toml")
    exact = dict(zip("RT", irid.colours(back, GLASS_SIDE_ANGLES)))
    bench.set_working_space("Linear Rec.709")
    for mode, channel in (("reflection", "R"), ("transmission", "T")):
        bench.set_world(mode)
        errors = [
            float(np.max(delta_e2000_rgb(
                bench.render(material, angle, TRANSMITTING_SAMPLES, below=True), exact[channel][k]
            )))
            for k, angle in enumerate(GLASS_SIDE_ANGLES)
        ]
        figures = ", ".join(f"{a:g}°: {e:.2f}" for a, e in zip(GLASS_SIDE_ANGLES, errors))
        results.check(f"coated glass from the glass side, {channel} vs the reversed stack",
                      np.mean(errors) <= MEAN_BOUND and max(errors) <= MAX_BOUND,
                      f"(ΔE00 max per angle {figures})")
    bench.set_world("white")


def test_furnace(results, bench, irid, workdir):
    """A coated glass cube in a uniform white world, every bounce followed:
    a lossless film on lossless glass keeps the light, so the cube averages 1
    (within 1 %), as Cycles' own Principled glass does."""
    case = next(c for c in CASES if c["name"] == "film on glass")
    directory = irid.export(REPO / case["stack"], workdir / "export-glass", case["layer"],
                            case["range"])
    film, pixels = bench.furnace(irid_blender.make_material(directory, thickness_nm=300.0))
    glass, _ = bench.furnace(glass_material(1.5))
    results.check("white furnace: a coated glass cube stays at 1 (±1 %)", abs(film - 1.0) <= 0.01,
                  f"(mean {film:.4f} over {pixels} pixels; Cycles' Principled glass {glass:.4f})")


LAYER_ANGLES = (0.0, 30.0, 60.0)


def test_layering(results, bench, irid, workdir):
    """add_film_layer in a white furnace. Over a diffuse Principled base of
    albedo 0.5 (its top medium the film's substrate, n = 1.5): R + 0.5 T. As
    the coat of a metal Principled of base colour 1: R + T, which is 1 for
    this lossless film; at 0° and 30° only, since the metal under the film
    has base colour T, and Cycles' metal Fresnel rises from its base colour
    towards grazing (by 0.5 % at 60°). Against irid color."""
    case = next(c for c in CASES if c["name"] == "film on glass")
    stack = REPO / case["stack"]
    directory = irid.export(stack, workdir / "export-glass", case["layer"], case["range"])
    r, t = irid.colours(stack, LAYER_ANGLES)
    bench.set_working_space("Linear Rec.709")
    bench.set_world("white")
    for coat, albedo, metallic, angles in ((False, 0.5, 0.0, LAYER_ANGLES),
                                           (True, 1.0, 1.0, LAYER_ANGLES[:2])):
        material = bpy.data.materials.new(f"layered coat={coat}")
        if material.node_tree is None:
            material.use_nodes = True
        base = next(n for n in material.node_tree.nodes if n.bl_idname == "ShaderNodeBsdfPrincipled")
        base.inputs["Base Color"].default_value = (albedo, albedo, albedo, 1.0)
        base.inputs["Metallic"].default_value = metallic
        base.inputs["Roughness"].default_value = 0.0
        base.inputs["Coat Weight"].default_value = 1.0 if coat else 0.0
        base.inputs["Coat Roughness"].default_value = 0.0
        irid_blender.add_film_layer(material, directory, thickness_nm=300.0, coat=coat)
        errors = np.concatenate([
            np.ravel(delta_e2000_rgb(bench.render(material, a, LAYER_SAMPLES), r[k] + albedo * t[k]))
            for k, a in enumerate(angles)
        ])
        what = "as the coat of a white metal (R + T)" if coat else "over a diffuse base (R + 0.5 T)"
        results.check(f"layering recipe: the film {what}",
                      errors.mean() <= MEAN_BOUND and errors.max() <= MAX_BOUND,
                      f"(ΔE00 mean {errors.mean():.3f}, max {errors.max():.3f})")
    # The recipe as docs/blender.md shows it, run as it is written: its
    # Principled keeps the default roughness 0.5, so its export has the rough table.
    snippet = next(b for b in re.findall(r"```python\n(.*?)```", (REPO / "docs/blender.md").read_text(),
                                         re.S) if "add_film_layer" in b)
    rough = irid.export(stack, workdir / "export-glass-rough", case["layer"], case["range"], rough=True)
    exec(snippet.replace('"glass-film"', repr(str(rough))), {})
    material = bpy.data.materials["coated paint"]
    out = next(n for n in material.node_tree.nodes if n.bl_idname == "ShaderNodeOutputMaterial")
    feeds = out.inputs["Surface"].links[0].from_node.bl_idname
    results.check("layering recipe: docs/blender.md's snippet runs and layers the film",
                  feeds == "ShaderNodeAddShader", f"(the surface is fed by {feeds})")
    try:
        material = bpy.data.materials.new("emission surface")
        if material.node_tree is None:
            material.use_nodes = True
        tree = material.node_tree
        tree.nodes.clear()
        out = tree.nodes.new("ShaderNodeOutputMaterial")
        tree.links.new(tree.nodes.new("ShaderNodeEmission").outputs[0], out.inputs["Surface"])
        irid_blender.add_film_layer(material, directory)
        ok = False
    except ValueError as e:
        ok = "Principled" in str(e)
    results.check("layering recipe: a surface that is not a Principled BSDF is refused", ok)


# The closures of a layered material are picked at random per sample, by
# their mean weight: under a uniform world each pick returns nearly the same
# value, and 256 samples leave about 5e-4 of noise.
LAYER_SAMPLES = 256


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
        test_bad_input(results, workdir)
        test_addon(results, workdir)
        test_inputs(results, bench, workdir)
        test_rough_mapping(results, bench, workdir)
        test_atlas_mapping(results, bench, workdir)
        test_rough_refused(results, workdir)
        test_white(results, irid, workdir)
        table = measure(results, bench, irid, workdir)
        test_glass_side(results, bench, irid, workdir)
        test_layering(results, bench, irid, workdir)
        test_furnace(results, bench, irid, workdir)
        table_text = format_table(table)
        print()
        print(table_text)
        if args.table:
            Path(args.table).write_text(table_text)
        if args.docs:
            update_docs(table_text)
        if args.image:
            case = next(c for c in CASES if c["name"] == "film on copper")
            render_picture(irid, case, REPO / case["stack"], workdir, Path(args.image))
    print(f"{bench.renders} renders in {time.monotonic() - started:.0f} s")
    print(f"{results.passed} passed, {results.failed} failed")
    return 1 if results.failed else 0


if __name__ == "__main__":
    sys.exit(main())
