"""What the bench scripts (compare.py, floor.py) share: one timing of a child process, its wall
time and its CPU time (user + system, every thread), from the children's rusage around the run;
their common command-line options; and the `rig analyze` rows they time."""
import argparse
import resource
import subprocess
import time


def timed(cmd):
    """Run cmd (stdout discarded, failure raises); return (wall s, cpu s)."""
    r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
    wall = time.perf_counter() - t0
    r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    return wall, (r1.ru_utime - r0.ru_utime) + (r1.ru_stime - r0.ru_stime)


def bench_args(rounds):
    """The options every bench script takes: the rig under test, the record, the rounds."""
    ap = argparse.ArgumentParser()
    ap.add_argument("--rig", default="build/bin/rig")
    ap.add_argument("--file", default="/tmp/rig-bench-1h.f64")
    ap.add_argument("--rounds", type=int, default=rounds)
    return ap


# The deviations timed alone (each with `--no-oadev`), besides OADEV with and without the PSD.
DEVIATIONS = ["mdev", "tdev", "hdev", "ohdev", "totdev"]


def analyze_rows():
    """[(row, rig analyze's extra arguments)]: OADEV without and with the PSD, then each of
    DEVIATIONS alone (the figures issue 17 names)."""
    rows = [("oadev", ["--no-psd"]), ("oadev+psd", [])]
    return rows + [(d, ["--no-psd", "--dev", d, "--no-oadev"]) for d in DEVIATIONS]
