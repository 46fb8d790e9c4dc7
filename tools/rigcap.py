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


MAX_RATE_HZ = 1e6  # rig/capture/capture.cpp's kMaxRateHz


def _no_constant(path):
    def refuse(name):  # NaN, Infinity: not JSON, and rig's reader refuses them
        raise ValueError(f"{path}: capture header is not valid JSON: {name}")
    return refuse


def _check_header(path, h):
    """What the samples mean is stated, never guessed, as rig's own reader does
    (docs/capture-format.md): a format it does not know, units other than g, or no rate
    (a rate guessed as 1000 Hz would put every tau off by the true rate's ratio) are refused."""
    if not isinstance(h, dict):
        raise ValueError(f"{path}: capture header is not a JSON object")
    for k in ("serial", "phase", "orientation", "started", "units"):
        if k in h and not isinstance(h[k], str):
            raise ValueError(f"{path}: capture header field {k} is {json.dumps(h[k])}, not a string")
    if "format" in h and h["format"] != "rig.capture/1":
        raise ValueError(f"{path}: capture header format is {json.dumps(h['format'], ensure_ascii=False)}, "
                         "not \"rig.capture/1\" (written by another program or version?)")
    if h.get("units", "g") != "g":
        raise ValueError(f"{path}: capture header units is {json.dumps(h['units'], ensure_ascii=False)}, not \"g\" "
                         "(a rig capture's samples are in g)")
    if "rate_hz" not in h:
        raise ValueError(f"{path}: capture header has no rate_hz (the samples' rate, Hz)")
    r = h["rate_hz"]
    if isinstance(r, bool) or not isinstance(r, (int, float)):
        raise ValueError(f"{path}: capture header field rate_hz is {json.dumps(r)}, not a number")
    try:
        r = float(r)
    except OverflowError:  # an integer beyond any double: rig's JSON parser says "number overflow"
        raise ValueError(f"{path}: capture header is not valid JSON: rate_hz beyond the range of a double") from None
    if not (0 < r <= MAX_RATE_HZ):
        raise ValueError(f"{path}: capture header rate_hz = {r:g} is out of range (0, {MAX_RATE_HZ:g}] Hz")


def _with_header(raw, header):
    """The capture `raw` with its header replaced (tests: a damaged or foreign header)."""
    hlen = struct.unpack_from("<I", raw, 8)[0]
    data = raw[(16 + hlen + 15) & ~15:]
    hjson = json.dumps(header).encode()
    out = raw[:8] + struct.pack("<II", len(hjson), zlib.crc32(hjson)) + hjson
    return out + b"\0" * (-len(out) % 16) + data


def load(path):
    raw = open(path, "rb").read()
    if raw[:8] != b"RIGCAP1\n":
        raise ValueError(f"{path}: not a rig capture (bad magic)")
    hlen, hcrc = struct.unpack_from("<II", raw, 8)
    hjson = raw[16:16 + hlen]
    if zlib.crc32(hjson) != hcrc:
        raise ValueError(f"{path}: header CRC mismatch")
    header = json.loads(hjson, parse_constant=_no_constant(path))
    _check_header(path, header)
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
        passed = 1
        raw = open(p, "rb").read()
        bad = {"no rate": ({k: v for k, v in h.items() if k != "rate_hz"}, "has no rate_hz"),
               "rate as text": (dict(h, rate_hz="1000"), 'rate_hz is "1000", not a number'),
               "rate 0": (dict(h, rate_hz=0), "rate_hz = 0 is out of range"),
               "format": (dict(h, format="other/2"), 'format is "other/2"'),
               "units": (dict(h, units="\u00b5g"), 'units is "\u00b5g", not "g"'),
               "serial": (dict(h, serial=5), "field serial is 5, not a string"),
               "NaN": (dict(h, extra={"t": float("nan")}), "not valid JSON: NaN"),
               "huge rate": (dict(h, rate_hz=10**400), "rate_hz beyond the range of a double")}
        for name, (header, says) in bad.items():
            q = os.path.join(d, "bad.cap")
            open(q, "wb").write(_with_header(raw, header))
            try:
                load(q)
                raise AssertionError(f"{name}: accepted")
            except ValueError as e:
                assert str(e).startswith(q + ": ") and says in str(e), (name, str(e))
            passed += 1
        h2, data2, rep2 = load(_write(os.path.join(d, "same.cap"), _with_header(raw, h)))
        assert h2 == h and rep2 == rep and np.array_equal(data2, data), "rewriting the header moved the samples"
        passed += 1
    print(f"rigcap self-test: {passed} passed, 0 failed")


def _write(path, raw):
    open(path, "wb").write(raw)
    return path


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
