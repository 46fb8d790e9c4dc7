#!/usr/bin/env python3
"""Mutated hardware files and profiles against `rig run --dry-run` (issue 13, item 5).

A fixed-seed generator edits one line of a valid file at a time. Each mutant's verdict is
known by construction from the documented keys (docs/hardware-config.md,
docs/table-registers.md, docs/profiles.md), written down here independently of the readers:
  valid   -- a value inside its documented range, an optional key removed, a comment added:
             the dry run must accept it (exit 0);
  invalid -- a value outside its range, NaN or inf, a wrong type, an unknown key or section:
             the dry run must refuse it with exit 2 and name FILE:LINE of the mutated line.
Usage: test_config_mutants.py RIG_BINARY [COUNT]   (RIG_CONFIG_MUTANTS=N overrides COUNT)"""
import math
import os
import random
import subprocess
import sys
import tempfile

SEED = 20261124

# (section, key, kind, lo, hi, base value); kind: int | num | str | bool.
HARDWARE_KEYS = [
    ("table", "modbus", "str", None, None, '"tcp:127.0.0.1:1502"'),
    ("table", "unit", "int", 1, 247, "1"),
    ("table", "response_timeout_s", "num", 0.01, 10.0, "0.3"),
    ("table", "retries", "int", 0, 10, "2"),
    ("table", "backoff_s", "num", 0.0, 10.0, "0.05"),
    ("table", "tolerance_deg", "num", 0.0, 10.0, "0.01"),
    ("table", "settle_s", "num", 0.0, 600.0, "0.5"),
    ("table", "poll_s", "num", 0.001, 10.0, "0.05"),
    ("table", "move_timeout_s", "num", 0.0, 3600.0, "0.0"),
    ("table", "home_timeout_s", "num", 0.1, 3600.0, "180.0"),
    ("table", "ack_timeout_s", "num", 0.01, 60.0, "1.0"),
    ("table", "heartbeat_timeout_s", "num", 0.05, 600.0, "2.0"),
    ("table", "velocity_dps", "num", 0.001, 4000.0, "20.0"),
    ("table", "accel_dps2", "num", 0.001, 4000.0, "40.0"),
    ("table", "in_position_window_deg", "num", 0.0001, 6.5, "0.01"),
    ("table", "drive_settle_s", "num", 0.0, 65.0, "0.2"),
    # [table] u10_deg / u20_deg are left out: never used, they must equal the angles the run turns
    # to ([procedure]'s, which these mutants move), RigCli.AnglesTheRunWouldNotUse... covers them.
    ("dut", "can", "str", None, None, '"vcan0"'),
    ("dut", "silence_ms", "num", 5.0, 60000.0, "100"),
    ("dut", "command_timeout_ms", "num", 1.0, 60000.0, "250"),
    ("dut", "command_attempts", "int", 1, 100, "3"),
    ("dut", "reorder_window", "int", 1, 4096, "8"),
    ("dut", "rcvbuf_kb", "int", 16, 1 << 20, "8192"),
    ("dut", "loop_test", "bool", None, None, "true"),
    ("gpio", "chip", "str", None, None, '"gpiochip0"'),
    ("gpio", "power", "str", None, None, '"DUT_POWER"'),
    ("gpio", "estop", "str", None, None, '"ESTOP"'),
    ("gpio", "lamp_ready", "str", None, None, '"LAMP_READY"'),
    ("gpio", "power_active_low", "bool", None, None, "false"),
    ("gpio", "estop_active_low", "bool", None, None, "true"),
    ("procedure", "u10_deg", "u10", -360.0, 360.0, "0.0"),
    ("procedure", "u20_deg", "u20", -360.0, 540.0, "180.0"),
    ("rig", "name", "str", None, None, '"bench-1"'),
    ("history", "url", "str", None, None, '"sqlite:///tmp/rig-mutants.sqlite"'),
]
# [procedure]'s angles are a pair (one alone is refused): never removed one at a time.
HARDWARE_REQUIRED = {("table", "modbus"), ("dut", "can"), ("gpio", "power"), ("gpio", "estop"),
                     ("procedure", "u10_deg"), ("procedure", "u20_deg")}

