#!/usr/bin/python3
"""A third-party Modbus master (pymodbus, Debian's python3-pymodbus) drives the
emulated CiA 402 drive through the state machine to a homing run and a move,
knowing nothing but docs/cia402-drive-maps.md and drives/generic-cia402.toml.
Usage: cia402_pymodbus.py HOST PORT. Exit 0 and "OK ..." on success."""
import sys
import time

from pymodbus.client import ModbusTcpClient

# drives/generic-cia402.toml: holding registers, 0-based, 32-bit high word first.
CONTROLWORD, STATUSWORD, ERROR_CODE, MODES, MODES_DISPLAY = 0, 1, 2, 3, 4
POSITION_ACTUAL, TARGET_POSITION, HOMING_METHOD = 5, 9, 19
COUNTS_PER_DEG = 131072 * 90 / 360


def fail(msg):
    print("FAIL " + msg)
    sys.exit(1)


def main():
    c = ModbusTcpClient(sys.argv[1], port=int(sys.argv[2]))
    if not c.connect():
        fail("cannot connect")

    def read(addr, n=1):
        r = c.read_holding_registers(addr, n, slave=1)
        if r.isError():
            fail("read %d: %s" % (addr, r))
        return r.registers

    def write(addr, value):
        r = c.write_register(addr, value, slave=1)
        if r.isError():
            fail("write %d: %s" % (addr, r))

    def statusword():
        return read(STATUSWORD)[0]

    def wait(pred, what, timeout=30.0):
        t0 = time.time()
        while time.time() - t0 < timeout:
            s = statusword()
            if pred(s):
                return s
            time.sleep(0.01)
        fail("%s: statusword 0x%04X" % (what, statusword()))

    def i32(words):
        v = (words[0] << 16) | words[1]
        return v - (1 << 32) if v & 0x80000000 else v

    # Section 2 of the map page: 0x4F -> 0x40, then 0x6F -> 0x21, 0x23, 0x27.
    wait(lambda s: s & 0x4F == 0x40, "switch on disabled")
    write(CONTROLWORD, 0x0006)
    wait(lambda s: s & 0x6F == 0x21, "ready to switch on")
    write(CONTROLWORD, 0x0007)
    wait(lambda s: s & 0x6F == 0x23, "switched on")
    write(CONTROLWORD, 0x000F)
    wait(lambda s: s & 0x6F == 0x27, "operation enabled")
    # Homing (mode 6): bit 4 start, bits 12 + 10 attained.
    write(MODES, 6)
    t0 = time.time()
    while read(MODES_DISPLAY)[0] != 6:
        if time.time() - t0 > 2:
            fail("modes display")
    write(HOMING_METHOD, 19)
    write(CONTROLWORD, 0x001F)
    wait(lambda s: s & 0x1400 == 0x1400 or s & 0x2000, "homing attained")
    if statusword() & 0x2000:
        fail("homing error")
    write(CONTROLWORD, 0x000F)
    # Profile position (mode 1): target, new set-point, acknowledge, target reached.
    write(MODES, 1)
    target = int(round(-45.0 * COUNTS_PER_DEG))
    words = [(target >> 16) & 0xFFFF, target & 0xFFFF]
    r = c.write_registers(TARGET_POSITION, words, slave=1)
    if r.isError():
        fail("target: %s" % r)
    write(CONTROLWORD, 0x001F)
    wait(lambda s: s & 0x1000, "set-point acknowledge")
    write(CONTROLWORD, 0x000F)
    wait(lambda s: not s & 0x1000, "acknowledge dropped")
    wait(lambda s: s & 0x0400, "target reached")
    pos = i32(read(POSITION_ACTUAL, 2))
    if abs(pos - target) > COUNTS_PER_DEG * 0.01:
        fail("position %d, target %d" % (pos, target))
    if read(ERROR_CODE)[0] != 0:
        fail("error code")
    print("OK position_actual %d counts = %.4f deg" % (pos, pos / COUNTS_PER_DEG))
    c.close()


main()
