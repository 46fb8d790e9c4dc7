#!/usr/bin/env python3
"""Counts docs/plant.md's calibration-table rows over a sweep saved by `dut_calibrate --save DIR`.

    calibration_sweep.py [--csv OUT] LABEL=DIR=K_RRW_TOTAL [LABEL=DIR=K ...]

Each setting is a label, the folder its seeds were saved to (seed-N.passport.json,
seed-N.analysis.json) and the plant's K on x in g/s^0.5 from its parameters,
hypot(polling_k_g_per_rts, rrw_k_g_per_rts), which the K bounds or upper limit should hold.
Prints one markdown column per setting: per row the seeds inside the row's band (docs/plant.md's
targets), the medians, how the paper's B was read, and the seeds meeting every row. K's row is
"reported and within x1.5 of the paper's"; Q's band is x2 (the calibration test's; x1.5 is met
on no seed since the fit starts past the tones' ripple, docs/analysis.md). `--csv` writes the
per-seed values.
"""
import argparse
import csv
import glob
import json
import math
import os
import re
import statistics
import sys

PAPER = dict(bias=-5.0137e-4, base=3.8549e-4, gost=4e-6, bx=2.1e-6, q=6.3603e-10, n=2.2306e-7, k=5.1167e-6,
             by=0.86e-6, ratio=2.5, settling=0.003, bandwidth=492.0)
EVERY_ROW = ["bias", "base", "gost", "bx", "q", "n", "k", "r", "by", "ratio", "loop"]


def value(passport, name):
    v = passport["values"][name]["value"]
    return None if v is None else float(v)


def within_rel(v, target, rel):
    return v is not None and abs(v - target) <= rel * abs(target)


def within_factor(v, target, factor):
    return v is not None and target / factor <= v <= target * factor


def seed_row(passport, analysis, plant_k_per_hour):
    """The row checks and values of one seed (passport units)."""
    nt = analysis["allan"]["x"]["noise_terms"]
    k_hour = nt["K"]["per_hour"]
    v = {name: value(passport, key) for name, key in [
        ("bias", "bias"), ("base", "base_error"), ("gost", "in_run_b_gost_100s"), ("bx", "in_run_b_allan"),
        ("tau_cp", "tau_cp"), ("by", "in_run_b_allan_filtered"), ("q", "q"), ("n", "n"), ("k", "k"), ("r", "r"),
        ("settling", "settling_time"), ("bandwidth", "bandwidth_0p5")]}
    v["b_method"] = nt.get("b_method") or "null"
    v["k_lo"], v["k_hi"] = k_hour.get("lo"), k_hour.get("hi")
    v["ratio"] = v["bx"] / v["by"] if v["bx"] and v["by"] else None
    hi = v["k_hi"]
    if hi is None:
        held = False
    elif v["k"] is None:
        held = plant_k_per_hour <= hi  # a null: its upper limit
    else:
        held = v["k_lo"] is not None and v["k_lo"] <= plant_k_per_hour <= hi
    ok = dict(bias=within_rel(v["bias"], PAPER["bias"], 0.01), base=within_rel(v["base"], PAPER["base"], 0.01),
              gost=within_rel(v["gost"], PAPER["gost"], 0.5), bx=within_rel(v["bx"], PAPER["bx"], 0.3),
              q=within_factor(v["q"], PAPER["q"], 2.0), q15=within_factor(v["q"], PAPER["q"], 1.5),
              n=within_factor(v["n"], PAPER["n"], 1.5), k=within_factor(v["k"], PAPER["k"], 1.5), r=v["r"] is None,
              by=within_rel(v["by"], PAPER["by"], 0.3),
              ratio=v["ratio"] is not None and abs(v["ratio"] - PAPER["ratio"]) <= 0.5,
              loop=within_rel(v["settling"], PAPER["settling"], 0.2) and within_rel(v["bandwidth"], PAPER["bandwidth"], 0.05),
              held=held)
    ok["every"] = all(ok[r] for r in EVERY_ROW)
    ok["every_held"] = all(ok[r] for r in EVERY_ROW if r != "k") and held
    return v, ok


