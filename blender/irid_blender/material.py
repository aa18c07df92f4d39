"""What a user calls: make_material, make_node_group and add_film_layer
(docs/blender.md), and the Blender data-blocks they create (the tables'
images, the group, the material), removed again when building fails."""

import bpy

from .export import TABLES, Export, ExportError
from .nodes import Builder, build_group


def make_node_group(export_dir, name=None, ior=None):
    """A shader node group for an export: inputs Thickness (0-1 over the export's
    thickness range), Thickness nm, Roughness (only when the export has the
    rough table) and Normal; outputs BSDF, Reflection, Reflectance and
    Transmittance (docs/blender.md). A back face is shaded with the export's
    back side (light arriving from the substrate), when it has one. Without
    the rough table both lobes are mirror-smooth: the group has no Roughness
    input, so no roughness can reach it that it would render wrongly.

    Raises ExportError for a bad export directory; nothing stays in the .blend
    when building fails."""
    export = export_dir if isinstance(export_dir, Export) else Export(export_dir)
    if not export.transmits():
        ior = None  # Glossy only: nothing leaves through the substrate
    elif ior is None:
        ior = export.relative_ior()
    group_name = name or f"irid film {export.label}"
    created = []
    try:
        images = {}
        files = [(table, export.paths[table], export.size) for table in TABLES]
        if export.rough is not None:
            files.append(("rough", export.rough.path, export.rough.size))
        for table, path, size in files:
            images[table] = _load_image(path, size, f"{group_name} {table}")
            created.append(images[table])
        group = bpy.data.node_groups.new(group_name, "ShaderNodeTree")
        created.append(group)
        build_group(group, export, images, ior)
    except BaseException:
        for block in reversed(created):
            _remove(block)
        raise
    return group


def make_material(export_dir, thickness_nm=None, name=None, roughness=0.0, ior=None):
    """A material shading with the film of an `irid export` directory.

    thickness_nm: the film's thickness, a constant inside the export's range,
    set on the group's Thickness nm input; None leaves the 0-1 Thickness input
    (over the range, like glTF's iridescenceThicknessTexture) for an attribute
    or texture to drive (default 0.5). roughness: GGX roughness of both
    lobes, 0 to 1; above 0 the reflection lobe's colour is the film's F_eff
    from the export's rough table (`irid export --rough`), which it then
    needs; None leaves the group's Roughness input (default 0) for a texture
    or value to drive, and needs the rough table too. ior: relative index of
    refraction when the film transmits into a lossless substrate (default:
    substrate over ambient at 550 nm, from the stack in film.json); over an
    absorbing substrate (a metal) the material has no refraction lobe.

    Raises ExportError (a ValueError) with one message for a missing file, a
    damaged film.json, an export for another white than Blender's (`--white
    e`) or a roughness above 0 (or None) with an export without the rough
    table; ValueError for a thickness outside the export's range or a
    roughness outside [0, 1]; nothing half-built stays in the .blend."""
    export = Export(export_dir)
    if thickness_nm is not None:
        export.thickness_fraction(thickness_nm)  # refuses one outside the range
    if roughness is None:
        export.require_rough("roughness=None leaves the roughness to a node")
    else:
        roughness = float(roughness)
        if not 0.0 <= roughness <= 1.0:
            raise ValueError(f"roughness {roughness} is outside [0, 1]")
        if roughness > 0.0:
            export.require_rough(f"roughness {roughness:g} asks for the film's rough reflectance")
    material_name = name or f"irid {export.label}"
    group = make_node_group(export, name=f"{material_name} film", ior=ior)
    material = None
    try:
        material = bpy.data.materials.new(material_name)
        if material.node_tree is None:  # Blender before 5.0 creates it on request
            material.use_nodes = True
        tree = material.node_tree
        tree.nodes.clear()
        build = Builder(tree)
        film = build.node("ShaderNodeGroup", 0, 0, label="irid film")
        film.node_tree = group
        film.width = 220
        out = build.node("ShaderNodeOutputMaterial", 2, 0)
        build.link(film.outputs["BSDF"], out.inputs["Surface"])
        if thickness_nm is not None:
            film.inputs["Thickness nm"].default_value = float(thickness_nm)
        if export.rough is not None:
            film.inputs["Roughness"].default_value = roughness or 0.0
        material["irid_export"] = export.directory
        if thickness_nm is not None:
            material["irid_thickness_nm"] = float(thickness_nm)
    except BaseException:
        if material is not None:
            _remove(material)
        images = [n.image for n in group.nodes if n.bl_idname == "ShaderNodeTexImage"]
        _remove(group)
        for image in set(images):
            _remove(image)
        raise
    return material


def _load_image(path, expected_size, name):
    try:
        image = bpy.data.images.load(path, check_existing=False)
    except RuntimeError as e:
        raise ExportError(f"irid export {path}: Blender cannot read it ({e})") from None
    try:
        image.name = name
        image.colorspace_settings.name = _texture_colorspace(image)
        image.alpha_mode = "CHANNEL_PACKED"
        # Reading the size loads the pixels: a damaged file shows here, not at render time.
        size = tuple(image.size)
        if size == (0, 0):
            raise ExportError(f"irid export {path}: Blender cannot read it (damaged or not an image)")
        if size != tuple(expected_size):
            raise ExportError(
                f"irid export {path}: image is {size[0]}×{size[1]}, film.json says "
                f"{expected_size[0]}×{expected_size[1]}"
            )
    except BaseException:
        _remove(image)
        raise
    return image


