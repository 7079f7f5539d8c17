"""Shared helpers of the Python API's tests: the seiche CLI of the same build (SEICHE_EXE), the
source tree (SEICHE_SOURCE_DIR), and a reader for the binary PLY frames both write."""

import os
import subprocess

import numpy as np
import pytest

SOURCE_DIR = os.environ.get("SEICHE_SOURCE_DIR", os.path.join(os.path.dirname(__file__), "..", ".."))
SCENES = os.path.join(SOURCE_DIR, "scenes")
SEICHE_EXE = os.environ.get("SEICHE_EXE", os.path.join(SOURCE_DIR, "build", "release", "apps", "seiche"))

# The PLY vertex of `seiche run`: float x y z vx vy vz, int id, little-endian (README).
PLY_VERTEX = np.dtype([("x", "<f4"), ("y", "<f4"), ("z", "<f4"), ("vx", "<f4"), ("vy", "<f4"), ("vz", "<f4"),
                       ("id", "<i4")])


def scene_path(name):
    return os.path.join(SCENES, name)


def run_cli(*args):
    """Runs the seiche CLI; returns (exit code, stdout, stderr)."""
    r = subprocess.run([SEICHE_EXE, *args], capture_output=True, text=True, check=False)
    return r.returncode, r.stdout, r.stderr


def cli_error_message(stderr):
    """The message of a failed CLI run: its last 'seiche: error: ' line, without that prefix."""
    lines = [line for line in stderr.splitlines() if line.startswith("seiche: error: ")]
    assert lines, stderr
    return lines[-1][len("seiche: error: "):]


def read_ply(path):
    with open(path, "rb") as f:
        data = f.read()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    header = data[:end].decode("ascii")
    assert "format binary_little_endian 1.0" in header, header
    count = int(next(line.split()[2] for line in header.splitlines() if line.startswith("element vertex")))
    vertices = np.frombuffer(data, dtype=PLY_VERTEX, offset=end)
    assert len(vertices) == count
    return vertices


@pytest.fixture
def small_fluid():
    """The dam break at a coarse spacing (about 3,400 particles): quick, and still a fluid column
    that the neighbor sort reorders every substep."""
    return scene_path("dam_break.json"), ["fluids[0].spacing=0.066"]
