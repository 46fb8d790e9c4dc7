#!/bin/sh
# Guest side of the e-stop test: an e-stop edge (gpio-sim pull on the e-stop
# line) while `rig run --hardware` is recording must end the run with exit
# code 3 and the DUT power line low within 50 ms of the edge.
set -eu
. "$RIG_SRC/tests/kernel/guest/plant-setup.sh"
"$RIG_BIN/gpio_sim_probe" "$RIG_GPIO_CHIP" 1 0 ${RIG_ESTOP_AFTER_S:-3} > /tmp/probe.log 2>&1 &
PROBE=$!
rc=0
"$RIG_BIN/rig" run --hardware $HW --profile "$PROFILE" --out /tmp/run --yes || rc=$?
probe_rc=0
wait $PROBE || probe_rc=$?
stop_plant
cat /tmp/probe.log
cp /tmp/probe.log "$KIL_OUT/"
power=$(cat /sys/bus/gpio/devices/$RIG_GPIO_CHIP/sim_gpio0/value)
echo "rig run exit code $rc, probe $probe_rc, DUT power line now $power"
[ -f /tmp/run/passport.json ] && { grep -o '"outcome": *"[A-Z]*"' /tmp/run/passport.json | head -1; cp /tmp/run/passport.json "$KIL_OUT/"; }
[ $rc -eq 3 ] || { echo "FAIL: expected exit code 3 (aborted), got $rc"; exit 1; }
[ $probe_rc -eq 0 ] || { echo "FAIL: DUT power not off within 50 ms of the e-stop edge"; exit 1; }
[ "$power" = 0 ] || { echo "FAIL: DUT power line high after the abort"; exit 1; }
echo ESTOP-OK
