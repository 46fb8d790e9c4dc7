#!/bin/sh
# Guest side of the kernel GPIO test: libgpiod against gpio-sim.
set -eu
. "$RIG_SRC/tests/kernel/guest/gpio-sim-setup.sh"
exec "$RIG_BIN/test_kernel_gpio" --gtest_output="xml:$KIL_OUT/test_kernel_gpio.xml"
