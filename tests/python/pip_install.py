"""`pip install .` as a user runs it (docs/python.md), for ctest: a fresh virtual environment,
the package built from this checkout by scikit-build-core (pyproject.toml), then imported from
another folder, where it must find its own data and run a loading cycle. Skips (exit 77) when PyPI
cannot be reached, since pip fetches scikit-build-core, pybind11 and NumPy from it.

usage: pip_install.py BUILD_DIR SOURCE_DIR
"""
import os
import shutil
import subprocess
import sys
import tempfile
import urllib.request
import venv

SKIP = 77

SMOKE = """
import os, talus
assert os.path.isdir(os.path.join(talus.DATA_DIR, "scenarios")), talus.DATA_DIR
sim = talus.Simulation(scenario="fb35", level="G400", loading_cycle=True, cycle_s=0.7)
while not sim.done:
    sim.step()
c = sim.cycle_summary()
assert c.completed and c.loaded_mass > 1000.0, (c.loaded_mass, c.completed)
print(f"installed talus: FB35-G400 cycle at s = 0.7, {c.loaded_mass:.0f} kg in {c.cycle_time:.1f} s")
"""


def main():
    build, source = sys.argv[1], sys.argv[2]
    try:
        urllib.request.urlopen("https://pypi.org/simple/scikit-build-core/", timeout=10).close()
    except OSError as e:
        print(f"pip_install: PyPI unreachable ({e}); skipped", file=sys.stderr)
        return SKIP
    env_dir = os.path.join(build, "pip-venv")
    shutil.rmtree(env_dir, ignore_errors=True)
    venv.EnvBuilder(with_pip=True).create(env_dir)
    python = os.path.join(env_dir, "bin", "python")
    r = subprocess.run([python, "-m", "pip", "install", "--quiet", "--disable-pip-version-check", source])
    if r.returncode != 0:
        print("pip_install: pip install failed", file=sys.stderr)
        return 1
    # from a folder with no data nearby, with the environment's python only
    with tempfile.TemporaryDirectory() as elsewhere:
        env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "TALUS_DATA_DIR")}
        return subprocess.run([python, "-c", SMOKE], cwd=elsewhere, env=env).returncode


if __name__ == "__main__":
    sys.exit(main())
