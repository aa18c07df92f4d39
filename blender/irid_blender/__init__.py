"""irid thin films in Blender: a Cycles/EEVEE material built from an `irid export`.

`irid export --white e` writes a directory with reflectance.exr,
transmittance.exr and film.json: an atlas of the film's exact reflected and
transmitted colour in charts over (thickness, cos θ), for light arriving
from the ambient and for light arriving from a lossless substrate, and the
closed-form mapping from (thickness, cos θ) to texture coordinates
(docs/gpu.md; film.json version 3: several charts per side in optical
thickness, chosen per lookup). This package turns such a directory into a
shader node group that evaluates the same mapping and choice with math
nodes (on a back face, the substrate side's charts), reads both tables
bilinearly, and shades with a GGX Glossy BSDF coloured by the film's
reflectance (no Fresnel of its own: the table already holds it) plus, when
light leaves through the substrate, a Refraction BSDF coloured by its
transmittance (into a metal the transmitted power is absorbed).
add_film_layer puts the film over a Principled BSDF.

Use it as a module from Blender's Python, with the folder holding this
package (blender/ in the repository) on sys.path:

    import bpy
    import irid_blender
    mat = irid_blender.make_material("/path/to/export", thickness_nm=350.0)
    bpy.context.object.data.materials.append(mat)

or install it as an add-on (a zip of this folder; Preferences > Add-ons >
Install from Disk): File > Import > irid film (film.json) builds the
material and assigns it to the selected objects.

What is exact: at roughness 0 the colour of every reflected and transmitted
ray is the table's bilinear interpolation of the exact film response at the
ray's angle to the shading normal. At roughness > 0 the reflection lobe's
colour is the film's reflectance pre-integrated over the GGX lobe, F_eff of
docs/rough.md, from the export's rough table (`irid export --rough`: slices
over roughness, each an atlas of the front side's charts read by the same
lookup as the smooth atlas; without it the material has no roughness:
asking for one raises ExportError); the refraction lobe keeps the
transmittance at the view angle, and a back face seen from a substrate with
its own chart the smooth reflectance at the view angle (the rough table
holds light from the ambient only).

The modules, each importing only those listed before it: film (the
film.json reader rule, shared with the other hosts), charts (the chart
mapping and choice in Python), export (an export directory checked), nodes
(the node graph), material (the public functions), operators (the add-on's
import dialog).
"""

bl_info = {
    "name": "irid thin film",
    "author": "irid",
    "version": (0, 2, 0),
    "blender": (4, 2, 0),
    "location": "File > Import > irid film (film.json)",
    "description": "Exact thin-film iridescence from an irid export (lookup tables + node group)",
    "category": "Material",
}

from .charts import AtlasChart, atlas_chart_for  # noqa: E402
from .export import BLENDER_WHITE, TABLES, Export, Rough  # noqa: E402
from .film import FILM_FORMAT, FILM_VERSION, ExportError, check_film, read_film  # noqa: E402
from .material import add_film_layer, make_material, make_node_group  # noqa: E402
from .operators import IRID_OT_import_film, middle_thickness_nm, register, unregister  # noqa: E402

__all__ = [
    "AtlasChart",
    "BLENDER_WHITE",
    "Export",
    "ExportError",
    "FILM_FORMAT",
    "FILM_VERSION",
    "IRID_OT_import_film",
    "Rough",
    "TABLES",
    "add_film_layer",
    "atlas_chart_for",
    "check_film",
    "make_material",
    "make_node_group",
    "middle_thickness_nm",
    "read_film",
    "register",
    "unregister",
]
