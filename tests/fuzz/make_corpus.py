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


if __name__ == "__main__":
    main()
