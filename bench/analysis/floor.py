#!/usr/bin/python3
"""What bounds the HDEV figure of compare.py (issue 17): the whole `rig analyze` process
against the NumPy twin's compute alone. Measures, alternately and on the same file, the
processes that do less and less of the work, so the part of the rig's time that is not the
deviation is measured rather than estimated:

  exec            /bin/true: the kernel's exec and exit of a minimal process
  start-up        rig --version: exec, the dynamic loader (rig's 10 shared objects since
                  2026-11-24's fifth pass; 36 before libpq was loaded on demand), static
                  initialisation and the command line; nothing read
  pass            rig analyze FILE --dev hdev --no-oadev --no-bounds --taus decade: start-up,
                  mapping the file, the engine's pass (page-in, value check, integration into
                  the whole-record phase array, whose fresh pages the kernel zeroes), six
                  non-overlapped HDEV sums (1.11 N terms), no noise identification, JSON
  hdev            the compare.py figure: --taus log:100 with bounds (106 taus)
  twin            the NumPy twin's compute alone (twins.hdev, as compare.py times it)

    /usr/bin/python3 bench/analysis/floor.py [--rig build/bin/rig] [--file y.f64] [--rounds 20]

Each row: minimum and median wall and CPU time (user + system, all threads) over the rounds.
"""
import os
import statistics
import subprocess
import sys
import time

import numpy as np

here = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, here)
import twins  # noqa: E402
from timed import bench_args, timed  # noqa: E402

ap = bench_args(20)
args = ap.parse_args()

out = "/tmp/rig-floor.json"
analyze = [args.rig, "analyze", args.file, "--input", "f64", "--rate", "1000", "--no-psd", "--json", out]
rows = {
    "exec": ["/bin/true"],
    "start-up": [args.rig, "--version"],
    "pass": analyze + ["--dev", "hdev", "--no-oadev", "--no-bounds", "--taus", "decade"],
    "hdev": analyze + ["--dev", "hdev", "--no-oadev", "--taus", "log:100"],
}


y = np.fromfile(args.file, dtype="<f8")
tau0 = 1e-3
subprocess.run(rows["hdev"], check=True, stdout=subprocess.DEVNULL)  # warm-up, and the taus
import json  # noqa: E402

ms = [p["m"] for p in json.load(open(out))["hdev"]]
res = {k: ([], []) for k in list(rows) + ["twin"]}
for _ in range(args.rounds):
    for k, cmd in rows.items():
        w, c = timed(cmd)
        res[k][0].append(w)
        res[k][1].append(c)
    t0, c0 = time.perf_counter(), time.process_time()
    twins.hdev(twins.phase_from_freq(y, tau0), tau0, ms)
    res["twin"][0].append(time.perf_counter() - t0)
    res["twin"][1].append(time.process_time() - c0)

print(f"# {time.strftime('%Y-%m-%d %H:%M')} {os.uname().nodename}, {os.cpu_count()} cores, load "
      f"{os.getloadavg()[0]:.2f}; {len(y)} values, {args.rounds} rounds")
print(f"{'row':<10} {'wall min':>9} {'wall med':>9} {'cpu min':>9} {'cpu med':>9}   (ms)")
for k, (w, c) in res.items():
    print(f"{k:<10} {1e3 * min(w):9.2f} {1e3 * statistics.median(w):9.2f} {1e3 * min(c):9.2f} "
          f"{1e3 * statistics.median(c):9.2f}")
tw, tc = min(res["twin"][0]), min(res["twin"][1])
print(f"# the best ratio a process could reach that did only the pass (no noise identification, 6 taus): "
      f"wall {tw / min(res['pass'][0]):.1f}x, cpu {tc / min(res['pass'][1]):.1f}x; start-up alone: "
      f"wall {tw / min(res['start-up'][0]):.1f}x, cpu {tc / min(res['start-up'][1]):.1f}x")
print(f"# load at the end {os.getloadavg()[0]:.2f}")
