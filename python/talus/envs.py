"""Bucket filling as a Gymnasium environment (docs/python.md): the paper's loading cycle (§7) with
the fill commanded by an agent instead of the force-feedback controller.

An episode is one fill. ``reset`` builds the loading cycle on a settled pile (read from the pile
cache after the first time), drives the approach itself (8 km/h, bucket flat, from 5 m before the
pile) and returns when the bucket reaches the pile. Each ``step`` then sets the drive, lift and
tilt target speeds for one timestep of the level. The episode ends (``terminated``) when the
bucket breaks out of the pile, or is cut (``truncated``) at the cycle's 15 s limit on the fill.

Observation: the run contract's 14 sensor channels (SPEC §2.4, ``talus.CHANNELS``, SI units) after
the step, as float32. Action: the drive, lift and tilt target speeds as fractions of the machine's
top speeds, in [-1, 1] each (``Simulation.top_speeds``; positive drives forward, raises the boom,
curls the bucket).

Reward, in tonnes (paper §7 measures productivity M/T and efficiency M/W):
    r = ΔM − time_cost · Δt − work_cost · ΔW
with ΔM the change of the bucket's load [t], Δt the timestep [s] and ΔW the work done [kJ] over
the step. The return of a fill is M − time_cost · T_fill − work_cost · W_fill. With the default
time_cost of 0.4 t/s (the paper's best productivities, 366–416 kg/s) filling pays while it adds
mass faster than a whole cycle's productivity; work_cost 0.005 t/kJ is a quarter of the paper's
typical efficiency (about 20 kg/kJ), so work counts without dominating. Both are parameters.
"""
import numpy as np

import gymnasium as gym
from gymnasium import spaces

from . import CHANNELS, Simulation

# the most piles whose fill start a reset keeps (Simulation.state bytes, one per pile seed)
MAX_SAVED_STARTS = 16

# the paper's productivity scale (§7: best M/T 366-416 kg/s) [t/s]
DEFAULT_TIME_COST = 0.4
# a quarter of the paper's typical efficiency M/W (about 20 kg/kJ) [t/kJ]
DEFAULT_WORK_COST = 0.005


