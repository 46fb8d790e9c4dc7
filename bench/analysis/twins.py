"""Straightforward vectorised NumPy twins of rig's statistics, written as a user would write
them (allantools' methods, NIST SP 1065 formulas), for bench/analysis/compare.py.

Every function takes the phase x (seconds, len N), tau0 and the averaging factors m, and
returns one deviation per m. No bounds, no noise identification: the twin's compute only.
"""
import numpy as np


def phase_from_freq(y, tau0):
    """x = cumsum(y) * tau0 with x[0] = 0 (N = len(y) + 1 phase points)."""
    return np.concatenate(([0.0], np.cumsum(y))) * tau0


def oadev(x, tau0, ms):
    """Overlapping ADEV, SP 1065 eq. 11 (allantools.oadev)."""
    out = []
    for m in ms:
        d = x[2 * m:] - 2 * x[m:-m] + x[:-2 * m]
        out.append(np.sqrt(np.sum(d * d) / (2.0 * len(d) * (m * tau0) ** 2)))
    return out


def mdev(x, tau0, ms):
    """Modified ADEV, SP 1065 eq. 14: the m-window sums of second differences, slid by a
    cumulative sum of third differences (allantools.mdev's vectorised form)."""
    out = []
    n = len(x)
    for m in ms:
        s0 = np.sum(x[2 * m:3 * m] - 2 * x[m:2 * m] + x[:m])
        e = x[3 * m:] - 3 * x[2 * m:n - m] + 3 * x[m:n - 2 * m] - x[:n - 3 * m]
        s = np.concatenate(([s0], s0 + np.cumsum(e)))
        out.append(np.sqrt(np.sum(s * s) / (2.0 * len(s) * m * m * (m * tau0) ** 2)))
    return out


def tdev(x, tau0, ms):
    """Time deviation, SP 1065 eq. 15: tau / sqrt(3) * MDEV."""
    return [m * tau0 / np.sqrt(3.0) * d for m, d in zip(ms, mdev(x, tau0, ms))]


def hdev(x, tau0, ms):
    """Hadamard deviation (non-overlapped), SP 1065 eq. 17 with stride m: the terms allantools'
    hdev() sums (calc_hdev_phase(phase, rate, mj, stride=mj): phase[3m::m] - 3 phase[2m::m] +
    3 phase[m::m] - phase[::m]); its overlapped form (stride 1) is ohdev() below, as in
    allantools. Reading N/m points per tau, it is cheap: 0.1 s for 106 taus of 3.6e6 samples."""
    out = []
    for m in ms:
        xs = x[::m]
        d = xs[3:] - 3 * xs[2:-1] + 3 * xs[1:-2] - xs[:-3]
        out.append(np.sqrt(np.sum(d * d) / (6.0 * len(d) * (m * tau0) ** 2)))
    return out


def ohdev(x, tau0, ms):
    """Overlapping Hadamard deviation, SP 1065 eq. 18 (allantools.ohdev)."""
    out = []
    n = len(x)
    for m in ms:
        d = x[3 * m:] - 3 * x[2 * m:n - m] + 3 * x[m:n - 2 * m] - x[:n - 3 * m]
        out.append(np.sqrt(np.sum(d * d) / (6.0 * len(d) * (m * tau0) ** 2)))
    return out


def totdev(x, tau0, ms):
    """Total deviation, SP 1065 eq. 25: the phase extended by odd reflection at both ends,
    then second differences centred on i = 1 .. N-2 (allantools.totdev)."""
    n = len(x)
    left = (2 * x[0] - x[1:-1])[::-1]
    right = 2 * x[-1] - x[1:-1][::-1]
    xe = np.concatenate((left, x, right))
    off = n - 2  # index of x[0] in xe
    out = []
    for m in ms:
        c = xe[off + 1:off + n - 1]
        d = xe[off + 1 - m:off + n - 1 - m] - 2 * c + xe[off + 1 + m:off + n - 1 + m]
        out.append(np.sqrt(np.sum(d * d) / (2.0 * (n - 2) * (m * tau0) ** 2)))
    return out


def welch(y, rate, segment, overlap=0.5):
    """Welch PSD with a Hann window and each segment's mean removed (scipy.signal.welch's
    defaults, one-sided density), as in rig's analysis/psd.cpp."""
    step = max(1, int(round(segment * (1 - overlap))))
    segs = np.lib.stride_tricks.sliding_window_view(y, segment)[::step]
    w = 0.5 - 0.5 * np.cos(2 * np.pi * np.arange(segment) / segment)
    spec = np.fft.rfft((segs - segs.mean(axis=1, keepdims=True)) * w, axis=1)
    p = np.mean(spec.real ** 2 + spec.imag ** 2, axis=0) / (rate * np.sum(w * w))
    p[1:-1] *= 2
    return np.fft.rfftfreq(segment, 1.0 / rate), p


DEVIATIONS = {"oadev": oadev, "mdev": mdev, "tdev": tdev, "hdev": hdev, "ohdev": ohdev, "totdev": totdev}


