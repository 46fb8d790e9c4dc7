#!/usr/bin/python3
"""An independent generator of accelerometer output with known IEEE 952 terms (written by an
outside review, helper-59, 2026-12-01, from the Allan-variance relations alone, without reading
the rig's generator): sigma^2(tau) = 3Q^2/tau^2 + N^2/tau + (2 ln2/pi) B^2 + K^2 tau/3 + R^2 tau^2/2,
per-second units (Q g s, N g s^0.5, B g, K g/s^0.5, R g/s).

    gen.py SET I OUT.f64      one record of set SET, seed 590000 + 1000 set_index + I (float64 LE)

Q: white phase; N: white rate; B: FFT-shaped 1/f on twice the length (the first half kept); K:
random walk of the rate; R: a ramp; plus a 0.01 g offset. Checked by the review against the
formula with its own NumPy OADEV over 300 realisations per term: within sampling error at every
octave tau except B and K at the first 1-4 tau0 (discretisation; negligible in these sets).
Used by compare.sh (docs/analysis.md, "Long-end misfit, measured").
"""
import numpy as np, sys

def gen(n, fs, Q=0, N=0, B=0, K=0, R=0, seed=0, offset=0.01):
    rng = np.random.default_rng(seed)
    t0 = 1.0/fs
    y = np.full(n, float(offset))
    if Q:
        x = rng.standard_normal(n+1)*Q
        y += np.diff(x)/t0
    if N:
        y += rng.standard_normal(n)*N*np.sqrt(fs)
    if B:
        L = 2*n
        f = np.fft.rfftfreq(L, t0)
        h = B*B/np.pi
        S = np.zeros_like(f); S[1:] = h/f[1:]
        # white unit variance -> one-sided PSD 2/fs; scale spectrum
        W = np.fft.rfft(rng.standard_normal(L))
        Y = W*np.sqrt(S*fs/2.0)
        y += np.fft.irfft(Y, L)[:n]
    if K:
        y += np.cumsum(rng.standard_normal(n)*K*np.sqrt(t0))
    if R:
        y += R*np.arange(n)*t0
    return y
def oadev(y, fs, ms):
    t0=1.0/fs
    x = np.concatenate([[0.0], np.cumsum(y-y[:4096].mean())*t0])
    out=[]
    for m in ms:
        d = x[2*m:]-2*x[m:-m]+x[:-2*m]
        out.append(np.sqrt(np.mean(d*d)/(2*(m*t0)**2)))
    return np.array(out)
def avar_model(tau,Q=0,N=0,B=0,K=0,R=0):
    return 3*Q**2/tau**2 + N**2/tau + 2*np.log(2)/np.pi*B**2 + K**2*tau/3 + R**2*tau**2/2
SETS = {
 'S1_QN':   dict(fs=1000, hours=1, Q=3e-6, N=2e-5, B=1e-7, K=0,    R=0),
 'S2_B':    dict(fs=1000, hours=1, Q=0,    N=1e-5, B=4e-6, K=2e-8, R=0),
 'S3_K':    dict(fs=1000, hours=1, Q=0,    N=1e-5, B=2e-7, K=5e-7, R=0),
 'S4_mixed':dict(fs=1000, hours=1, Q=2e-6, N=8e-6, B=1.5e-6, K=1e-7, R=0),
 'S5_R1h':  dict(fs=1000, hours=1, Q=0,    N=1e-5, B=1e-6, K=0,    R=2e-8),
 'S6_Nonly':dict(fs=100,  hours=1, Q=0,    N=1e-5, B=0,    K=0,    R=0),
 'S7_QK':   dict(fs=100,  hours=1, Q=2e-5, N=0,    B=0,    K=1e-6, R=0),
}
ORDER = list(SETS)
def seed_of(name, i): return 590000 + 1000*ORDER.index(name) + i
if __name__ == '__main__':
    name, i, path = sys.argv[1], int(sys.argv[2]), sys.argv[3]
    p = SETS[name]; fs=p['fs']; n=int(p['hours']*3600*fs)
    y = gen(n, fs, p['Q'], p['N'], p['B'], p['K'], p['R'], seed=seed_of(name,i))
    y.astype('<f8').tofile(path)
