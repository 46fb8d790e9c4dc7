#!/usr/bin/env python3
"""Writes the seed corpora of the fuzz harnesses (tests/fuzz/corpus/<target>/): small valid
inputs of each format and a few near-misses, so the fuzzer starts from the real grammar.
Run: python3 tests/fuzz/make_corpus.py build/bin/make_test_capture. The output is committed; the capture
seeds come from the rig's own capture writer."""
import json
import pathlib
import shutil
import struct
import zlib

HERE = pathlib.Path(__file__).resolve().parent
ROOT = HERE.parents[1]
OUT = HERE / "corpus"


def put(target, name, data):
    d = OUT / target
    d.mkdir(parents=True, exist_ok=True)
    (d / name).write_bytes(data if isinstance(data, bytes) else data.encode())


def frame(can_id, payload, extended=False):
    rid = can_id | (1 << 31 if extended else 0)
    return struct.pack("<IB", rid, len(payload)) + payload.ljust(8, b"\0")


def half(can_id, seq, status, value):
    return frame(can_id, struct.pack("<I", seq & 0xFFFFFF)[:3] + bytes([status]) + struct.pack("<f", value))


def can_stream():
    ok = b"".join(half(0x100, s, 1, 0.001 * s) + half(0x101, s, 1, 0.002 * s) for s in range(20))
    put("can_stream", "in_order", b"\x07" + ok)
    swapped = b"".join(half(0x101, s, 0, 1.0) + half(0x100, s, 0, 1.0) for s in (0, 2, 1, 3, 5, 4))
    put("can_stream", "reordered", b"\x03" + swapped)
    wrap = b"".join(half(c, s, 0, 0.5) for s in (0xFFFFFE, 0xFFFFFF, 0, 1) for c in (0x100, 0x101))
    put("can_stream", "wrap24", b"\x01" + wrap)
    gap = b"".join(half(c, s, 0, 0.5) for s in (10, 11, 40, 41, 41) for c in (0x100, 0x101))
    put("can_stream", "gap_dup", b"\x05" + gap)
    other = frame(0x011, bytes([1, 7, 0, 0, 1, 0, 0, 0])) + frame(0x700, bytes([1, 2, 0x10, 0x09, 5, 0, 0, 0]))
    put("can_stream", "response_heartbeat", b"\x00" + other + frame(0x100, b"\x01\x02"))


def dbc():
    put("dbc", "rig-dut.dbc", (ROOT / "docs" / "rig-dut.dbc").read_bytes())
    put("dbc", "minimal.dbc", 'VERSION ""\nBU_: DUT\nBO_ 256 X: 8 DUT\n SG_ seq : 0|24@1+ (1,0) [0|16777215] "" Vector__XXX\n SG_ x : 32|32@1- (1,0) [-12|12] "g" Vector__XXX\nSIG_VALTYPE_ 256 x : 1;\n')
    # Real-world syntax: every section of the format, and a file canmatrix exported.
    put("dbc", "hand_written.dbc", (ROOT / "tests" / "data" / "dbc" / "hand_written.dbc").read_bytes())
    put("dbc", "canmatrix.dbc", (ROOT / "tests" / "data" / "dbc" / "canmatrix.dbc").read_bytes())
    put("dbc", "missing_semicolon.dbc", 'BO_ 256 M: 8 DUT\n SG_ a : 0|8@1+ (1,0) [0|1] "" X\nCM_ SG_ 256 a "x"\nVAL_ 256 a 1 "one";\n')
    put("dbc", "motorola_ext.dbc", 'BO_ 2164260864 EXT: 8 DUT\n SG_ cnt : 7|16@0+ (1,0) [0|65535] "" Vector__XXX\n SG_ v : 23|32@0- (0.001,-5) [0|0] "g" Vector__XXX\nCM_ SG_ 2164260864 v "value";\n')


