# Reader of the particle frames `particles.%04d.ply` (core/src/run/output_files.cpp,
# encode_particles_ply): binary little-endian PLY, one element "vertex" with
# `float x y z vx vy vz` and `int id`, in id order. Blender's own PLY reader keeps the
# positions only; this one keeps every property, as NumPy columns. Any binary little-endian
# vertex element with x, y, z reads (other properties are kept by name); anything else raises
# BakeFolderError naming the file.
import numpy as np

from .bake_folder import BakeFolderError

_TYPES = {
    "char": "i1", "int8": "i1", "uchar": "u1", "uint8": "u1",
    "short": "<i2", "int16": "<i2", "ushort": "<u2", "uint16": "<u2",
    "int": "<i4", "int32": "<i4", "uint": "<u4", "uint32": "<u4",
    "float": "<f4", "float32": "<f4", "double": "<f8", "float64": "<f8",
}
_MAX_HEADER = 64 * 1024


def read_ply_points(path):
    """The vertex element of the PLY file at `path` as a NumPy structured array (one field per property)."""
    try:
        with open(path, "rb") as f:
            data = f.read()
    except OSError as e:
        raise BakeFolderError(f"{path}: cannot read: {e.strerror}") from None
    end = data.find(b"end_header\n", 0, _MAX_HEADER)
    if not data.startswith(b"ply\n") or end < 0:
        raise BakeFolderError(f"{path}: not a PLY file (no 'ply' ... 'end_header' header)")
    lines = data[:end].decode("ascii", "replace").splitlines()
    body = end + len(b"end_header\n")
    if "format binary_little_endian 1.0" not in lines:
        raise BakeFolderError(f"{path}: PLY format is not binary_little_endian 1.0 (what seiche writes)")
    count, fields, element = None, [], None
    for line in lines:
        words = line.split()
        if words[:1] == ["element"]:
            element = words[1] if len(words) > 1 else ""
            if count is None and element == "vertex" and len(words) == 3 and words[2].isdigit():
                count = int(words[2])
            elif count is None:
                raise BakeFolderError(f"{path}: the first PLY element must be 'vertex <count>', got '{line}'")
        elif words[:1] == ["property"] and element == "vertex":
            if len(words) != 3 or words[1] not in _TYPES:
                raise BakeFolderError(f"{path}: unsupported PLY vertex property '{line}' (lists are not read)")
            fields.append((words[2], _TYPES[words[1]]))
    names = [n for n, _ in fields]
    if count is None or not {"x", "y", "z"} <= set(names) or len(set(names)) != len(names):
        raise BakeFolderError(f"{path}: the PLY vertex element needs properties x, y, z (once each), has {names}")
    dtype = np.dtype(fields)
    if len(data) - body < count * dtype.itemsize:
        raise BakeFolderError(f"{path}: truncated: {count} vertices need {count * dtype.itemsize} bytes "
                              f"after the header, the file has {len(data) - body}")
    return np.frombuffer(data, dtype=dtype, count=count, offset=body)


def positions(points):
    """The points' positions as an (n, 3) float32 array."""
    return np.stack([points["x"], points["y"], points["z"]], axis=1).astype(np.float32)


def velocities(points):
    """The points' velocities (vx, vy, vz) as an (n, 3) float32 array, or None without them."""
    if not {"vx", "vy", "vz"} <= set(points.dtype.names):
        return None
    return np.stack([points["vx"], points["vy"], points["vz"]], axis=1).astype(np.float32)


def ids(points):
    """The points' ids as int32, or None without them."""
    return points["id"].astype(np.int32) if "id" in points.dtype.names else None
