#!/usr/bin/env python3
"""Tests of scripts/motion-features.py on synthetic runs whose motions are known by construction."""
import csv
import importlib.util
import json
import pathlib
import subprocess
import sys
import tempfile
import unittest

SCRIPT = pathlib.Path(__file__).resolve().parents[2] / "scripts" / "motion-features.py"
# the script as a module, for its list of features (its file name is not an identifier)
_spec = importlib.util.spec_from_file_location("motion_features", SCRIPT)
motion_features = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(motion_features)
COLUMNS = ["t", "f_lift", "f_tilt", "f_traction", "v_drive", "d_lift", "d_tilt", "boom_deg",
           "bucket_deg", "pitch_deg", "x_vehicle", "bucket_tip_x", "bucket_tip_z", "power"]


def write_run(directory, tip_z=0.1, reverse_at=4.0, lift_at=2.0, end_at=6.0, depth=0.8,
              tilt_stroke=0.36, travel=4.0):
    """A run at 100 Hz: the tip drives from x 3 at 1 m/s (for `travel` metres) into a 30-degree pile
    face whose toe is at x 5.1 (the scan's first point above 5 cm; entry at 2.1 s), holds its height
    tip_z over the first metre, then follows 0.2 m under the surface with one dip to `depth` under it
    around 3.5 s; the boom starts at lift_at, the machine reverses at reverse_at with the bucket at
    20 degrees, and the tilt cylinder strokes tilt_stroke from 0.05 m by end_at (0.36: to the
    WA320's end at 0.41 m)."""
    directory.mkdir(parents=True, exist_ok=True)
    slope = 0.5773502691896257  # tan 30 deg
    with (directory / "scan.csv").open("w") as f:
        f.write("x,z\n")
        for i in range(200):
            x = 1.0 + 0.05 * i
            f.write(f"{x:.6f},{max(0.0, (x - 5.0) * slope):.6f}\n")
    with (directory / "timeseries.csv").open("w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=COLUMNS)
        w.writeheader()
        for n in range(801):
            t = 0.01 * n
            x = 3.0 + min(t, travel)
            z = tip_z if x < 6.1 else (x - 5.0) * slope - 0.2
            if 3.4 <= t < 3.6:
                z = (x - 5.0) * slope - depth
            row = dict.fromkeys(COLUMNS, 0.0)
            row.update(t=t, bucket_tip_x=x, bucket_tip_z=z,
                       v_drive=1.0 if t < reverse_at else -0.8,
                       d_lift=0.1 + (0.05 * (t - lift_at) if t > lift_at else 0.0),
                       d_tilt=0.05 + tilt_stroke * min(max(t - 1.0, 0.0) / (end_at - 1.0), 1.0),
                       bucket_deg=20.0 if t >= reverse_at - 0.2 else 0.0)
            w.writerow(row)
    (directory / "summary.json").write_text(json.dumps(
        {"scenario": "SYN", "fidelity": "D400", "loaded_mass_kg": 1000.0, "work_J": 5e4}))


def write_scenario(path, **targets):
    path.write_text(json.dumps({"name": "SYN", "motion": {"source": "test", **targets}}))


def run(*args):
    return subprocess.run([sys.executable, str(SCRIPT), *map(str, args)], capture_output=True, text=True)


class MotionFeaturesTest(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.TemporaryDirectory()
        self.dir = pathlib.Path(self.tmp.name)

    def tearDown(self):
        self.tmp.cleanup()

    def features(self, run_dir, scenario):
        out = run(run_dir, "--scenario", scenario, "--json")
        self.assertIn(out.returncode, (0, 1), out.stderr)
        return json.loads(out.stdout), out.returncode

    def test_measures_the_constructed_motions(self):
        write_run(self.dir / "run", tip_z=0.1, reverse_at=4.0, lift_at=2.0, end_at=6.0, depth=0.8)
        write_scenario(self.dir / "s.json", tip_height_m={"target": 0.1, "tolerance": 0.01})
        result, code = self.features(self.dir / "run", self.dir / "s.json")
        f = result["features"]
        self.assertEqual(code, 0)
        self.assertAlmostEqual(f["toe_x_m"], 5.1, places=6)  # first scan point above 5 cm
        self.assertAlmostEqual(f["entry_s"], 2.1, delta=0.011)
        self.assertAlmostEqual(f["tip_height_m"], 0.1, places=9)
        self.assertAlmostEqual(f["max_depth_below_surface_m"], 0.8, delta=1e-6)
        self.assertAlmostEqual(f["penetration_m"], 7.0 - 5.1, delta=1e-6)
        self.assertAlmostEqual(f["lift_start_s"], 2.11, delta=0.011)  # 5 mm at 0.05 m/s after 2 s
        self.assertEqual(f["tilt_at_reversal_deg"], 20.0)
        self.assertAlmostEqual(f["bucket_end_s"], 6.0 - 0.005 / 0.36 * 5.0, delta=0.011)

    def test_a_target_missed_fails_with_status_1(self):
        write_run(self.dir / "run", end_at=6.0)
        write_scenario(self.dir / "s.json", bucket_end_s={"target": 7.0, "tolerance": 0.3},
                       max_depth_below_surface_m={"max": 0.9})
        result, code = self.features(self.dir / "run", self.dir / "s.json")
        self.assertEqual(code, 1)
        self.assertFalse(result["targets"]["bucket_end_s"]["met"])
        self.assertTrue(result["targets"]["max_depth_below_surface_m"]["met"])
        table = run(self.dir / "run", "--scenario", self.dir / "s.json")
        self.assertIn("NOT MET", table.stdout)

    def test_a_motion_that_never_happens_fails_its_target(self):
        write_run(self.dir / "run", reverse_at=100.0)
        write_scenario(self.dir / "s.json", tilt_at_reversal_deg={"target": 20.0, "tolerance": 2.0})
        result, code = self.features(self.dir / "run", self.dir / "s.json")
        self.assertIsNone(result["features"]["tilt_at_reversal_deg"])
        self.assertEqual(code, 1)

    def test_a_bucket_short_of_its_end_and_a_cut_short_of_a_metre_measure_never(self):
        # the tilt stops 5 cm short of the stroke; the tip gets 0.6 m past the toe
        write_run(self.dir / "run", tilt_stroke=0.31, travel=2.7)
        write_scenario(self.dir / "s.json", bucket_end_s={"target": 6.0, "tolerance": 0.3})
        result, code = self.features(self.dir / "run", self.dir / "s.json")
        self.assertIsNone(result["features"]["bucket_end_s"])
        self.assertIsNone(result["features"]["tip_height_m"])
        self.assertEqual(code, 1)

    def test_bad_input_names_the_file_and_exits_2(self):
        out = run(self.dir / "nothing")
        self.assertEqual(out.returncode, 2)
        self.assertIn("timeseries.csv: missing", out.stderr)
        write_run(self.dir / "run")
        (self.dir / "s.json").write_text(json.dumps({"name": "SYN"}))
        out = run(self.dir / "run", "--scenario", self.dir / "s.json")
        self.assertEqual(out.returncode, 2)
        self.assertIn("has no 'motion' block", out.stderr)
        write_scenario(self.dir / "s.json", bucket_angle={"max": 1.0})
        out = run(self.dir / "run", "--scenario", self.dir / "s.json")
        self.assertEqual(out.returncode, 2)
        self.assertIn("'bucket_angle' is not a measured feature", out.stderr)

    def test_shipped_scenarios_have_well_formed_targets(self):
        # every target names a feature the script measures, with a target and tolerance or a max
        measured = set(motion_features.FEATURES)
        for name in ("fb35", "hd27", "rd21"):
            path = SCRIPT.parent.parent / "data" / "scenarios" / f"{name}.json"
            motion = json.loads(path.read_text())["motion"]
            self.assertIn("source", motion, name)
            for key, target in motion.items():
                if key == "source":
                    continue
                self.assertIn(key, measured, f"{name}: {key}")
                self.assertTrue({"target", "tolerance"} <= target.keys() or "max" in target, f"{name}: {key}")


if __name__ == "__main__":
    unittest.main()
