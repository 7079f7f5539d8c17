#!/usr/bin/env python3
"""The particles for ParaView read back: bakes (and runs) a small scene with
output.particle_formats = ["ply", "vtp"] and checks that every particles.%04d.vtp holds the
positions, velocities and ids of the same frame's PLY, bit for bit, and that particles.pvd lists
every frame with its simulated time frame * frame_dt.

The reader is our own, Python's standard library only: the XML header with ElementTree, the
appended raw arrays (a UInt64 byte count, then the bytes) with struct and array; arrays are
compared as bytes. Where VTK's Python is installed
(`import vtk`), vtkXMLPolyDataReader reads every frame too; run under ParaView's pvbatch, its
PVDReader reads the series as ParaView does.

usage: vtp_readback.py --seiche BUILD/apps/seiche --out FOLDER [--require-paraview]
Exit 0 when every check holds; otherwise 1, printing what differs.
"""
import argparse
import json
import struct
import shutil
import subprocess
import sys
import xml.etree.ElementTree as ET
from array import array
from pathlib import Path

FRAMES = 3
# A fluid that falls and splashes (the grid sort reorders the store: id order matters), beside a
# chain of raw particles, one of them pinned.
SCENE = {
    "name": "vtp_readback",
    "solver": {"frame_dt": 0.02, "substeps": 4, "iterations": 2},
    "domain": {"min": [0, 0, 0], "max": [1, 1, 0.5]},
    "output": {"frames": FRAMES, "vdb": [], "particle_formats": ["ply", "vtp"]},
    "fluids": [{"box": {"min": [0, 0, 0], "max": [0.36, 0.6, 0.3]}, "spacing": 0.03}],
    "particles": [{"x": [0.8, 0.9, 0.25], "mass": 0}, {"x": [0.85, 0.9, 0.25]}, {"x": [0.9, 0.9, 0.25]}],
    "distance_constraints": [{"i": 0, "j": 1}, {"i": 1, "j": 2}],
}

# VTK's type names: their bytes and the array module's type code (4 and 8 bytes on Linux).
VTK_TYPES = {"Float32": (4, "f"), "Float64": (8, "d"), "Int32": (4, "i"), "Int64": (8, "q"), "UInt32": (4, "I"),
             "UInt64": (8, "Q")}
APPENDED = b'<AppendedData encoding="raw">'
TAIL = b"\n  </AppendedData>\n</VTKFile>\n"

failures = []


def check(condition, what):
    if not condition:
        failures.append(what)
        print("FAIL:", what)
    return condition