PROFILE_HEAD = 'base = "ci"\n'
PROFILE_KEYS = [
    ("profile", "name", "str", None, None, '"mutant"'),
    ("procedure", "rate_hz", "rate", 1.0, 1e6, "1000.0"),
    ("procedure", "settle_s", "num", 0.0, 1e5, "0.5"),
    ("procedure", "max_lost_samples", "int", 0, None, "0"),
    ("procedure", "retries", "int", 0, 10, "1"),
    ("table", "u10_deg", "u10", -360.0, 360.0, "0.0"),
    ("table", "u20_deg", "u20", -360.0, 540.0, "180.0"),
    ("loop", "amplitude_g", "num", -5.0, 5.0, "1.0"),
    ("loop", "steps", "int", 1, 100, "5"),
    ("loop", "record_ms", "int", 10, 200, "100"),
    ("analysis", "taus", "taus", None, None, '"log:40"'),
    ("analysis", "confidence", "num", 0.01, 0.9999, "0.68"),
    ("analysis", "r_min_record_s", "num", 0.0, None, "180000.0"),
    ("plant", "seed", "int", 0, None, "7"),
]
PROFILE_REQUIRED = {("profile", "name")}


def render(keys, head=""):
    """The file's text and the line of each (section, key)."""
    lines, where, section = [], {}, None
    for line in head.splitlines():
        lines.append(line)
    for sec, key, _, _, _, value in keys:
        if sec != section:
            lines.append(f"[{sec}]")
            section = sec
        lines.append(f"{key} = {value}")
        where[(sec, key)] = len(lines)
    return lines, where


def fmt(x, kind):
    return str(int(x)) if kind == "int" else repr(float(x))


# Kinds with a rule beyond their range: u10/u20 are the orientations' angles, which must stay
# 180° ± 10° apart (the other keeps its base value, 0 or 180); rate is a profile's rate_hz,
# which the emulated DUT (1000 Hz, docs/profiles.md) must stream -- another rate is refused on the
# emulated plant only, so it is no mutant here (RigCli.AProfileRateTheEmulatedDut... covers it).
# Out of range, each is a num.
RANGED = {"u10": "num", "u20": "num", "rate": "num"}


def valid_value(rng, kind, lo, hi):
    if kind == "u10":
        return fmt(rng.uniform(-9.9, 9.9), "num")
    if kind == "u20":
        return fmt(rng.choice([1, -1]) * rng.uniform(170.1, 189.9), "num")
    if kind == "rate":
        return rng.choice(["1000.0", "1e3", "1000"])
    if kind == "int":
        return str(rng.randint(lo, min(hi, lo + 1000)) if hi is not None else rng.randint(lo, lo + 1000))
    if kind == "num":
        top = hi if hi is not None else lo + 1e6
        return fmt(rng.uniform(lo, top), kind)
    if kind == "bool":
        return rng.choice(["true", "false"])
    if kind == "taus":
        return rng.choice(['"octave"', '"decade"', '"all"', f'"log:{rng.randint(2, 100000)}"'])
    return None  # strings keep their value (names must stay distinct, endpoints parseable)


def invalid_values(rng, kind, lo, hi):
    """Values that must be refused for a key of this kind and range."""
    out = []
    if kind in ("u10", "u20"):
        out.append(fmt(rng.uniform(20.0, 160.0) * rng.choice([1, -1]) + (0 if kind == "u10" else 180), "num"))
    kind = RANGED.get(kind, kind)
    if kind in ("int", "num"):
        if lo is not None:
            out.append(fmt(lo - (1 if kind == "int" else max(abs(lo), 1.0) * rng.uniform(0.01, 10)), kind))
        if hi is not None:
            out.append(fmt(hi + (1 if kind == "int" else max(abs(hi), 1.0) * rng.uniform(0.01, 10)), kind))
            out.append("1e7" if kind == "num" and hi < 1e7 else fmt(hi * 3 + 1, kind))
        out += ['"12"', "true", "[1, 2]"]
        if kind == "num":
            out += ["nan", "inf", "-inf"]
        if kind == "int":
            out += [fmt(lo + 0.5, "num")]
    elif kind == "bool":
        out += ["1", '"yes"']
    elif kind == "taus":
        out += ['"log:1"', '"weekly"', '"log:x"', "40"]
    else:
        out += ["1", "true", "[]"]
    return out


