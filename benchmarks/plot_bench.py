#!/usr/bin/env python3
"""Plots a `seiche bench` CSV: error against wall time per frame, one point per setting.

    python3 benchmarks/plot_bench.py DIR/bench.csv DIR/bench.png [--title TEXT] [--unit TEXT]

The y axis (log) is the rms position error against the reference in units of the scene's
length (`--unit` names it: the fluid spacing, the mean cloth edge, ...), the x
axis (log) the wall time per frame. Every swept setting is a labelled point; the Pareto front
(the `pareto` column the C++ side computed: no other setting is both faster and more accurate)
is drawn as a line; the reference check's error (how far the reference itself can be trusted)
is a dashed line: errors below it are not resolved. The image is written atomically.
"""
import argparse
import csv
import math
import os
import sys
import textwrap

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def label_of(row, axes):
    short = {"solver.substeps": "s", "solver.iterations": "i"}
    return " ".join(f"{short.get(a, a.split('.')[-1] + '=')}{row[a]}" for a in axes)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("csv")
    parser.add_argument("png")
    parser.add_argument("--title", default="")
    parser.add_argument("--unit", default="particle spacings", help="what the error is measured in")
    args = parser.parse_args()

    with open(args.csv, newline="") as f:
        reader = csv.DictReader(f)
        rows = list(reader)
        fields = reader.fieldnames or []
    if "role" not in fields or "error_rms" not in fields:
        sys.exit(f"{args.csv}: not a seiche bench CSV (no role/error_rms columns)")
    first_fixed = fields.index("substeps")
    axes = fields[1:first_fixed]
    sweep = [r for r in rows if r["role"] == "sweep" and r["diverged"] == "0" and math.isfinite(float(r["error_rms"]))]
    diverged = [r for r in rows if r["role"] == "sweep" and r["diverged"] == "1"]
    check = next((r for r in rows if r["role"] == "reference_check"), None)
    if not sweep:
        sys.exit(f"{args.csv}: no finished sweep run to plot")

    fig, ax = plt.subplots(figsize=(8, 5.5), dpi=120)
    times = [float(r["ms_per_frame"]) for r in sweep]
    errors = [max(float(r["error_rms"]), 1e-12) for r in sweep]
    ax.scatter(times, errors, s=18, color="tab:blue", zorder=3, label="settings (median time)")
    if "ms_per_frame_q1" in fields:  # the spread of the timed runs
        low = [t - float(r["ms_per_frame_q1"]) for t, r in zip(times, sweep)]
        high = [float(r["ms_per_frame_q3"]) - t for t, r in zip(times, sweep)]
        ax.errorbar(times, errors, xerr=[low, high], fmt="none", ecolor="tab:blue", elinewidth=0.8, capsize=2,
                    zorder=2, label="time quartiles of the timed runs")
    for r, t, e in zip(sweep, times, errors):
        ax.annotate(label_of(r, axes), (t, e), textcoords="offset points", xytext=(4, 3), fontsize=7)

    front = sorted((t, e, r) for t, e, r in zip(times, errors, sweep) if r["pareto"] == "1")
    if front:
        ax.plot([p[0] for p in front], [p[1] for p in front], "-o", color="tab:red", markersize=5, zorder=4,
                label="Pareto front")
    if check is not None and math.isfinite(float(check["error_rms"])) and float(check["error_rms"]) > 0:
        ax.axhline(float(check["error_rms"]), color="gray", linestyle="--", linewidth=1,
                   label=f"reference's own error ({float(check['error_rms']):.2g})")
    if diverged:
        ax.text(0.01, 0.01, "diverged: " + ", ".join(label_of(r, axes) for r in diverged), transform=ax.transAxes,
                fontsize=7, color="tab:red", va="bottom")

    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("wall time per frame (ms)")
    ax.set_ylabel(f"rms position error against the reference\n(in units of {args.unit})")
    ax.set_title("\n".join(textwrap.wrap(args.title, 100)), fontsize=9)
    ax.grid(True, which="both", linewidth=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()

    tmp = args.png + ".tmp"
    fig.savefig(tmp, format="png")
    os.replace(tmp, args.png)


if __name__ == "__main__":
    main()
