# Reader of the OBJ frames Seiche writes: every cloth's `<name>.%04d.obj` (positions, normals,
# UVs, the faces as read; core/src/families/cloth) and the fluid surface `<scene>.%04d.obj`
# (core/export/src/obj_mesh.cpp: positions, normals, quads). Reads `v`, `vt` and `f`
# (`f a/b/c ...`, 1-based or negative indices); normals are left to Blender. A frame's
# positions alone are read by read_obj_positions, for meshes whose faces do not change.
import numpy as np

from .bake_folder import BakeFolderError


class ObjMesh:
    """positions (n, 3) float32; face corners (loop_vertices), faces (loop_totals); loop_uvs (loops, 2) or None."""

    def __init__(self, positions, loop_vertices, loop_totals, loop_uvs):
        self.positions = positions
        self.loop_vertices = loop_vertices
        self.loop_totals = loop_totals
        self.loop_uvs = loop_uvs


def _read_lines(path):
    try:
        with open(path, "r", encoding="ascii", errors="replace") as f:
            return f.read().splitlines()
    except OSError as e:
        raise BakeFolderError(f"{path}: cannot read: {e.strerror}") from None


def _vectors(path, rows, width, what):
    if not rows:
        return np.zeros((0, width), dtype=np.float32)
    try:
        array = np.array([r[1:width + 1] for r in rows], dtype=np.float32)
    except ValueError:
        array = None
    if array is None or array.shape != (len(rows), width) or not np.isfinite(array).all():
        raise BakeFolderError(f"{path}: malformed OBJ {what} (each needs {width} finite numbers)")
    return array.reshape(len(rows), width)


def read_obj_positions(path):
    """The `v` lines of the OBJ file at `path` as an (n, 3) float32 array."""
    rows = [line.split() for line in _read_lines(path) if line.startswith("v ")]
    return _vectors(path, rows, 3, "vertex ('v' line)")


def read_obj(path):
    """The OBJ file at `path` as an ObjMesh."""
    v_rows, vt_rows, face_rows = [], [], []
    for line in _read_lines(path):
        if line.startswith("v "):
            v_rows.append(line.split())
        elif line.startswith("vt "):
            vt_rows.append(line.split())
        elif line.startswith("f "):
            face_rows.append(line.split()[1:])
    positions = _vectors(path, v_rows, 3, "vertex ('v' line)")
    uvs = _vectors(path, vt_rows, 2, "texture coordinate ('vt' line)") if vt_rows else None
    loop_vertices, loop_uv_index, loop_totals = [], [], []

    def index(text, count, line):
        try:
            k = int(text)
        except ValueError:
            k = 0
        k = k - 1 if k > 0 else count + k  # 1-based, or negative: counted from the end
        if not (text and 0 <= k < count):
            raise BakeFolderError(f"{path}: face 'f {' '.join(line)}' refers to an element that does not exist")
        return k

    for corners in face_rows:
        if len(corners) < 3:
            raise BakeFolderError(f"{path}: face 'f {' '.join(corners)}' has fewer than 3 corners")
        for corner in corners:
            parts = corner.split("/")
            loop_vertices.append(index(parts[0], len(positions), corners))
            if uvs is not None:
                has_uv = len(parts) > 1 and parts[1]
                loop_uv_index.append(index(parts[1], len(uvs), corners) if has_uv else 0)
        loop_totals.append(len(corners))
    loop_uvs = uvs[np.array(loop_uv_index, dtype=np.int64)] if uvs is not None and loop_uv_index else None
    return ObjMesh(positions, np.array(loop_vertices, dtype=np.int32), np.array(loop_totals, dtype=np.int32), loop_uvs)
