#!/bin/sh
# Guest side of the end-to-end test: `rig run --hardware` against the emulated
# plant served as a separate process, through the real SocketCAN, Modbus TCP and
# libgpiod backends. The short profile must run to completion and pass.
set -eu
. "$RIG_SRC/tests/kernel/guest/plant-setup.sh"
rc=0
"$RIG_BIN/rig" run --hardware $HW --profile "$PROFILE" --out /tmp/run --yes || rc=$?
stop_plant
echo "rig run exit code $rc"
mkdir -p "$KIL_OUT/run"
cp /tmp/run/passport.json /tmp/run/junit.xml "$KIL_OUT/run/" 2>/dev/null || true
ls -la /tmp/run || true
[ -f /tmp/run/passport.json ] || { echo "FAIL: no passport.json"; exit 1; }
grep -q '"plant": *"hardware"' /tmp/run/passport.json || { echo "FAIL: passport does not say plant = hardware"; exit 1; }
[ "$(cat /sys/bus/gpio/devices/$RIG_GPIO_CHIP/sim_gpio0/value)" = 0 ] || { echo "FAIL: DUT power left on"; exit 1; }
[ $rc -eq 0 ] || { echo "FAIL: rig run exit code $rc (expected 0: every measurement passed)"; exit 1; }
echo E2E-OK
