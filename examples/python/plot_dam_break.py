"""Runs the built-in dam break from Python and plots how far the water front has run and the
fluid's density error, frame by frame (docs/python.md).

    PYTHONPATH=build/release/python python3 examples/python/plot_dam_break.py [PNG] [--frames N]

The particle columns are NumPy views of the engine's store, read between steps without a copy.
"""

import argparse

import matplotlib.pyplot as plt
import numpy as np

import seiche


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("png", nargs="?", default="dam_break.png")
    parser.add_argument("--frames", type=int, default=30)
    parser.add_argument("--spacing", type=float, default=0.05, help="fluid particle spacing (m); the scene's is 0.027")
    args = parser.parse_args()

    sim = seiche.Simulation(None, set={"fluids[0].spacing": args.spacing})
    time, front = [], []
    for _ in range(args.frames):
        sim.step()
        x, _, _ = sim.positions  # a view, valid until the next step
        time.append(sim.time)
        front.append(float(np.max(x)))
    density = [f["fluid_density_error"]["mean"] * 100 for f in sim.report()["frames"]]

    fig, (ax_front, ax_density) = plt.subplots(2, 1, sharex=True, figsize=(6, 5))
    ax_front.plot(time, front)
    ax_front.set_ylabel("water front x (m)")
    ax_density.plot(time, density, color="tab:red")
    ax_density.set_ylabel("mean density error (%)")
    ax_density.set_xlabel("time (s)")
    fig.suptitle(f"dam break, {len(sim)} particles")
    fig.tight_layout()
    fig.savefig(args.png, dpi=100)
    print(f"seiche {seiche.__version__}, {len(sim)} particles: front at {front[-1]:.3f} m after {sim.time:.3f} s; "
          f"plot: {args.png}")


if __name__ == "__main__":
    main()
