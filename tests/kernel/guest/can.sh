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
if [ -x "$RIG_BIN/rig" ] && "$RIG_BIN/rig" dut --help 2>/dev/null | grep -q decode; then
  "$RIG_BIN/rig" dut decode "$LOG" --summary || rc=$?
fi
exit $rc
