#!/usr/bin/env python3
"""The lift force while the bucket carries its load, per kg of load (docs/validation.md, "Type G
against type D").

  scripts/carry-lift.py --window T0 T1 RUN...

For each run folder (timeseries.csv and summary.json of `talus run`) prints the loaded mass and,
over the window [T0, T1] s (a stretch where the bucket holds its load and no longer cuts: the
type-G zone is empty), the lift cylinder's force above the empty bucket's (its mean over 0.2-0.8 s,
before the dig) per kg of load, and its fluctuation: the RMS of the force minus its 0.5 s moving
mean, per kg. The weight sets the first; the load's inertia under the bucket's accelerations sets
the second, which is how a dig whose bucket content is a weight alone and one whose content has
its inertia (type D's particles, type G's payload body) differ. Standard library only."""
import argparse
import csv
import json
import math
import pathlib

EMPTY_WINDOW = (0.2, 0.8)  # [s] the machine at rest before any scenario's dig starts
SMOOTHING = 0.5            # [s] the moving mean the fluctuation is taken about


def carry_lift(run, t0, t1):
    with open(run / "timeseries.csv") as f:
        rows = list(csv.DictReader(f))
    t = [float(r["t"]) for r in rows]
    force = [float(r["f_lift"]) for r in rows]
    summary = json.loads((run / "summary.json").read_text())
    mass = summary["loaded_mass_kg"]
    dt = t[1] - t[0]
    half = max(1, round(SMOOTHING / dt)) // 2
    empty = [f for s, f in zip(t, force) if EMPTY_WINDOW[0] < s < EMPTY_WINDOW[1]]
    if not empty:
        raise SystemExit(f"{run}: no samples in {EMPTY_WINDOW} s for the empty bucket")
    f_empty = sum(empty) / len(empty)
    above, wiggle = [], []
    for k, s in enumerate(t):
        if not t0 < s < t1:
            continue
        window = force[max(0, k - half):k + half + 1]
        above.append(force[k] - f_empty)
        wiggle.append(force[k] - sum(window) / len(window))
    if not above:
        raise SystemExit(f"{run}: no samples in the window [{t0}, {t1}] s")
    mean_above = sum(above) / len(above)
    mean_wiggle = sum(wiggle) / len(wiggle)
    rms = math.sqrt(sum((w - mean_wiggle) ** 2 for w in wiggle) / len(wiggle))
    return mass, mean_above / mass, rms / mass


ap = argparse.ArgumentParser(description="lift force per kg of load while the bucket carries it")
ap.add_argument("--window", nargs=2, type=float, required=True, metavar=("T0", "T1"),
                help="the carry's stretch [s]")
ap.add_argument("runs", nargs="+", type=pathlib.Path, help="run folders of talus run")
args = ap.parse_args()
print("| run | loaded mass [kg] | lift force above the empty bucket [N/kg] | its fluctuation, RMS [N/kg] |")
print("|---|---:|---:|---:|")
for run in args.runs:
    mass, per_kg, rms_per_kg = carry_lift(run, *args.window)
    print(f"| {run.name} | {mass:.0f} | {per_kg:.1f} | {rms_per_kg:.2f} |")
