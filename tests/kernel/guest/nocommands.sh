#!/bin/sh
# Guest side of kernel_e2e_nocommands (issue 15, 2): `rig run --hardware` against the emulated
# plant whose firmware has no command channel ([plant.firmware] commands = false: it streams
# from power-on and answers nothing), the hardware file saying so ([dut] commands = false).
# Without --serial the run is refused at validation (exit 2, nothing opened); with it the run
# completes, the passport lists the skipped steps, and the loop figures -- null, with limits in
# the short profile -- fail it (exit 1) while everything the stream gives passes.
set -eu
RIG_PROFILE=/tmp/nocommands.toml
cat "$RIG_SRC/tests/kernel/config/kernel-short.toml" > $RIG_PROFILE
printf '\n[plant.firmware]\ncommands = false\n' >> $RIG_PROFILE
RIG_DUT_KEYS='commands = false'
. "$RIG_SRC/tests/kernel/guest/plant-setup.sh"
grep -q '^commands = false$' $HW || { echo "FAIL: hardware file without commands = false"; cat $HW; exit 1; }
grep -q 'no command channel' /tmp/plant.log || { echo "FAIL: plant serve does not say the firmware has no commands"; exit 1; }
fail() { stop_plant; echo "FAIL: $*"; exit 1; }
rc=0
"$RIG_BIN/rig" run --hardware $HW --profile "$RIG_PROFILE" --out /tmp/run0 --yes > /tmp/run0.log 2>&1 || rc=$?
cat /tmp/run0.log
[ $rc -eq 2 ] || fail "rig run without --serial exited $rc (expected 2)"
grep -q 'give it with --serial' /tmp/run0.log || fail "no reason given for refusing the run"
[ ! -e /tmp/run0 ] || fail "the refused run created its folder"
rc=0
"$RIG_BIN/rig" run --hardware $HW --profile "$RIG_PROFILE" --serial LBL-0412 --out /tmp/run --yes || rc=$?
stop_plant
echo "rig run exit code $rc"
mkdir -p "$KIL_OUT/run"
cp /tmp/run/passport.json /tmp/run/junit.xml /tmp/run/run.log "$KIL_OUT/run/" 2>/dev/null || true
P=/tmp/run/passport.json
[ -f $P ] || { echo "FAIL: no passport.json"; exit 1; }
[ $rc -eq 1 ] || { echo "FAIL: exit code $rc (expected 1: the loop figures are required and null)"; exit 1; }
grep -q '"serial": "LBL-0412"' $P || { echo "FAIL: the passport's serial is not the one given"; exit 1; }
for step in identify "set output filter" "loop test"; do
  grep -q "\"step\": \"$step\"" $P || { echo "FAIL: skipped step '$step' not in the passport"; exit 1; }
done
# FAIL three times: the run's outcome, bandwidth_0p5 and settling_time; nothing else.
[ "$(grep -c '"outcome": "FAIL"' $P)" = 3 ] || { echo "FAIL: other values than the loop figures failed"; grep -n outcome $P; exit 1; }
[ "$(grep -c 'no command channel' $P)" -ge 5 ] || { echo "FAIL: the reasons do not name the missing command channel"; exit 1; }
grep -q 'skipped: identify' /tmp/run/run.log || { echo "FAIL: run.log does not log the skipped steps"; exit 1; }
[ "$(cat /sys/bus/gpio/devices/$RIG_GPIO_CHIP/sim_gpio0/value)" = 0 ] || { echo "FAIL: DUT power left on"; exit 1; }
echo NOCOMMANDS-OK
