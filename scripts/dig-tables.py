#!/usr/bin/env python3
"""Tables of issue 11's digging studies from talus run summaries (docs/validation.md).

  scripts/dig-tables.py [DIR] [--label TEXT]

Reads DIR/*/summary.json (default out/dig) and prints, as Markdown:
  - per scenario and level: loaded mass and work over pile seeds (mean, coefficient of variation),
    against the field values, labelled TEXT (default: the first stage's "mu_r 0.02, gravel ground");
  - across levels: each level's seed mean against the finest level run for that scenario;
  - convergence: each run with --dt or --iterations changed against the same level's seed-1 run;
  - the particle rows' residual at the end of each step (median, 95th percentile).
Run names follow scripts' convention S-L-seedN, S-L-dtX, S-L-itN (the study queue in the docs)."""
import argparse
import json
import pathlib
import re
import statistics

ap = argparse.ArgumentParser(description="Markdown tables of the digging studies (docs/validation.md)")
ap.add_argument("dir", nargs="?", default="out/dig", type=pathlib.Path, help="folder of run folders")
ap.add_argument("--label", default="mu_r 0.02, gravel ground (now)", help="the first column of these runs' rows")
args = ap.parse_args()
root = args.dir
runs = {}
earlier = {}
for f in sorted(root.glob("*/summary.json")):
    m = re.fullmatch(r"(fb35|hd27|rd21)-([DG]\d+)-(seed\d+|dt[\d.]+|it\d+)", f.parent.name)
    if m:
        runs[m.groups()] = json.loads(f.read_text())
    # earlier stages of the study, kept for the before/after table: mu_r 1.0 (talus before issue
    # 11) and mu_r 0.02 on a polished floor (before the ground's rolling resistance)
    m = re.fullmatch(r"(fb35|hd27|rd21)-(D\d+)-mur([\d.]+)-(seed\d+)", f.parent.name)
    if m:
        earlier.setdefault(m.group(3), {})[(m.group(1), m.group(2), m.group(4))] = json.loads(f.read_text())

# convergence over pile seeds: S-L-dtX-seedN and S-L-itN-seedN, the same seeds with one knob changed
ensembles = {}
for f in sorted(root.glob("*/summary.json")):
    m = re.fullmatch(r"(fb35|hd27|rd21)-(D\d+)-(dt[\d.]+|it\d+)-seed\d+", f.parent.name)
    if m:
        ensembles.setdefault(m.groups(), []).append(json.loads(f.read_text()))

field = {"fb35": (3460, 209e3), "hd27": (2700, 127e3), "rd21": (2100, 112e3)}
scenarios = ("fb35", "hd27", "rd21")
# each family's levels, coarsest first: type D (particles) and type G (the multiscale terrain)
levels = ("D400", "D200", "D100", "D50", "G400", "G200", "G100", "G50")


def seed_runs(table, s, level):
    """The runs of scenario s at a level that differ only in their pile seed (S-L-seedN)."""
    return [r for (sc, l, k), r in table.items() if sc == s and l == level and k.startswith("seed")]


def mean_cv(x):
    """Mean and coefficient of variation (population standard deviation over the mean: the spread
    of these seeds, not an estimate of a standard error)."""
    return statistics.mean(x), (statistics.pstdev(x) / statistics.mean(x) if len(x) > 1 else float("nan"))


print("| gravel | scenario | level | seeds | loaded mass [t] mean (CV) | E_M | work [kJ] mean (CV) | E_W |")
print("|---|---|---|---|---|---|---|---|")
names = {"1.0": "mu_r 1.0 (before)", "0.02": "mu_r 0.02, polished floor"}
variants = [(names.get(k, k), v) for k, v in sorted(earlier.items(), key=lambda kv: -float(kv[0]))]
variants.append((args.label, runs))
for label, table in variants:
    for s in scenarios:
        for level in levels:
            seeds = seed_runs(table, s, level)
            if not seeds:
                continue
            (mm, mc) = mean_cv([r["loaded_mass_kg"] for r in seeds])
            (wm, wc) = mean_cv([r["work_J"] for r in seeds])
            spread = lambda c: f"{100 * c:.0f} %" if len(seeds) > 1 else "one seed"
            print(f"| {label} | {s.upper()} | {level} | {len(seeds)} | {mm / 1e3:.2f} ({spread(mc)}) "
                  f"| {mm / field[s][0] - 1:+.2f} | {wm / 1e3:.0f} ({spread(wc)}) | {wm / field[s][1] - 1:+.2f} |")

