#!/bin/sh
# Guest side of the kernel CAN test (run by harness/hil.sh inside Debian's kernel).
# Needs: RIG_BIN (the build's bin/), KIL_OUT (writable), RIG_STREAM_SECONDS (optional).
set -eu
echo "kernel $(uname -r), $(nproc) cpus"
# vcan delivers through the per-CPU backlog (netdev_max_backlog, 1000 by
# default): a TCG stall followed by the firmware's catch-up burst can overflow it.
echo 100000 > /proc/sys/net/core/netdev_max_backlog
ip link add dev vcan0 type vcan
ip link set up vcan0
# Every frame of the session, in candump's log format, for the DBC decode check.
# Logged to the guest's tmpfs (a 9p write per line would slow the emulated CPU),
# with a large socket buffer and error frames included (#FFFFFFFF = all classes).
LOG=/tmp/session.candump.log
candump -L -r 16777216 vcan0,0:0,#FFFFFFFF > "$LOG" &
DUMP=$!
sleep 0.5
rc=0
"$RIG_BIN/test_kernel_can" --gtest_filter='KernelCan.*' --gtest_output="xml:$KIL_OUT/test_kernel_can.xml" || rc=$?
sleep 0.5
kill $DUMP; wait $DUMP 2>/dev/null || true
# Frames the kernel itself dropped in the backlog (2nd column, per CPU, hex).
echo "softnet_stat dropped per cpu: $(awk '{print $2}' /proc/net/softnet_stat | tr '\n' ' ')"
echo "candump: $(wc -l < "$LOG") frames logged"
cp "$LOG" "$KIL_OUT/"
RIG_CANDUMP_LOG=$LOG "$RIG_BIN/test_kernel_can" --gtest_filter='KernelCanLog.*' \
  --gtest_output="xml:$KIL_OUT/test_kernel_can_log.xml" || rc=$?
# The technician's decoder gives the same verdict (non-zero on an undecodable frame).
"$RIG_BIN/rig" dut decode "$LOG" --summary || rc=$?

# `rig dut` against the emulated DUT served by `rig plant serve --can vcan0` (a separate process).
"$RIG_BIN/rig" plant serve --can vcan0 --profile ci --duration 120 > /tmp/serve.log 2>&1 &
SERVE=$!
i=0
until grep -q serving /tmp/serve.log; do
  i=$((i + 1)); [ $i -lt 600 ] && kill -0 $SERVE 2>/dev/null || { cat /tmp/serve.log; echo "FAIL: plant serve"; exit 1; }
  sleep 0.1
done
cli() { echo "+ rig dut $*"; "$RIG_BIN/rig" dut "$@" > /tmp/cli.out 2>&1 || { cat /tmp/cli.out; echo "FAIL: rig dut $* exited $?"; rc=1; }; cat /tmp/cli.out; }
cli info --can vcan0
grep -q "^serial: *EMU" /tmp/cli.out || { echo "FAIL: rig dut info shows no serial"; rc=1; }
cli set-filter --can vcan0 --paper --rate 10000
grep -q "b = \[0.14889" /tmp/cli.out || { echo "FAIL: set-filter did not read back the paper's filter"; rc=1; }
cli filter-off --can vcan0
cli info --can vcan0
grep -q "^filter: *off" /tmp/cli.out || { echo "FAIL: filter-off not reported"; rc=1; }
cli filter-on --can vcan0
"$RIG_BIN/rig" dut stream --can vcan0 --count 3000 --out /tmp/stream.txt 2> /tmp/cli.out || { echo "FAIL: rig dut stream"; rc=1; }
cat /tmp/cli.out
[ "$(grep -vc '^#' /tmp/stream.txt)" = 3000 ] || { echo "FAIL: rig dut stream did not write 3000 samples"; rc=1; }
grep -q "3000 samples, 0 gaps" /tmp/cli.out || { echo "FAIL: rig dut stream reported gaps"; rc=1; }
kill $SERVE; wait $SERVE 2>/dev/null || true
exit $rc
