#!/usr/bin/env python3
"""Measure the motions the paper's text describes in a talus dig, against the scenario's targets.

The field operators' time series are not public; the paper (section 3) describes each test in a few
sentences ("bucket lowered flat to the ground", "tilted 20 deg, then reversed", "tilted to the end
around 10 s"). Each shipped scenario quantifies those sentences in its "motion" block; this script
measures the same quantities in a run (DIR/timeseries.csv, DIR/scan.csv, DIR/summary.json) so that
retuning the reconstructed inputs is a procedure with a pass/fail answer, not a judgement by eye
(docs/digging.md, "How the inputs were retuned").

  scripts/motion-features.py RUN_DIR [RUN_DIR ...] [--scenario FILE] [--json]

Exit status: 0 when every run meets every target, 1 when one does not, 2 on bad input.

Features (t from the start of the run, tip = the bucket's cutting edge in the plane of motion):
  entry_s                    first time the tip reaches the pile's toe (scan height above toe_height_m)
  tip_height_m               median tip height while it travels the first metre past the toe (never
                             when it does not get a metre in before the machine backs)
  max_depth_below_surface_m  deepest the tip goes under the scanned (pre-dig) surface
  penetration_m              furthest the tip goes past the toe
  lift_start_s               first time the boom cylinder has extended lift_start_stroke_m past its
                             length at the start (the machine starts at rest); the threshold delays it
                             by 5 mm over the cylinder's speed: 0.1 s at FB35's slight lift
                             (0.05 m/s), 0.02 s at HD27's full-speed lift (0.218 m/s)
  tilt_at_reversal_deg       bucket angle when the machine first backs at more than reversal_speed
  bucket_end_s               first time the tilt cylinder is within end_margin_m of the end of its
                             stroke (the machine file's length_range; never when it stops short)
"""
import argparse
import bisect
import csv
import json
import pathlib
import statistics
import sys

# thresholds of the definitions above; each is a choice of this script, stated with its reason
toe_height_m = 0.05        # where the bucket first meets grains: the scan's first point off the floor
                           # (flat static ground; the smallest grains, D100, stand 0.1 m). The
                           # force-feedback cycle detects the pile at half a grain (feedback_sweep.cpp),
                           # a threshold for a controller, not a measurement of the operator's motion
entry_travel_m = 1.0       # "during penetration": the first metre past the toe
lift_start_stroke_m = 0.005  # 5 mm of boom cylinder: beyond the few mm the linkage settles under load
reversal_speed = 0.3       # m/s backwards: a deliberate reverse, not the push-back of a stalled bucket
end_margin_m = 0.005       # 5 mm short of the tilt cylinder's full stroke counts as its end

# what measure() returns, in this order (the targets of a scenario's motion block must be among them)
FEATURES = ("toe_x_m", "entry_s", "tip_height_m", "max_depth_below_surface_m", "penetration_m",
            "lift_start_s", "tilt_at_reversal_deg", "bucket_end_s")


def fail(message):
    print(f"motion-features: {message}", file=sys.stderr)
    sys.exit(2)


def read_run(run):
    """The run's time series (dict of float columns per row) and the scanned surface [(x, z)]."""
    files = {name: run / name for name in ("timeseries.csv", "scan.csv", "summary.json")}
    for name, path in files.items():
        if not path.is_file():
            fail(f"{path}: missing; give a directory written by 'talus run' with a pile scenario")
    with files["timeseries.csv"].open() as f:
        try:
            rows = [{k: float(v) for k, v in r.items()} for r in csv.DictReader(f)]
        except ValueError as e:
            fail(f"{files['timeseries.csv']}: {e}; the file is not a talus time series")
    with files["scan.csv"].open() as f:
        scan = [(float(r["x"]), float(r["z"])) for r in csv.DictReader(f)]
    summary = json.loads(files["summary.json"].read_text())
    needed = {"t", "v_drive", "d_lift", "d_tilt", "bucket_deg", "bucket_tip_x", "bucket_tip_z"}
    if not rows or not needed <= rows[0].keys():
        fail(f"{files['timeseries.csv']}: needs the columns {sorted(needed)}")
    if len(scan) < 2:
        fail(f"{files['scan.csv']}: fewer than two points; the run had no pile")
    return rows, scan, summary


def surface(scan, x):
    """Scanned height at x, linear between points, flat beyond the ends."""
    xs = [p[0] for p in scan]
    i = bisect.bisect_left(xs, x)
    if i <= 0:
        return scan[0][1]
    if i >= len(scan):
        return scan[-1][1]
    (x0, z0), (x1, z1) = scan[i - 1], scan[i]
    return z0 + (z1 - z0) * (x - x0) / (x1 - x0)


def tilt_stroke(machine_path):
    """The tilt cylinder's stroke [m] from a machine file: d_tilt runs from 0 to it."""
    machine = json.loads(machine_path.read_text())
    for c in machine.get("cylinders", []):
        if c.get("role") == "tilt":
            low, high = c["length_range"]["value"]
            return high - low
    fail(f"{machine_path}: no cylinder with role 'tilt'; the bucket's end cannot be measured")


