#!/bin/sh
# Guest side of kernel_layouts (issue 15, 4), on a CAN FD vcan (mtu 72):
#  1. the firmware emulator streams duts/qpa-counts.dbc (int24 counts, big-endian, 16-bit
#     counter, extended id, x and y in one frame); `rig run --hardware` records and analyses it
#     through [dut.stream] and passes with 0 lost samples; candump logs the session (-L), and
#     `rig capture import` of that log holds the live raw capture sample for sample;
#  2. the firmware emulator streams duts/qpa-fd.dbc (7 samples per 64-byte CAN FD frame);
#     `rig dut stream` reads it with 0 gaps and candump's log of it imports with 0 lost.
set -eu
DUTS=$RIG_SRC/duts
RIG_VCAN_FD=1
RIG_PROFILE=/tmp/counts.toml
COUNTS_STREAM='counter = "QPA_XY.cnt"
x = "QPA_XY.x_counts"
y = "QPA_XY.y_counts"'
{ cat "$RIG_SRC/tests/kernel/config/kernel-short.toml"
  printf '\n[plant.firmware]\ndbc = "%s/qpa-counts.dbc"\n[plant.firmware.stream]\n%s\n' "$DUTS" "$COUNTS_STREAM"; } > $RIG_PROFILE
RIG_DUT_KEYS="dbc = \"$DUTS/qpa-counts.dbc\""
RIG_HW_TAIL="[dut.stream]
$COUNTS_STREAM"
# Every frame of the session, as candump logs it (-L: the log format on stdout).
candump_start() {
  candump -L -r 16777216 vcan0 > "$1" &
  DUMP=$!
  sleep 0.5
}
candump_stop() { sleep 0.5; kill $DUMP; wait $DUMP 2>/dev/null || true; }
. "$RIG_SRC/tests/kernel/guest/plant-setup.sh"
[ "$(cat /sys/class/net/vcan0/mtu)" = 72 ] || { stop_plant; echo "FAIL: vcan0 is not CAN FD (mtu $(cat /sys/class/net/vcan0/mtu))"; exit 1; }
candump_start /tmp/counts.log
rc=0
"$RIG_BIN/rig" run --hardware $HW --profile "$RIG_PROFILE" --out /tmp/run --yes || rc=$?
candump_stop
stop_plant
echo "rig run exit code $rc; candump: $(wc -l < /tmp/counts.log) frames logged"
echo "softnet_stat dropped per cpu: $(awk '{print $2}' /proc/net/softnet_stat | tr '\n' ' ')"
mkdir -p "$KIL_OUT/run"
cp /tmp/run/passport.json /tmp/run/run.log "$KIL_OUT/run/" 2>/dev/null || true
[ $rc -eq 0 ] || { echo "FAIL: rig run on the counts layout exited $rc (expected 0)"; exit 1; }
grep -q '18FF1000#' /tmp/counts.log || { echo "FAIL: no QPA_XY frame (18FF1000) in the log"; head /tmp/counts.log; exit 1; }
rc=0
"$RIG_BIN/rig" capture import /tmp/counts.log --hardware $HW --out /tmp/imported.rigcap > /tmp/import.out 2>&1 || rc=$?
cat /tmp/import.out
[ $rc -eq 0 ] || { echo "FAIL: rig capture import exited $rc"; exit 1; }
rc=0
RIG_LIVE_CAPTURE=/tmp/run/captures/raw-U10.cap RIG_IMPORTED_CAPTURE=/tmp/imported.rigcap RIG_RUN_LOG=/tmp/run/run.log \
  "$RIG_BIN/test_kernel_layouts" --gtest_filter='KernelLayouts.CountsSession*' \
  --gtest_output="xml:$KIL_OUT/test_kernel_layouts_counts.xml" || rc=$?
[ $rc -eq 0 ] || { echo "FAIL: the imported log does not hold the live capture"; exit 1; }

# 2. CAN FD: seven samples per frame, read live by the rig's link and from candump's log.
FD_STREAM='counter = "QPA_FD.cnt"
x = "QPA_FD.x"
y = "QPA_FD.y"
status = "QPA_FD.status"
filter_on_bit = 0
saturated_bit = 1
loop_fault_bit = 2
samples_per_frame = 7'
{ cat "$RIG_SRC/tests/kernel/config/kernel-short.toml"
  printf '\n[plant.firmware]\ndbc = "%s/qpa-fd.dbc"\n[plant.firmware.stream]\n%s\n' "$DUTS" "$FD_STREAM"; } > /tmp/fd.toml
printf '[dut]\ncan = "vcan0"\nsilence_ms = 1000\ncommand_timeout_ms = 500\ndbc = "%s/qpa-fd.dbc"\n[dut.stream]\n%s\n' \
  "$DUTS" "$FD_STREAM" > /tmp/hw-fd.toml
"$RIG_BIN/rig" plant serve --can vcan0 --profile /tmp/fd.toml --duration 120 > /tmp/serve-fd.log 2>&1 &
SERVE=$!
i=0
until grep -q serving /tmp/serve-fd.log; do
  i=$((i + 1)); [ $i -lt 600 ] && kill -0 $SERVE 2>/dev/null || { cat /tmp/serve-fd.log; echo "FAIL: plant serve (FD)"; exit 1; }
  sleep 0.1
done
candump_start /tmp/fd.log
rc=0
"$RIG_BIN/rig" dut stream --hardware /tmp/hw-fd.toml --count 14000 --out /tmp/fd-stream.txt 2> /tmp/fd-stream.err || rc=$?
candump_stop
kill $SERVE; wait $SERVE 2>/dev/null || true
cat /tmp/fd-stream.err
cp /tmp/serve-fd.log "$KIL_OUT/" 2>/dev/null || true
[ $rc -eq 0 ] || { echo "FAIL: rig dut stream on the FD layout exited $rc"; exit 1; }
[ "$(grep -vc '^#' /tmp/fd-stream.txt)" = 14000 ] || { echo "FAIL: rig dut stream did not write 14000 samples"; exit 1; }
grep -q "14000 samples, 0 gaps" /tmp/fd-stream.err || { echo "FAIL: the FD stream had gaps"; exit 1; }
grep -q '18FF2000##' /tmp/fd.log || { echo "FAIL: no CAN FD frame (18FF2000##) in candump's log"; head -3 /tmp/fd.log; exit 1; }
rc=0
"$RIG_BIN/rig" capture import /tmp/fd.log --hardware /tmp/hw-fd.toml --out /tmp/fd.rigcap > /tmp/import-fd.out 2>&1 || rc=$?
cat /tmp/import-fd.out
[ $rc -eq 0 ] || { echo "FAIL: rig capture import of the FD log exited $rc"; exit 1; }
grep -q 'gaps 0 (0 samples lost)' /tmp/import-fd.out || { echo "FAIL: the FD log imported with gaps"; exit 1; }
cp /tmp/fd.log "$KIL_OUT/" 2>/dev/null || true
echo LAYOUTS-OK
