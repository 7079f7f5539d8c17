# The Blender add-on's test (blender/addons/seiche_importer), run by ctest through
# run_addon_test.sh inside Debian's Blender, headless:
#   blender -b --factory-startup --python-exit-code 1 --python addon_test.py -- REPO BAKE_DIR OUT_DIR BODIES_DIR
# BAKE_DIR is a bake of tests/data/blender_small.json (3 frames: a fluid block and a cloth),
# BODIES_DIR one of tests/data/blender_bodies.json (4 frames: a box and an OBJ mesh body; each
# body one object whose keyframes are the bodies.%04d.jsonl transforms and whose vertices are the
# frame's <body>.%04d.obj, and no body OBJ imported a second time as a cloth).
# It enables the add-on from the repository, imports the bake, steps the frames and checks
# against the files, read here independently of the add-on: the particles' count, positions,
# `velocity` and `id` (= the PLY's, and readable by Geometry Nodes), the cloth's vertices (= the
# OBJ's), the fluid surface's enclosed volume (within 5 % of the fluid's), the frame rate and
# range; bad folders fail with a message, not a traceback; one frame renders to a PNG that is
# not uniform.
import json
import os
import shutil
import sys

import addon_utils
import bpy
import numpy as np

REPO, BAKE, OUT, BODIES = sys.argv[sys.argv.index("--") + 1:][:4]
FRAMES = (1, 2, 3)
SPACING = 0.025  # tests/data/blender_small.json: fluids[0].spacing
FRAME_DT = 0.04  # solver.frame_dt
failures = []


def check(ok, what):
    print(("ok    " if ok else "FAIL  ") + what)
    if not ok:
        failures.append(what)


# ---- the bake's files, read without the add-on ------------------------------------------------
def ply(frame):
    """particles.%04d.ply as seiche writes it: float x y z vx vy vz, int id (output_files.cpp)."""
    data = open(os.path.join(BAKE, f"particles.{frame:04d}.ply"), "rb").read()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    count = int(next(l for l in data[:end].decode().splitlines() if l.startswith("element vertex")).split()[2])
    dtype = np.dtype([("p", "<f4", 3), ("v", "<f4", 3), ("id", "<i4")])
    return np.frombuffer(data, dtype, count, end)


def obj_vertices(path):
    return np.array([l.split()[1:4] for l in open(path) if l.startswith("v ")], dtype=np.float32)


def signed_volume(mesh):
    """Divergence theorem: the sum over triangles of det(a, b, c) / 6 (outward faces: positive)."""
    mesh.calc_loop_triangles()
    co = np.empty(3 * len(mesh.vertices), dtype=np.float64)
    mesh.vertices.foreach_get("co", co)
    tri = np.empty(3 * len(mesh.loop_triangles), dtype=np.int64)
    mesh.loop_triangles.foreach_get("vertices", tri)
    p = co.reshape(-1, 3)[tri.reshape(-1, 3)]
    return float(np.einsum("ij,ij->i", p[:, 0], np.cross(p[:, 1], p[:, 2])).sum() / 6.0)


def evaluated_mesh_copy(obj):
    evaluated = obj.evaluated_get(bpy.context.evaluated_depsgraph_get())
    return bpy.data.meshes.new_from_object(evaluated)


def attribute(mesh, name, width, kind):
    a = mesh.attributes.get(name)
    if a is None or a.domain != "POINT":
        return None
    values = np.empty(len(mesh.vertices) * width, dtype=np.float32 if kind == "FLOAT" else np.int32)
    a.data.foreach_get("vector" if width == 3 else "value", values)
    return values.reshape(-1, width) if width == 3 else values


# ---- enable the add-on from the repository ------------------------------------------------------
bpy.ops.wm.read_factory_settings(use_empty=True)
bpy.context.preferences.filepaths.script_directory = os.path.join(REPO, "blender")
bpy.utils.refresh_script_paths()
module = addon_utils.enable("seiche_importer", default_set=True, handle_error=None)
check(module is not None and os.path.realpath(module.__file__).startswith(os.path.realpath(REPO)),
      f"the add-on enables from the repository ({module and module.__file__})")
