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
    """Hadamard deviation (non-overlapped), SP 1065 eq. 17 with stride m."""
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
