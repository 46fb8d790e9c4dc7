# Sourced by the end-to-end guest scripts: vcan0, the gpio-sim chip, the
# emulated plant as a separate process (`rig plant serve`), the hardware file.
# vcan delivers through the per-CPU backlog (netdev_max_backlog, 1000 by
# default): a TCG stall followed by the firmware's catch-up burst can overflow it.
echo 100000 > /proc/sys/net/core/netdev_max_backlog
ip link add dev vcan0 type vcan
# RIG_VCAN_FD=1: a CAN FD vcan (classic frames pass unchanged).
if [ "${RIG_VCAN_FD:-0}" = 1 ]; then ip link set vcan0 mtu 72; fi
ip link set up vcan0
. "$RIG_SRC/tests/kernel/guest/gpio-sim-setup.sh"
PORT=15020
HW=/tmp/hardware.toml
PROFILE=${RIG_PROFILE:-$RIG_SRC/tests/kernel/config/kernel-short.toml}
sed "s/@PORT@/$PORT/" "$RIG_SRC/tests/kernel/config/hardware.toml.in" > $HW
# RIG_DUT_KEYS: lines added to the hardware file's [dut] (e.g. commands = false, dbc = ...);
# RIG_HW_TAIL: text appended to it (e.g. a [dut.stream] table).
if [ -n "${RIG_DUT_KEYS:-}" ]; then
  awk -v keys="$RIG_DUT_KEYS" '{ print } /^can = "vcan0"$/ { print keys }' $HW > $HW.new && mv $HW.new $HW
fi
if [ -n "${RIG_HW_TAIL:-}" ]; then printf '%s\n' "$RIG_HW_TAIL" >> $HW; fi
# RIG_DRIVE=cia402: the table is the emulated CiA 402 drive on the generic map (issue 14).
DRIVE_ARGS=""
if [ "${RIG_DRIVE:-rig-v1}" = cia402 ]; then
  MAP=$RIG_SRC/drives/generic-cia402.toml
  awk -v map="$MAP" '{ print } /^unit = 1$/ { print "drive = \"cia402\""; print "drive_map = \"" map "\"" }' \
    $HW > $HW.new && mv $HW.new $HW
  DRIVE_ARGS="--drive cia402 --drive-map $MAP"
  grep -q 'drive = "cia402"' $HW || { echo "FAIL: hardware file without drive = cia402"; cat $HW; exit 1; }
fi
"$RIG_BIN/rig" plant serve --can vcan0 --modbus 127.0.0.1:$PORT --profile "$PROFILE" $DRIVE_ARGS > /tmp/plant.log 2>&1 &
PLANT=$!
i=0
until grep -q "serving" /tmp/plant.log; do
  i=$((i + 1))
  if [ $i -gt 600 ] || ! kill -0 $PLANT 2>/dev/null; then
    echo "rig plant serve did not come up:"; cat /tmp/plant.log; exit 1
  fi
  sleep 0.1
done
cat /tmp/plant.log
stop_plant() {
  kill $PLANT 2>/dev/null || true
  wait $PLANT 2>/dev/null || true
  cp /tmp/plant.log "$KIL_OUT/" 2>/dev/null || true
}
