# Sourced by the guest scripts: one gpio-sim chip "rig-sim" with the rig's line
# names (the [gpio] section of tests/kernel/hardware.toml.in); exports RIG_GPIO_CHIP.
mountpoint -q /sys/kernel/config || mount -t configfs none /sys/kernel/config
G=/sys/kernel/config/gpio-sim/rig
mkdir $G $G/bank0
echo 8 > $G/bank0/num_lines
echo rig-sim > $G/bank0/label
i=0
for name in rig-dut-power rig-estop rig-lamp-ready rig-lamp-running rig-lamp-pass rig-lamp-fail; do
  mkdir $G/bank0/line$i
  echo $name > $G/bank0/line$i/name
  i=$((i + 1))
done
echo 1 > $G/live
RIG_GPIO_CHIP=$(cat $G/bank0/chip_name)
export RIG_GPIO_CHIP
# The e-stop loop starts closed (active-low input held high).
echo pull-up > /sys/bus/gpio/devices/$RIG_GPIO_CHIP/sim_gpio1/pull
echo "gpio-sim: $RIG_GPIO_CHIP ($(cat $G/dev_name))"
gpioinfo $RIG_GPIO_CHIP | head -8
