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


MAX_RATE_HZ = 1e6  # rig/capture/capture.hpp's kMaxRateHz
MIN_RATE_HZ = 1e-6  # and kMinRateHz


def _unique_keys(path):
    def pairs(kv):  # a key twice: json keeps the last, as nlohmann does; rig's reader refuses it
        seen = set()
        for k, _ in kv:
            if k in seen:
                raise ValueError(f"{path}: capture header: key '{k}' appears twice in one object")
            seen.add(k)
        return dict(kv)
    return pairs


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
    r = float(r)  # (a number beyond a double was refused while parsing, as rig's parser does)
    if not (MIN_RATE_HZ <= r <= MAX_RATE_HZ):
        raise ValueError(f"{path}: capture header rate_hz = {r:g} is out of range [{MIN_RATE_HZ:g}, {MAX_RATE_HZ:g}] Hz")


def _with_header(raw, header):
    """The capture `raw` with its header replaced (tests: a damaged or foreign header)."""
    hlen = struct.unpack_from("<I", raw, 8)[0]
    data = raw[(16 + hlen + 15) & ~15:]
    hjson = json.dumps(header).encode()
    out = raw[:8] + struct.pack("<II", len(hjson), zlib.crc32(hjson)) + hjson
    return out + b"\0" * (-len(out) % 16) + data


GAP_BEFORE = 1 << 8  # status bit: samples were lost before this one (rig/core/types.hpp)
MAX_BLOCK_SAMPLES = 1 << 20  # rig/capture/capture.hpp's kMaxBlockSamples
MAX_DOUBLE = 1.7976931348623157e308


def _number(path):
    """JSON numbers as rig's parser (nlohmann::json) takes them: beyond a double is an error
    ("number overflow"), not inf or a Python big integer."""
    def as_float(text):
        v = float(text)
        if v in (float("inf"), float("-inf")):
            raise ValueError(f"{path}: capture header is not valid JSON: number overflow parsing '{text}'")
        return v

    def as_int(text):
        v = int(text)
        if abs(v) > MAX_DOUBLE:
            raise ValueError(f"{path}: capture header is not valid JSON: number overflow parsing '{text[:20]}...'")
        return v
    return as_float, as_int


