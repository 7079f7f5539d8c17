# Meshes whose data follow the timeline: a frame-change handler (registered by the add-on, kept
# across file loads, run in renders too, headless included) reads the frame's file into every
# object tagged with the custom property "seiche_sequence":
#   "particles"  particles.%04d.ply  -> a vertex-only mesh with `velocity` and `id` (set_points)
#   "mesh"       <cloth>.%04d.obj    -> the same faces, the frame's vertex positions
#   "surface"    <scene>.%04d.obj    -> the fluid surface mesh, faces and all, of the frame
# Frames outside the bake's hold its first or last one. The tag's other properties say where
# the files are: seiche_directory, seiche_stem, seiche_ext, seiche_first, seiche_last.
import os

import bpy
from bpy.app.handlers import persistent

from . import mesh_data, obj_frames, ply_points
from .bake_folder import BakeFolderError

_loaded = {}  # mesh (as_pointer) -> the file its data came from
_warned = set()  # files whose problem was already printed


def tag(obj, kind, sequence):
    """Marks `obj` as following `sequence` (a bake_folder.FrameSequence) as `kind`."""
    obj["seiche_sequence"] = kind
    obj["seiche_directory"] = sequence.directory
    obj["seiche_stem"] = sequence.stem
    obj["seiche_ext"] = sequence.ext
    obj["seiche_first"] = sequence.first
    obj["seiche_last"] = sequence.last


def frame_file(obj, frame):
    """The file that `obj` shows at scene frame `frame`."""
    frame = min(max(int(frame), obj["seiche_first"]), obj["seiche_last"])
    directory = bpy.path.abspath(obj["seiche_directory"])
    return os.path.join(directory, f"{obj['seiche_stem']}.{frame:04d}.{obj['seiche_ext']}")


def load_frame(obj, frame, force=False):
    """Reads `obj`'s file of `frame` into its mesh (unless it holds it already); BakeFolderError if the file is bad."""
    path = frame_file(obj, frame)
    mesh = obj.data
    if not force and _loaded.get(mesh.as_pointer()) == path:
        return
    kind = obj["seiche_sequence"]
    if kind == "particles":
        points = ply_points.read_ply_points(path)
        mesh_data.set_points(mesh, ply_points.positions(points), ply_points.velocities(points), ply_points.ids(points))
    elif kind == "mesh":
        positions = obj_frames.read_obj_positions(path)
        if len(positions) == len(mesh.vertices) and len(mesh.polygons):
            mesh_data.set_positions(mesh, positions)
        else:
            mesh_data.set_faces(mesh, obj_frames.read_obj(path))
    elif kind == "surface":
        mesh_data.set_faces(mesh, obj_frames.read_obj(path))
    else:
        raise BakeFolderError(f"object \"{obj.name}\": unknown seiche_sequence \"{kind}\"")
    _loaded[mesh.as_pointer()] = path


@persistent
def on_frame_change(scene, *_):
    for obj in scene.objects:
        if obj.type != "MESH" or "seiche_sequence" not in obj:
            continue
        try:
            load_frame(obj, scene.frame_current)
        except (BakeFolderError, KeyError) as e:  # a missing or damaged frame: keep the last one
            message = f"Seiche: {obj.name}: {e}"
            if message not in _warned:
                _warned.add(message)
                print(message)


@persistent
def on_load(*_):
    _loaded.clear()  # the meshes are new ones (an old address may be reused)
    _warned.clear()


def register():
    bpy.app.handlers.frame_change_pre.append(on_frame_change)
    bpy.app.handlers.load_post.append(on_load)


def unregister():
    for handlers, handler in ((bpy.app.handlers.frame_change_pre, on_frame_change),
                              (bpy.app.handlers.load_post, on_load)):
        if handler in handlers:
            handlers.remove(handler)
