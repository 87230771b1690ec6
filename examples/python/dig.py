#!/usr/bin/env python3
"""A dig from Python: replay a field test's inputs (HD27 by default) at a particle level, then
print the loaded mass and work and save the 100 Hz channels as CSV and the particles as NumPy.

    PYTHONPATH=build/python python3 examples/python/dig.py --level D400 --out out/py-dig
"""
import argparse
import os
import sys

import numpy as np

import talus


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scenario", default="hd27", help="hd27, fb35, rd21 (or a scenario file)")
    ap.add_argument("--level", default="D400", help="D400, D200, D100, D50 or G400 ... G50")
    ap.add_argument("--seed", type=int, default=1, help="the pile's random seed")
    ap.add_argument("--out", required=True, help="output folder (channels.csv, particles.npz)")
    args = ap.parse_args()

    talus.check_output_arguments(ap, folders=[("--out", args.out)])
    try:
        sim = talus.Simulation(scenario=args.scenario, level=args.level, seed=args.seed, progress=True)
    except talus.InputError as e:
        print(f"dig.py: {e}", file=sys.stderr)
        return 2
    print(f"{sim.scenario_name} at {sim.level}: {sim.particle_count} particles on {sim.device}")
    # the scenario's own inputs to its end, a line per simulated second
    next_report = 1.0
    while not sim.done:
        sim.step()
        if sim.time >= next_report:
            print(f"  t = {sim.time:5.2f} s  load {sim.loaded_mass:7.0f} kg  work {sim.work / 1e3:6.1f} kJ")
            next_report += 1.0
    print(f"loaded {sim.loaded_mass:.0f} kg, work {sim.work / 1e3:.1f} kJ")

    os.makedirs(args.out, exist_ok=True)
    log = sim.sensor_log()
    header = ",".join(talus.CHANNELS)
    np.savetxt(os.path.join(args.out, "channels.csv"), log, delimiter=",", header=header, comments="")
    np.savez_compressed(os.path.join(args.out, "particles.npz"), **sim.particles())
    print(f"wrote {args.out}/channels.csv ({log.shape[0]} samples) and particles.npz")
    return 0


if __name__ == "__main__":
    sys.exit(main())
