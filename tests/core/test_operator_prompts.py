#!/usr/bin/env python3
"""The technician's run on a real pseudo-terminal: `rig run` asks before it
starts (DUT mounted, serial, table clear), after printing the plan; 'y' to
each proceeds, 'n' aborts with exit 3 before anything moves. Usage: test_operator_prompts.py RIG_BINARY"""
import os
import re
import pty
import select
import shutil
import sys
import tempfile


def run_with_answers(rig, args, answers, env, timeout=120, stderr_file=None):
    pid, fd = pty.fork()
    if pid == 0:
        if stderr_file:  # `rig run ... 2> FILE` typed at the terminal
            os.dup2(os.open(stderr_file, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o644), 2)
        os.execve(rig, [rig] + args, env)
    out, sent = b"", 0
    while True:
        ready, _, _ = select.select([fd], [], [], timeout)
        if not ready:
            os.kill(pid, 9)
            raise AssertionError("timed out; output so far:\n" + out.decode(errors="replace"))
        try:
            chunk = os.read(fd, 4096)
        except OSError:  # the child closed the terminal
            break
        if not chunk:
            break
        out += chunk
        if sent < len(answers) and out.count(b"[y/N]") > sent:
            os.write(fd, answers[sent].encode() + b"\n")
            sent += 1
    _, status = os.waitpid(pid, 0)
    return os.waitstatus_to_exitcode(status), out.decode(errors="replace")


def main():
    rig = sys.argv[1]
    d = tempfile.mkdtemp(prefix="rig-prompts-")
    env = dict(os.environ, RIG_HISTORY="sqlite:" + os.path.join(d, "history.sqlite"))
    passed = failed = 0
    try:
        # An answer that is neither yes nor no is asked again ("yet to fasten" confirmed a mount).
        for answers, want_rc, want_text, made in ((["y", "y", "y"], 0, "OUTCOME: PASS", False),
                                                  (["y", "n"], 3, "did not confirm the serial", False),
                                                  (["n"], 3, "did not confirm the DUT is mounted: nothing was "
                                                   "powered or moved; give the same command again when ready", True),
                                                  (["yet to fasten", "yess", " No "], 3,
                                                   "Answer y (yes) or n (no). Is the DUT mounted", False),
                                                  (["maybe", " YES", "Y", "yes"], 0, "OUTCOME: PASS", False)):
            out_dir = os.path.join(d, f"run-exit{want_rc}-{len(answers)}-{answers[0].strip()}")
            if made:  # a folder the operator made beforehand stays after a "no"
                os.mkdir(out_dir)
            rc, out = run_with_answers(rig, ["run", "--profile", "ci", "--serial", "EMU-QPA-0001", "--out", out_dir],
                                       answers, env)
            ok = rc == want_rc and want_text in out and out.count("[y/N]") == len(answers)
            # The plan comes before the first question, whatever the answers.
            ok = ok and 0 <= out.find("Plan: ") < out.find("[y/N]")
            # A run typed without --hardware says, before the first question, that it is the emulated plant.
            ok = ok and 0 <= out.find("EMULATED PLANT: no device on the bench is touched") < out.find("[y/N]")
            if want_rc == 3:  # nothing ran: not even its empty folder is left, unless the operator made it
                ok = ok and (os.path.isdir(out_dir) and not os.listdir(out_dir) if made else not os.path.exists(out_dir))
            else:  # the prompt's device time is the plan's (it was the profile's own estimate)
                asked = re.search(r"Device time (\d\d:\d\d:\d\d)\.", out)
                plan = re.search(r"Plan: \d+ phases, (\d\d:\d\d:\d\d) of device time", out)
                ok = ok and asked is not None and plan is not None and asked.group(1) == plan.group(1)
            print(f"{'ok' if ok else 'FAIL'}: answers {answers} -> exit {rc}")
            if ok:
                passed += 1
            else:
                failed += 1
                print(out[-3000:])
        # stderr sent to a file at the terminal: the questions still reach the operator, on the
        # controlling terminal (they went to the file, and the run waited on answers nobody saw).
        err = os.path.join(d, "stderr.txt")
        rc, out = run_with_answers(rig, ["run", "--profile", "ci", "--serial", "EMU-QPA-0001", "--out",
                                         os.path.join(d, "run-stderr-to-file")], ["y", "y", "y"], env, stderr_file=err)
        with open(err) as f:
            logged = f.read()
        ok = rc == 0 and out.count("[y/N]") == 3 and "EMULATED PLANT" in out and "OUTCOME: PASS" in out
        ok = ok and "[y/N]" not in logged and "Plan: " in logged
        print(f"{'ok' if ok else 'FAIL'}: stderr to a file -> exit {rc}, questions on the terminal")
        if ok:
            passed += 1
        else:
            failed += 1
            print(out[-3000:], logged[-2000:])
    finally:
        shutil.rmtree(d, ignore_errors=True)
    print(f"{passed} passed, {failed} failed")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
