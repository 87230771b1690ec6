"""Runs the Python package's tests (tests/python) for ctest: the build tree's package on the path,
in a virtual environment at <build>/pyenv that sees Debian's numpy and pytest and holds Gymnasium
from PyPI. Without PyPI the environment's tests skip, saying why; the bindings' tests still run.

usage: run_pytest.py BUILD_DIR SOURCE_DIR [pytest arguments]
"""
import os
import subprocess
import sys
import venv


def main():
    build, source = sys.argv[1], sys.argv[2]
    env_dir = os.path.join(build, "pyenv")
    python = os.path.join(env_dir, "bin", "python")
    # idempotent set-up: the environment once, Gymnasium into it when it is missing
    if not os.path.exists(python):
        venv.EnvBuilder(system_site_packages=True, with_pip=True).create(env_dir)
    has_gym = subprocess.run([python, "-c", "import gymnasium"], capture_output=True).returncode == 0
    if not has_gym:
        r = subprocess.run([python, "-m", "pip", "install", "--quiet", "--disable-pip-version-check",
                            "--timeout", "30", "gymnasium>=0.29"], capture_output=True, text=True)
        if r.returncode != 0:
            print("run_pytest: could not install gymnasium from PyPI (no network?); the environment's "
                  "tests will skip:\n" + r.stderr[-600:], file=sys.stderr)
    env = dict(os.environ)
    env["PYTHONPATH"] = os.path.join(build, "python") + os.pathsep + env.get("PYTHONPATH", "")
    cmd = [python, "-m", "pytest", "-q", "-rs", "-p", "no:cacheprovider", os.path.join(source, "tests", "python")]
    return subprocess.run(cmd + sys.argv[3:], env=env).returncode


if __name__ == "__main__":
    sys.exit(main())