def load_setting(folder, plant_k):
    seeds = sorted(int(m.group(1)) for f in glob.glob(os.path.join(folder, "seed-*.passport.json"))
                   if (m := re.search(r"seed-(\d+)\.passport\.json$", f)))
    if not seeds:
        sys.exit(f"calibration_sweep: no seed-N.passport.json in {folder}")
    rows = []
    for s in seeds:
        stem = os.path.join(folder, f"seed-{s}")
        with open(stem + ".passport.json") as p, open(stem + ".analysis.json") as a:
            v, ok = seed_row(json.load(p), json.load(a), plant_k * 60)
        rows.append((s, v, ok))
    return rows


def med(xs):
    xs = [x for x in xs if x is not None]
    return statistics.median(xs) if xs else float("nan")


def column(rows, plant_k):
    n = lambda key: sum(ok[key] for _, _, ok in rows)
    vals = lambda key: [v[key] for _, v, _ in rows]
    read = lambda key: sum(x is not None for x in vals(key))
    ks = [x for x in vals("k") if x is not None]
    methods = {}
    for m in vals("b_method"):
        methods[m] = methods.get(m, 0) + 1
    ratios = [x for x in vals("ratio") if x is not None]
    return {
        "seeds": f"{len(rows)} ({rows[0][0]}..{rows[-1][0]})",
        "plant K, g/h^0.5": f"{plant_k * 60:.3g}",
        "bias ±1 %": f"{n('bias')}",
        "base error ±1 %": f"{n('base')}",
        "B GOST 100 s ±50 % (median)": f"{n('gost')} ({med(vals('gost')):.3g})",
        "B Allan x ±30 %: in band / read (median)": f"{n('bx')}/{read('bx')} ({med(vals('bx')):.3g})",
        "B Allan read at": ", ".join(f"{k} {c}" for k, c in sorted(methods.items())),
        "Q ×2 / ×1.5 (median)": f"{n('q')}/{n('q15')} ({med(vals('q')):.3g})",
        "N ×1.5 (median)": f"{n('n')} ({med(vals('n')):.3g})",
        "K reported / within ×1.5": f"{len(ks)}/{n('k')}",
        "median K of those reporting (× paper)": f"{med(ks):.3g} (×{med(ks) / PAPER['k']:.2f})" if ks else "-",
        "median K, a null as 0": f"{med([x or 0.0 for x in vals('k')]):.3g}",
        "plant K held (bounds / upper limit)": f"{n('held')}",
        "R null": f"{n('r')}",
        "B filtered ±30 %: in band / read (median)": f"{n('by')}/{read('by')} ({med(vals('by')):.3g})",
        "ratio 2.5 ± 0.5 (median, range)": (f"{n('ratio')} ({med(ratios):.2f}, {min(ratios):.2f}–{max(ratios):.2f})"
                                            if ratios else f"{n('ratio')}"),
        "loop rows": f"{n('loop')}",
        "every row (seeds)": f"{n('every')} ({', '.join(str(s) for s, _, ok in rows if ok['every'])})",
        "every row, K row = plant K held": f"{n('every_held')}",
    }


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("settings", nargs="+", help="LABEL=DIR=K (K: the plant's K in g/s^0.5)")
    ap.add_argument("--csv", help="write the per-seed values here")
    a = ap.parse_args()
    cols, per_seed = [], []
    for spec in a.settings:
        try:
            label, folder, k = spec.split("=")
            plant_k = float(k)
        except ValueError:
            sys.exit(f"calibration_sweep: '{spec}': expected LABEL=DIR=K")
        rows = load_setting(folder, plant_k)
        cols.append((label, column(rows, plant_k)))
        per_seed += [(label, s, v, ok) for s, v, ok in rows]
    names = list(cols[0][1])
    print("| row | " + " | ".join(label for label, _ in cols) + " |")
    print("|---|" + "---|" * len(cols))
    for name in names:
        print(f"| {name} | " + " | ".join(c[name] for _, c in cols) + " |")
    if a.csv:
        keys = ["bias", "base", "gost", "bx", "b_method", "tau_cp", "q", "n", "k", "k_lo", "k_hi", "r", "by", "ratio",
                "settling", "bandwidth"]
        with open(a.csv, "w", newline="") as f:
            w = csv.writer(f)
            w.writerow(["setting", "seed"] + keys + ["plant_k_held", "every_row"])
            for label, s, v, ok in per_seed:
                w.writerow([label, s] + ["" if v[k] is None else (f"{v[k]:.6g}" if isinstance(v[k], float) else v[k])
                                         for k in keys] + [int(ok["held"]), int(ok["every"])])


if __name__ == "__main__":
    main()
