#!/bin/sh
# Guest-side smoke check of the harness itself: kernel, CAN modules, vcan, gpio-sim.
set -e
echo "kernel $(uname -r)"
grep -E '^(can|can_raw|vcan|gpio_sim_oot) ' /proc/modules | cut -d' ' -f1 | tr '\n' ' '; echo
ip link add dev vcan0 type vcan && ip link set up vcan0 && ip -br link show vcan0
echo "RIG_BIN=${RIG_BIN:-unset}"
