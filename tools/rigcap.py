#!/usr/bin/env python3
"""Load a rig capture file (docs/capture-format.md) into NumPy.

    from rigcap import load
    header, data, report = load("runs/demo-2026-11-23T205900Z/captures/raw-U10.cap")  # scripts/demo prints its folder
    x = data["x"]            # float32, g (unfiltered output)
    y = data["y"]            # float32, g (filtered output)
    seq, status = data["seq"], data["status"]

Damaged blocks are skipped (their CRC fails) and reported; a file whose writer
was killed is read up to its last complete block.
"""
import json
import struct
import sys
import zlib

import numpy as np

RECORD = np.dtype([("seq", "<u4"), ("x", "<f4"), ("y", "<f4"), ("status", "<u4")])
BLOCK, END = 0x314B4C42, 0x31444E45


def load(path):
    raw = open(path, "rb").read()
    if raw[:8] != b"RIGCAP1\n":
        raise ValueError(f"{path}: not a rig capture (bad magic)")
    hlen, hcrc = struct.unpack_from("<II", raw, 8)
    hjson = raw[16:16 + hlen]
    if zlib.crc32(hjson) != hcrc:
        raise ValueError(f"{path}: header CRC mismatch")
    header = json.loads(hjson)
    pos = (16 + hlen + 15) & ~15
    parts, report = [], {"complete": False, "damaged": [], "samples": 0}
    while pos + 16 <= len(raw):
        magic, count, pcrc, bcrc = struct.unpack_from("<IIII", raw, pos)
        if zlib.crc32(raw[pos:pos + 12]) != bcrc:
            report["damaged"].append(pos)
            pos += 16  # resync: blocks start on 16-byte boundaries
            continue
        if magic == END:
            report["complete"] = not report["damaged"]
            break
        payload = raw[pos + 16:pos + 16 + 16 * count]
        if len(payload) < 16 * count:
            break  # writer killed mid-block
        if zlib.crc32(payload) == pcrc:
            parts.append(np.frombuffer(payload, dtype=RECORD))
        else:
            report["damaged"].append(pos)
        pos += 16 + 16 * count
    data = np.concatenate(parts) if parts else np.zeros(0, dtype=RECORD)
    report["samples"] = int(data.size)
    return header, data, report


def _self_test(generator):
    import os
    import subprocess
    import tempfile
    with tempfile.TemporaryDirectory() as d:
        p = os.path.join(d, "t.cap")
        subprocess.run([generator, p], check=True)
        h, data, rep = load(p)
        assert h["serial"] == "PY-1" and h["orientation"] == "U20", h
        assert rep["complete"] and rep["samples"] == 2500, rep
        i = np.arange(2500)
        assert np.array_equal(data["seq"], i)
        assert np.array_equal(data["x"], (i * 0.5).astype(np.float32))
        assert np.array_equal(data["y"], (-i * 0.25).astype(np.float32))
        assert np.array_equal(data["status"], i & 1)
    print("rigcap self-test: 1 passed, 0 failed")


if __name__ == "__main__":
    if len(sys.argv) == 3 and sys.argv[1] == "--self-test":
        _self_test(sys.argv[2])
    elif len(sys.argv) == 2:
        h, d, r = load(sys.argv[1])
        print(json.dumps(h, indent=1))
        print(f"{r['samples']} samples, complete={r['complete']}, damaged blocks at {r['damaged']}")
        if d.size:
            print(f"x: mean {d['x'].mean():.6e} g  y: mean {d['y'].mean():.6e} g")
    else:
        print(__doc__)
        sys.exit(2)
