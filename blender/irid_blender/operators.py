"""The add-on's File > Import > irid film (film.json): builds the material
and assigns it to the selected meshes. The thickness defaults to the middle
of the chosen export's range."""

import os

import bpy

from .export import Export
from .film import ExportError, read_film
from .material import make_material


def middle_thickness_nm(film_path):
    """The middle of the thickness range of the export whose film.json is
    `film_path`; ExportError when it cannot be read."""
    low, high = read_film(film_path)["domain"]["thickness_nm"]
    return 0.5 * (low + high)


class IRID_OT_import_film(bpy.types.Operator):
    """Build a material from an irid export (film.json) and assign it to the selected objects"""

    bl_idname = "import_scene.irid_film"
    bl_label = "Import irid film"
    bl_options = {"REGISTER", "UNDO"}

    filepath: bpy.props.StringProperty(subtype="FILE_PATH")
    filter_glob: bpy.props.StringProperty(default="film.json", options={"HIDDEN"})
    use_thickness: bpy.props.BoolProperty(
        name="Constant thickness",
        description="Use one thickness in nm; off leaves the 0-1 Thickness socket to a texture",
        default=True,
    )
    thickness_nm: bpy.props.FloatProperty(
        name="Thickness (nm)",
        description="The film's thickness; choosing a film.json sets it to the middle of "
        "the export's range",
        default=0.0,
        min=0.0,
    )
    # The film.json whose range set thickness_nm, so that the dialog moves
    # the thickness only when another export is chosen.
    thickness_from: bpy.props.StringProperty(options={"HIDDEN", "SKIP_SAVE"})
    roughness: bpy.props.FloatProperty(name="Roughness", default=0.0, min=0.0, max=1.0)

    def check(self, context):
        """The file browser calls this when the selection changes: a newly
        chosen export's range sets the thickness (True redraws the dialog)."""
        if self.filepath == self.thickness_from or not os.path.isfile(self.filepath):
            return False
        try:
            self.thickness_nm = middle_thickness_nm(self.filepath)
        except ExportError:
            return False
        self.thickness_from = self.filepath
        return True

    def execute(self, context):
        meshes = [obj for obj in context.selected_objects if obj.type == "MESH"]
        if not meshes:
            self.report({"ERROR"}, "No mesh is selected: select the meshes to put the film on")
            return {"CANCELLED"}
        directory = os.path.dirname(self.filepath)
        try:
            thickness = None
            if self.use_thickness:
                thickness = self.thickness_nm
                if not self.properties.is_property_set("thickness_nm"):
                    export = Export(directory)
                    thickness = 0.5 * (export.thickness_min_nm + export.thickness_max_nm)
            material = make_material(directory, thickness_nm=thickness, roughness=self.roughness)
        except ValueError as e:
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        # The film takes the active material slot; the mesh's other slots
        # (and the faces assigned to them) stay as they were.
        for obj in meshes:
            if obj.material_slots:
                obj.active_material = material
            else:
                obj.data.materials.append(material)
        self.report(
            {"INFO"},
            f"Built material {material.name}, in the active slot of {len(meshes)} mesh"
            f"{'' if len(meshes) == 1 else 'es'}",
        )
        return {"FINISHED"}

    def invoke(self, context, event):
        context.window_manager.fileselect_add(self)
        return {"RUNNING_MODAL"}


def _menu_import(self, context):
    self.layout.operator(IRID_OT_import_film.bl_idname, text="irid film (film.json)")


def register():
    bpy.utils.register_class(IRID_OT_import_film)
    bpy.types.TOPBAR_MT_file_import.append(_menu_import)


def unregister():
    bpy.types.TOPBAR_MT_file_import.remove(_menu_import)
    bpy.utils.unregister_class(IRID_OT_import_film)
