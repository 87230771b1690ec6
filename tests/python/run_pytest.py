"""Runs the Python package's tests (tests/python) for ctest: the build tree's package on the path,
in a virtual environment at <build>/pyenv that sees Debian's numpy and pytest and holds Gymnasium
from PyPI. Without PyPI the environment's tests skip, saying why; the bindings' tests still run.
Exit 77 (ctest's skip) when pytest or NumPy is neither installed nor installable.

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
    # what the tests need: pytest and NumPy (Debian's, seen through the system site packages, or
    # from PyPI for an interpreter without them), Gymnasium from PyPI; a missing Gymnasium skips
    # the environment's tests, a missing pytest or NumPy skips the run (exit 77), saying why
    for module, requirement, needed in (("pytest", "pytest>=7", True), ("numpy", "numpy>=1.21", True),
                                        ("gymnasium", "gymnasium>=0.29", False)):
        if subprocess.run([python, "-c", f"import {module}"], capture_output=True).returncode == 0:
            continue
        r = subprocess.run([python, "-m", "pip", "install", "--quiet", "--disable-pip-version-check",
                            "--timeout", "30", requirement], capture_output=True, text=True)
        if r.returncode != 0:
            why = f"run_pytest: could not install {requirement} from PyPI (no network?)"
            if needed:
                print(f"{why}; apt-get install python3-pytest python3-numpy; skipped:\n{r.stderr[-600:]}",
                      file=sys.stderr)
                return 77
            print(f"{why}; the tests that need it will skip:\n{r.stderr[-600:]}", file=sys.stderr)
    env = dict(os.environ)
    env["PYTHONPATH"] = os.path.join(build, "python") + os.pathsep + env.get("PYTHONPATH", "")
    # the built tool, for the tests that read what `talus run` writes
    env["TALUS_BUILD_DIR"] = build
    cmd = [python, "-m", "pytest", "-q", "-rs", "-p", "no:cacheprovider", os.path.join(source, "tests", "python")]
    return subprocess.run(cmd + sys.argv[3:], env=env).returncode


if __name__ == "__main__":
    sys.exit(main())