def load(path):
    """(header, data, report) as rig's own reader (rig/capture/capture.cpp, Reader) reads the
    file: report["samples"], report["complete"] and report["damaged"] (each damaged block's
    offset) are what `rig analyze FILE --input capture` says of it, and the first sample after
    a skipped block carries GAP_BEFORE in its status. report["notes"]: what else kept the file
    from being complete (a repeated block, bytes after the end marker, a count mismatch)."""
    raw = open(path, "rb").read()
    if len(raw) < 16:
        raise ValueError(f"{path}: not a rig capture (shorter than its header)")
    if raw[:8] != b"RIGCAP1\n":
        raise ValueError(f"{path}: not a rig capture (bad magic)")
    hlen, hcrc = struct.unpack_from("<II", raw, 8)
    if hlen > 1 << 20:
        raise ValueError(f"{path}: capture header length {hlen} is invalid (offset 8)")
    if 16 + hlen > len(raw):
        raise ValueError(f"{path}: capture header truncated: its length says {hlen} bytes from offset 16, "
                         f"the file has {len(raw)} bytes (a file cut short?)")
    hjson = raw[16:16 + hlen]
    if zlib.crc32(hjson) != hcrc:
        raise ValueError(f"{path}: header CRC mismatch")
    as_float, as_int = _number(path)
    header = json.loads(hjson, parse_constant=_no_constant(path), parse_float=as_float, parse_int=as_int,
                        object_pairs_hook=_unique_keys(path))
    _check_header(path, header)
    pos = (16 + hlen + 15) & ~15
    parts = []
    report = {"complete": False, "damaged": [], "samples": 0, "notes": [], "truncated": False}
    gap_pending, prev = False, None  # prev: (count, payload CRC) of the last block read

    def valid_header(p):
        m, _, _, c = struct.unpack_from("<IIII", raw, p)
        return m in (BLOCK, END) and zlib.crc32(raw[p:p + 12]) == c

    while True:
        if pos + 16 > len(raw):
            report["truncated"] = True  # the writer did not close it (killed, disk full)
            break
        magic, count, pcrc, bcrc = struct.unpack_from("<IIII", raw, pos)
        hdr_ok = zlib.crc32(raw[pos:pos + 12]) == bcrc
        if hdr_ok and magic == END:
            after = len(raw) - (pos + 16)
            if after:
                report["notes"].append(f"offset {pos + 16}: {after} bytes after the end marker (ignored)")
            n = count | (pcrc << 32)
            read = sum(p.size for p in parts)
            if n != read:
                report["notes"].append(f"end marker counts {n} samples, {read} were readable")
            report["complete"] = not report["damaged"] and not report["notes"]
            break
        if hdr_ok and magic == BLOCK and 0 < count <= MAX_BLOCK_SAMPLES:
            payload = raw[pos + 16:pos + 16 + 16 * count]
            if len(payload) < 16 * count:
                report["truncated"] = True  # writer killed mid-block
                break
            if zlib.crc32(payload) != pcrc:
                report["damaged"].append(pos)
                gap_pending = True
            elif prev == (count, pcrc):  # the same block twice: counted once
                report["notes"].append(f"offset {pos}: block of {count} samples repeats the previous block (skipped)")
            else:
                prev = (count, pcrc)
                block = np.frombuffer(payload, dtype=RECORD)
                if gap_pending:
                    block = block.copy()
                    block["status"][0] |= GAP_BEFORE
                    gap_pending = False
                parts.append(block)
            pos += 16 + 16 * count
            continue
        # A damaged block header (bad CRC, unknown magic, impossible count): one damaged block,
        # then the next valid header, 16 bytes at a time (blocks start on 16-byte boundaries).
        report["damaged"].append(pos)
        gap_pending = True
        pos += 16
        while pos + 16 <= len(raw) and not valid_header(pos):
            pos += 16
    data = np.concatenate(parts) if parts else np.zeros(0, dtype=RECORD)
    report["samples"] = int(data.size)
    return header, data, report


def _self_test(generator, rig=None):
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
               "huge rate": (dict(h, rate_hz=10**400), "not valid JSON: number overflow")}
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
        passed += _damaged_files_read_as_rig_reads_them(d, raw, rig)
    print(f"rigcap self-test: {passed} passed, 0 failed")


