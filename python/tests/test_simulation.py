"""seiche.Simulation: the worked example, the zero-copy views, scenes from dicts, overrides and
the run report."""

import gc
import threading
import time
import json

import numpy as np
import pytest

import seiche
from conftest import scene_path


def test_seed_worked_example_gives_the_lecture_answer():
    # m1 = 10, m2 = 2, p1 = (5,3,2), p2 = (1,5,6), d = 3: one projection of the distance constraint
    # gives p1' = (14/3, 19/6, 7/3), p2' = (8/3, 25/6, 13/3). The store is float32 and the
    # projection rounds a few times on the way (difference, length, scale), so each coordinate is
    # asserted within one float32 ulp of the exact value (2.4e-7 at 2..4, 4.8e-7 at 4..8): 8/3 comes
    # out as 2.6666665, the float below the nearest one.
    sim = seiche.Simulation(scene_path("seed_example.json"))
    assert sim.pipeline == ["predict", "distance", "collisions", "update"]
    sim.step()
    assert repr(sim) == "<seiche.Simulation seed_example: 2 particles, frame 1, t = 0.0166667 s>"
    order = np.argsort(sim.ids)
    got = np.stack(sim.positions, axis=1)[order].astype(np.float64)
    exact = np.array([[14 / 3, 19 / 6, 7 / 3], [8 / 3, 25 / 6, 13 / 3]])
    ulp = np.spacing(exact.astype(np.float32)).astype(np.float64)
    assert np.all(np.abs(got - exact) <= ulp), (got, exact)
    # The constraint holds: |p1' - p2'| = d, to float32 rounding.
    assert abs(np.linalg.norm(got[0] - got[1]) - 3.0) < 1e-6


def test_columns_are_read_only_views_of_the_store(small_fluid):
    scene, overrides = small_fluid
    sim = seiche.Simulation(scene, set=overrides)
    sim.step(2)
    x1 = sim.positions[0]
    x2 = sim.column("x")
    assert x1.__array_interface__["data"][0] == x2.__array_interface__["data"][0]  # no copy
    assert x1.dtype == np.float32 and x1.shape == (len(sim),)
    assert not x1.flags.writeable and not x1.flags.owndata
    with pytest.raises(ValueError):
        x1[0] = 1.0
    ids = sim.ids
    assert ids.dtype == np.int32 and sorted(ids) == list(range(len(sim)))
    # Every column the store holds, typed as the store types it.
    assert {"x", "vx", "id", "phase", "density"} <= set(sim.columns)
    assert sim.column("phase").dtype == np.uint32
    with pytest.raises(KeyError, match="no particle column \"pressure\""):
        sim.column("pressure")


def test_a_view_keeps_its_simulation_alive_and_the_step_moves_the_particles(small_fluid):
    scene, overrides = small_fluid
    sim = seiche.Simulation(scene, set=overrides)
    assert np.array_equal(sim.ids, np.arange(len(sim)))  # creation order before the first step
    y_view = sim.positions[1]
    sim.step()
    # The neighbor sort reordered the store: index i holds another particle now (ids say which).
    assert not np.array_equal(sim.ids, np.arange(len(sim)))
    ids_view = sim.ids
    del sim
    gc.collect()
    # The views' base holds the simulation: its buffers are still there to read (stale, not freed).
    assert ids_view.base is not None
    assert sorted(ids_view) == list(range(len(ids_view)))
    assert np.isfinite(y_view).all()


def test_scene_from_a_dict_runs_like_the_file():
    with open(scene_path("seed_example.json"), encoding="utf-8") as f:
        scene = json.load(f)
    from_dict = seiche.Simulation(scene)
    from_file = seiche.Simulation(scene_path("seed_example.json"))
    for sim in (from_dict, from_file):
        sim.step(3)
    for a, b in zip(from_dict.positions + from_dict.velocities, from_file.positions + from_file.velocities):
        assert np.array_equal(a, b)
    assert seiche.Simulation(None, set={"fluids[0].spacing": 0.1}).scene_name == "dam_break"
    assert seiche.default_scene()["name"] == "dam_break"


