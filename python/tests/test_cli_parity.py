"""The Python API against the CLI of the same build: the same particles, files, reports and error
messages."""

import os

import numpy as np
import pytest

import seiche
from conftest import cli_error_message, read_ply, run_cli, scene_path


def test_fluid_views_match_the_ply_the_cli_writes(tmp_path, small_fluid):
    scene, overrides = small_fluid
    frames = 3
    code, _, err = run_cli("run", scene, "--frames", str(frames), "--threads", "2", "--out", str(tmp_path),
                           *[a for o in overrides for a in ("--set", o)])
    assert code == 0, err
    ply = read_ply(tmp_path / f"particles.{frames:04d}.ply")  # in id order

    sim = seiche.Simulation(scene, set=overrides, threads=1)  # results do not depend on threads
    sim.step(frames)
    ids = sim.ids
    assert sorted(ids) == list(ply["id"])
    # Index i of the store holds particle ids[i]: its row in the (id-ordered) PLY is ids[i].
    for name, view in zip(("x", "y", "z", "vx", "vy", "vz"), sim.positions + sim.velocities):
        assert np.array_equal(view, ply[name][ids]), name
    # write_frame writes the same bytes as the CLI.
    written = sim.write_frame(tmp_path / "py")
    assert written == [str(tmp_path / "py" / f"particles.{frames:04d}.ply")]
    with open(written[0], "rb") as a, open(tmp_path / f"particles.{frames:04d}.ply", "rb") as b:
        assert a.read() == b.read()


def test_run_writes_the_cli_files_and_returns_the_report(tmp_path):
    scene = scene_path("seed_example.json")
    code, _, err = run_cli("run", scene, "--frames", "4", "--out", str(tmp_path / "cli"), "--report",
                           str(tmp_path / "cli.json"))
    assert code == 0, err
    report = seiche.run(scene, frames=4, out=tmp_path / "py", report=tmp_path / "py.json")
    for k in range(1, 5):
        name = f"particles.{k:04d}.ply"
        assert (tmp_path / "py" / name).read_bytes() == (tmp_path / "cli" / name).read_bytes()
    assert os.path.exists(tmp_path / "py.json")
    assert report["settings"]["frames"] == 4 and len(report["frames"]) == 4
    assert report["frames"][-1]["distance_error"]["max"] < 1e-3


@pytest.mark.parametrize("overrides, problem", [
    (["solver.substeps=0"], "solver.substeps"),
    (["fluids[0].spacing=-0.1"], "fluids[0].spacing"),
    (["solver.no_such_key=1"], "solver.no_such_key"),
    (["solver.iterations"], "solver.iterations"),
])
def test_a_bad_override_raises_the_cli_message(overrides, problem):
    scene = scene_path("dam_break.json")
    code, _, err = run_cli("run", scene, "--frames", "1", "--out", "/nonexistent/never",
                           *[a for o in overrides for a in ("--set", o)])
    assert code == 2
    with pytest.raises(seiche.SceneError) as caught:
        seiche.Simulation(scene, set=overrides)
    assert str(caught.value) == cli_error_message(err)
    assert caught.value.exit_code == 2 and isinstance(caught.value, ValueError)
    assert problem in caught.value.json_path
    assert caught.value.file in (scene, "(command line)")  # a malformed override names the command line


def test_a_bad_scene_file_raises_the_cli_message(tmp_path):
    bad = tmp_path / "bad.json"
    bad.write_text('{ "solver": { "substeps": 4, "iterations": -2 } }')
    broken = tmp_path / "broken.json"
    broken.write_text('{ "solver": { "substeps": 4,, } }')
    for scene in (bad, broken, tmp_path / "missing.json", tmp_path):
        code, _, err = run_cli("run", str(scene), "--frames", "1", "--out", str(tmp_path / "out"))
        assert code == 2, err
        with pytest.raises(seiche.SceneError) as caught:
            seiche.Simulation(scene)
        assert str(caught.value) == cli_error_message(err)
        assert str(caught.value).startswith(str(scene) + ": ")
    with pytest.raises(seiche.SceneError, match=r"^<scene dict>: solver.iterations: "):
        seiche.Simulation({"solver": {"iterations": -2}})


def test_memory_and_work_bounds_as_the_cli():
    scene = scene_path("seed_example.json")
    huge = ["solver.substeps=10000", "solver.iterations=10000"]
    code, _, err = run_cli("run", scene, "--frames", "1", "--out", "/nonexistent/never", *[a for o in huge for a in ("--set", o)])
    assert code == 2
    with pytest.raises(seiche.SceneError) as caught:
        seiche.Simulation(scene, set=huge)
    assert str(caught.value) == cli_error_message(err)
    seiche.Simulation(scene, set=["solver.substeps=1000", "solver.iterations=101"], allow_huge_work=True)
    with pytest.raises(seiche.SceneError, match="over the limit|--max-memory|estimate"):
        seiche.Simulation(None, max_memory="1M")
    with pytest.raises(seiche.InputError, match=r'^--max-memory: expected a size such as 512M, 8G or 1.5GiB, got "lots"$'):
        seiche.Simulation(None, max_memory="lots")


def test_an_unwritable_output_is_an_output_error(tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("not a folder")
    with pytest.raises(seiche.OutputError) as caught:
        seiche.run(scene_path("seed_example.json"), frames=1, out=blocker / "out")
    assert caught.value.exit_code == 3 and isinstance(caught.value, OSError)
    assert str(blocker / "out") in str(caught.value)
