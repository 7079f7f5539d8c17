"""Seiche from Python: load a scene, step it, read its particles as NumPy views, run, bake, bench.

    import seiche
    sim = seiche.Simulation("scenes/dam_break.json", set={"solver.substeps": 4})
    sim.step(10)
    x, y, z = sim.positions          # read-only float32 views of the store, valid until the next step
    ids = sim.ids                    # creation index of each particle (the store is reordered)
    report = sim.report()            # the run report as a dict (what `seiche run --report` writes)

Scenes: None (the built-in dam break), a dict (the scene's JSON), or a path to a scene file.
Overrides (`set`): ["solver.iterations=8", ...] with the syntax and checks of the CLI's --set,
or a dict {"solver.iterations": 8} whose values are written as JSON.
Errors: seiche.Error and its subclasses, whose text is what the CLI prints after
"seiche: error: " and whose exit_code is what the CLI would return (docs/python.md).
"""

import csv as _csv
import io as _io
import json as _json
import os as _os

from ._seiche import (  # noqa: F401  (re-exported)
    Error,
    InputError,
    OutputError,
    SceneError,
    Simulation,
    SimulationError,
    __version__,
    default_scene_json,
    simd,
)
from . import _seiche

__all__ = ["Simulation", "run", "bake", "bench", "default_scene", "Error", "InputError", "SceneError",
           "OutputError", "SimulationError", "simd", "__version__"]


def default_scene():
    """The built-in dam break as a dict (scenes/dam_break.json)."""
    return _json.loads(default_scene_json())


def run(scene=None, *, frames=0, out=None, report=None, set=None, threads=0, max_memory=None,
        allow_huge_work=False, base_dir=None, progress=False):
    """`seiche run`: simulates `frames` frames (0: the scene's output.frames), writes
    out/particles.%04d.ply (and each cloth's OBJ) when `out` is given and the report to `report`
    when given. Returns the run report as a dict."""
    text = _seiche.run(scene, set, frames, out, report, threads, max_memory, allow_huge_work, base_dir, progress)
    return _json.loads(text)


def bake(scene=None, *, out=None, frames=None, set=None, threads=0, max_memory=None, allow_huge_work=False,
         base_dir=None, progress=False):
    """`seiche bake`: writes every output the scene asks for (.ply, .vdb, .obj), checkpoints,
    bake.json and report.json into `out` (default out/<scene name>). `frames`: N (frames 1..N) or
    (A, B) (simulate from the start, write A..B); default the scene's output.frames. Ctrl-C stops
    after the current frame with a checkpoint (KeyboardInterrupt); `seiche bake --resume OUT`
    continues. Returns the result as a dict, with the run report under "report"."""
    if frames is None:
        first, last = 0, 0
    elif isinstance(frames, int):
        first, last = 1, frames
    else:
        first, last = frames
    result = _seiche.bake(scene, set, out, first, last, threads, max_memory, allow_huge_work, base_dir, progress)
    with open(_os.path.join(result["out"], "report.json"), encoding="utf-8") as f:
        result["report"] = _json.load(f)
    return result


def _number(text):
    for kind in (int, float):
        try:
            return kind(text)
        except ValueError:
            pass
    return text


def bench(scene=None, *, sweep=(), frames=0, out=None, set=None, threads=0, reference="auto",
          reference_substeps=0, reference_iterations=0, max_memory=None, allow_huge_work=False,
          base_dir=None, progress=False):
    """`seiche bench SCENE --sweep ...`: every combination of the swept values (default substeps
    1,2,4,8,16 x iterations 1,2,4,8) against a converged reference. Writes out/bench.csv when `out`
    is given. Returns a dict: scene, axes, reference, spacing, spacing_source, frames, threads,
    particles, csv (bench.csv's text) and runs (one dict per CSV row, numbers as numbers)."""
    if isinstance(sweep, str):
        sweep = [sweep]
    result = _seiche.bench(scene, set, list(sweep), frames, out, threads, reference, reference_substeps,
                           reference_iterations, max_memory, allow_huge_work, base_dir, progress)
    rows = _csv.DictReader(_io.StringIO(result["csv"]))
    result["runs"] = [{key: _number(value) for key, value in row.items()} for row in rows]
    return result
