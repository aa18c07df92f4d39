"""Cycles helpers for blender/tests/test_blender.py: the measuring scene,
the materials it renders beside irid's, the irid command line, and the
spheres picture of docs/blender.md."""

import json
import math
import os
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import OpenEXR

import bpy

import irid_blender
from colour_exr import read_exr_rgb

RESOLUTION = 4  # pixels a side: every pixel sees the same angle
SAMPLES = 2  # a mirror under a uniform world is noise-free; 2 checks that
# The white furnace: a lossless material keeps every path's weight at 1,
# so few samples settle the mean; paths inside glass bounce often.
FURNACE_SIZE = 24
FURNACE_SAMPLES = 64
FURNACE_BOUNCES = 128

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
        if bpy.data.colorspace.working_space == name:
            return
        done = bpy.ops.wm.set_working_color_space(working_space=name, convert_colors=False)
        if done != {"FINISHED"} or bpy.data.colorspace.working_space != name:
            raise RuntimeError(f"cannot set the working colour space to {name}")

    def render(self, material, angle_deg, samples=SAMPLES, below=False):
        """Linear Rec.709 RGB of every pixel, shape (H, W, 3). below: the camera
        looks at the plane's back face (from the side its normal points away
        from), at angle_deg to the normal there."""
        self.scene.cycles.samples = samples
        self.plane.data.materials.clear()
        self.plane.data.materials.append(material)
        theta = math.radians(angle_deg)
        distance = 10.0
        up = -1.0 if below else 1.0
        self.camera.location = (0.0, -distance * math.sin(theta), up * distance * math.cos(theta))
        self.camera.rotation_euler = (math.pi - theta if below else theta, 0.0, 0.0)
        return self._render()

    def _render(self):
        path = self.workdir / f"render-{self.renders}.exr"
        self.renders += 1
        self.scene.render.filepath = str(path)
        with quiet_stdout():
            bpy.ops.render.render(write_still=True)
        return read_exr_rgb(path)

    def furnace(self, material, size=FURNACE_SIZE, samples=FURNACE_SAMPLES):
        """The mean over a cube's pixels of a render of the cube (side 2, turned
        to show three faces) in the uniform white world, orthographic, with up
        to FURNACE_BOUNCES bounces of every kind: 1 for a material that
        neither absorbs nor emits. The cube's pixels are those a black
        emitter covers in a render of its own."""
        scene = self.scene
        saved = (scene.render.resolution_x, scene.camera.data.ortho_scale)
        cycles = scene.cycles
        bounces = ("max_bounces", "diffuse_bounces", "glossy_bounces",
                   "transmission_bounces", "transparent_max_bounces")
        saved_bounces = {name: getattr(cycles, name) for name in bounces}
        self.set_world("white")
        self.plane.hide_render = True
        cube = bpy.data.objects.new("furnace cube", _cube_mesh())
        cube.rotation_euler = (0.5, 0.3, 0.7)
        scene.collection.objects.link(cube)
        try:
            for name in bounces:
                setattr(cycles, name, FURNACE_BOUNCES)
            scene.render.resolution_x = scene.render.resolution_y = size
            scene.camera.data.ortho_scale = 4.0
            self.camera.location = (0.0, -10.0, 0.0)
            self.camera.rotation_euler = (math.pi / 2, 0.0, 0.0)
            cycles.samples = 1
            cube.data.materials.append(emission_black())
            mask = self._render().mean(axis=-1) < 0.5
            cube.data.materials[0] = material
            cycles.samples = samples
            image = self._render()
        finally:
            bpy.data.objects.remove(cube)
            self.plane.hide_render = False
            scene.render.resolution_x = scene.render.resolution_y = saved[0]
            scene.camera.data.ortho_scale = saved[1]
            for name, value in saved_bounces.items():
                setattr(cycles, name, value)
        return float(image[mask].mean()), int(mask.sum())


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


def _cube_mesh():
    """A cube of side 2 about the origin, its faces' normals pointing out."""
    corners = [(x, y, z) for z in (-1.0, 1.0) for y in (-1.0, 1.0) for x in (-1.0, 1.0)]
    faces = []
    for quad in ((0, 1, 3, 2), (4, 5, 7, 6), (0, 1, 5, 4), (2, 3, 7, 6), (0, 2, 6, 4), (1, 3, 7, 5)):
        a, b, c = (np.array(corners[i]) for i in quad[:3])
        centre = np.mean([corners[i] for i in quad], axis=0)
        faces.append(quad if np.dot(np.cross(b - a, c - a), centre) > 0 else quad[::-1])
    mesh = bpy.data.meshes.new("furnace cube")
    mesh.from_pydata(corners, [], faces)
    mesh.update()
    return mesh