def _texture_colorspace(image):
    """The export's colours are linear sRGB, i.e. linear Rec.709 primaries, with
    no transfer curve. Tagged so, Blender converts them into the scene's
    working space (Blender 5.0 offers ACEScg and Rec.2020, where film colours
    outside Rec.709 keep their negative Rec.709 channels instead of being
    clipped by the BSDF); in the default Rec.709 working space it is the same
    as Non-Color. Blender builds without that colour space read them as
    Non-Color (raw numbers)."""
    names = image.colorspace_settings.bl_rna.properties["name"].enum_items.keys()
    return "Linear Rec.709" if "Linear Rec.709" in names else "Non-Color"


def _remove(block):
    collections = {
        bpy.types.Image: bpy.data.images,
        bpy.types.Material: bpy.data.materials,
        bpy.types.NodeTree: bpy.data.node_groups,
    }
    for kind, collection in collections.items():
        if isinstance(block, kind):
            collection.remove(block)
            return


def add_film_layer(material, export_dir, thickness_nm=None, coat=False, name=None):
    """Puts an export's film on top of a material whose surface is a Principled
    BSDF: the film's reflection lobe is added to the Principled BSDF, whose
    Base Color is multiplied by the film's transmittance (the light the film
    lets through to the base, once, at the viewing angle). Returns the film's
    group node.

    coat=False, the film over the base: the export's substrate is the base's
    own top medium (paint, plastic: e.g. n = 1.5), so the film's reflectance
    already holds that surface's reflection and the Principled's Specular IOR
    Level is set to 0; the film takes the Principled's Normal and Roughness.
    coat=True, the film as the coat: the base keeps its own specular layer
    (the film lies on a clear coat over it), the Principled's Coat Weight is
    set to 0 (the film replaces the coat) and the film takes its Coat Normal
    and Coat Roughness.

    The film's roughness follows the Principled's: above 0 (or driven by a
    node) the export needs the rough table (`irid export --rough`).

    Raises ValueError when the material's output is not fed by a Principled
    BSDF, ExportError for a bad export or a rough base with an export without
    the rough table; the material is unchanged then."""
    tree = material.node_tree
    outputs = [n for n in tree.nodes if n.bl_idname == "ShaderNodeOutputMaterial"] if tree else []
    out = next((n for n in outputs if n.is_active_output), outputs[0] if outputs else None)
    links = out.inputs["Surface"].links if out is not None else ()
    base = links[0].from_node if links else None
    if base is None or base.bl_idname != "ShaderNodeBsdfPrincipled":
        raise ValueError(f"material {material.name}: its surface is not a Principled BSDF")
    export = Export(export_dir)
    if thickness_nm is not None:
        export.thickness_fraction(thickness_nm)  # refuses one outside the range
    normal, roughness = ("Coat Normal", "Coat Roughness") if coat else ("Normal", "Roughness")
    if base.inputs[roughness].links:
        export.require_rough(f"the Principled BSDF's {roughness} is driven by a node")
    elif base.inputs[roughness].default_value > 0.0:
        export.require_rough(
            f"the Principled BSDF's {roughness} is {base.inputs[roughness].default_value:g}"
        )
    group = make_node_group(export, name=name or f"{material.name} film")
    build = Builder(tree)
    x, y = base.location
    film = tree.nodes.new("ShaderNodeGroup")
    film.node_tree = group
    film.label = "irid film"
    film.location = (x - 500.0, y + 300.0)
    if thickness_nm is not None:
        film.inputs["Thickness nm"].default_value = float(thickness_nm)
    if base.inputs[normal].links:
        build.link(base.inputs[normal].links[0].from_socket, film.inputs["Normal"])
    if export.rough is None:
        pass  # the base's roughness is 0 (checked above): the film is a mirror too
    elif base.inputs[roughness].links:
        build.link(base.inputs[roughness].links[0].from_socket, film.inputs["Roughness"])
    else:
        film.inputs["Roughness"].default_value = base.inputs[roughness].default_value
    through = tree.nodes.new("ShaderNodeVectorMath")
    through.operation = "MULTIPLY"
    through.label = "base colour × film transmittance"
    through.location = (x - 250.0, y + 100.0)
    colour = base.inputs["Base Color"]
    if colour.links:
        build.link(colour.links[0].from_socket, through.inputs[0])
    else:
        through.inputs[0].default_value = tuple(colour.default_value)[:3]
    build.link(film.outputs["Transmittance"], through.inputs[1])
    build.link(through.outputs["Vector"], colour)
    off = base.inputs["Coat Weight" if coat else "Specular IOR Level"]
    for link in list(off.links):
        tree.links.remove(link)
    off.default_value = 0.0
    add = tree.nodes.new("ShaderNodeAddShader")
    add.location = (x + 300.0, y)
    build.link(film.outputs["Reflection"], add.inputs[0])
    build.link(base.outputs["BSDF"], add.inputs[1])
    build.link(add.outputs["Shader"], out.inputs["Surface"])
    return film
