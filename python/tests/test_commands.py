"""seiche.bake and seiche.bench: the CLI's commands as calls, with the same files."""

import json

import numpy as np
import pytest

import seiche
from conftest import read_ply, run_cli, scene_path


def test_bake_writes_the_frames_checkpoint_and_report_of_the_cli(tmp_path):
    scene = scene_path("cloth_hanging.json")
    code, _, err = run_cli("bake", scene, "--frames", "2-3", "--out", str(tmp_path / "cli"))
    assert code == 0, err
    result = seiche.bake(scene, frames=(2, 3), out=tmp_path / "py")
    assert result["status"] == "complete"
    assert (result["first_frame"], result["last_frame"], result["frames_done"]) == (2, 3, 3)
    assert result["checkpoint_frame"] == 3 and result["bytes_written"] > 0
    assert [f["frame"] for f in result["report"]["frames"]] == [1, 2, 3]
    cli_files = sorted(p.name for p in (tmp_path / "cli").iterdir())
    assert sorted(p.name for p in (tmp_path / "py").iterdir()) == cli_files
    assert "particles.0001.ply" not in cli_files and "checkpoint.bin" in cli_files
    for name in cli_files:
        if name.endswith((".ply", ".obj")):
            assert (tmp_path / "py" / name).read_bytes() == (tmp_path / "cli" / name).read_bytes(), name
    # The CLI resumes the Python bake: it is already complete.
    code, out, err = run_cli("bake", "--resume", str(tmp_path / "py"))
    assert code == 0 and "already complete" in out, err


def test_bake_of_a_dict_scene_records_its_text(tmp_path):
    scene = {"name": "pair", "domain": {"min": [0, 0, 0], "max": [10, 10, 10]}, "output": {"frames": 2},
             "particles": [{"x": [5, 3, 2], "mass": 10}, {"x": [1, 5, 6], "mass": 2}],
             "distance_constraints": [{"i": 0, "j": 1, "rest_length": 3}]}
    result = seiche.bake(scene, out=tmp_path / "pair")
    assert result["last_frame"] == 2
    ply = read_ply(tmp_path / "pair" / "particles.0002.ply")
    assert np.isclose(np.linalg.norm([ply["x"][0] - ply["x"][1], ply["y"][0] - ply["y"][1],
                                      ply["z"][0] - ply["z"][1]]), 3.0, atol=1e-3)
    recipe = json.loads((tmp_path / "pair" / "bake.json").read_text())
    assert recipe["scene_source"] == "<scene dict>" and json.loads(recipe["scene"]) == scene


def test_bench_returns_a_row_per_run_and_writes_the_csv(tmp_path):
    result = seiche.bench(scene_path("cloth_hanging.json"), sweep=["substeps=1,4"], frames=3,
                          set=["solver.iterations=1"], out=tmp_path, reference="implicit")
    runs = result["runs"]
    assert len(runs) == 4  # the two settings, the reference and its check
    assert result["axes"] == ["solver.substeps"] and result["frames"] == 3
    assert (tmp_path / "bench.csv").read_text() == result["csv"]
    sweep = runs[:2]
    assert [r["solver.substeps"] for r in sweep] == [1, 4]
    # More substeps: closer to the implicit-Euler reference.
    assert sweep[1]["error_rms"] < sweep[0]["error_rms"]
    with pytest.raises(seiche.InputError, match=r'^--reference: expected auto, xpbd or implicit, got "exact"$'):
        seiche.bench(scene_path("cloth_hanging.json"), reference="exact")
