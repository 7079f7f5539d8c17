# Seiche bake importer for Blender 3.4 to 3.6 (tested with 3.4.1): File > Import > Seiche bake reads a folder written by
# `seiche bake` as animated objects in one step (import_bake.py says which), with the scene's
# frame rate and frame range. Install: Edit > Preferences > Add-ons > Install..., pick the zip
# `make blender-addon` writes (build/seiche_importer.zip), tick "Import-Export: Seiche bake".
# Scripts: bpy.ops.import_scene.seiche_bake(directory="out/dam_break").
import os

import bpy
from bpy.props import BoolProperty, EnumProperty, StringProperty
from bpy.types import Operator

from . import bake_folder, frame_sequences, import_bake

bl_info = {
    "name": "Seiche bake",
    "author": "Seiche",
    "version": (1, 0, 0),
    "blender": (3, 4, 0),
    "location": "File > Import > Seiche bake",
    "description": "Imports a Seiche bake folder: fluid surface, density volume, particles with "
                   "velocity and id, cloth meshes, rigid bodies (keyframed), frame rate and range",
    "category": "Import-Export",
}


class IMPORT_SCENE_OT_seiche_bake(Operator):
    """Import a Seiche bake folder as animated objects"""

    bl_idname = "import_scene.seiche_bake"
    bl_label = "Import Seiche bake"
    bl_options = {"REGISTER", "UNDO"}

    directory: StringProperty(name="Bake folder", subtype="DIR_PATH",
                              description="The folder `seiche bake` wrote (it holds bake.json)")
    filepath: StringProperty(subtype="FILE_PATH", options={"HIDDEN", "SKIP_SAVE"})
    filter_folder: BoolProperty(default=True, options={"HIDDEN"})
    filter_glob: StringProperty(default="bake.json", options={"HIDDEN"})
    fluid_surface: EnumProperty(
        name="Fluid surface",
        items=(("AUTO", "Automatic", "The level set of the .vdb files if they hold it, else the baked OBJ mesh"),
               ("VDB", "Level set (.vdb)", "Volume to Mesh of the \"surface\" level set at 0"),
               ("OBJ", "Baked mesh (.obj)", "The fluid surface OBJ sequence (output.mesh)"),
               ("NONE", "None", "No fluid surface")),
        default="AUTO")
    density_volume: BoolProperty(name="Render density volume", default=False,
                                 description="Render the \"density\" grid as a volume (hidden otherwise)")
    render_particles: BoolProperty(name="Render particles", default=False,
                                   description="Render the particles as points (shown in the viewport either way)")
    set_timing: BoolProperty(name="Set frame rate and range", default=True,
                             description="The scene's frame rate from solver.frame_dt and its range from the bake")

    def invoke(self, context, event):
        context.window_manager.fileselect_add(self)
        return {"RUNNING_MODAL"}

    def execute(self, context):
        folder = self.directory or (os.path.dirname(self.filepath) if self.filepath else "")
        if not folder:
            self.report({"ERROR"}, "Seiche bake: no folder given (pick the folder `seiche bake` wrote)")
            return {"CANCELLED"}
        try:
            bake = bake_folder.read_bake_folder(bpy.path.abspath(folder))
            import_bake.import_bake(context, bake, self.fluid_surface, self.density_volume,
                                    self.render_particles, self.set_timing)
        except bake_folder.BakeFolderError as e:
            self.report({"ERROR"}, f"Seiche bake: {e}")
            return {"CANCELLED"}
        first, last = bake.frames_present
        self.report({"INFO"}, f"Seiche bake: imported \"{bake.scene_name}\", frames {first}-{last} "
                              f"at {1.0 / bake.frame_dt:.4g} frames per second")
        return {"FINISHED"}


def menu_import(self, context):
    self.layout.operator(IMPORT_SCENE_OT_seiche_bake.bl_idname, text="Seiche bake")


def register():
    bpy.utils.register_class(IMPORT_SCENE_OT_seiche_bake)
    bpy.types.TOPBAR_MT_file_import.append(menu_import)
    frame_sequences.register()


def unregister():
    frame_sequences.unregister()
    bpy.types.TOPBAR_MT_file_import.remove(menu_import)
    bpy.utils.unregister_class(IMPORT_SCENE_OT_seiche_bake)
