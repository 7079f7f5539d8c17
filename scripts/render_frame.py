# Renders one baked Seiche frame with Blender (headless, Cycles on the CPU): the .vdb file is
# imported as a Volume object, its "density" grid is turned into a surface with Blender's
# Volume to Mesh modifier and shaded as water, inside the scene's domain box.
#
#   blender -b --factory-startup -P scripts/render_frame.py -- FRAME.vdb OUT.png \
#       [--domain x0 y0 z0 x1 y1 z1] [--samples 32] [--size 960 540]
#
# Seiche is y-up, Blender z-up: the volume is rotated +90 degrees about x on import.
import argparse
import math
import sys

import bpy
from mathutils import Vector


def parse_args():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    p = argparse.ArgumentParser(prog="render_frame.py")
    p.add_argument("vdb")
    p.add_argument("png")
    p.add_argument("--domain", type=float, nargs=6, default=[0, 0, 0, 4, 3, 1.5])
    p.add_argument("--samples", type=int, default=32)
    p.add_argument("--size", type=int, nargs=2, default=[960, 540])
    p.add_argument("--grid", default="density")
    return p.parse_args(argv)


def y_up_to_z_up(v):
    # Seiche (x, y, z) with y up -> Blender (x, -z, y) with z up: a +90 degree turn about x.
    return Vector((v[0], -v[2], v[1]))


def material(name, color, roughness, transmission=0.0):
    m = bpy.data.materials.new(name)
    m.use_nodes = True
    nodes = m.node_tree.nodes
    bsdf = next((n for n in nodes if n.type == "BSDF_PRINCIPLED"), None)
    if bsdf is None:  # some builds start a node material empty
        bsdf = nodes.new("ShaderNodeBsdfPrincipled")
        output = next((n for n in nodes if n.type == "OUTPUT_MATERIAL"), None) or nodes.new("ShaderNodeOutputMaterial")
        m.node_tree.links.new(bsdf.outputs["BSDF"], output.inputs["Surface"])
    bsdf.inputs["Base Color"].default_value = (*color, 1.0)
    bsdf.inputs["Roughness"].default_value = roughness
    bsdf.inputs["Transmission"].default_value = transmission
    bsdf.inputs["IOR"].default_value = 1.33
    return m


def main():
    a = parse_args()
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene

    # The fluid: VDB volume -> mesh of the density grid's 0.5 level.
    bpy.ops.object.volume_import(filepath=a.vdb)
    fluid = bpy.context.object
    fluid.rotation_euler = (math.radians(90), 0, 0)
    fluid.data.grids.load()
    names = [g.name for g in fluid.data.grids]
    if a.grid not in names:
        sys.exit(f"render_frame.py: {a.vdb} has no grid '{a.grid}' (it has {names})")
    # Volume to Mesh lives on a mesh object and reads the volume object.
    surface = bpy.data.objects.new("fluid surface", bpy.data.meshes.new("fluid surface"))
    scene.collection.objects.link(surface)
    to_mesh = surface.modifiers.new("surface", "VOLUME_TO_MESH")
    to_mesh.object = fluid
    to_mesh.grid_name = a.grid
    to_mesh.threshold = 0.5
    to_mesh.resolution_mode = "GRID"
    to_mesh.use_smooth_shade = True
    surface.data.materials.append(material("water", (0.18, 0.45, 0.75), 0.08))
    fluid.hide_render = True

    # The domain: a floor and the two back walls, so the splash reads against something.
    lo, hi = y_up_to_z_up(a.domain[:3]), y_up_to_z_up(a.domain[3:])
    lo, hi = Vector(map(min, lo, hi)), Vector(map(max, lo, hi))
    size = hi - lo
    wall = material("walls", (0.8, 0.8, 0.78), 0.6)
    for name, center, scale in [
        ("floor", (lo.x + size.x / 2, lo.y + size.y / 2, lo.z), (size.x / 2, size.y / 2, 1)),
        ("back", (lo.x + size.x / 2, hi.y, lo.z + size.z / 2), (size.x / 2, size.z / 2, 1)),
        ("left", (lo.x, lo.y + size.y / 2, lo.z + size.z / 2), (size.y / 2, size.z / 2, 1)),
    ]:
        bpy.ops.mesh.primitive_plane_add(location=center)
        plane = bpy.context.object
        plane.name = name
        plane.scale = scale
        if name == "back":
            plane.rotation_euler = (math.radians(90), 0, 0)
        if name == "left":
            plane.rotation_euler = (math.radians(90), 0, math.radians(90))
        plane.data.materials.append(wall)

    # Camera in front and above, looking at the middle of the domain; sun and sky light.
    target = lo + Vector((size.x * 0.5, size.y * 0.5, size.z * 0.25))
    bpy.ops.object.camera_add(location=target + Vector((size.x * 0.15, -size.x * 1.05, size.x * 0.55)))
    camera = bpy.context.object
    camera.rotation_euler = (target - camera.location).to_track_quat("-Z", "Y").to_euler()
    camera.data.lens = 32
    scene.camera = camera
    bpy.ops.object.light_add(type="SUN", rotation=(math.radians(40), math.radians(15), math.radians(30)))
    bpy.context.object.data.energy = 3.0
    world = bpy.data.worlds.new("sky")
    world.use_nodes = True
    background = next((n for n in world.node_tree.nodes if n.type == "BACKGROUND"), None)
    if background is None:
        background = world.node_tree.nodes.new("ShaderNodeBackground")
        output = next((n for n in world.node_tree.nodes if n.type == "OUTPUT_WORLD"), None) or \
            world.node_tree.nodes.new("ShaderNodeOutputWorld")
        world.node_tree.links.new(background.outputs["Background"], output.inputs["Surface"])
    background.inputs["Color"].default_value = (0.55, 0.6, 0.68, 1)
    background.inputs["Strength"].default_value = 0.6
    scene.world = world

    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = a.samples
    scene.cycles.use_denoising = False  # Debian's Blender is built without OpenImageDenoise
    scene.render.resolution_x, scene.render.resolution_y = a.size
    scene.render.resolution_percentage = 100
    scene.render.image_settings.file_format = "PNG"
    scene.render.filepath = a.png
    bpy.ops.render.render(write_still=True)
    print(f"render_frame.py: wrote {a.png}")


main()