if module is None:
    sys.exit(1)
scene = bpy.context.scene

# ---- bad input: a clear message (a RuntimeError from the operator's report), nothing made ----
def import_error(folder):
    before = len(bpy.data.objects)
    try:
        bpy.ops.import_scene.seiche_bake(directory=folder)
    except RuntimeError as e:
        return str(e), len(bpy.data.objects) - before
    return None, len(bpy.data.objects) - before


message, made = import_error(OUT)
check(message is not None and "not a Seiche bake folder" in message and "bake.json" in message and made == 0,
      f"a folder that is not a bake is refused: {message}")
broken = os.path.join(OUT, "truncated_bake")
shutil.rmtree(broken, ignore_errors=True)
shutil.copytree(BAKE, broken)
with open(os.path.join(broken, "particles.0001.ply"), "r+b") as f:
    f.truncate(os.path.getsize(os.path.join(broken, "particles.0001.ply")) - 100)
message, made = import_error(broken)
check(message is not None and "particles.0001.ply" in message and "truncated" in message and made == 0,
      f"a truncated particle file is refused, naming it, and nothing is made: {message}")

# ---- the frame rate without report.json: the scene's solver.frame_dt after the bake's overrides
from seiche_importer import bake_folder  # noqa: E402

doc = {"fluids": [{"spacing": 0.02}], "solver": {}}
for override in ("fluids[0].spacing=0.03", "solver.frame_dt=0.05", "fluids.0.rest_density=998", "output.vdb=[]"):
    bake_folder.apply_override(doc, override)
check(doc == {"fluids": [{"spacing": 0.03, "rest_density": 998}], "solver": {"frame_dt": 0.05}, "output": {"vdb": []}},
      f"--set overrides apply to the scene as Seiche's loader applies them: {doc}")
no_report = os.path.join(OUT, "bake_without_report")
shutil.rmtree(no_report, ignore_errors=True)
shutil.copytree(BAKE, no_report)
os.remove(os.path.join(no_report, "report.json"))
description = json.load(open(os.path.join(no_report, "bake.json")))
description["overrides"] = ["solver.frame_dt=0.05"]
json.dump(description, open(os.path.join(no_report, "bake.json"), "w"))
check(bake_folder.read_bake_folder(no_report).frame_dt == 0.05,
      "without report.json the frame time is the scene's solver.frame_dt with the bake's overrides")

# ---- import -----------------------------------------------------------------------------------
bpy.ops.import_scene.seiche_bake(directory=BAKE)
objects = {o.name: o for o in scene.objects}
particles, cloth, surface = objects.get("blender_small particles"), objects.get("sheet"), objects.get("blender_small surface")
check(particles is not None and cloth is not None and surface is not None and "blender_small volume" in objects,
      f"the import makes the surface, volume, particles and cloth objects ({sorted(objects)})")
check(abs(scene.render.fps / scene.render.fps_base - 1 / FRAME_DT) < 1e-6 and
      (scene.frame_start, scene.frame_end) == (1, 3),
      f"frame rate 1/frame_dt = {scene.render.fps / scene.render.fps_base:g} fps, frames "
      f"{scene.frame_start}-{scene.frame_end}")

water_material = surface.data.materials[0] if surface and surface.data.materials else None
bsdf = next((n for n in water_material.node_tree.nodes if n.type == "BSDF_PRINCIPLED"), None) if water_material else None
check(bsdf is not None and bsdf.inputs["Transmission"].default_value == 1.0 and
      abs(bsdf.inputs["IOR"].default_value - 1.33) < 1e-6,
      "the surface's material is water: Principled BSDF, transmission 1, IOR 1.33")

