#!/usr/bin/env python3
"""Steps per second of the bucket-filling environment (talus.envs, docs/python.md) against the
facade's own loop on the same fill, side by side in one run, as medians over repeats.

    PYTHONPATH=build/python python3 bench/python_env.py --levels G400,D400 --repeats 5 --json FILE

Per level: `facade_steps_per_s` (Simulation.step() through a fill with the force-feedback
controller, the loop `talus sweep` runs, called from Python), `env_steps_per_s` (the environment's
step() through the same fill, its action the controller's targets), `vector4_steps_per_s` (four environments in one
SyncVectorEnv, environment-steps per second), the real-time factors (simulated over wall seconds)
and `reset_s` (a reset: the pile from the cache, the approach driven).
"""
import argparse
import json
import statistics
import sys
import time

import numpy as np

import talus
from talus.envs import BucketFillingEnv, make_vector_env

ACTION = np.array([0.3, 0.5, 1.0], dtype=np.float32)  # vectorised: push on, lift at half, curl at full
FILL_STEPS = 200  # at most, per measurement


def facade_rate(level):
    sim = talus.Simulation(scenario="fb35", level=level, loading_cycle=True)
    while sim.cycle_phase == "approach":
        sim.step()
    steps, t0, start = 0, sim.time, time.perf_counter()
    while sim.cycle_phase == "fill" and steps < FILL_STEPS:
        sim.step()
        steps += 1
    wall = time.perf_counter() - start
    return steps / wall, (sim.time - t0) / wall


def env_rate(level):
    env = BucketFillingEnv(level=level, pile_seeds=(1,))
    start = time.perf_counter()
    env.reset(seed=0)
    reset_s = time.perf_counter() - start
    top = env.sim.top_speeds()
    top = np.array([top.drive, top.lift, top.tilt])
    steps, t0, start = 0, env.sim.time, time.perf_counter()
    done = False
    while not done and steps < FILL_STEPS:
        # the force-feedback controller's targets as the action: the facade's fill, through the env
        c = env.sim.scenario_targets()
        _, _, terminated, truncated, _ = env.step(np.array([c.drive, c.lift, c.tilt]) / top)
        done = terminated or truncated
        steps += 1
    wall = time.perf_counter() - start
    return steps / wall, (env.sim.time - t0) / wall, reset_s


def vector_rate(level, n=4):
    envs = make_vector_env(n, level=level)
    envs.reset(seed=0)
    steps, start = 0, time.perf_counter()
    for _ in range(FILL_STEPS // 4):
        envs.step(np.tile(ACTION, (n, 1)))
        steps += n
    return steps / (time.perf_counter() - start)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--levels", default="G400,D400")
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--json", help="write the results here")
    args = ap.parse_args()
    if args.repeats < 1:
        print("python_env.py: --repeats must be at least 1", file=sys.stderr)
        return 2
    talus.check_output_arguments(ap, files=[("--json", args.json)])
    results = {"machine": talus.Simulation(scenario="fb35", level="G400").device, "levels": {}}
    for level in args.levels.split(","):
        # one warm-up (the pile cache, the kernels), then the repeats interleaved
        facade_rate(level), env_rate(level)
        f, e, v, rtf_f, rtf_e, resets = [], [], [], [], [], []
        for _ in range(args.repeats):
            a, ra = facade_rate(level)
            b, rb, reset_s = env_rate(level)
            f.append(a), rtf_f.append(ra), e.append(b), rtf_e.append(rb), resets.append(reset_s)
            v.append(vector_rate(level))
        r = {"facade_steps_per_s": statistics.median(f), "env_steps_per_s": statistics.median(e),
             "vector4_steps_per_s": statistics.median(v), "facade_realtime_factor": statistics.median(rtf_f),
             "env_realtime_factor": statistics.median(rtf_e), "reset_s": statistics.median(resets),
             "env_over_facade": statistics.median(b / a for a, b in zip(f, e)), "repeats": args.repeats}
        results["levels"][level] = r
        print(f"{level}: facade {r['facade_steps_per_s']:.0f} steps/s ({r['facade_realtime_factor']:.2f}x real time), "
              f"env {r['env_steps_per_s']:.0f} steps/s ({r['env_realtime_factor']:.2f}x), "
              f"4 envs {r['vector4_steps_per_s']:.0f} env-steps/s, reset {r['reset_s']:.2f} s", flush=True)
    if args.json:
        with open(args.json, "w") as f:
            json.dump(results, f, indent=2)
    return 0


if __name__ == "__main__":
    sys.exit(main())