def read_vtp(path):
    """The raw bytes of the arrays of a .vtp written with appended raw data ('points', 'velocity',
    'id', 'connectivity', 'offsets'), and the point count; checks the header (types, sizes) and
    that the arrays tile the appended data."""
    data = path.read_bytes()
    at = data.find(APPENDED)
    if not check(at > 0, f"{path.name}: no <AppendedData encoding=\"raw\">"):
        return None
    underscore = data.index(b"_", at + len(APPENDED))
    check(data[at + len(APPENDED):underscore].strip() == b"", f"{path.name}: text before the '_' of the data")
    root = ET.fromstring(data[:at] + b"</VTKFile>")
    check(root.tag == "VTKFile", f"{path.name}: root is {root.tag}")
    for key, value in {"type": "PolyData", "version": "1.0", "byte_order": "LittleEndian",
                       "header_type": "UInt64"}.items():
        check(root.get(key) == value, f"{path.name}: VTKFile {key}={root.get(key)!r}, expected {value!r}")
    pieces = root.findall("PolyData/Piece")
    if not check(len(pieces) == 1, f"{path.name}: {len(pieces)} pieces"):
        return None
    piece = pieces[0]
    n = int(piece.get("NumberOfPoints"))
    check(int(piece.get("NumberOfVerts")) == n, f"{path.name}: NumberOfVerts != NumberOfPoints")
    for cells in ("NumberOfLines", "NumberOfStrips", "NumberOfPolys"):
        check(int(piece.get(cells, "0")) == 0, f"{path.name}: {cells} = {piece.get(cells)}")
    body = data[underscore + 1:]
    check(body.endswith(TAIL), f"{path.name}: does not end with </AppendedData></VTKFile>")
    body = body[:len(body) - len(TAIL)]
    arrays, spans = {}, []
    for where, name in (("PointData", "velocity"), ("PointData", "id"), ("Points", "Points"),
                        ("Verts", "connectivity"), ("Verts", "offsets")):
        found = [a for a in piece.findall(f"{where}/DataArray") if a.get("Name") == name]
        if not check(len(found) == 1, f"{path.name}: {where}/{name} appears {len(found)} times"):
            return None
        a = found[0]
        check(a.get("format") == "appended", f"{path.name}: {name} format {a.get('format')}")
        itemsize, _ = VTK_TYPES[a.get("type")]
        components = int(a.get("NumberOfComponents", "1"))
        offset = int(a.get("offset"))
        (size,) = struct.unpack_from("<Q", body, offset)
        check(size == n * components * itemsize,
              f"{path.name}: {name} holds {size} bytes, expected {n} x {components} x {itemsize}")
        arrays[name] = body[offset + 8:offset + 8 + size]
        spans.append((offset, offset + 8 + size))
    spans.sort()
    check(spans[0][0] == 0 and all(a[1] == b[0] for a, b in zip(spans, spans[1:])) and spans[-1][1] == len(body),
          f"{path.name}: the arrays do not tile the appended data: {spans}, {len(body)} bytes")
    check(piece.find("PointData").get("Vectors") == "velocity", f"{path.name}: velocity is not the active vector")
    check(piece.find("Points/DataArray").get("type") == "Float32", f"{path.name}: Points are not Float32")
    check(piece.find("PointData/DataArray[@Name='id']").get("type") == "Int32", f"{path.name}: id is not Int32")
    arrays["points"] = arrays.pop("Points")
    return n, arrays


def read_ply(path):
    """The PLY's columns as the bytes a .vtp holds them in: 'points' (x y z per particle),
    'velocity' (vx vy vz), 'id'; and the particle count."""
    data = path.read_bytes()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    header = data[:end].decode().splitlines()
    n = int(next(line.split()[2] for line in header if line.startswith("element vertex")))
    check(header[-8:-1] == [f"property {t} {p}" for t, p in (("float", "x"), ("float", "y"), ("float", "z"),
                            ("float", "vx"), ("float", "vy"), ("float", "vz"), ("int", "id"))],
          f"{path.name}: PLY properties {header[-8:-1]}")
    records = [data[end + 28 * k:end + 28 * (k + 1)] for k in range(n)]
    check(len(data) == end + 28 * n, f"{path.name}: {len(data) - end} bytes for {n} vertices")
    return n, {"points": b"".join(r[0:12] for r in records), "velocity": b"".join(r[12:24] for r in records),
               "id": b"".join(r[24:28] for r in records)}


def read_pvd(path):
    root = ET.parse(path).getroot()
    check(root.get("type") == "Collection", f"{path.name}: type {root.get('type')}")
    return [(float(d.get("timestep")), d.get("file")) for d in root.findall("Collection/DataSet")]


def check_folder(folder, frame_dt):
    series = read_pvd(folder / "particles.pvd")
    check([f for _, f in series] == [f"particles.{k:04d}.vtp" for k in range(1, FRAMES + 1)],
          f"{folder.name}: the series lists {[f for _, f in series]}")
    # The times: frame * frame_dt as the simulation computes it (a double product), to the bit.
    check([t for t, _ in series] == [k * frame_dt for k in range(1, FRAMES + 1)],
          f"{folder.name}: the series' times {[t for t, _ in series]}")
    for k in range(1, FRAMES + 1):
        read = read_vtp(folder / f"particles.{k:04d}.vtp")
        n, ply = read_ply(folder / f"particles.{k:04d}.ply")
        if read is None:
            continue
        points, vtp = read
        check(n > 0 and points == n, f"{folder.name} frame {k}: {points} points, the PLY {n}")
        # Bytes, so bit for bit: -0.0 is not 0.0, a NaN only equals the same NaN.
        for name in ("points", "velocity", "id"):
            check(vtp[name] == ply[name], f"{folder.name} frame {k}: {name} differs from the PLY")
        check(vtp["connectivity"] == array("i", range(n)).tobytes(), f"{folder.name} frame {k}: connectivity")
        check(vtp["offsets"] == array("i", range(1, n + 1)).tobytes(), f"{folder.name} frame {k}: offsets")
        check(ply["id"] == array("i", range(n)).tobytes(), f"{folder.name} frame {k}: ids are not 0..n-1 in order")
    return series