def _damaged_files_read_as_rig_reads_them(d, raw, rig):
    """The generator's file (blocks of 1000, 1000 and 500 samples) damaged the ways a disk or a
    killed writer damages it: this loader gives the samples, completeness, damaged blocks and gap
    flags that rig's reader gives (`rig analyze FILE --input capture`, when `rig` is given)."""
    import os
    import re
    import subprocess
    hlen = struct.unpack_from("<I", raw, 8)[0]
    blocks, pos = [], (16 + hlen + 15) & ~15
    while True:
        magic, count = struct.unpack_from("<II", raw, pos)
        if magic == END:
            end = pos
            break
        blocks.append(pos)
        pos += 16 + 16 * count
    b0, b1, b2 = blocks

    def edit(at, fn):
        out = bytearray(raw)
        fn(out, at)
        return bytes(out)

    def header(magic, count, pcrc):
        h = struct.pack("<III", magic, count, pcrc)
        return h + struct.pack("<I", zlib.crc32(h))

    def flip(out, at):
        out[at] ^= 0xFF

    cases = {  # name: (bytes, samples, complete, damaged blocks, gap flags)
        "payload CRC": (edit(b0 + 16 + 5, flip), 1500, False, 1, 1),
        "header CRC": (edit(b1 + 4, flip), 1500, False, 1, 1),
        "unknown block magic": (raw[:b1] + header(0x12345678, 1000, struct.unpack_from("<I", raw, b1 + 8)[0])
                                + raw[b1 + 16:], 1500, False, 1, 1),
        "block of 0 samples": (raw[:b1] + header(BLOCK, 0, 0) + raw[b1:], 2500, False, 1, 1),
        "repeated block": (raw[:b1] + raw[b0:b1] + raw[b1:], 2500, False, 0, 0),
        "bytes after the end": (raw + b"x" * 48, 2500, False, 0, 0),
        "killed mid-block": (raw[:b2 + 16 + 100], 2000, False, 0, 0),
        "no end marker": (raw[:end], 2500, False, 0, 0),
    }
    passed = 0
    for name, (data, samples, complete, damaged, gaps) in cases.items():
        q = _write(os.path.join(d, name.replace(" ", "-") + ".cap"), data)
        _, got, rep = load(q)
        flagged = int(np.count_nonzero(got["status"] & GAP_BEFORE))
        assert (rep["samples"], rep["complete"], len(rep["damaged"]), flagged) == (samples, complete, damaged, gaps), \
            (name, rep, flagged)
        if rig:
            out = subprocess.run([rig, "analyze", q, "--input", "capture", "--no-psd", "--taus", "octave"],
                                 capture_output=True, text=True).stdout
            m = re.search(r": (\d+) samples in \d+ blocks, (complete|INCOMPLETE)", out)
            k = re.search(r"(\d+) damaged block", out)
            assert m, (name, out)
            rig_says = (int(m.group(1)), m.group(2) == "complete", int(k.group(1)) if k else 0)
            assert rig_says == (rep["samples"], rep["complete"], len(rep["damaged"])), (name, rig_says, rep)
        passed += 1
    # Shorter than a header, or a header length past the file: refused as rig refuses them.
    for name, data, says in (("short", raw[:11], "shorter than its header"),
                             ("length", raw[:8] + struct.pack("<II", len(raw), 0) + raw[16:], "capture header truncated"),
                             ("huge", raw[:8] + struct.pack("<II", (1 << 20) + 1, 0) + raw[16:], "is invalid (offset 8)"),
                             ("cut", raw[:100], "capture header truncated: its length says")):
        try:
            load(_write(os.path.join(d, name + ".cap"), data))
            raise AssertionError(f"{name}: accepted")
        except ValueError as e:
            assert says in str(e), (name, str(e))
        passed += 1
    # A number beyond a double anywhere in the header, as rig's parser refuses it.
    h = json.loads(raw[16:16 + hlen])
    for name, value in (("1e400", "1e400"), ("a 340-digit integer", "1" * 340)):
        text = json.dumps(dict(h, extra={"table_deg": 0})).replace('"table_deg": 0', '"table_deg": ' + value)
        q = os.path.join(d, "huge.cap")
        body = raw[(16 + hlen + 15) & ~15:]
        head = raw[:8] + struct.pack("<II", len(text), zlib.crc32(text.encode())) + text.encode()
        _write(q, head + b"\0" * (-len(head) % 16) + body)
        try:
            load(q)
            raise AssertionError(f"{name} in the header: accepted")
        except ValueError as e:
            assert "number overflow" in str(e), (name, str(e))
        passed += 1
    return passed


def _write(path, raw):
    open(path, "wb").write(raw)
    return path


if __name__ == "__main__":
    if len(sys.argv) in (3, 4) and sys.argv[1] == "--self-test":
        _self_test(sys.argv[2], sys.argv[3] if len(sys.argv) == 4 else None)
    elif len(sys.argv) == 2:
        h, d, r = load(sys.argv[1])
        print(json.dumps(h, indent=1))
        print(f"{r['samples']} samples, complete={r['complete']}, damaged blocks at {r['damaged']}")
        if d.size:
            print(f"x: mean {d['x'].mean():.6e} g  y: mean {d['y'].mean():.6e} g")
    else:
        print(__doc__)
        sys.exit(2)