check(not np.array_equal(ply(1)["p"], ply(3)["p"]) and
      not np.array_equal(obj_vertices(os.path.join(BAKE, "sheet.0001.obj")), obj_vertices(os.path.join(BAKE, "sheet.0003.obj"))),
      "the particles and the cloth move between frames 1 and 3 (so the frame checks below can fail)")
for frame in FRAMES:
    scene.frame_set(frame)
    expected = ply(frame)
    mesh = particles.data
    co = np.empty(3 * len(mesh.vertices), dtype=np.float32)
    mesh.vertices.foreach_get("co", co)
    velocity, ids = attribute(mesh, "velocity", 3, "FLOAT"), attribute(mesh, "id", 1, "INT")
    check(len(mesh.vertices) == len(expected) and np.array_equal(co.reshape(-1, 3), expected["p"]),
          f"frame {frame}: {len(mesh.vertices)} particles at the PLY's {len(expected)} positions")
    check(velocity is not None and np.array_equal(velocity, expected["v"]) and
          ids is not None and np.array_equal(ids, expected["id"]),
          f"frame {frame}: point attributes velocity (float vector) and id (int) hold the PLY's values")
    cloth_expected = obj_vertices(os.path.join(BAKE, f"sheet.{frame:04d}.obj"))
    cloth_co = np.empty(3 * len(cloth.data.vertices), dtype=np.float32)
    cloth.data.vertices.foreach_get("co", cloth_co)
    check(len(cloth.data.vertices) == len(cloth_expected) and
          np.abs(cloth_co.reshape(-1, 3) - cloth_expected).max() < 1e-6,
          f"frame {frame}: the cloth has the OBJ's {len(cloth_expected)} vertices at its positions")

    # The water: (particles - cloth vertices) x spacing^3, the volume the lattice filled at rest
    # density (the bake keeps the density within about 1 %): independent of any surface code.
    water = (len(expected) - len(cloth_expected)) * SPACING ** 3
    level_set = evaluated_mesh_copy(surface)
    volume = signed_volume(level_set)
    check(abs(volume / water - 1) < 0.05,
          f"frame {frame}: the surface mesh encloses {volume:.5f} m^3, the fluid {water:.5f} m^3 "
          f"({100 * (volume / water - 1):+.2f} %, within 5 %)")
    # Where Seiche's own mesh of the same level set lies (output.mesh): Blender's has the same
    # vertices (the volume object takes back Volume to Mesh's half-voxel shift).
    baked = obj_vertices(os.path.join(BAKE, f"blender_small.{frame:04d}.obj"))
    co = np.empty(3 * len(level_set.vertices), dtype=np.float32)
    level_set.vertices.foreach_get("co", co)
    co = co.reshape(-1, 3)
    check(len(co) == len(baked) and np.abs(np.sort(co, axis=0) - np.sort(baked, axis=0)).max() < 1e-4,
          f"frame {frame}: the surface's {len(co)} vertices lie where the baked OBJ's {len(baked)} do")
    bpy.data.meshes.remove(level_set)

# The route the issue replaced (the density grid at 0.5) loses water: the check above can fail.
scene.frame_set(3)
old = bpy.data.objects.new("density 0.5", bpy.data.meshes.new("density 0.5"))
scene.collection.objects.link(old)
to_mesh = old.modifiers.new("old", "VOLUME_TO_MESH")
to_mesh.object, to_mesh.grid_name, to_mesh.threshold = objects["blender_small volume"], "density", 0.5
old_mesh = evaluated_mesh_copy(old)
check(signed_volume(old_mesh) < 0.9 * water, f"the density-0.5 mesh holds {signed_volume(old_mesh):.5f} m^3: "
      "less than 90 % of the water")
bpy.data.objects.remove(old)
bpy.data.meshes.remove(old_mesh)

