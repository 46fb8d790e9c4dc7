#!/bin/sh
# Guest side of the operator-stop test: `rig table stop` from a second shell of this station
# while `rig run --hardware` turns the table must end the run as the operator's abort (exit 3,
# passport ABORTED naming the stop), not a hardware fault (exit 4, "halted by another master"),
# with the run's safe state (DUT power off).
set -eu
. "$RIG_SRC/tests/kernel/guest/plant-setup.sh"
# Turns slow enough (30 deg/s: a 180-degree turn in about 6.5 s) for the second shell to catch one.
sed -i 's/^velocity_dps = 180.0$/velocity_dps = 30.0/' $HW
grep -q '^velocity_dps = 30.0$' $HW || { echo "FAIL: velocity_dps not set in $HW"; cat $HW; exit 1; }
rc=0
"$RIG_BIN/rig" run --hardware $HW --profile "$PROFILE" --out /tmp/run --yes > /tmp/run.out 2>&1 &
RUN=$!
# A turn under way, after the homing (a stop during the homing ends it the same way: "homing
# halted by ..."; the turn is what the run repeats at every run of procedure A).
moving_homed() {
  s=$("$RIG_BIN/rig" table --modbus 127.0.0.1:$PORT status --json 2>/dev/null) || return 1
  echo "$s" | grep -q '"moving": true' && echo "$s" | grep -q '"homed": true'
}
i=0
until moving_homed; do
  i=$((i + 1))
  if [ $i -gt 900 ] || ! kill -0 $RUN 2>/dev/null; then
    echo "FAIL: the run's table never moved"; cat /tmp/run.out; stop_plant; exit 1
  fi
  sleep 0.1
done
"$RIG_BIN/rig" table --modbus 127.0.0.1:$PORT stop || { echo "FAIL: rig table stop"; stop_plant; exit 1; }
wait $RUN || rc=$?
stop_plant
cat /tmp/run.out
mkdir -p "$KIL_OUT/run"
cp /tmp/run/passport.json /tmp/run/run.log "$KIL_OUT/run/" 2>/dev/null || true
echo "rig run exit code $rc"
[ $rc -eq 3 ] || { echo "FAIL: expected exit code 3 (the operator's abort), got $rc"; exit 1; }
grep -q '"outcome": *"ABORTED"' /tmp/run/passport.json || { echo "FAIL: passport not ABORTED"; exit 1; }
grep -q 'aborted: moving to [0-9.]*° halted by `rig table stop` (pid [0-9]*) on this station' /tmp/run/passport.json ||
  { echo "FAIL: the passport does not name the stop"; grep -o '"aborted_reason"[^,]*' /tmp/run/passport.json; exit 1; }
if grep -q 'another master' /tmp/run/passport.json; then echo "FAIL: said as another master's halt"; exit 1; fi
[ "$(cat /sys/bus/gpio/devices/$RIG_GPIO_CHIP/sim_gpio0/value)" = 0 ] || { echo "FAIL: DUT power left on"; exit 1; }
echo OPSTOP-OK
