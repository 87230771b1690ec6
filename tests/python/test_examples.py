"""examples/python: each example runs at G400 with small sizes and writes what it says."""
import os
import subprocess
import sys

import pytest

EXAMPLES = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "examples", "python")


def run(script, *args):
    r = subprocess.run([sys.executable, os.path.join(EXAMPLES, script), *args], capture_output=True, text=True,
                       timeout=600)
    assert r.returncode == 0, r.stdout + r.stderr
    return r.stdout


def test_the_dig_example_writes_channels_and_particles(tmp_path):
    out = run("dig.py", "--level", "G400", "--out", str(tmp_path))
    assert "loaded" in out
    header = (tmp_path / "channels.csv").read_text().splitlines()[0]
    assert header.startswith("t,f_lift,f_tilt")
    assert (tmp_path / "particles.npz").stat().st_size > 0


def test_the_dig_example_refuses_a_bad_level(tmp_path):
    r = subprocess.run([sys.executable, os.path.join(EXAMPLES, "dig.py"), "--level", "D37", "--out", str(tmp_path)],
                       capture_output=True, text=True)
    assert r.returncode == 2 and "level" in r.stderr


def test_unwritable_outputs_are_refused_before_the_run():
    for script, args in (("dig.py", ["--out", "/proc/talus-nope"]),
                         ("sweep.py", ["--csv", "/proc/talus-nope/s.csv"]),
                         ("random_rollout.py", ["--out", "/proc/talus-nope/r.png"])):
        r = subprocess.run([sys.executable, os.path.join(EXAMPLES, script), "--level", "G400", *args],
                           capture_output=True, text=True, timeout=60)
        assert r.returncode == 2 and "cannot write there" in r.stderr, script + ": " + r.stderr


def test_the_sweep_example_prints_each_point_and_the_best(tmp_path):
    csv = tmp_path / "sweep.csv"
    out = run("sweep.py", "--level", "G400", "--samples", "2", "--csv", str(csv))
    assert "best productivity" in out
    assert len(csv.read_text().splitlines()) == 3


def test_the_random_rollout_example_plots(tmp_path):
    pytest.importorskip("gymnasium", reason="gymnasium is not installed (PyPI unreachable?)")
    pytest.importorskip("matplotlib", reason="matplotlib is not installed (apt-get install python3-matplotlib)")
    png = tmp_path / "rollout.png"
    out = run("random_rollout.py", "--level", "G400", "--max-steps", "60", "--out", str(png))
    assert "steps" in out
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
