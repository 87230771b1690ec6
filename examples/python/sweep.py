#!/usr/bin/env python3
"""A controller sweep from Python: the paper's force-feedback loading cycle (§7) at several
points s of its search line, each on the same settled pile, with productivity M/T and efficiency
M/W per point (what `talus sweep` does, here one cycle after the other in Python).

    PYTHONPATH=build/python python3 examples/python/sweep.py --level G400 --samples 5
"""
import argparse
import sys

import numpy as np

import talus


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scenario", default="fb35", help="the pile dug (fb35 as the paper's §7)")
    ap.add_argument("--level", default="G400", help="D400 ... D50 or G400 ... G50")
    ap.add_argument("--samples", type=int, default=5, help="points on the search line, s in [0, 1]")
    ap.add_argument("--csv", help="also write the table here")
    args = ap.parse_args()
    if args.samples < 2:
        print("sweep.py: --samples must be at least 2", file=sys.stderr)
        return 2
    talus.check_output_arguments(ap, files=[("--csv", args.csv)])

    rows = []
    print(f"{'s':>5} {'M [kg]':>8} {'T [s]':>6} {'W [kJ]':>7} {'M/T [kg/s]':>10} {'M/W [kg/kJ]':>11} breakout")
    for s in np.linspace(0.0, 1.0, args.samples):
        sim = talus.Simulation(scenario=args.scenario, level=args.level, loading_cycle=True, cycle_s=float(s))
        while not sim.done:
            sim.step()
        c = sim.cycle_summary()
        efficiency = c.loaded_mass / (c.work / 1e3) if c.work > 0 else 0.0
        rows.append((s, c.loaded_mass, c.cycle_time, c.work / 1e3, c.productivity, efficiency, c.broke_out))
        print(f"{s:5.2f} {c.loaded_mass:8.0f} {c.cycle_time:6.1f} {c.work / 1e3:7.0f} {c.productivity:10.0f} "
              f"{efficiency:11.1f} {'yes' if c.broke_out else 'no (15 s limit)'}"
              f"{'' if c.completed else ' (cycle time limit)'}")
    best = max(rows, key=lambda r: r[4])
    print(f"best productivity {best[4]:.0f} kg/s at s = {best[0]:.2f} (the paper: 366-416 kg/s)")
    if args.csv:
        np.savetxt(args.csv, np.array(rows, dtype=float), delimiter=",", comments="",
                   header="s,loaded_mass_kg,cycle_time_s,work_kJ,productivity_kg_s,efficiency_kg_kJ,broke_out")
    return 0


if __name__ == "__main__":
    sys.exit(main())
