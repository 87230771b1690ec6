"""talus._talus, the facade bound for Python (python/bindings.cpp): stepping, readings as NumPy
arrays that own their data, the loading cycle, and errors as Python exceptions."""
import numpy as np
import pytest

import talus


def test_the_machine_alone_steps_and_logs_the_contracts_channels():
    sim = talus.Simulation(scenario="flat-lift")
    assert sim.level == "vehicle" and not sim.has_particles
    assert len(talus.CHANNELS) == 14 and talus.CHANNELS[0] == "t" and talus.UNITS[0] == "s"
    steps = 40
    for _ in range(steps):
        sim.step(drive=0.0, lift=0.05, tilt=0.0)
    reading = sim.sensors()
    assert reading.shape == (14,) and reading.dtype == np.float64
    assert reading[0] == pytest.approx(steps * sim.timestep)
    d = talus.CHANNELS.index("d_lift")
    assert sim.channels()["d_lift"] == reading[d]
    log = sim.sensor_log()
    # the lift stroke grows at about the commanded speed (the cylinder accelerates first)
    stroke = reading[d] - log[0, d]
    assert 0.5 * 0.05 * sim.time < stroke < 1.05 * 0.05 * sim.time
    assert log.shape[1] == 14 and log.shape[0] == int(round(sim.time / 0.01)) + 1
    assert np.allclose(np.diff(log[:, 0]), 0.01)
    # the arrays own what they show: a view's base keeps the facade's vector alive
    assert log.base is not None and not log.flags["OWNDATA"]


def test_a_dig_gives_the_particles_as_arrays_of_the_levels_size():
    sim = talus.Simulation(scenario="hd27", level="D400", seed=1)
    n = sim.particle_count
    p = sim.particles()
    assert n > 500
    assert p["position"].shape == (n, 3) and p["velocity"].shape == (n, 3)
    assert p["angular_velocity"].shape == (n, 3) and p["radius"].shape == (n,)
    # D400: grains of 0.4 m diameter, sizes spread around it
    assert 0.1 < p["radius"].mean() < 0.3
    assert np.all(np.isfinite(p["position"]))
    sim.step()
    assert sim.time == pytest.approx(sim.timestep)


def test_the_loading_cycle_commanded_with_its_own_targets_gives_its_own_result():
    own = talus.Simulation(scenario="fb35", level="G400", loading_cycle=True, cycle_s=0.7)
    assert own.cycle_phase == "approach"
    with pytest.raises(talus.Error, match="not the fill"):
        own.step(drive=1.0, lift=0.0, tilt=0.0)
    while not own.done:
        own.step()
    mine = talus.Simulation(scenario="fb35", level="G400", loading_cycle=True, cycle_s=0.7)
    fill_steps = 0
    while not mine.done:
        if mine.cycle_phase == "fill":
            mine.step(mine.scenario_targets())
            fill_steps += 1
        else:
            mine.step()
    a, b = own.cycle_summary(), mine.cycle_summary()
    assert fill_steps > 10
    assert a.completed and b.completed
    assert (a.loaded_mass, a.cycle_time, a.work) == (b.loaded_mass, b.cycle_time, b.work)
    assert a.productivity == pytest.approx(a.loaded_mass / a.cycle_time)
    assert a.loaded_mass > 1000.0


def test_a_saved_state_rewinds_the_run_bit_for_bit(tmp_path):
    sim = talus.Simulation(scenario="hd27", level="D400", seed=1)
    for _ in range(30):
        sim.step(drive=1.5, lift=0.0, tilt=0.0)
    state = sim.state()
    assert isinstance(state, bytes) and state[:8] == b"TALUSSTA"
    for _ in range(20):
        sim.step(drive=1.5, lift=0.02, tilt=0.0)
    later = sim.particles()["position"], sim.sensors()
    # rewound in memory, and from a file into a second simulation: the same 20 steps again
    sim.set_state(state)
    path = tmp_path / "dig.state"
    sim.save_state(str(path))
    other = talus.Simulation(scenario="hd27", level="D400", seed=1)
    other.restore_state(str(path))
    for s in (sim, other):
        for _ in range(20):
            s.step(drive=1.5, lift=0.02, tilt=0.0)
        assert np.array_equal(s.particles()["position"], later[0])
        assert np.array_equal(s.sensors(), later[1])
    with pytest.raises(talus.InputError, match="not a talus state file"):
        sim.set_state(b"garbage")


def test_effects_are_options_as_talus_run_takes_them():
    plain = talus.Simulation(scenario="flat-lift")
    biased = talus.Simulation(scenario="flat-lift", effects=["sensor_bias:channel=f_lift,bias=1000"])
    for s in (plain, biased):
        for _ in range(20):
            s.step(drive=0.0, lift=0.05, tilt=0.0)
    f = talus.CHANNELS.index("f_lift")
    assert biased.sensors()[f] - plain.sensors()[f] == pytest.approx(1000.0)
    with pytest.raises(talus.InputError, match="no_such_effect"):
        talus.Simulation(scenario="flat-lift", effects=["no_such_effect"])


def test_errors_name_the_option_and_are_python_exceptions():
    with pytest.raises(talus.InputError, match="scenario 'nope'"):
        talus.Simulation(scenario="nope")
    assert issubclass(talus.InputError, ValueError) and issubclass(talus.Error, RuntimeError)
    assert issubclass(talus.InputError, talus.Error)  # as talus::InputError is a talus::Error
    options = talus.SimulationOptions()
    options.scenario = "flat-lift"
    talus.Simulation(options)
    assert options.data_dir == ""  # the caller's options are not changed
    with pytest.raises(talus.InputError, match="level"):
        talus.Simulation(scenario="hd27", level="D37")
    with pytest.raises(talus.InputError, match="cycle_s"):
        talus.Simulation(scenario="fb35", level="G400", loading_cycle=True, cycle_s=1.5)
    with pytest.raises(talus.InputError, match="has no pile"):
        talus.Simulation(scenario="flat-lift", loading_cycle=True)
    with pytest.raises(TypeError, match="unknown option 'bogus'; the options are cycle_approach, .*seed"):
        talus.Simulation(bogus=1)
    with pytest.raises(talus.Error, match="replays"):
        talus.Simulation(scenario="flat-lift").cycle_summary()
