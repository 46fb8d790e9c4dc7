"""One timing of a child process for the bench scripts (compare.py, floor.py): its wall time
and its CPU time (user + system, every thread), from the children's rusage around the run."""
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
