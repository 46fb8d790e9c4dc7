#!/usr/bin/python3
"""DBC files and frames written by another tool (python3-canmatrix from Debian), for
tests/link/test_dbc_canmatrix.cpp.

  canmatrix_dbc.py export DIR   writes DIR/canmatrix.dbc (Intel and Motorola, signed,
                                float32/float64, extended id, multiplexed, CAN FD 64 bytes,
                                value tables, comments, attributes, a signal group) and
                                DIR/frames.txt: frames canmatrix encoded, with their values
  canmatrix_dbc.py decode DBC   reads "ID EXT HEX" lines on stdin (frames the rig encoded)
                                and prints, per line, "name=value ..." as canmatrix decodes them

frames.txt lines: NAME ID EXT HEX name=value name=value ...
"""
import decimal
import sys

import canmatrix
import canmatrix.formats


def sig(name, start, size, little, signed=True, factor=1, offset=0, unit="", is_float=False, mux=None,
        multiplex=None):
    s = canmatrix.Signal(name, size=size, is_little_endian=little, is_signed=signed, factor=factor,
                         offset=offset, unit=unit, is_float=is_float, receivers=["RIG"])
    # DBC numbering for both byte orders: the LSB's bit (Intel) or the MSB's bit (Motorola).
    s.set_startbit(start, bitNumbering=1)
    if multiplex is not None:
        s.multiplex = multiplex
        if multiplex == "Multiplexor":
            s.is_multiplexer = True
        else:
            s.mux_val = multiplex
    return s


def build():
    db = canmatrix.CanMatrix()
    db.add_ecu(canmatrix.Ecu("DUT"))
    db.add_ecu(canmatrix.Ecu("RIG"))
    db.add_frame_defines("GenMsgCycleTime", "INT 0 65535")
    db.add_signal_defines("GenSigStartValue", "INT 0 100000")
    db.add_define_default("GenMsgCycleTime", "0")
    db.add_attribute("BusType", "CAN FD")
    db.add_global_defines("BusType", "STRING")

    intel = canmatrix.Frame("SENSOR_INTEL", arbitration_id=canmatrix.ArbitrationId(0x123, extended=False), size=8,
                            transmitters=["DUT"])
    intel.add_signal(sig("counter", 0, 16, True, signed=False))
    intel.add_signal(sig("x_counts", 16, 32, True, factor=1e-6, unit="g"))
    intel.add_signal(sig("temp", 48, 12, True, factor=0.0625, offset=-10, unit="degC"))
    st = sig("state", 60, 4, True, signed=False)
    st.add_values(0, "IDLE")
    st.add_values(1, "RUN")
    st.add_values(2, "FAULT")
    st.add_comment("operating state")
    st.add_attribute("GenSigStartValue", "1")
    intel.add_signal(st)
    intel.add_comment("Intel layout, scaled counts")
    intel.add_attribute("GenMsgCycleTime", "1")
    intel.add_signal_group("SAMPLE", 1, ["counter", "x_counts"])
    db.add_frame(intel)

    moto = canmatrix.Frame("SENSOR_MOTO", arbitration_id=canmatrix.ArbitrationId(0x18FF1234, extended=True), size=8,
                           transmitters=["DUT"])
    moto.add_signal(sig("counter", 7, 16, False, signed=False))
    moto.add_signal(sig("x_g", 23, 32, False, is_float=True, unit="g"))
    moto.add_signal(sig("small", 55, 5, False, signed=True, factor=0.5))
    moto.add_signal(sig("flag", 48, 1, False, signed=False))
    moto.add_comment("Motorola layout\nover two lines")
    db.add_frame(moto)

    mux = canmatrix.Frame("MUXED", arbitration_id=canmatrix.ArbitrationId(0x200, extended=False), size=8,
                          transmitters=["DUT"])
    mux.add_signal(sig("page", 0, 8, True, signed=False, multiplex="Multiplexor"))
    mux.add_signal(sig("a", 8, 16, True, signed=False, multiplex=0))
    mux.add_signal(sig("b", 15, 16, False, signed=True, factor=0.01, multiplex=1))
    mux.add_signal(sig("common", 32, 32, True, signed=False))
    db.add_frame(mux)

    dbl = canmatrix.Frame("DOUBLE", arbitration_id=canmatrix.ArbitrationId(0x201, extended=False), size=8,
                          transmitters=["DUT"])
    dbl.add_signal(sig("d", 0, 64, True, is_float=True))
    db.add_frame(dbl)

    fd = canmatrix.Frame("FD_BLOCK", arbitration_id=canmatrix.ArbitrationId(0x300, extended=False), size=64,
                         transmitters=["DUT"])
    fd.is_fd = True
    fd.add_signal(sig("counter", 0, 16, True, signed=False))
    for k in range(8):
        fd.add_signal(sig("x%d" % k, 32 + 32 * k, 32, True, factor=1e-7, unit="g"))
    fd.add_signal(sig("tail", 7 + 8 * 50, 16, False, signed=False))
    db.add_frame(fd)
    db.add_value_table("STATES", {0: "IDLE", 1: "RUN", 2: "FAULT"})
    return db


SAMPLES = [
    ("SENSOR_INTEL", {"counter": 65535, "x_counts": -1.234567, "temp": 25.5, "state": 2}),
    ("SENSOR_INTEL", {"counter": 7, "x_counts": 2.000001, "temp": -10, "state": 0}),
    ("SENSOR_MOTO", {"counter": 0xBEEF, "x_g": -0.5, "small": -4.0, "flag": 1}),
    ("SENSOR_MOTO", {"counter": 1, "x_g": 1.25, "small": 7.5, "flag": 0}),
    ("MUXED", {"page": 0, "a": 0x1234, "common": 4000000000}),
    ("MUXED", {"page": 1, "b": -123.45, "common": 1}),
    ("DOUBLE", {"d": -9.80665e-3}),
    ("FD_BLOCK", dict({"counter": 65534, "tail": 0xA55A}, **{"x%d" % k: (k - 3.5) * 1e-3 for k in range(8)})),
]


def export(out):
    db = build()
    canmatrix.formats.dumpp({"": db}, out + "/canmatrix.dbc")
    with open(out + "/frames.txt", "w") as f:
        for name, values in SAMPLES:
            fr = db.frame_by_name(name)
            # Frame.encode takes raw values: the physical ones go through canmatrix's phys2raw.
            data = fr.encode({k: fr.signal_by_name(k).phys2raw(decimal.Decimal(repr(v)))
                              for k, v in values.items()})
            decoded = fr.decode(data)
            vals = " ".join("%s=%r" % (k, float(v.phys_value)) for k, v in decoded.items())
            f.write("%s %d %d %s %s\n" % (name, fr.arbitration_id.id, int(fr.arbitration_id.extended),
                                          bytes(data).hex().upper(), vals))


def decode(path):
    db = canmatrix.formats.loadp_flat(path)
    for line in sys.stdin:
        parts = line.split()
        if not parts:
            continue
        fid, ext, hexdata = int(parts[0]), parts[1] == "1", parts[2]
        fr = db.frame_by_id(canmatrix.ArbitrationId(fid, extended=ext))
        decoded = fr.decode(bytearray.fromhex(hexdata))
        print(" ".join("%s=%r" % (k, float(v.phys_value)) for k, v in decoded.items()))


if __name__ == "__main__":
    if len(sys.argv) == 3 and sys.argv[1] == "export":
        export(sys.argv[2])
    elif len(sys.argv) == 3 and sys.argv[1] == "decode":
        decode(sys.argv[2])
    else:
        sys.exit(__doc__)