class BucketFillingEnv(gym.Env):
    """One bucket fill of the paper's loading cycle, commanded by the agent.

    Parameters: ``level`` ("D400", "D200", ... or "G400", ...), ``scenario`` (whose pile is dug:
    "fb35" by default, as the paper's §7), ``pile_seeds`` (the piles a reset draws from, with the
    environment's random generator; one seed: the same pile every episode), ``time_cost`` and
    ``work_cost`` (the reward's weights, above), ``approach`` [m] and ``max_cycle_time`` [s] (the
    loading cycle's), ``complete_cycle`` (after the fill, drive the cycle's hold and retreat and
    report the paper's M, T, W in ``info["cycle"]``), ``progress`` (pile building on stderr).
    """

    metadata = {"render_modes": []}

    def __init__(self, level="D400", scenario="fb35", pile_seeds=(1,), time_cost=DEFAULT_TIME_COST,
                 work_cost=DEFAULT_WORK_COST, approach=5.0, max_cycle_time=40.0,
                 complete_cycle=False, progress=False, render_mode=None):
        if render_mode is not None:
            raise ValueError(f"BucketFillingEnv: render_mode {render_mode!r}: this environment does not "
                             "render; write the particles with Simulation.particles() instead")
        if len(pile_seeds) == 0:
            raise ValueError("BucketFillingEnv: pile_seeds is empty; give at least one pile seed")
        # the reward's weights [t/s, t/kJ] and the cycle's distances and times, finite and in range
        for name, value, low in (("time_cost", time_cost, 0.0), ("work_cost", work_cost, 0.0),
                                 ("approach", approach, 1e-9), ("max_cycle_time", max_cycle_time, 1e-9)):
            if not (np.isfinite(value) and value >= low):
                raise ValueError(f"BucketFillingEnv: {name} {value!r}: give a finite number "
                                 f"{'above 0' if low > 0 else 'of 0 or more'}")
        self.level = level
        self.scenario = scenario
        self.pile_seeds = tuple(int(s) for s in pile_seeds)
        self.time_cost = float(time_cost)
        self.work_cost = float(work_cost)
        self.approach = float(approach)
        self.max_cycle_time = float(max_cycle_time)
        self.complete_cycle = bool(complete_cycle)
        self.progress = bool(progress)
        self.render_mode = None
        self.observation_space = spaces.Box(-np.inf, np.inf, shape=(len(CHANNELS),), dtype=np.float32)
        self.action_space = spaces.Box(-1.0, 1.0, shape=(3,), dtype=np.float32)
        self.sim = None
        self._sim_seed = None
        # each pile's state at the start of its fill (bytes of Simulation.state), once reached
        self._fill_states = {}
        self._top = None

    # the simulation at the start of the fill, on pile `seed`. The first episode on a pile drives
    # the approach and saves the state at the fill's start (Simulation.state); later ones restore
    # it, bit for bit the same start, without building the machine's approach again (type D and
    # type G alike)
    def _start(self, seed):
        if self.sim is not None and self._sim_seed == seed and seed in self._fill_states:
            self.sim.set_state(self._fill_states[seed])
            return
        self.sim = None  # the previous episode's device memory goes first
        self.sim = Simulation(scenario=self.scenario, level=self.level, seed=seed, loading_cycle=True,
                              cycle_approach=self.approach, cycle_max_time=self.max_cycle_time,
                              progress=self.progress)
        self._sim_seed = seed
        top = self.sim.top_speeds()
        self._top = np.array([top.drive, top.lift, top.tilt])
        if seed in self._fill_states:
            self.sim.set_state(self._fill_states[seed])
            return
        # the approach drives itself, up to the pile
        while self.sim.cycle_phase == "approach" and not self.sim.done:
            self.sim.step()
        if self.sim.cycle_phase != "fill":
            raise RuntimeError(f"BucketFillingEnv: the loading cycle never reached the pile "
                               f"(phase {self.sim.cycle_phase!r} at t = {self.sim.time:.2f} s); "
                               "give a longer max_cycle_time or a shorter approach")
        self._fill_states[seed] = self.sim.state()
        # the oldest start goes first beyond the cap (a D50 state is tens of megabytes)
        while len(self._fill_states) > MAX_SAVED_STARTS:
            del self._fill_states[next(iter(self._fill_states))]

    def _observation(self):
        return self.sim.sensors().astype(np.float32)

    # the load [kg], work [J] and time [s] now, read once per step (the load sums the bucket's soil)
    def _measure(self):
        self._mass, self._work, self._time = self.sim.loaded_mass, self.sim.work, self.sim.time

    def _info(self):
        return {"loaded_mass": self._mass, "work": self._work, "time": self._time,
                "phase": self.sim.cycle_phase, "pile_seed": self.pile_seed}

    def reset(self, *, seed=None, options=None):
        super().reset(seed=seed)
        options = options or {}
        if "pile_seed" in options:
            self.pile_seed = int(options["pile_seed"])
        else:
            self.pile_seed = self.pile_seeds[int(self.np_random.integers(len(self.pile_seeds)))]
        self._start(self.pile_seed)
        self._measure()
        return self._observation(), self._info()

    def step(self, action):
        if self.sim is None or self.sim.cycle_phase != "fill":
            raise RuntimeError("BucketFillingEnv.step: the fill is over (or never began); call reset()")
        action = np.clip(np.asarray(action, dtype=np.float64).reshape(3), -1.0, 1.0)
        drive, lift, tilt = action * self._top
        mass0, work0, time0 = self._mass, self._work, self._time
        self.sim.step(drive=drive, lift=lift, tilt=tilt)
        self._measure()
        # the reward in tonnes: mass gained, less the time and the work it took
        reward = (1e-3 * (self._mass - mass0) - self.time_cost * (self._time - time0)
                  - self.work_cost * 1e-3 * (self._work - work0))
        over = self.sim.cycle_phase != "fill"
        broke_out = over and self.sim.cycle_summary().broke_out
        terminated = broke_out
        truncated = (over and not broke_out) or (self.sim.done and not terminated)
        info = self._info()
        info["broke_out"] = broke_out
        # the observation at the end of the fill, before the rest of the cycle drives on
        observation = self._observation()
        if (terminated or truncated) and self.complete_cycle:
            info["cycle"] = self._finish_cycle()
        return observation, float(reward), bool(terminated), bool(truncated), info

    # the rest of the loading cycle with its own targets (hold, retreat), and the paper's measures
    def _finish_cycle(self):
        while not self.sim.done:
            self.sim.step()
        c = self.sim.cycle_summary()
        return {"loaded_mass": c.loaded_mass, "cycle_time": c.cycle_time, "work": c.work,
                "completed": c.completed, "productivity": c.productivity,
                "efficiency": c.loaded_mass / c.work if c.work > 0 else 0.0}

    def close(self):
        self.sim = None


def make_vector_env(num_envs, **kwargs):
    """``num_envs`` bucket-filling environments stepped together in this process
    (gymnasium.vector.SyncVectorEnv); each gets its own pile seed, pile_seeds[0] + i, unless
    ``pile_seeds`` is given."""
    if num_envs < 1:
        raise ValueError(f"make_vector_env: num_envs {num_envs}; give at least 1")
    base = kwargs.pop("pile_seeds", None)

    def factory(i):
        seeds = base if base is not None else (1 + i,)
        return lambda: BucketFillingEnv(pile_seeds=seeds, **kwargs)

    return gym.vector.SyncVectorEnv([factory(i) for i in range(num_envs)])
