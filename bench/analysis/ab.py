#!/usr/bin/python3
"""Two builds of rig side by side (issue 17): the same `rig analyze` commands as compare.py's
rows (timed.analyze_rows), each run by the build before and the build after a change, alternately in one loop (so
both see the same load), and the outputs compared byte for byte.

    /usr/bin/python3 bench/analysis/ab.py BEFORE_RIG AFTER_RIG [--file y.f64] [--rounds 15]
                                          [--only oadev,hdev,...]

Per row: minimum and median wall and CPU time (user + system, all threads) of each build over
the rounds, and the change of the medians. On a shared machine the CPU columns are the steadier
comparison; the wall columns are what a user waits for. A row whose JSON differs between the
builds is flagged (every change here is meant to keep the results' bits).
"""
import argparse
import filecmp
import os
import statistics
import sys
import tempfile

here = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, here)
from timed import analyze_rows, timed  # noqa: E402

ap = argparse.ArgumentParser()
ap.add_argument("before")
ap.add_argument("after")
ap.add_argument("--file", default="/tmp/rig-bench-1h.f64")
ap.add_argument("--rounds", type=int, default=15)
ap.add_argument("--only", default="")
args = ap.parse_args()

tmp = tempfile.mkdtemp(prefix="rig-ab-")
rows = [("start-up", None)] + analyze_rows()
if args.only:
    keep = set(args.only.split(","))
    rows = [r for r in rows if r[0] in keep]


def command(rig, extra, out):
    if extra is None:
        return [rig, "--version"]
    return [rig, "analyze", args.file, "--input", "f64", "--rate", "1000", "--taus", "log:100", "--json", out] + extra


print(f"# {os.uname().nodename}, load {os.getloadavg()[0]:.2f}; {args.rounds} rounds, alternated; ms")
print(f"{'row':<10} {'before wall min/med':>20} {'after wall min/med':>20} {'before cpu min/med':>20} "
      f"{'after cpu min/med':>20} {'wall':>7} {'cpu':>7}  json")
for name, extra in rows:
    outs = [os.path.join(tmp, f"{name}-{k}.json") for k in (0, 1)]
    t = {0: ([], []), 1: ([], [])}
    for k, rig in enumerate((args.before, args.after)):
        timed(command(rig, extra, outs[k]))  # warm-up
    for _ in range(args.rounds):
        for k, rig in enumerate((args.before, args.after)):
            w, c = timed(command(rig, extra, outs[k]))
            t[k][0].append(w * 1e3)
            t[k][1].append(c * 1e3)
    same = "-" if extra is None else ("same" if filecmp.cmp(outs[0], outs[1], shallow=False) else "DIFFERS")
    mm = lambda v: f"{min(v):8.2f} /{statistics.median(v):8.2f}"  # noqa: E731
    dw = statistics.median(t[1][0]) / statistics.median(t[0][0]) - 1
    dc = statistics.median(t[1][1]) / statistics.median(t[0][1]) - 1
    print(f"{name:<10} {mm(t[0][0]):>20} {mm(t[1][0]):>20} {mm(t[0][1]):>20} {mm(t[1][1]):>20} "
          f"{dw:+7.1%} {dc:+7.1%}  {same}", flush=True)
print(f"# load at the end {os.getloadavg()[0]:.2f}")