# ---- long-tau statistics (rig's analysis/theo.hpp). Each takes the averaging factors and the
# stride rig used per factor (its JSON's `stride`: 1, or every stride-th subsequence start
# summed), so that both compute the same statistic; raw values (no bias removal). ----

def _starts(count, stride):
    return np.arange(0, count, stride)


def theo1(x, tau0, ms, strides):
    """Theo1, SP 1065 eq. 30: sum over starts i and k = m/2 - delta of
    [(x_i + x_{i+m}) - (x_{i+k} + x_{i+m-k})]^2 / k, over 0.75 (N-m) (m tau0)^2."""
    n = len(x)
    out = []
    for m, st in zip(ms, strides):
        h = m // 2
        k = np.arange(1, h + 1)
        w = 1.0 / k
        starts = _starts(n - m, st)
        total = 0.0
        block = max(1, 4_000_000 // h)
        for b in range(0, len(starts), block):
            i = starts[b:b + block][:, None]
            d = (x[i] + x[i + m]) - x[i + k] - x[i + m - k]
            total += np.sum((d * d) @ w)
        out.append(np.sqrt(total / (0.75 * len(starts) * (m * tau0) ** 2)))
    return out


def _reflected_second_differences(v, starts, m):
    """For each start: the 3m values less their half-mean line, reflected to 9m, and the sum of
    squared second differences of m-point sums over the 6m positions (SP 1065 eqs. 27, 29)."""
    L = 3 * m
    h1, h2 = L // 2, (L + 1) // 2
    spacing = L / 2 if L % 2 == 0 else (L - 1) / 2 + 1
    j = np.arange(L)
    sums = np.empty(len(starts))
    block = max(1, 4_000_000 // (9 * m))
    for b in range(0, len(starts), block):
        s = starts[b:b + block]
        seq = v[s[:, None] + j]
        slope = (seq[:, h2:].mean(axis=1) - seq[:, :h1].mean(axis=1)) / spacing
        d = seq - slope[:, None] * j
        d -= d.mean(axis=1, keepdims=True)
        ext = np.concatenate((d[:, ::-1], d, d[:, ::-1]), axis=1)
        P = np.concatenate((np.zeros((len(s), 1)), np.cumsum(ext, axis=1)), axis=1)
        q = np.arange(6 * m)
        e = P[:, q + 3 * m] - 3 * P[:, q + 2 * m] + 3 * P[:, q + m] - P[:, q]
        sums[b:b + block] = np.sum(e * e, axis=1)
    return sums


def mtot(x, tau0, ms, strides):
    """Modified total deviation, SP 1065 eq. 27."""
    out = []
    for m, st in zip(ms, strides):
        starts = _starts(len(x) - 3 * m + 1, st)
        s = _reflected_second_differences(x, starts, m) / (m * m) / (6.0 * m)
        out.append(np.sqrt(np.sum(s) / (2.0 * (m * tau0) ** 2 * len(starts))))
    return out


def ttot(x, tau0, ms, strides):
    """Time total deviation, SP 1065 eq. 28 (tau^2/3 MTOT)."""
    return [m * tau0 / np.sqrt(3.0) * d for m, d in zip(ms, mtot(x, tau0, ms, strides))]


def htot(x, tau0, ms, strides):
    """Hadamard total deviation, SP 1065 eq. 29, on the frequencies; OHDEV at m = 1."""
    y = np.diff(x) / tau0
    out = []
    for m, st in zip(ms, strides):
        if m == 1:
            out.extend(ohdev(x, tau0, [1]))
            continue
        starts = _starts(len(y) - 3 * m + 1, st)
        s = _reflected_second_differences(y, starts, m) / (m * m) / (6.0 * m) / 6.0
        out.append(np.sqrt(np.sum(s) / len(starts)))
    return out


def theoh(x, tau0, ms, strides, estimators):
    """TheoH (Howe, Taylor & Tasset 2006): OADEV below 0.2 T, Theo1 times the TheoBR ratio
    mean_i AVAR(9+3i)/Theo1(12+4i), n = floor(0.1 N/3 - 3) (64 i spread over 0..n if more)."""
    n = len(x)
    nr = int(np.floor(0.1 * n / 3 - 3))
    idx = np.arange(nr + 1) if nr + 1 <= 64 else np.rint(np.arange(64) * nr / 63).astype(int)
    t_ms = [12 + 4 * int(i) for i in idx]
    t_st = [max(1, int(np.ceil((n - m) / max(64.0, 6e7 / (m // 2))))) if (n - m) > max(64.0, 6e7 / (m // 2)) else 1
            for m in t_ms]
    av = np.array(oadev(x, tau0, [9 + 3 * int(i) for i in idx])) ** 2
    th = np.array(theo1(x, tau0, t_ms, t_st)) ** 2
    ratio = np.mean(av / th)
    out = []
    for m, st, e in zip(ms, strides, estimators):
        out.append(oadev(x, tau0, [m])[0] if e == "avar" else np.sqrt(ratio) * theo1(x, tau0, [m], [st])[0])
    return out


LONG_TAU = {"theo1": theo1, "mtot": mtot, "ttot": ttot, "htot": htot}
