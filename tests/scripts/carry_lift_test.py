#!/usr/bin/env python3
"""Tests of scripts/carry-lift.py on synthetic runs whose lift force is known by construction."""
import csv
import json
import math
import pathlib
import subprocess
import sys
import tempfile
import unittest

SCRIPT = pathlib.Path(__file__).resolve().parents[2] / "scripts" / "carry-lift.py"
EMPTY = 50e3  # [N] the empty bucket's lift force


def write_run(directory, mass, per_kg, amplitude, frequency=2.0, ramp=0.0):
    """A run at 100 Hz for 9 s: the empty bucket's force until 2 s, then per_kg N per kg of load
    above it plus a sine of `amplitude` N at `frequency` Hz (2 Hz: one period per 0.5 s moving mean,
    which it averages to zero, so the fluctuation is the whole sine) and a ramp of `ramp` N/s from
    2.5 s (as the boom's geometry changes the force slowly: the moving mean follows it, so it is no
    fluctuation; its mean over the window shifts the force above the empty bucket)."""
    directory.mkdir(parents=True, exist_ok=True)
    with (directory / "timeseries.csv").open("w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["t", "f_lift"])
        for n in range(901):
            t = 0.01 * n
            force = EMPTY
            if t >= 2.0:
                force += per_kg * mass + amplitude * math.sin(2.0 * math.pi * frequency * t)
                force += ramp * max(0.0, t - 2.5)
            w.writerow([f"{t:.2f}", f"{force:.6f}"])
    (directory / "summary.json").write_text(json.dumps({"loaded_mass_kg": mass}))


def table(*args):
    out = subprocess.run([sys.executable, str(SCRIPT), *args], capture_output=True, text=True)
    return out


class CarryLift(unittest.TestCase):
    def row(self, run, **shape):
        """The script's row for a synthetic run of this shape (write_run's), window 3-8 s."""
        write_run(run, **shape)
        out = table("--window", "3", "8", str(run))
        self.assertEqual(out.returncode, 0, out.stderr)
        return [c.strip() for c in out.stdout.splitlines()[-1].strip("|").split("|")]

    def test_weight_and_fluctuation_per_kg(self):
        with tempfile.TemporaryDirectory() as tmp:
            cells = self.row(pathlib.Path(tmp) / "loaded", mass=2000.0, per_kg=37.0,
                             amplitude=1500.0)
            self.assertEqual(cells[0], "loaded")
            self.assertEqual(float(cells[1]), 2000.0)
            self.assertAlmostEqual(float(cells[2]), 37.0, delta=0.05)
            # RMS of the sine: amplitude / sqrt 2, per kg
            self.assertAlmostEqual(float(cells[3]), 1500.0 / math.sqrt(2.0) / 2000.0, delta=0.01)

    def test_a_slow_change_is_not_a_fluctuation(self):
        with tempfile.TemporaryDirectory() as tmp:
            # 20 kN/s from 2.5 s: 110 kN by the window's end, 100 times the sine's RMS
            cells = self.row(pathlib.Path(tmp) / "ramped", mass=2000.0, per_kg=37.0,
                             amplitude=1500.0, ramp=20e3)
            # the ramp's mean over the window (its middle, 5.5 s, is 3 s into the ramp), per kg
            self.assertAlmostEqual(float(cells[2]), 37.0 + 20e3 * 3.0 / 2000.0, delta=0.1)
            self.assertAlmostEqual(float(cells[3]), 1500.0 / math.sqrt(2.0) / 2000.0, delta=0.01)

    def test_a_load_that_only_weighs_does_not_fluctuate(self):
        with tempfile.TemporaryDirectory() as tmp:
            cells = self.row(pathlib.Path(tmp) / "still", mass=3000.0, per_kg=30.0, amplitude=0.0)
            self.assertAlmostEqual(float(cells[2]), 30.0, delta=1e-6)
            self.assertAlmostEqual(float(cells[3]), 0.0, delta=1e-6)

    def test_a_window_without_samples_is_an_error_naming_the_run(self):
        with tempfile.TemporaryDirectory() as tmp:
            run = pathlib.Path(tmp) / "short"
            write_run(run, mass=1000.0, per_kg=30.0, amplitude=100.0)
            out = table("--window", "20", "30", str(run))
            self.assertNotEqual(out.returncode, 0)
            self.assertIn("short", out.stderr)
            self.assertIn("window", out.stderr)


if __name__ == "__main__":
    unittest.main()