def node_material(name):
    """A new material whose node tree is empty; returns both."""
    material = bpy.data.materials.new(name)
    if material.node_tree is None:  # Blender before 5.0 creates it on request
        material.use_nodes = True
    tree = material.node_tree
    tree.nodes.clear()
    return material, tree


def emission_black(name="mask"):
    """A black emitter: the furnace's mask, the picture's labels."""
    material, tree = node_material(name)
    emission = tree.nodes.new("ShaderNodeEmission")
    emission.inputs["Color"].default_value = (0.0, 0.0, 0.0, 1.0)
    out = tree.nodes.new("ShaderNodeOutputMaterial")
    tree.links.new(emission.outputs[0], out.inputs["Surface"])
    return material


def glass_material(ior):
    """Cycles' Principled glass: the furnace's control."""
    material = bpy.data.materials.new("Principled glass")
    if material.node_tree is None:
        material.use_nodes = True
    bsdf = next(n for n in material.node_tree.nodes if n.bl_idname == "ShaderNodeBsdfPrincipled")
    bsdf.inputs["Transmission Weight"].default_value = 1.0
    bsdf.inputs["Roughness"].default_value = 0.0
    bsdf.inputs["IOR"].default_value = ior
    bsdf.inputs["Base Color"].default_value = (1.0, 1.0, 1.0, 1.0)
    return material


def emission_material(name, group, output, thickness_fraction, normal=None, **inputs):
    """A material showing one of a film group's colour outputs as emission.
    normal: a constant vector for the group's Normal input; inputs: other
    input values by name (a space in a name written as an underscore)."""
    material, tree = node_material(name)
    film = tree.nodes.new("ShaderNodeGroup")
    film.node_tree = group
    film.inputs["Thickness"].default_value = thickness_fraction
    for key, value in inputs.items():
        film.inputs[key.replace("_", " ")].default_value = value
    if normal is not None:
        vector = tree.nodes.new("ShaderNodeCombineXYZ")
        for axis, value in zip("XYZ", normal):
            vector.inputs[axis].default_value = value
        tree.links.new(vector.outputs["Vector"], film.inputs["Normal"])
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
    material, tree = node_material(name)
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

    def export(self, stack_path, out_dir, layer, thickness_range, white="e", rough=False):
        """An export directory, made once per stack, layer, range, white and
        rough table (`--rough`) or not."""
        key = (str(stack_path), layer, tuple(thickness_range), white, rough)
        made = getattr(self, "_exports", {})
        self._exports = made
        if key in made:
            return made[key]
        self.run(
            "export",
            stack_path,
            "-o",
            out_dir,
            "--white",
            white,
            "--layer",
            layer,
            "--thickness",
            f"{thickness_range[0]:g}:{thickness_range[1]:g}",
            *(["--rough"] if rough else []),
        )
        made[key] = out_dir
        return out_dir


def stack_with_thickness(source_text, layer, thickness_nm):
    """A stack file's text with the layer-th (from 1) layer's thickness replaced."""
    pattern = re.compile(r"^(\s*thickness_nm\s*=\s*)([0-9.eE+-]+)", re.M)
    matches = list(pattern.finditer(source_text))
    if len(matches) < layer:
        raise ValueError(f"the stack has fewer than {layer} layers with thickness_nm")
    m = matches[layer - 1]
    return source_text[: m.start(2)] + f"{thickness_nm!r}" + source_text[m.end(2) :]


# ---------------------------------------------------------------- the docs' pictures


def _picture_scene(samples, width, height):
    """An empty Cycles scene (CPU, no denoising, Standard view) that writes an
    RGB PNG of width × height pixels."""
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = samples
    scene.cycles.use_denoising = False
    scene.view_settings.view_transform = "Standard"
    scene.render.resolution_x, scene.render.resolution_y = width, height
    scene.render.image_settings.file_format = "PNG"
    scene.render.image_settings.color_mode = "RGB"
    scene.render.image_settings.compression = 100
    return scene


def _picture_world(scene, name, colour):
    """Gives the scene a new world: one Background node whose colour is the
    socket that colour(tree) returns after adding its nodes to the world's tree."""
    world = bpy.data.worlds.new(name)
    scene.world = world
    if world.node_tree is None:
        world.use_nodes = True
    tree = world.node_tree
    tree.nodes.clear()
    background = tree.nodes.new("ShaderNodeBackground")
    tree.links.new(colour(tree), background.inputs["Color"])
    out = tree.nodes.new("ShaderNodeOutputWorld")
    tree.links.new(background.outputs[0], out.inputs["Surface"])


def _sphere(x, z, material):
    """A smooth UV sphere of radius 1 at (x, 0, z) with `material`."""
    bpy.ops.mesh.primitive_uv_sphere_add(segments=96, ring_count=48, location=(x, 0, z))
    sphere = bpy.context.active_object
    bpy.ops.object.shade_smooth()
    sphere.data.materials.append(material)
    return sphere