# The baked OBJ surface (fluid_surface="OBJ") follows the frames and encloses the same water.
bpy.ops.import_scene.seiche_bake(directory=BAKE, fluid_surface="OBJ", set_timing=False)
obj_surface = next(o for o in scene.objects if o.name.startswith("blender_small surface") and o != surface)
for frame in FRAMES:
    scene.frame_set(frame)
    n = len(obj_vertices(os.path.join(BAKE, f"blender_small.{frame:04d}.obj")))
    a, b = signed_volume(obj_surface.data), signed_volume(evaluated_mesh_copy(surface))
    check(len(obj_surface.data.vertices) == n and abs(a / b - 1) < 1e-3,
          f"frame {frame}: the OBJ surface has the file's {n} vertices and encloses {a:.5f} m^3 "
          f"(the level set's mesh: {b:.5f})")
bpy.data.collections.remove(obj_surface.users_collection[0])

# ---- Geometry Nodes read the attributes: offset = velocity + (id, 0, 0) ---------------------
group = bpy.data.node_groups.new("test attributes", "GeometryNodeTree")
group.inputs.new("NodeSocketGeometry", "Geometry")
group.outputs.new("NodeSocketGeometry", "Geometry")
n = group.nodes
gin, gout, setpos = n.new("NodeGroupInput"), n.new("NodeGroupOutput"), n.new("GeometryNodeSetPosition")
velocity_node = n.new("GeometryNodeInputNamedAttribute")
velocity_node.data_type = "FLOAT_VECTOR"
velocity_node.inputs["Name"].default_value = "velocity"
id_node, combine, add = n.new("GeometryNodeInputID"), n.new("ShaderNodeCombineXYZ"), n.new("ShaderNodeVectorMath")
group.links.new(id_node.outputs["ID"], combine.inputs["X"])
group.links.new(velocity_node.outputs["Attribute"], add.inputs[0])
group.links.new(combine.outputs["Vector"], add.inputs[1])
group.links.new(add.outputs["Vector"], setpos.inputs["Offset"])
group.links.new(gin.outputs["Geometry"], setpos.inputs["Geometry"])
group.links.new(setpos.outputs["Geometry"], gout.inputs["Geometry"])
scene.frame_set(2)
for m in particles.modifiers:
    m.show_viewport = False
particles.modifiers.new("test attributes", "NODES").node_group = group
moved = evaluated_mesh_copy(particles)
co = np.empty(3 * len(moved.vertices), dtype=np.float32)
moved.vertices.foreach_get("co", co)
expected = ply(2)
offset = expected["v"] + np.stack([expected["id"].astype(np.float32), np.zeros(len(expected)), np.zeros(len(expected))], 1)
check(np.allclose(co.reshape(-1, 3), expected["p"] + offset, rtol=1e-6, atol=1e-6),
      "Geometry Nodes read velocity (Named Attribute) and id (the ID node) per particle")
particles.modifiers.remove(particles.modifiers["test attributes"])
for m in particles.modifiers:
    m.show_viewport = True

# ---- rigid bodies: one object per body, keyframed from bodies.%04d.jsonl ----------------------
def body_lines(frame):
    with open(os.path.join(BODIES, f"bodies.{frame:04d}.jsonl")) as f:
        return {b["name"]: b for b in map(json.loads, f.read().splitlines())}


before = set(bpy.data.objects)
bpy.ops.import_scene.seiche_bake(directory=BODIES, set_timing=False)
made = [o for o in bpy.data.objects if o not in before]
bodies_root = next((o for o in made if o.name == "blender_bodies"), None)
check(sorted(o.name for o in made) == ["ball", "blender_bodies", "swing"],
      f"the bodies' bake makes its root and one object per body, no body OBJ as a cloth ({sorted(o.name for o in made)})")
check(body_lines(1)["swing"]["position"] != body_lines(4)["swing"]["position"] and
      body_lines(1)["ball"]["orientation"] != body_lines(4)["ball"]["orientation"],
      "the bodies move and turn between frames 1 and 4 (so the checks below can fail)")
