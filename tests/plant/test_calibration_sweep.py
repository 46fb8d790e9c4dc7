#!/usr/bin/env python3
"""bench/plant/calibration_sweep.py counts the calibration table's rows the way docs/plant.md
states them: two saved seeds with known values, one meeting every row (K reported, its bounds
holding the plant's K), one with K null under an upper limit below the plant's K and the paper's
B not read. Usage: test_calibration_sweep.py SCRIPT"""
import csv
import json
import os
import subprocess
import sys
import tempfile


def passport(k, bx, by, r=None):
    v = lambda x: {"value": x}
    return {"values": {"bias": v(-5.01e-4), "base_error": v(3.855e-4), "in_run_b_gost_100s": v(3.7e-6),
                       "in_run_b_allan": v(bx), "tau_cp": v(200.0 if bx else None), "in_run_b_allan_filtered": v(by),
                       "q": v(1.1e-9), "n": v(1.6e-7), "k": v(k), "r": v(r), "settling_time": v(0.0031),
                       "bandwidth_0p5": v(495.0)}}


def analysis(k_per_hour, b_method):
    return {"allan": {"x": {"noise_terms": {"b_method": b_method, "K": {"per_hour": k_per_hour}}}}}


def write(folder, seed, p, a):
    with open(os.path.join(folder, f"seed-{seed}.passport.json"), "w") as f:
        json.dump(p, f)
    with open(os.path.join(folder, f"seed-{seed}.analysis.json"), "w") as f:
        json.dump(a, f)


def main():
    script = sys.argv[1]
    plant_k = 9.38e-8  # g/s^0.5: 5.628e-6 g/h^0.5
    with tempfile.TemporaryDirectory() as d:
        write(d, 1, passport(5.5e-6, 2.0e-6, 0.85e-6), analysis({"value": 5.5e-6, "lo": 4e-6, "hi": 7e-6}, "polynomial_minimum"))
        write(d, 2, passport(None, None, 0.8e-6, r=2e-5), analysis({"value": None, "hi": 3e-6}, None))
        out_csv = os.path.join(d, "out.csv")
        res = subprocess.run([sys.executable, script, "--csv", out_csv, f"S={d}={plant_k}"], capture_output=True,
                             text=True, check=True)
        table = {line.split(" | ")[0].lstrip("| "): line.split(" | ")[1].rstrip(" |")
                 for line in res.stdout.splitlines()[2:]}
        expect = {"seeds": "2 (1..2)", "K reported / within ×1.5": "1/1", "plant K held (bounds / upper limit)": "1",
                  "B Allan x ±30 %: in band / read (median)": "1/1 (2e-06)", "R null": "1",
                  "median K, a null as 0": "2.75e-06", "every row (seeds)": "1 (1)",
                  "every row, K row = plant K held": "1", "B Allan read at": "null 1, polynomial_minimum 1"}
        for k, v in expect.items():
            assert table.get(k) == v, f"{k}: got {table.get(k)!r}, expected {v!r}\n{res.stdout}"
        rows = list(csv.DictReader(open(out_csv)))
        assert [(r["seed"], r["plant_k_held"], r["every_row"]) for r in rows] == [("1", "1", "1"), ("2", "0", "0")], rows
        bad = subprocess.run([sys.executable, script, f"S={d}"], capture_output=True, text=True)
        assert bad.returncode != 0 and "LABEL=DIR=K" in bad.stderr, bad.stderr
        empty = os.path.join(d, "empty")
        os.mkdir(empty)
        bad = subprocess.run([sys.executable, script, f"S={empty}=1e-7"], capture_output=True, text=True)
        assert bad.returncode != 0 and "no seed-N.passport.json" in bad.stderr, bad.stderr
    print("calibration_sweep: ok")


if __name__ == "__main__":
    main()