def _label(scene, body, x, z, size, material):
    """Text facing the camera (which looks along +y), centred on x, hidden
    from glossy rays so the spheres do not mirror it."""
    curve = bpy.data.curves.new(body, "FONT")
    curve.body = body
    curve.size = size
    curve.align_x = "CENTER"
    text = bpy.data.objects.new(body, curve)
    text.location = (x, 0, z)
    text.rotation_euler = (math.radians(90), 0, 0)
    text.data.materials.append(material)
    text.visible_glossy = False
    scene.collection.objects.link(text)


def _render_front(scene, ortho_scale, png_path):
    """An orthographic camera on -y looking at the origin; renders the PNG."""
    camera = bpy.data.cameras.new("camera")
    camera.type = "ORTHO"
    camera.ortho_scale = ortho_scale
    camera_object = bpy.data.objects.new("camera", camera)
    camera_object.location = (0, -10, 0)
    camera_object.rotation_euler = (math.radians(90), 0, 0)
    scene.collection.objects.link(camera_object)
    scene.camera = camera_object
    png_path.parent.mkdir(parents=True, exist_ok=True)
    scene.render.filepath = str(png_path)
    with quiet_stdout():
        bpy.ops.render.render(write_still=True)
    print(f"wrote {png_path}")


def render_picture(irid, case, stack, workdir, png_path):
    """Two mirror spheres under a white world, film on copper with a noise
    thickness: irid's material on the left, Cycles' Principled thin film on the
    right (copper as its base colour), the same thickness texture driving both.
    case is the film-on-copper entry of test_blender.CASES, stack its file."""
    t_min, t_max = case["range"]
    directory = irid.export(stack, workdir / "export-picture", 1, (t_min, t_max))
    bare = workdir / "bare-picture.toml"
    bare.write_text(f'ambient = {{ n = 1.0 }}\nsubstrate = {{ material = "{case["cycles"]["metal"]}" }}\n')
    base, _ = irid.colours(bare, (0.0,))

    scene = _picture_scene(32, 560, 320)

    def white_lit_grey_seen(tree):
        """White light on the spheres; a grey backdrop for the camera only."""
        mix = tree.nodes.new("ShaderNodeMix")
        mix.data_type = "RGBA"
        mix.inputs["A"].default_value = (1.0, 1.0, 1.0, 1.0)
        mix.inputs["B"].default_value = (0.45, 0.45, 0.45, 1.0)
        path = tree.nodes.new("ShaderNodeLightPath")
        tree.links.new(path.outputs["Is Camera Ray"], mix.inputs["Factor"])
        return mix.outputs["Result"]

    _picture_world(scene, "white", white_lit_grey_seen)

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

    label_material = emission_black("label")

    for x, material, label in (
        (-1.15, irid_material, "irid export"),
        (1.15, cycles_material, "Cycles thin film"),
    ):
        sphere = _sphere(x, 0.15, material)
        sphere.visible_glossy = False  # each sphere shows the white world only
        sphere.visible_transmission = False
        _label(scene, label, x, -1.2, 0.2, label_material)
    _render_front(scene, 4.9, png_path)


def render_rough_picture(directory, thickness_nm, png_path, roughness=(0.0, 0.3, 0.6)):
    """Three spheres of irid's material from an export with the rough table
    (`directory`), at each roughness, under a sky that is bright above the
    horizon and dark below it, so the lobe's width shows; labelled."""
    scene = _picture_scene(64, 600, 240)

    def sky(tree):
        coords = tree.nodes.new("ShaderNodeTexCoord")
        split = tree.nodes.new("ShaderNodeSeparateXYZ")
        tree.links.new(coords.outputs["Generated"], split.inputs[0])
        ramp = tree.nodes.new("ShaderNodeValToRGB")
        ramp.color_ramp.elements[0].position = 0.45
        ramp.color_ramp.elements[0].color = (0.05, 0.05, 0.05, 1.0)
        ramp.color_ramp.elements[1].position = 0.55
        ramp.color_ramp.elements[1].color = (1.5, 1.5, 1.5, 1.0)
        tree.links.new(split.outputs["Z"], ramp.inputs[0])
        return ramp.outputs[0]

    _picture_world(scene, "sky", sky)
    label_material = emission_black("label")
    for k, r in enumerate(roughness):
        x = 2.2 * (k - (len(roughness) - 1) / 2)
        material = irid_blender.make_material(directory, thickness_nm=thickness_nm, roughness=r,
                                              name=f"irid roughness {r:g}")
        _sphere(x, 0.2, material)
        _label(scene, f"roughness {r:g}", x, -1.25, 0.22, label_material)
    _render_front(scene, 6.8, png_path)