for name in ("swing", "ball"):
    body = bpy.data.objects.get(name)
    if body is None or bodies_root is None:
        check(False, f"body {name} imported")
        continue
    check(body.type == "MESH" and body.parent == bodies_root and body.rotation_mode == "QUATERNION" and
          "seiche_sequence" not in body,
          f"{name}: a mesh under the scene's root, turned by quaternion keyframes, not a frame sequence")
    for frame in (1, 2, 3, 4):
        scene.frame_set(frame)
        line = body_lines(frame)[name]
        q = np.array(body.rotation_quaternion)
        check(np.abs(np.array(body.location) - line["position"]).max() < 1e-6 and
              abs(abs(float(np.dot(q, line["orientation"]))) - 1) < 1e-6,
              f"frame {frame}: {name}'s keyframed location and rotation are the JSON line's")
        # The object's vertices through its keyframed transform (in the root's Seiche frame) are
        # the frame's OBJ.
        local = np.array(bodies_root.matrix_world.inverted() @ body.matrix_world)
        co = np.empty(3 * len(body.data.vertices), dtype=np.float64)
        body.data.vertices.foreach_get("co", co)
        co = co.reshape(-1, 3) @ local[:3, :3].T + local[:3, 3]
        expected = obj_vertices(os.path.join(BODIES, f"{name}.{frame:04d}.obj"))
        check(len(co) == len(expected) and np.abs(co - expected).max() < 1e-5,
              f"frame {frame}: {name}'s {len(co)} vertices lie on its OBJ's {len(expected)}")

# ---- render frame 3 headless: the handler loads frame 3 in the render itself ----------------
scene.frame_set(1)
bpy.ops.object.camera_add(location=(0.3, -1.3, 0.7))
camera = bpy.context.object
camera.rotation_euler = (np.radians(65), 0, 0)
scene.camera = camera
bpy.ops.object.light_add(type="SUN", rotation=(0.6, 0.2, 0.4))
world = bpy.data.worlds.new("sky")
world.color = (0.5, 0.55, 0.6)
scene.world = world
scene.render.engine = "CYCLES"
scene.cycles.device = "CPU"
scene.cycles.samples = 4
scene.cycles.use_denoising = False
scene.render.resolution_x, scene.render.resolution_y, scene.render.resolution_percentage = 96, 64, 100
scene.render.image_settings.file_format = "PNG"
scene.render.filepath = os.path.join(OUT, "frame_")
scene.frame_start = scene.frame_end = 3
rendered = {}


def record_particles(*_):  # after the frame renders (the frame goes back to 1 after the render)
    co = np.empty(3 * len(particles.data.vertices), dtype=np.float32)
    particles.data.vertices.foreach_get("co", co)
    rendered["co"] = co.reshape(-1, 3)


bpy.app.handlers.render_post.append(record_particles)
bpy.ops.render.render(animation=True)
png = os.path.join(OUT, "frame_0003.png")
check("co" in rendered and np.array_equal(rendered["co"], ply(3)["p"]),
      "the render of frame 3 (from frame 1) had frame 3's particles: the frame handler runs in renders")
check(os.path.isfile(png) and os.path.getsize(png) > 0, f"the render wrote {png}")
if os.path.isfile(png):
    image = bpy.data.images.load(png)
    pixels = np.empty(len(image.pixels), dtype=np.float32)
    image.pixels.foreach_get(pixels)
    rgb = pixels.reshape(-1, 4)[:, :3]
    check(image.size[0] == 96 and image.size[1] == 64 and rgb.std(axis=0).max() > 0.02,
          f"the PNG is {image.size[0]} x {image.size[1]} and not uniform (std {rgb.std(axis=0).max():.3f})")

print(f"addon_test: {len(failures)} failed" if failures else "addon_test: all passed")
sys.exit(1 if failures else 0)
