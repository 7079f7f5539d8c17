# Renders one frame of a Seiche bake with Blender (headless, Cycles on the CPU), through the
# repository's add-on (blender/addons/seiche_importer): the bake folder is imported as the add-on
# does it (the fluid surface is the "surface" level set meshed at 0, so all the water shows, with
# a water material: transmission 1, IOR 1.33), then a floor, two walls, a camera, a sun and a sky
# are added around the scene's domain.
#
#   blender -b --factory-startup -P scripts/render_frame.py -- BAKE_DIR FRAME OUT.png \
#       [--samples 32] [--size 960 540] [--particles]
#
# Seiche is y-up, Blender z-up: the add-on turns the imported objects +90 degrees about x.
import argparse
import math
import os
import sys

import bpy
from mathutils import Vector

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "blender", "addons"))
import seiche_importer  # noqa: E402  (the add-on, from the repository)
from seiche_importer import bake_folder, import_bake, materials  # noqa: E402


def parse_args():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    p = argparse.ArgumentParser(prog="render_frame.py")
    p.add_argument("bake", help="the folder `seiche bake` wrote")
    p.add_argument("frame", type=int)
    p.add_argument("png")
    p.add_argument("--samples", type=int, default=32)
    p.add_argument("--size", type=int, nargs=2, default=[960, 540])
    p.add_argument("--particles", action="store_true", help="render the particles as points too")
    return p.parse_args(argv)


def y_up_to_z_up(v):
    # Seiche (x, y, z) with y up -> Blender (x, -z, y) with z up: a +90 degree turn about x.
    return Vector((v[0], -v[2], v[1]))


def wall_material():
    m, bsdf, _ = materials.principled("walls")
    bsdf.inputs["Base Color"].default_value = (0.8, 0.8, 0.78, 1.0)
    bsdf.inputs["Roughness"].default_value = 0.6
    return m


def main():
    a = parse_args()
    bpy.ops.wm.read_factory_settings(use_empty=True)
    seiche_importer.register()
    scene = bpy.context.scene
    try:
        bake = bake_folder.read_bake_folder(a.bake)
        import_bake.import_bake(bpy.context, bake, render_particles=a.particles)
    except bake_folder.BakeFolderError as e:
        sys.exit(f"render_frame.py: {e}")
    first, last = bake.frames_present
    if not first <= a.frame <= last:
        sys.exit(f"render_frame.py: {a.bake} holds frames {first}-{last}, not {a.frame}")
    scene.frame_set(a.frame)

    # The domain: a floor and the two back walls, so the splash reads against something.
    domain = bake.scene.get("domain", {})
    lo = y_up_to_z_up(domain.get("min", [0, 0, 0]))
    hi = y_up_to_z_up(domain.get("max", [1, 1, 1]))
    lo, hi = Vector(map(min, lo, hi)), Vector(map(max, lo, hi))
    size = hi - lo
    wall = wall_material()
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
    # No caustics and blurred glossy paths: a sun through clear water is otherwise mostly noise
    # at a few dozen samples.
    scene.cycles.caustics_reflective = False
    scene.cycles.caustics_refractive = False
    scene.cycles.blur_glossy = 1.0
    scene.render.resolution_x, scene.render.resolution_y = a.size
    scene.render.resolution_percentage = 100
    scene.render.image_settings.file_format = "PNG"
    scene.render.filepath = os.path.abspath(a.png)
    bpy.ops.render.render(write_still=True)
    print(f"render_frame.py: wrote {a.png}")


main()
