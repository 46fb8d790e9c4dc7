#!/usr/bin/python3
"""Issue 17's figures in one run: for each statistic, the whole `rig analyze` process against
a straightforward NumPy twin's compute alone (bench/analysis/twins.py) on the same data and
the same taus (read back from rig's JSON), measured alternately; prints both times and the ratio.

    /usr/bin/python3 bench/analysis/compare.py [--rig build/bin/rig] [--file y.f64] [--n 3.6e6]
                                               [--rounds 5] [--only oadev,mdev,...]
                                               [--only theo1,theoh,mtot,ttot,htot] (long-tau, opt-in)

The rig's figure is the wall time of the whole process (start-up, reading the float64 file,
the deviations with noise identification and bounds, the noise terms, the JSON written);
the twin's is the NumPy computation only (the file already loaded, no bounds). Each is the
minimum over the rounds (the machine is shared: the minimum is the least disturbed run).
Figures, one row each:
  oadev        rig analyze --no-psd                         vs  twin OADEV
  oadev+psd    rig analyze                                  vs  twin OADEV + twin Welch PSD
  mdev ..      rig analyze --no-psd --dev X --no-oadev      vs  twin X (the deviation alone)
  mdev+oadev   rig analyze --no-psd --dev X                 vs  twin OADEV + twin X (the same
               outputs: without --no-oadev the rig computes OADEV and its noise terms too)
The CPU columns give the same comparison in CPU time (rig: both threads; the twin is
single-threaded), which other load on a shared machine disturbs much less than wall time.
"""
import json
import os
import subprocess
import sys
import tempfile
import time

import numpy as np

here = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, here)
import twins  # noqa: E402
from timed import DEVIATIONS, analyze_rows, bench_args, timed  # noqa: E402

ap = bench_args(5)
ap.add_argument("--n", type=float, default=3.6e6)
ap.add_argument("--rate", type=float, default=1000.0)
ap.add_argument("--taus", default="log:100")
ap.add_argument("--only", default="")
args = ap.parse_args()

if not os.path.exists(args.file):
    subprocess.run([sys.executable, os.path.join(here, "make_signal.py"), args.file, str(args.n), "1"], check=True)
y = np.fromfile(args.file, dtype="<f8")
tau0 = 1.0 / args.rate
tmp = tempfile.mkdtemp(prefix="rig-compare-")


def rig_run(extra):
    out = os.path.join(tmp, "a.json")
    cmd = [args.rig, "analyze", args.file, "--input", "f64", "--rate", str(args.rate), "--taus", args.taus,
           "--json", out] + extra
    wall, cpu = timed(cmd)
    return wall, out, cpu


def taus_of(json_path, key):
    """The factors rig chose under `key`, or a dict of them for a tuple of keys."""
    j = json.load(open(json_path))
    if isinstance(key, tuple):
        return {k: [p["m"] for p in j[k]] for k in key}
    return [p["m"] for p in j[key]]


def psd_segment(n):  # rig's automatic choice (analysis/psd.cpp welch_segment)
    s = 1 << max(0, int(n // 8).bit_length() - 1)
    return min(max(s, 256), 65536)


# (figure, rig's extra arguments, the JSON key whose taus the twin uses, twin(x, ms) -> None)
twin_of = {"oadev": lambda x, ms: twins.oadev(x, tau0, ms),
           "oadev+psd": lambda x, ms: (twins.oadev(x, tau0, ms), twins.welch(y, args.rate, psd_segment(len(y))))}
for d in DEVIATIONS:
    twin_of[d] = lambda x, ms, f=twins.DEVIATIONS[d]: f(x, tau0, ms)
figures = [(name, extra, "oadev" if name.startswith("oadev") else name, twin_of[name]) for name, extra in analyze_rows()]
for d in DEVIATIONS:
    # The twin's taus per key: OADEV's and the deviation's grids differ (max factor (N-1)/4 vs /2).
    figures.append((d + "+oadev", ["--no-psd", "--dev", d], (d, "oadev"),
                    lambda x, ms, f=twins.DEVIATIONS[d], d=d: (twins.oadev(x, tau0, ms["oadev"]), f(x, tau0, ms[d]))))
# Long-tau statistics (opt-in: --only theo1,theoh,mtot,ttot,htot; the twins take minutes on
# 3.6e6 samples). rig sums every stride-th subsequence start beyond its work cap; the twin is
# given the same strides (from rig's JSON) so both compute the same statistic.
pts = {}
LONG = ["theo1", "theoh", "mtot", "ttot", "htot"]
for d in LONG:
    if d == "theoh":
        twin_fn = (lambda x, ms: twins.theoh(x, tau0, ms, [p["stride"] for p in pts["theoh"]],
                                             [p["estimator"] for p in pts["theoh"]]))
    else:
        twin_fn = (lambda x, ms, d=d: twins.LONG_TAU[d](x, tau0, ms, [p["stride"] for p in pts[d]]))
    figures.append((d, ["--no-psd", "--dev", d], d, twin_fn))
if not args.only:
    figures = [f for f in figures if f[0] not in LONG]
if args.only:
    keep = set(args.only.split(","))
    figures = [f for f in figures if f[0] in keep]

print(f"# {time.strftime('%Y-%m-%d %H:%M')} {os.uname().nodename}, {os.cpu_count()} cores, "
      f"load {os.getloadavg()[0]:.2f}; n = {len(y)}, taus {args.taus}, {args.rounds} rounds (minimum)")
# Issue 17's targets: the whole process at least 20x the twin's compute (10x with the PSD); the
# "+oadev" rows (two statistics against two twins) have none of their own.
TARGET = {"oadev": 20, "oadev+psd": 10, "mdev": 20, "tdev": 20, "hdev": 20, "ohdev": 20, "totdev": 20}
print(f"{'figure':<12} {'taus':>5} {'rig s':>8} {'numpy s':>8} {'ratio':>7}   {'rig cpu':>8} {'np cpu':>8} {'ratio':>7}"
      f"   target (wall / cpu)")
for name, extra, key, twin in figures:
    _, out, _ = rig_run(extra)  # warm-up, and the taus rig chose
    ms = taus_of(out, key)
    if key in LONG:
        pts[key] = json.load(open(out))[key]  # the long-tau twins' strides and TheoH's estimators
    rig_t, np_t, rig_c, np_c = [], [], [], []
    for _ in range(args.rounds):
        w, _, c = rig_run(extra)
        rig_t.append(w)
        rig_c.append(c)
        t0, c0 = time.perf_counter(), time.process_time()
        x = twins.phase_from_freq(y, tau0)  # the twin's own integration is part of its compute
        twin(x, ms)
        np_t.append(time.perf_counter() - t0)
        np_c.append(time.process_time() - c0)
        del x
    r, p, rc, pc = min(rig_t), min(np_t), min(rig_c), min(np_c)
    t = TARGET.get(name)
    verdict = "-" if t is None else (f"{t}x: " + ("met" if p / r >= t else "not met") + " / " +
                                     ("met" if pc / rc >= t else "not met"))
    print(f"{name:<12} {len(ms[key[0]]) if isinstance(key, tuple) else len(ms):>5} {r:>8.3f} {p:>8.3f} {p / r:>6.1f}x   {rc:>8.3f} {pc:>8.3f} {pc / rc:>6.1f}x"
          f"   {verdict}", flush=True)
print(f"# load at the end {os.getloadavg()[0]:.2f}. wall: the figures the targets name; cpu: the process's CPU time "
      "(rig: both threads, start-up and JSON included), less disturbed by other load")
