#!/usr/bin/env python3
"""A short random-policy rollout of the bucket-filling environment (talus.envs), with a plot of
the load, the reward and the commanded and achieved cylinder speeds over the fill.

    PYTHONPATH=build/python python3 examples/python/random_rollout.py --level G400 --out out/rollout.png

Needs Gymnasium (pip install gymnasium) and Matplotlib (Debian: python3-matplotlib).
"""
import argparse
import sys

import numpy as np

import talus
from talus.envs import BucketFillingEnv


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--level", default="G400", help="D400 ... D50 or G400 ... G50")
    ap.add_argument("--seed", type=int, default=0, help="the policy's and the reset's seed")
    ap.add_argument("--max-steps", type=int, default=400, help="stop the rollout here at the latest")
    ap.add_argument("--out", required=True, help="the plot (PNG)")
    args = ap.parse_args()

    talus.check_output_arguments(ap, files=[("--out", args.out)])
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    env = BucketFillingEnv(level=args.level)
    obs, info = env.reset(seed=args.seed)
    rng = np.random.default_rng(args.seed)
    t0 = info["time"]
    t, load, rewards, actions, lift_speed = [], [], [], [], []
    d_lift = talus.CHANNELS.index("d_lift")
    previous = obs[d_lift]
    total = 0.0
    for _ in range(args.max_steps):
        # a random policy biased forward, so the bucket meets the pile: uniform in [-0.2, 1] x [-1, 1]^2
        action = np.array([rng.uniform(-0.2, 1.0), rng.uniform(-1, 1), rng.uniform(-1, 1)], dtype=np.float32)
        obs, reward, terminated, truncated, info = env.step(action)
        total += reward
        t.append(info["time"] - t0)
        load.append(info["loaded_mass"])
        rewards.append(total)
        actions.append(action)
        lift_speed.append((obs[d_lift] - previous) / env.sim.timestep)
        previous = obs[d_lift]
        if terminated or truncated:
            break
    end = "broke out" if terminated else ("fill time limit" if truncated else "step limit")
    print(f"{len(t)} steps, {t[-1]:.2f} s of fill ({end}): load {load[-1]:.0f} kg, return {total:.3f} t")

    actions = np.array(actions)
    fig, ax = plt.subplots(3, 1, figsize=(8, 8), sharex=True)
    ax[0].plot(t, np.array(load) / 1e3)
    ax[0].set_ylabel("load [t]")
    ax[1].plot(t, rewards)
    ax[1].set_ylabel("return so far [t]")
    top = env.sim.top_speeds()
    ax[2].plot(t, actions[:, 1] * top.lift, label="lift target")
    ax[2].plot(t, lift_speed, label="lift achieved")
    ax[2].set_ylabel("lift stroke speed [m/s]")
    ax[2].set_xlabel("time since the bucket reached the pile [s]")
    ax[2].legend()
    fig.suptitle(f"random policy, bucket filling at {args.level} ({end})")
    fig.tight_layout()
    fig.savefig(args.out, dpi=100)
    print(f"wrote {args.out}")
    env.close()
    return 0


if __name__ == "__main__":
    sys.exit(main())
