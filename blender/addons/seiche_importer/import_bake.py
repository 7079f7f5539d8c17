# Builds the Blender objects of a bake folder (bake_folder.BakeFolder), under one empty named
# after the scene that turns Seiche's y-up into Blender's z-up (+90 degrees about x); every
# object below it is in Seiche's coordinates (m), so the particles' positions and velocities are
# the PLY's numbers:
#   <scene> surface    the fluid surface: the "surface" level set of the .vdb sequence meshed at
#                      0 by a Volume to Mesh modifier (all the water), or else the baked OBJ
#                      sequence; water material
#   <scene> volume     the .vdb sequence as a Volume object (Blender loads the frame's file); its
#                      "density" grid renders as a volume when asked for, hidden otherwise
#   <scene> particles  a vertex-only mesh with `velocity` and `id`, shown as points by a
#                      Geometry Nodes modifier (Mesh to Points, radius half the spacing)
#   <stem>             one mesh per other OBJ sequence (every cloth), vertices following frames
#   <body name>        one object per rigid body: its mesh in the body frame (from the first
#                      frame's <body name>.%04d.obj, taken back through that frame's transform;
#                      an empty without body meshes), and its transforms from bodies.%04d.jsonl
#                      as keyframes (location, rotation_quaternion; linear between frames)
# and sets the scene's frame rate (1 / frame_dt) and frame range. Every first frame is read
# before any object is made, so a bad file leaves the scene as it was.
import math

import bpy
import numpy as np
from mathutils import Matrix, Quaternion, Vector

from . import frame_sequences, materials, mesh_data, obj_frames, ply_points
from .bake_folder import BakeFolderError, read_body_frame

SURFACE_GRID = "surface"  # the level set: signed distance, negative inside; its 0 level is the surface


def _new_object(name, data, collection, parent):
    obj = bpy.data.objects.new(name, data)
    collection.objects.link(obj)
    obj.parent = parent
    return obj


def _points_modifier(obj, radius, material):
    """Geometry Nodes: Mesh to Points (radius `radius`) with `material`; the attributes go along."""
    group = bpy.data.node_groups.new("Seiche particles as points", "GeometryNodeTree")
    group.inputs.new("NodeSocketGeometry", "Geometry")
    group.outputs.new("NodeSocketGeometry", "Geometry")
    nodes, links = group.nodes, group.links
    group_in, group_out = nodes.new("NodeGroupInput"), nodes.new("NodeGroupOutput")
    to_points = nodes.new("GeometryNodeMeshToPoints")
    to_points.inputs["Radius"].default_value = radius
    set_material = nodes.new("GeometryNodeSetMaterial")
    set_material.inputs["Material"].default_value = material
    links.new(group_in.outputs["Geometry"], to_points.inputs["Mesh"])
    links.new(to_points.outputs["Points"], set_material.inputs["Geometry"])
    links.new(set_material.outputs["Geometry"], group_out.inputs["Geometry"])
    for k, n in enumerate((group_in, to_points, set_material, group_out)):
        n.location = (200 * k, 0)
    modifier = obj.modifiers.new("Seiche points", "NODES")
    modifier.node_group = group
    return modifier


def probe_vdb(path):
    """(grid names, index-to-object matrix of the first grid) of the .vdb file at `path`, read by
    Blender itself through a volume datablock that is removed again."""
    volume = bpy.data.volumes.new("Seiche probe")
    try:
        volume.filepath = path
        volume.grids.load()
        if not volume.grids.is_loaded:
            raise BakeFolderError(f"{path}: Blender cannot read it: {volume.grids.error_message}")
        names = [g.name for g in volume.grids]
        return names, (volume.grids[0].matrix_object.copy() if names else Matrix.Identity(4))
    finally:
        bpy.data.volumes.remove(volume)