print()
print("| scenario | level | seeds | loaded mass [t] | against the finest | work [kJ] | against the finest |")
print("|---|---|---|---|---|---|---|")
for s in scenarios:
    means = {}
    for level in levels:
        seeds = seed_runs(runs, s, level)
        if seeds:
            means[level] = (len(seeds), statistics.mean(r["loaded_mass_kg"] for r in seeds),
                            statistics.mean(r["work_J"] for r in seeds))
    for level, (n, m, w) in means.items():
        # against the finest level run of the same family
        finest = [l for l in levels if l in means and l[0] == level[0]][-1:]
        fm, fw = means[finest[0]][1:]
        rel = lambda a, b: "-" if level == finest[0] else f"{100 * (a / b - 1):+.0f} % vs {finest[0]}"
        print(f"| {s.upper()} | {level} | {n} | {m / 1e3:.2f} | {rel(m, fm)} | {w / 1e3:.0f} | {rel(w, fw)} |")

print()
print("| run | loaded mass [t] | change | work [kJ] | change | residual median / p95 [m/s] |")
print("|---|---|---|---|---|---|")
# each level's own seed-1 run first, then its studies
order = lambda item: (item[0][0], -int(item[0][1][1:]), item[0][2] != "seed1", item[0][2])
for (s, level, k), r in sorted(runs.items(), key=order):
    base = runs.get((s, level, "seed1"))
    res = r.get("step_residual_m_s", {})
    res_text = f"{res.get('median', float('nan')):.1e} / {res.get('p95', float('nan')):.1e}" if res else "-"
    if k.startswith("seed") and k != "seed1":
        continue
    if base is None or k == "seed1":
        print(f"| {s.upper()}-{level} ({r['dt_s']*1e3:g} ms, {r['iterations']} sweeps) "
              f"| {r['loaded_mass_kg']/1e3:.2f} | - "
              f"| {r['work_J']/1e3:.0f} | - | {res_text} |")
        continue
    dm = r["loaded_mass_kg"] / base["loaded_mass_kg"] - 1
    dw = r["work_J"] / base["work_J"] - 1
    print(f"| {s.upper()}-{level} {k} ({r['dt_s']*1e3:g} ms, {r['iterations']} sweeps) | {r['loaded_mass_kg']/1e3:.2f} "
          f"| {100*dm:+.1f} % | {r['work_J']/1e3:.0f} | {100*dw:+.1f} % | {res_text} |")

if ensembles:
    # the study knob's effect over the same pile seeds: each seed's run with the knob changed
    # against that seed's run at the level's settings, the mean change and its standard error
    # (sample standard deviation of the paired changes over sqrt(n)); a change within about two
    # standard errors is what the seeds' own spread can make
    print()
    print("| scenario | level | Δt, sweeps | seeds | loaded mass [t] mean (CV) | paired change ± SE | "
          "work [kJ] mean (CV) | paired change ± SE |")
    print("|---|---|---|---|---|---|---|---|")

    def paired(changed, base, key):
        by_seed = {r["seed"]: r[key] for r in base}
        d = [r[key] / by_seed[r["seed"]] - 1 for r in changed if r["seed"] in by_seed]
        if len(d) < 2:
            return f"{100 * statistics.mean(d):+.1f} % (one pile)"
        se = statistics.stdev(d) / len(d) ** 0.5
        return f"{100 * statistics.mean(d):+.1f} ± {100 * se:.1f} %"

    for s in scenarios:
        for level in levels:
            base = seed_runs(runs, s, level)
            studies = [(k, v) for (sc, l, k), v in sorted(ensembles.items()) if sc == s and l == level]
            if not studies or len(base) < 2:
                continue
            for k, rs in [("level's", base)] + studies:
                (mm, mc) = mean_cv([r["loaded_mass_kg"] for r in rs])
                (wm, wc) = mean_cv([r["work_J"] for r in rs])
                knob = f"{rs[0]['dt_s'] * 1e3:g} ms, {rs[0]['iterations']}"
                change = lambda key: "-" if k == "level's" else paired(rs, base, key)
                cv = lambda c: f"{100 * c:.0f} %" if len(rs) > 1 else "one pile"
                print(f"| {s.upper()} | {level} | {knob} | {len(rs)} | {mm / 1e3:.2f} ({cv(mc)}) "
                      f"| {change('loaded_mass_kg')} | {wm / 1e3:.0f} ({cv(wc)}) | {change('work_J')} |")