def measure(rows, scan, stroke):
    """The features of the module docstring; None where the run never shows the motion. stroke:
    the tilt cylinder's stroke [m]."""
    toe = next((x for x, z in scan if z > toe_height_m), None)
    if toe is None:
        fail("the scan never rises above the floor: no pile to dig")
    entry = next((r for r in rows if r["bucket_tip_x"] >= toe), None)
    f = {"toe_x_m": toe, "entry_s": entry["t"] if entry else None}
    if entry is None:
        return f | {k: None for k in FEATURES[2:]}
    after = [r for r in rows if r["t"] >= entry["t"]]
    # tip height over the first metre of penetration: from entry until the tip first passes it,
    # none when the machine backs first
    first_metre, reached = [], False
    for r in after:
        if r["bucket_tip_x"] >= toe + entry_travel_m:
            reached = True
            break
        if r["v_drive"] < -reversal_speed:
            break
        first_metre.append(r["bucket_tip_z"])
    f["tip_height_m"] = statistics.median(first_metre) if reached and first_metre else None
    # how deep and how far the tip went
    f["max_depth_below_surface_m"] = max(surface(scan, r["bucket_tip_x"]) - r["bucket_tip_z"] for r in after)
    f["penetration_m"] = max(r["bucket_tip_x"] for r in after) - toe
    # the boom's first extension, measured on the cylinder (before entry too: the text times it)
    lift0 = rows[0]["d_lift"]
    f["lift_start_s"] = next((r["t"] for r in rows if r["d_lift"] - lift0 > lift_start_stroke_m), None)
    # the bucket's angle when the operator reverses
    reverse = next((r for r in after if r["v_drive"] < -reversal_speed), None)
    f["tilt_at_reversal_deg"] = reverse["bucket_deg"] if reverse else None
    # the tilt cylinder at the end of its stroke
    f["bucket_end_s"] = next((r["t"] for r in rows if r["d_tilt"] >= stroke - end_margin_m), None)
    return f


def judge(features, targets):
    """[(name, measured, target text, ok)] for each target; a missing motion fails its target."""
    out = []
    for name, t in targets.items():
        if not isinstance(t, dict):
            continue
        if name not in FEATURES:
            fail(f"motion target '{name}' is not a measured feature; use one of {', '.join(FEATURES)}")
        value = features.get(name)
        if "target" in t:
            want = f"{t['target']} +- {t['tolerance']}"
            ok = value is not None and abs(value - t["target"]) <= t["tolerance"]
        elif "max" in t:
            want = f"<= {t['max']}"
            ok = value is not None and value <= t["max"]
        else:
            fail(f"motion target '{name}' has neither 'target' and 'tolerance' nor 'max'")
        out.append((name, value, want, ok))
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("runs", nargs="+", type=pathlib.Path, help="directories written by 'talus run'")
    ap.add_argument("--scenario", type=pathlib.Path,
                    help="scenario file with the 'motion' targets (default: data/scenarios/<name>.json)")
    ap.add_argument("--json", action="store_true", help="print one JSON object per run instead of a table")
    args = ap.parse_args()
    here = pathlib.Path(__file__).resolve().parent.parent
    all_ok = True
    for run in args.runs:
        rows, scan, summary = read_run(run)
        path = args.scenario or here / "data" / "scenarios" / f"{summary['scenario'].lower()}.json"
        if not path.is_file():
            fail(f"{path}: no such scenario file; pass --scenario FILE")
        scenario = json.loads(path.read_text())
        targets = scenario.get("motion")
        if not isinstance(targets, dict):
            fail(f"{path}: has no 'motion' block of targets; add one (docs/digging.md) or pass --scenario")
        machine = here / "data" / "machines" / f"{scenario.get('machine', 'wa320')}.json"
        if not machine.is_file():
            fail(f"{path}: field 'machine' names {machine}, which does not exist; fix the name")
        features = measure(rows, scan, tilt_stroke(machine))
        verdicts = judge(features, targets)
        ok = all(v[3] for v in verdicts)
        all_ok &= ok
        if args.json:
            print(json.dumps({"run": str(run), "scenario": summary["scenario"], "fidelity": summary["fidelity"],
                              "features": features,
                              "targets": {n: {"measured": v, "target": w, "met": k} for n, v, w, k in verdicts},
                              "met": ok}))
            continue
        print(f"{run}: {summary['scenario']} {summary['fidelity']}, "
              f"{summary['loaded_mass_kg'] / 1e3:.2f} t, {summary['work_J'] / 1e3:.0f} kJ")
        for name, value in features.items():
            v = next((x for x in verdicts if x[0] == name), None)
            shown = "never" if value is None else f"{value:.2f}"
            verdict = "" if v is None else f"  target {v[2]}: {'met' if v[3] else 'NOT MET'}"
            print(f"  {name:27s} {shown:>7s}{verdict}")
    sys.exit(0 if all_ok else 1)


if __name__ == "__main__":
    main()
