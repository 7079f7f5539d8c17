"""examples/python/plot_dam_break.py runs (matplotlib's Agg backend) and draws its plot."""

import os
import subprocess
import sys

from conftest import SOURCE_DIR


def test_the_documented_example_runs_and_plots(tmp_path):
    png = tmp_path / "dam_break.png"
    env = dict(os.environ, MPLBACKEND="Agg")
    r = subprocess.run([sys.executable, os.path.join(SOURCE_DIR, "examples", "python", "plot_dam_break.py"), str(png),
                        "--frames", "12"], capture_output=True, text=True, env=env, check=False)
    assert r.returncode == 0, r.stderr
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and png.stat().st_size > 10_000
    # The front has run out from the block's face at x = 1 m.
    front = float(r.stdout.split("front at ")[1].split(" m")[0])
    assert 1.0 < front < 4.0, r.stdout