def _volume_object(bake, index_to_object, grids, collection, parent, show_density):
    """The .vdb sequence as a Volume object, placed so that Blender's meshes of it lie where
    Seiche's are: Blender's Volume to Mesh moves its vertices by half a voxel along every axis
    (to match how it draws voxels), which the object's location takes back."""
    seq = bake.fluid_vdb
    volume = bpy.data.volumes.new(f"{bake.scene_name} volume")
    volume.filepath = seq.path(seq.first)
    volume.is_sequence = True
    volume.frame_start = seq.first
    volume.frame_duration = seq.last - seq.first + 1
    volume.frame_offset = seq.first - 1  # scene frame k shows file k
    volume.sequence_mode = "EXTEND"
    if "v" in grids:
        volume.velocity_grid = "v"  # motion blur (m/s; the object's units are m)
    volume.materials.append(materials.density_volume())
    obj = _new_object(f"{bake.scene_name} volume", volume, collection, parent)
    obj.location = -0.5 * sum((index_to_object.col[a].xyz for a in range(3)), Vector())
    obj.hide_render = not show_density
    if not show_density:
        obj.display_type = "BOUNDS"  # the viewport draws its box, not the fog over the surface
    return obj


def read_first_frames(bake, surface_source):
    """Reads every sequence's first frame (errors before anything is made) and picks the fluid
    surface's source: "AUTO" is "VDB" (the level set `surface`) when the .vdb files hold it,
    else "OBJ" (the baked surface mesh) when the bake wrote one, else "NONE"."""
    first = {}
    if bake.fluid_vdb:
        first["vdb"] = probe_vdb(bake.fluid_vdb.path(bake.fluid_vdb.first))
    has_level_set = "vdb" in first and SURFACE_GRID in first["vdb"][0]
    if bake.particles:
        first["particles"] = ply_points.read_ply_points(bake.particles.path(bake.particles.first))
    for seq in bake.meshes:
        first[seq.stem] = obj_frames.read_obj(seq.path(seq.first))
    if bake.bodies:
        first["bodies"] = {f: read_body_frame(bake.bodies.path(f)) for f in bake.bodies.frames}
    for name, seq in bake.body_meshes.items():
        if seq:
            first["body " + name] = obj_frames.read_obj(seq.path(seq.first))
    if surface_source == "AUTO":
        surface_source = "VDB" if has_level_set else ("OBJ" if bake.fluid_obj else "NONE")
    if surface_source == "VDB" and not bake.fluid_vdb:
        raise BakeFolderError(f"{bake.directory}: no {bake.scene_name}.%04d.vdb files for the fluid surface")
    if surface_source == "VDB" and not has_level_set:
        raise BakeFolderError(f"{bake.fluid_vdb.path(bake.fluid_vdb.first)}: no \"{SURFACE_GRID}\" grid "
                              f"(it has {first['vdb'][0]}); bake with \"{SURFACE_GRID}\" in output.vdb, "
                              "or import the OBJ surface (output.mesh)")
    if surface_source == "OBJ" and not bake.fluid_obj:
        raise BakeFolderError(f"{bake.directory}: no {bake.scene_name}.%04d.obj files for the fluid surface "
                              "(the scene's output.mesh was off)")
    if surface_source == "OBJ":
        first["surface"] = obj_frames.read_obj(bake.fluid_obj.path(bake.fluid_obj.first))
    return first, surface_source


def _body_objects(bake, first, collection, parent):
    """One object per rigid body (see the top of this file)."""
    poses = first.get("bodies", {})
    for name, seq in bake.body_meshes.items():
        frames = [f for f in sorted(poses) if name in poses[f]]
        if not frames:
            continue
        data = None
        if seq is not None and seq.first in poses and name in poses[seq.first]:
            obj_mesh = first["body " + name]
            position, orientation = poses[seq.first][name]
            turn = np.array(Quaternion(orientation).to_matrix(), dtype=np.float64)
            # World to body frame: R^T (p - x), as rows (p - x) R.
            obj_mesh.positions = ((obj_mesh.positions.astype(np.float64) - position) @ turn).astype(np.float32)
            data = bpy.data.meshes.new(name)
            mesh_data.set_faces(data, obj_mesh)
            data.polygons.foreach_set("use_smooth", np.zeros(len(data.polygons), dtype=bool))  # flat faces
            data.materials.append(materials.body(name))
        obj = _new_object(name, data, collection, parent)
        obj["seiche_body"] = name
        obj.rotation_mode = "QUATERNION"
        previous = None
        for f in frames:
            position, orientation = poses[f][name]
            q = Quaternion(orientation)
            if previous is not None and previous.dot(q) < 0.0:
                q.negate()  # the same turn; the nearer sign so that keys interpolate the short way
            obj.location = position
            obj.rotation_quaternion = q
            obj.keyframe_insert("location", frame=f)
            obj.keyframe_insert("rotation_quaternion", frame=f)
            previous = q
        for curve in obj.animation_data.action.fcurves:
            for key in curve.keyframe_points:
                key.interpolation = "LINEAR"


