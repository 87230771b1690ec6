"""talus.envs, bucket filling as a Gymnasium environment: Gymnasium's own checker, the episode's
end, the reward's definition, determinism and the vectorised form. On the type-G level G400,
whose fills take about a second here."""
import numpy as np
import pytest

gym = pytest.importorskip("gymnasium", reason="gymnasium is not installed (PyPI unreachable?)")
from gymnasium.utils.env_checker import check_env  # noqa: E402

from talus.envs import BucketFillingEnv, make_vector_env  # noqa: E402

LEVEL = "G400"


def test_gymnasiums_checker_accepts_the_environment():
    env = BucketFillingEnv(level=LEVEL)
    check_env(env, skip_render_check=True)
    env.close()


def test_the_environment_is_registered():
    env = gym.make("talus/BucketFilling-v0", level=LEVEL)
    obs, _ = env.reset(seed=3)
    assert obs.shape == (14,)
    env.close()


def test_a_fill_that_lifts_and_curls_breaks_out_and_its_return_is_the_rewards_definition():
    env = BucketFillingEnv(level=LEVEL, time_cost=0.4, work_cost=0.005, complete_cycle=True)
    obs, info = env.reset(seed=1)
    assert info["phase"] == "fill" and obs.dtype == np.float32
    mass0, work0, time0 = info["loaded_mass"], info["work"], info["time"]
    total, steps = 0.0, 0
    terminated = truncated = False
    while not (terminated or truncated):
        # drive on at a third of top speed, lift at half and curl at full speed
        obs, reward, terminated, truncated, info = env.step(np.array([0.3, 0.5, 1.0], dtype=np.float32))
        total += reward
        steps += 1
    assert terminated and not truncated and info["broke_out"]
    # the return telescopes to M - 0.4 t/s T - 0.005 t/kJ W over the fill
    expected = (1e-3 * (info["loaded_mass"] - mass0) - 0.4 * (info["time"] - time0)
                - 0.005 * 1e-3 * (info["work"] - work0))
    assert total == pytest.approx(expected, rel=1e-9, abs=1e-9)
    assert info["loaded_mass"] > 500.0
    cycle = info["cycle"]
    assert cycle["completed"] and cycle["productivity"] == pytest.approx(cycle["loaded_mass"] / cycle["cycle_time"])
    with pytest.raises(RuntimeError, match="call reset"):
        env.step(np.zeros(3, dtype=np.float32))
    env.close()


def test_a_fill_that_only_pushes_is_cut_at_the_fill_time_limit():
    env = BucketFillingEnv(level=LEVEL)
    env.reset(seed=1)
    terminated = truncated = False
    while not (terminated or truncated):
        _, _, terminated, truncated, info = env.step(np.array([0.2, 0.0, 0.0], dtype=np.float32))
    assert truncated and not terminated and not info["broke_out"]
    summary = env.sim.cycle_summary()
    assert summary.fill_end - summary.fill_start > 15.0
    env.close()


def test_the_same_seed_and_actions_give_the_same_episode():
    def rollout():
        env = BucketFillingEnv(level=LEVEL, pile_seeds=(1, 2))
        obs, _ = env.reset(seed=7)
        rng = np.random.default_rng(11)
        trace = [obs]
        for _ in range(30):
            obs, reward, terminated, truncated, _ = env.step(rng.uniform(-1, 1, 3).astype(np.float32))
            trace.append(np.append(obs, reward))
            if terminated or truncated:
                break
        env.close()
        return trace

    a, b = rollout(), rollout()
    assert len(a) == len(b)
    for x, y in zip(a, b):
        assert np.array_equal(x, y)


def test_the_vectorised_form_steps_several_fills_in_one_process():
    envs = make_vector_env(2, level=LEVEL)
    obs, infos = envs.reset(seed=0)
    assert obs.shape == (2, 14)
    assert list(infos["pile_seed"]) == [1, 2]
    for _ in range(5):
        obs, rewards, terminated, truncated, infos = envs.step(np.tile([0.3, 0.2, 0.2], (2, 1)).astype(np.float32))
    assert rewards.shape == (2,) and np.all(np.isfinite(obs))
    envs.close()


def test_bad_parameters_are_refused_at_construction_naming_them():
    for kwargs, name in (({"time_cost": float("nan")}, "time_cost"), ({"work_cost": -1.0}, "work_cost"),
                         ({"approach": 0.0}, "approach"), ({"max_cycle_time": float("inf")}, "max_cycle_time"),
                         ({"pile_seeds": ()}, "pile_seeds")):
        with pytest.raises(ValueError, match=name):
            BucketFillingEnv(level=LEVEL, **kwargs)


def test_a_type_d_reset_restores_the_fill_start_bit_for_bit():
    # the first reset drives the approach and saves the fill's start; the next restores it into
    # the same simulation (no new pile, no new approach), and an episode from it is the episode
    # of an environment that drove its own approach
    actions = [np.array([0.4, 0.2 * k % 1.0, 0.5], dtype=np.float32) for k in range(25)]

    def episode(env, reset_seed):
        obs, _ = env.reset(seed=reset_seed)
        out = [obs]
        for a in actions:
            obs, reward, terminated, truncated, _ = env.step(a)
            out.append(np.append(obs, reward))
            if terminated or truncated:
                break
        return out

    env = BucketFillingEnv(level="D400")
    first = episode(env, 5)
    sim = env.sim
    again = episode(env, 6)
    assert env.sim is sim, "the second reset built a new simulation instead of restoring"
    fresh = episode(BucketFillingEnv(level="D400"), 7)
    for a, b, c in zip(first, again, fresh):
        assert np.array_equal(a, b) and np.array_equal(a, c)
    assert len(first) == len(again) == len(fresh)
