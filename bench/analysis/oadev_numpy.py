#!/usr/bin/python3
"""Vectorised NumPy reference for the benchmark: overlapping Allan deviation of frequency
data via the cumulative sum (phase), for the same log-spaced taus as `rig analyze --taus log:N`.

    /usr/bin/python3 bench/analysis/oadev_numpy.py FILE.f64 [RATE_HZ] [LOG_N]

Prints the wall time of the OADEV computation (bounds not included) and a few values to
compare with rig's output.
"""
import sys
import time
import numpy as np

path = sys.argv[1]
rate = float(sys.argv[2]) if len(sys.argv) > 2 else 1000.0
log_n = int(sys.argv[3]) if len(sys.argv) > 3 else 100
y = np.fromfile(path, dtype="<f8")
n = len(y) + 1                    # phase points
top = (n - 1) // 4                # Stable32 stop ratio for OADEV
# The same grid as rig's log:N (analysis/tau_grid.cpp): log-spaced below 64,
# seeds in [64, 128) times powers of two above.
q = max(1, int(np.ceil((log_n - 1) / max(1.0, np.log2(top)))))
ms = set()
k = 0
while True:
    r = int(np.floor(2 ** (k / q) + 0.5))
    if r >= 64 or r > top:
        break
    ms.add(r)
    k += 1
for j in range(q):
    x = int(np.floor(64 * 2 ** (j / q) + 0.5))
    while x <= top:
        ms.add(x)
        x *= 2
ms = sorted(ms)

t0 = time.perf_counter()
x = np.concatenate(([0.0], np.cumsum(y - y[0])))   # phase in sample units
devs = []
for m in ms:
    d = x[2 * m:] - 2 * x[m:-m] + x[:-2 * m]
    devs.append(np.sqrt(np.mean(d * d) / (2.0 * m * m)))
t1 = time.perf_counter()
print(f"numpy oadev: n={len(y)} taus={len(ms)} wall={t1 - t0:.3f} s")
for m, d in list(zip(ms, devs))[:: max(1, len(ms) // 8)]:
    print(f"  m={m} tau={m / rate:g} s oadev={d:.6e}")