def mutants(rng, keys, required, head, count):
    """(text, expect_ok, line or None) triples."""
    base, where = render(keys, head)
    out = [("\n".join(base) + "\n", True, None)]
    while len(out) < count:
        sec, key, kind, lo, hi, _ = rng.choice(keys)
        line = where[(sec, key)]
        text = list(base)
        op = rng.random()
        if op < 0.3:
            v = valid_value(rng, kind, lo, hi)
            if v is None:
                continue
            text[line - 1] = f"{key} = {v}"
            out.append(("\n".join(text) + "\n", True, None))
        elif op < 0.4:
            if (sec, key) in required:
                continue
            del text[line - 1]
            out.append(("\n".join(text) + "\n", True, None))
        elif op < 0.8:
            text[line - 1] = f"{key} = {rng.choice(invalid_values(rng, kind, lo, hi))}"
            out.append(("\n".join(text) + "\n", False, line))
        elif op < 0.9:
            text.insert(line, f"{key}_typo = 1")
            out.append(("\n".join(text) + "\n", False, line + 1))
        else:
            text += ["", f"[{sec}_extra]", "x = 1"]  # at the end: the keys after stay in their section
            out.append(("\n".join(text) + "\n", False, len(text) - 1))
    return out


def run_dry(rig, args, out_dir):
    p = subprocess.run([rig, "run", *args, "--dry-run", "--out", out_dir], capture_output=True, text=True, timeout=60)
    return p.returncode, p.stderr


def main():
    rig = sys.argv[1]
    count = int(sys.argv[2]) if len(sys.argv) > 2 else 200
    # The sanitizer pass runs fewer (scripts/test): each dry run there takes ten times as long, and
    # the Release pass runs them all; the readers are fuzzed under ASan besides (tests/fuzz).
    count = int(os.environ.get("RIG_CONFIG_MUTANTS", count))
    rng = random.Random(SEED)
    failures = []
    tally = {"valid": 0, "invalid": 0}
    with tempfile.TemporaryDirectory() as d:
        out_dir = os.path.join(d, "run")
        valid_hw = os.path.join(d, "valid-hardware.toml")
        with open(valid_hw, "w") as f:
            f.write("\n".join(render(HARDWARE_KEYS)[0]) + "\n")
        for what, keys, required, head in (("hardware", HARDWARE_KEYS, HARDWARE_REQUIRED, ""),
                                           ("profile", PROFILE_KEYS, PROFILE_REQUIRED, PROFILE_HEAD)):
            path = os.path.join(d, f"mut-{what}.toml")
            for i, (text, ok, line) in enumerate(mutants(rng, keys, required, head, count)):
                with open(path, "w") as f:
                    f.write(text)
                if what == "hardware":
                    runs = [("", ["--hardware", path, "--profile", "ci"])]
                else:
                    # A profile is judged the same on both plants: its [plant] section is checked
                    # with --hardware too (a typo there must not wait for an emulated run).
                    runs = [("", ["--profile", path]), (" with --hardware", ["--profile", path, "--hardware", valid_hw])]
                for how, args in runs:
                    rc, err = run_dry(rig, args, out_dir)
                    tally["valid" if ok else "invalid"] += 1
                    if ok and rc != 0:
                        failures.append(f"{what} mutant {i}{how}: valid, refused (exit {rc}): {err.strip()}\n{text}")
                    elif not ok and (rc != 2 or f"mut-{what}.toml:{line}:" not in err):
                        failures.append(f"{what} mutant {i}{how}: invalid at line {line}, got exit {rc}: {err.strip()}\n{text}")
    print(f"{tally['valid']} valid and {tally['invalid']} invalid mutants (seed {SEED})")
    for f in failures[:10]:
        print("FAIL", f, file=sys.stderr)
    if failures:
        sys.exit(f"{len(failures)} mutant(s) judged wrongly")


if __name__ == "__main__":
    main()