def set_scene_timing(scene, bake):
    """Frame rate 1 / frame_dt (fps / fps_base, exact for whole rates) and the frames on disk."""
    rate = 1.0 / bake.frame_dt
    fps = max(1, round(rate))
    scene.render.fps = fps
    scene.render.fps_base = 1.0 if abs(rate - fps) < 1e-3 * rate else fps / rate
    scene.frame_start, scene.frame_end = bake.frames_present


def import_bake(context, bake, surface_source="AUTO", density_volume=False, render_particles=False,
                set_timing=True):
    """Makes the objects of `bake` in a new collection; returns the root empty."""
    first, surface_source = read_first_frames(bake, surface_source)
    scene = context.scene
    collection = bpy.data.collections.new(f"Seiche {bake.scene_name}")
    scene.collection.children.link(collection)
    root = _new_object(bake.scene_name, None, collection, None)
    root.rotation_euler = (math.radians(90), 0, 0)  # Seiche y-up -> Blender z-up
    root["seiche_bake"] = bake.directory

    water = materials.water()
    if bake.fluid_vdb:
        grids, index_to_object = first["vdb"]
        volume_obj = _volume_object(bake, index_to_object, grids, collection, root, density_volume)
    if surface_source == "VDB":
        surface = _new_object(f"{bake.scene_name} surface", bpy.data.meshes.new(f"{bake.scene_name} surface"),
                              collection, root)
        to_mesh = surface.modifiers.new("Seiche surface", "VOLUME_TO_MESH")
        to_mesh.object = volume_obj
        to_mesh.grid_name = SURFACE_GRID
        to_mesh.threshold = 0.0  # the level set's zero: the surface itself (density 0.5 lies inside it)
        to_mesh.resolution_mode = "GRID"
        to_mesh.adaptivity = 0.0
        to_mesh.use_smooth_shade = True
        surface.data.materials.append(water)
    elif surface_source == "OBJ":
        surface = _new_object(f"{bake.scene_name} surface", bpy.data.meshes.new(f"{bake.scene_name} surface"),
                              collection, root)
        frame_sequences.tag(surface, "surface", bake.fluid_obj)
        mesh_data.set_faces(surface.data, first["surface"])
        surface.data.materials.append(water)

    if bake.particles:
        points = first["particles"]
        particles = _new_object(f"{bake.scene_name} particles", bpy.data.meshes.new(f"{bake.scene_name} particles"),
                                collection, root)
        frame_sequences.tag(particles, "particles", bake.particles)
        mesh_data.set_points(particles.data, ply_points.positions(points), ply_points.velocities(points),
                             ply_points.ids(points))
        spacing = bake.fluid_spacing() or 0.02
        _points_modifier(particles, 0.5 * spacing, materials.particles())
        particles.hide_render = not render_particles

    for seq in bake.meshes:
        obj = _new_object(seq.stem, bpy.data.meshes.new(seq.stem), collection, root)
        frame_sequences.tag(obj, "mesh", seq)
        mesh_data.set_faces(obj.data, first[seq.stem])
        obj.data.materials.append(materials.cloth(seq.stem))

    _body_objects(bake, first, collection, root)

    if set_timing:
        set_scene_timing(scene, bake)
    if hasattr(scene, "eevee"):  # Eevee refracts through the water only with screen space refraction
        scene.eevee.use_ssr = True
        scene.eevee.use_ssr_refraction = True
    for obj in collection.objects:  # every sequence at the current frame
        if "seiche_sequence" in obj:
            frame_sequences.load_frame(obj, scene.frame_current, force=True)
    return root
