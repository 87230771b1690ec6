"""bench/soak.py, CI-sized (docs/reliability.md, "Soak"): half a minute of digging cycles at D400,
a minute at G400 and a minute of the machine alone, every check passing and the figures written."""
import json
import os
import subprocess
import sys

SOAK = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "bench", "soak.py")


def soak(tmp_path, *args):
    out = tmp_path / "soak.json"
    r = subprocess.run([sys.executable, SOAK, *args, "--json", str(out)], capture_output=True, text=True,
                       timeout=600)
    assert r.returncode == 0, r.stdout + r.stderr
    return json.loads(out.read_text())


def test_digging_cycles_keep_every_particle_finite_and_the_machine_upright(tmp_path):
    r = soak(tmp_path, "--level", "D400", "--minutes", "0.5")
    assert r["failure"] is None and r["particle_count_constant"]
    assert r["simulated_s"] >= 30.0 and r["cycles"] >= 1
    assert max(r["peak_load_kg_per_cycle"]) > 1000.0  # the cycles do dig


def test_the_machine_alone_soaks(tmp_path):
    r = soak(tmp_path, "--scenario", "load-carry", "--minutes", "1")
    assert r["failure"] is None and r["simulated_s"] >= 60.0


def test_type_g_cycles_keep_the_terrains_mass_while_particles_come_and_go(tmp_path):
    r = soak(tmp_path, "--level", "G400", "--minutes", "1")
    assert r["failure"] is None and r["simulated_s"] >= 60.0 and r["cycles"] >= 2
    assert r["max_abs_mass_drift"] <= 1e-9
    assert r["particles_min_max"][1] > 0  # the zone made particles
    assert max(r["peak_load_kg_per_cycle"]) > 1000.0


def test_a_level_that_is_not_one_is_refused(tmp_path):
    r = subprocess.run([sys.executable, SOAK, "--level", "G37", "--minutes", "0.1"], capture_output=True,
                       text=True, timeout=60)
    assert r.returncode == 2 and "G37" in r.stderr and "Traceback" not in r.stderr, r.stderr


def test_bad_length_and_unwritable_outputs_are_refused_before_the_soak():
    for args, says in ((["--minutes", "nan"], "--minutes"), (["--minutes", "0"], "--minutes"),
                       (["--json", "/proc/talus-nope/s.json"], "--json"),
                       (["--plot", "/proc/talus-nope/s.png"], "--plot")):
        r = subprocess.run([sys.executable, SOAK, *args], capture_output=True, text=True, timeout=60)
        assert r.returncode == 2 and says in r.stderr, r.stderr