def capture(make_test_capture):
    """Seeds from the rig's own writer (tests/core/make_test_capture): a complete file, the
    same cut mid-block (a writer killed), and one with a payload byte flipped (CRC damage)."""
    import subprocess, tempfile
    with tempfile.TemporaryDirectory() as t:
        cap = pathlib.Path(t) / "c.cap"
        subprocess.run([make_test_capture, str(cap)], check=True)
        whole = cap.read_bytes()
    put("capture", "complete.cap", whole)
    put("capture", "truncated.cap", whole[: len(whole) * 2 // 3])
    damaged = bytearray(whole)
    damaged[len(whole) // 2] ^= 0x40
    put("capture", "damaged.cap", bytes(damaged))


HARDWARE = """[rig]
name = "line-2-rig-1"

[table]
modbus = "tcp:192.0.2.10:502"
unit = 1
response_timeout_s = 0.3
retries = 2
tolerance_deg = 0.01
velocity_dps = 20.0

[dut]
can = "can0"
loop_test = true
silence_ms = 100
command_timeout_ms = 250

[gpio]
chip = "gpiochip0"
power = "DUT_POWER"
estop = "ESTOP"
lamp_ready = "LAMP_READY"
lamp_running = "LAMP_RUN"
lamp_pass = "LAMP_PASS"
lamp_fail = "LAMP_FAIL"

[procedure]
u10_deg = 0.0
u20_deg = 180.0

[history]
url = "sqlite:///var/lib/rig/history.sqlite"
"""


def hardware():
    """Hardware files: the documented one, the partial files of rig table / rig dut, an RTU
    table, and near-misses (a range, a type, an unknown key)."""
    put("hardware", "documented.toml", HARDWARE)
    put("hardware", "table_only.toml", '[table]\nrtu = "/dev/ttyUSB0,115200,N,8,1"\nunit = 247\n')
    put("hardware", "dut_only.toml", '[dut]\ncan = "vcan0"\nreorder_window = 64\nrcvbuf_kb = 1024\n')
    put("hardware", "unit_range.toml", HARDWARE.replace("unit = 1", "unit = -1"))
    put("hardware", "timeout_type.toml", HARDWARE.replace("response_timeout_s = 0.3", 'response_timeout_s = "fast"'))
    put("hardware", "unknown_key.toml", HARDWARE.replace("[procedure]", "[procedure]\nu30_deg = 1"))


def modbus():
    """Drive behaviour scripts (tests/fuzz/fuzz_modbus.cpp): byte 0 picks the client (even
    rig-v1, odd CiA 402), then calls and replies interleave; past the end the drive is silent."""
    regs = lambda words: b"".join(struct.pack("<H", w & 0xFFFF) for w in words)
    ready = [0, 0x0007, 0, 0] + [0] * 40  # a status block: ready, servo on, homed
    put("modbus", "status_rig_v1", b"\x00" + b"\x00" + b"\x02" + regs(ready))
    put("modbus", "move_rig_v1", b"\x00" + b"\x02" + struct.pack("<h", 90 * 64) + (b"\x02" + regs(ready)) * 6)
    put("modbus", "timeouts", b"\x00\x01\x10\x10\x10\x02\x00\x00\x11")
    put("modbus", "cia402_status", b"\x01" + b"\x00" + b"\x02" + regs([0x0237, 0, 0, 0, 0, 0, 0, 0] * 4))
    put("modbus", "cia402_home", b"\x01" + b"\x01" + (b"\x02" + regs([0x1637] + [0] * 15)) * 8)


def analyze_input(make_test_capture):
    """rig analyze's files behind a selector byte: 0 text, 1 float64 mapped, 2 float64 read in
    chunks, 3 a capture's x channel (7: its y)."""
    import subprocess, tempfile
    put("analyze_input", "text.txt", b"\x00" + b"# bias, g\n1.5e-3\n -2.25e-3 ,\n+4e-4;\n\n1e-310\n")
    put("analyze_input", "text_bad.txt", b"\x00" + b"0x10\ninf\n1e400\n")
    values = struct.pack("<6d", 1e-3, -2e-3, 0.0, 5e-324, 1e99, -7.5)
    put("analyze_input", "f64_mapped.bin", b"\x01" + values)
    put("analyze_input", "f64_pread.bin", b"\x02" + values + struct.pack("<d", float("nan")))
    with tempfile.TemporaryDirectory() as t:
        cap = pathlib.Path(t) / "c.cap"
        subprocess.run([make_test_capture, str(cap)], check=True)
        put("analyze_input", "capture_x.cap", b"\x03" + cap.read_bytes())


def candump():
    """Every format candump_log.hpp documents, and lines it must refuse with a reason."""
    put("candump", "log_format.log", "(1700000000.123456) vcan0 100#563412050000803F\n"
        "(1700000000.124456) can0 101#56341205 R\n(1700000000.125) vcan0 1FFFFFFF#00\n")
    put("candump", "cansend.log", "100#563412050000803F\n010#R\n12345678#0102\n# comment\n\n")
    put("candump", "screen.log", "(1700000000.123456)  vcan0  100   [8]  56 34 12 05 00 00 80 3F\n"
        "  vcan0  010   [0]  remote request\n  vcan0  7FF   [2]  01 02   '..'\n")
    put("candump", "bad.log", "vcan0 100##0102\n(x) vcan0 100#01\n100#0G\n800#01\n100#010203040506070809\n(1.0) vcan0 100#01")


def main():
    import sys
    if len(sys.argv) != 2:
        sys.exit("usage: make_corpus.py PATH/TO/make_test_capture")
    if OUT.exists():
        shutil.rmtree(OUT)
    capture(sys.argv[1])
    can_stream()
    dbc()
    for p in ("ci", "paper"):
        put("profile", p + ".toml", (ROOT / "profiles" / (p + ".toml")).read_text())
    put("profile", "based.toml", 'base = "ci"\n[profile]\nname = "short"\n[procedure]\nrun_s = 1\n')
    put("profile", "bad_type.toml", '[profile]\nname = 3\n')
    put("profile", "bad_taus.toml", 'base = "ci"\n[profile]\nname = "t"\n[analysis]\ntaus = "log:1"\n')
    hardware()
    modbus()
    analyze_input(sys.argv[1])
    candump()


if __name__ == "__main__":
    main()
