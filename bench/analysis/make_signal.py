#!/usr/bin/python3
"""Writes a synthetic accelerometer record (raw little-endian float64, g) for the benchmarks:
bias + white noise (N) + flicker (B) + random walk of rate (K), at 1 kHz.

    /usr/bin/python3 bench/analysis/make_signal.py OUT.f64 N_SAMPLES [SEED]

Generated in blocks so that the 1.8e8-sample (50 h, 1.44 GB) file needs little memory.
The flicker component is a sum of a few first-order Markov processes (time constants
spread over decades), which gives a ~1/f band between 0.1 s and 1e4 s.
"""
import sys
import numpy as np

out, n = sys.argv[1], int(float(sys.argv[2]))
rng = np.random.default_rng(int(sys.argv[3]) if len(sys.argv) > 3 else 1)
rate = 1000.0
tau0 = 1.0 / rate
N = 2.2306e-7 * 60       # g*s^0.5 (paper: 2.2306e-7 g*h^0.5)
K = 5.1167e-6 / 60       # g/s^0.5 (paper: 5.1167e-6 g/h^0.5)
B = 2.1e-6               # g
bias = -5.0137e-4
taus = np.logspace(-1, 4, 6)          # Markov time constants, s
a = np.exp(-tau0 / taus)
# Each Markov process contributes a Lorentzian; equal power per decade gives flicker.
sig = B * 0.6 * np.sqrt(1 - a * a)
state = np.zeros(len(taus))
rw = 0.0
block = 1 << 20
with open(out, "wb") as f:
    done = 0
    while done < n:
        m = min(block, n - done)
        y = bias + N / np.sqrt(tau0) * rng.standard_normal(m)
        # random walk of the rate: increments K*sqrt(tau0) per sample
        walk = rw + np.cumsum(K * np.sqrt(tau0) * rng.standard_normal(m))
        rw = walk[-1]
        y += walk
        for k in range(len(taus)):
            e = sig[k] * rng.standard_normal(m)
            # first-order recursion s[i] = a s[i-1] + e[i], vectorised through lfilter-free scan
            s = np.empty(m)
            prev = state[k]
            ak = a[k]
            # blockwise closed form: s = a^i * prev + conv(e, a^j) -- use cumulative trick in chunks
            c = 4096
            for j in range(0, m, c):
                ee = e[j:j + c]
                p = ak ** np.arange(1, len(ee) + 1)
                s[j:j + c] = p * (prev + np.cumsum(ee / p))
                prev = s[j + len(ee) - 1]
            state[k] = prev
            y += s
        y.astype("<f8").tofile(f)
        done += m
