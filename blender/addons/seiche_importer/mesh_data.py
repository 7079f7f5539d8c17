# Filling Blender meshes from arrays, fast (foreach_set, no Python loop per element): a mesh's
# faces and UVs (set_faces), its positions alone (set_positions), and a vertex-only mesh of
# points with per-point attributes (set_points). Attributes live on the POINT domain, so Geometry
# Nodes read them with a Named Attribute node.
import numpy as np


def set_faces(mesh, obj_mesh):
    """Replaces `mesh`'s geometry by an obj_frames.ObjMesh (vertices, faces, smooth shading, UVs)."""
    mesh.clear_geometry()
    n_loops, n_faces = len(obj_mesh.loop_vertices), len(obj_mesh.loop_totals)
    mesh.vertices.add(len(obj_mesh.positions))
    mesh.vertices.foreach_set("co", obj_mesh.positions.ravel())
    mesh.loops.add(n_loops)
    mesh.loops.foreach_set("vertex_index", obj_mesh.loop_vertices)
    mesh.polygons.add(n_faces)
    starts = np.zeros(n_faces, dtype=np.int32)
    if n_faces:
        np.cumsum(obj_mesh.loop_totals[:-1], out=starts[1:])
    mesh.polygons.foreach_set("loop_start", starts)
    mesh.polygons.foreach_set("loop_total", obj_mesh.loop_totals)
    mesh.polygons.foreach_set("use_smooth", np.ones(n_faces, dtype=bool))
    if obj_mesh.loop_uvs is not None and n_loops:
        layer = mesh.uv_layers.new(name="UVMap")
        layer.data.foreach_set("uv", obj_mesh.loop_uvs.ravel())
    mesh.update(calc_edges=True)


def set_positions(mesh, positions):
    """Moves `mesh`'s vertices to `positions` ((n, 3), n = the mesh's vertex count)."""
    mesh.vertices.foreach_set("co", np.ascontiguousarray(positions, dtype=np.float32).ravel())
    mesh.update()


def _point_attribute(mesh, name, data_type):
    attribute = mesh.attributes.get(name)
    if attribute is not None and (attribute.data_type != data_type or attribute.domain != "POINT"):
        mesh.attributes.remove(attribute)
        attribute = None
    return attribute or mesh.attributes.new(name, data_type, "POINT")


def set_points(mesh, positions, velocity=None, ids=None):
    """Makes `mesh` a vertex-only mesh of `positions` with the attributes `velocity` (float
    vector) and `id` (int) where given."""
    if len(mesh.vertices) != len(positions) or len(mesh.polygons) or len(mesh.edges):
        mesh.clear_geometry()
        mesh.vertices.add(len(positions))
    mesh.vertices.foreach_set("co", np.ascontiguousarray(positions, dtype=np.float32).ravel())
    if velocity is not None:
        _point_attribute(mesh, "velocity", "FLOAT_VECTOR").data.foreach_set(
            "vector", np.ascontiguousarray(velocity, dtype=np.float32).ravel())
    if ids is not None:
        _point_attribute(mesh, "id", "INT").data.foreach_set("value", np.ascontiguousarray(ids, dtype=np.int32))
    mesh.update()