def test_overrides_as_strings_or_a_dict_change_the_scene():
    base = seiche.Simulation(scene_path("seed_example.json"))
    as_text = seiche.Simulation(scene_path("seed_example.json"), set=["solver.gravity=[0,-9.81,0]", "solver.substeps=4"])
    as_dict = seiche.Simulation(scene_path("seed_example.json"), set={"solver.gravity": [0, -9.81, 0], "solver.substeps": 4})
    for sim in (base, as_text, as_dict):
        sim.step()
    assert np.array_equal(as_text.ids, as_dict.ids)
    assert np.array_equal(as_text.positions[1], as_dict.positions[1])
    assert not np.array_equal(as_text.positions[1], base.positions[1])
    assert as_text.report()["settings"]["substeps"] == 4
    assert base.report()["settings"]["substeps"] == 1


def test_report_has_the_settings_and_a_row_per_frame(small_fluid):
    scene, overrides = small_fluid
    sim = seiche.Simulation(scene, set=overrides, threads=2)
    sim.step(3)
    report = sim.report()
    assert report["status"] == "ok" and report["scene"] == "dam_break"
    assert report["settings"]["frames"] == 3 and report["settings"]["threads"] == 2
    assert report["settings"]["particles"] == len(sim)
    assert report["pipeline"] == sim.pipeline
    assert [f["frame"] for f in report["frames"]] == [1, 2, 3]
    last = report["frames"][-1]
    assert last["time"] == pytest.approx(sim.time)
    assert last["particles"] == len(sim) and last["non_finite"] == 0
    # The fluid's density error is measured: a resting column is compressed by a small fraction.
    assert 0.0 <= last["fluid_density_error"]["mean"] < 0.1
    assert last["kinetic_energy"] > 0.0  # the column has started to fall
    assert set(sim.pipeline) <= set(last["pass_ms"])  # every pass is timed


def test_step_releases_the_gil(small_fluid):
    # A Python thread counts while the main thread sleeps, then while it steps one long frame: with
    # the GIL released the count goes on at a good part of its rate (measured: 60-80 %); held, the
    # thread only runs when the interpreter forces a switch (measured: about 2 %).
    scene, overrides = small_fluid
    probe = seiche.Simulation(scene, set=overrides, threads=1)
    start = time.perf_counter()
    probe.step()
    substeps = probe.report()["settings"]["substeps"]
    scale = max(1, min(40, int(0.3 / max(time.perf_counter() - start, 1e-3))))  # a frame of about 0.3 s
    sim = seiche.Simulation(scene, set=overrides + [f"solver.substeps={substeps * scale}"], threads=1)

    stop = threading.Event()
    stamps = []

    def count():
        while not stop.is_set():
            stamps.append(time.perf_counter())

    counter = threading.Thread(target=count)
    counter.start()
    begin_sleep = time.perf_counter()
    time.sleep(0.1)
    begin_step = time.perf_counter()
    sim.step()
    end_step = time.perf_counter()
    stop.set()
    counter.join()
    assert sim.frame == 1

    def rate(a, b):
        return sum(1 for s in stamps if a <= s < b) / (b - a)

    assert rate(begin_step, end_step) > 0.25 * rate(begin_sleep, begin_step)


def test_bodies_follow_the_bodies_file(tmp_path):
    """The rigid bodies' state by name equals the bodies.%04d.jsonl the CLI writes (17 digits)."""
    import json
    sim = seiche.Simulation(scene_path("pendulums.json"))
    sim.step(3)
    bodies = sim.bodies
    sim.write_frame(str(tmp_path))
    lines = [json.loads(line) for line in open(tmp_path / "bodies.0003.jsonl")]
    assert [b["name"] for b in lines] == list(bodies)
    for line in lines:
        got = bodies[line["name"]]
        for key in ("position", "orientation", "velocity", "angular_velocity"):
            assert list(got[key]) == line[key], key
    q = next(iter(bodies.values()))["orientation"]
    assert abs(sum(c * c for c in q) - 1.0) < 1e-12
    assert seiche.Simulation(scene_path("dam_break.json"), set={"fluids[0].spacing": 0.1}).bodies == {}