def check_poly(who, k, poly, folder):
    """A frame as VTK read it (a vtkPolyData) against the frame's PLY, as bytes."""
    from vtkmodules.util.numpy_support import vtk_to_numpy
    n, ply = read_ply(folder / f"particles.{k:04d}.ply")
    check(poly.GetNumberOfPoints() == n and poly.GetNumberOfVerts() == n,
          f"{who} frame {k}: {poly.GetNumberOfPoints()} points, {poly.GetNumberOfVerts()} verts, the PLY {n}")
    check(vtk_to_numpy(poly.GetPoints().GetData()).tobytes() == ply["points"], f"{who} frame {k}: points")
    for name in ("velocity", "id"):
        check(vtk_to_numpy(poly.GetPointData().GetArray(name)).tobytes() == ply[name], f"{who} frame {k}: {name}")


def check_with_vtk(folder):
    try:
        from vtkmodules.vtkIOXML import vtkXMLPolyDataReader
        import numpy  # noqa: F401 (vtk_to_numpy needs it)
    except ImportError:
        print("VTK's Python is not installed: read with our own reader only")
        return
    for k in range(1, FRAMES + 1):
        reader = vtkXMLPolyDataReader()
        reader.SetFileName(str(folder / f"particles.{k:04d}.vtp"))
        reader.Update()
        check_poly("VTK", k, reader.GetOutput(), folder)
    print("VTK's vtkXMLPolyDataReader reads the same values")


def check_with_paraview(folder, series, required):
    """Under ParaView's pvbatch: its PVDReader, as the ParaView window opens the series."""
    try:
        from paraview import servermanager
        from paraview.simple import PVDReader
    except ImportError:
        check(not required, "--require-paraview, but ParaView's Python modules cannot be imported")
        return
    reader = PVDReader(FileName=str(folder / "particles.pvd"))
    check(list(reader.TimestepValues) == [t for t, _ in series], f"ParaView's times {list(reader.TimestepValues)}")
    check(sorted(reader.PointData.keys()) == ["id", "velocity"], f"ParaView's arrays {reader.PointData.keys()}")
    for k, (t, _) in enumerate(series, start=1):
        reader.UpdatePipeline(t)
        check_poly("ParaView", k, servermanager.Fetch(reader), folder)
    print("ParaView's PVDReader reads the series: times, velocity and id")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seiche", required=True)
    parser.add_argument("--out", required=True)
    parser.add_argument("--require-paraview", action="store_true", help="fail unless run by ParaView's pvbatch")
    args = parser.parse_args()
    out = Path(args.out)
    shutil.rmtree(out, ignore_errors=True)
    out.mkdir(parents=True)
    scene = out / "vtp_readback.json"
    scene.write_text(json.dumps(SCENE))
    bake, run = out / "bake", out / "run"
    for command in ([args.seiche, "bake", str(scene), "--out", str(bake)],
                    [args.seiche, "run", str(scene), "--out", str(run)]):
        done = subprocess.run(command, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
        if done.returncode != 0:
            print(" ".join(command), "failed:", done.returncode, done.stderr)
            return 1
    frame_dt = SCENE["solver"]["frame_dt"]
    series = check_folder(bake, frame_dt)
    check_folder(run, frame_dt)
    # seiche run writes the same particle files as the bake.
    for name in ["particles.pvd"] + [f"particles.{k:04d}.vtp" for k in range(1, FRAMES + 1)]:
        check((bake / name).read_bytes() == (run / name).read_bytes(), f"{name}: the run's differs from the bake's")
    check_with_vtk(bake)
    check_with_paraview(bake, series, args.require_paraview)
    if failures:
        print(f"{len(failures)} checks failed")
        return 1
    print(f"{FRAMES} frames of .vtp equal their PLY bit for bit; particles.pvd lists them with their times")
    return 0


if __name__ == "__main__":
    sys.exit(main())
