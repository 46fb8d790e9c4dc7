#!/bin/bash
# (rig: adapted from a kernel-in-the-loop QEMU recipe, docs/kernel-harness.md)
# Boot the Debian kernel under QEMU with the host root shared read-only over
# virtio-9p, run SCRIPT (a host path) as root inside the guest (chroot into the
# host root), and return its exit status. Guest stdout/stderr -> OUTDIR/guest.log
# (and the serial console); exit status -> OUTDIR/exit_status.
# usage: run-guest.sh [--tcg|--kvm] SCRIPT OUTDIR
# env: KERNEL (bzImage or extracted vmlinux = PVH boot), INITRD, MEM, SMP, CPU,
#      MACHINE (pc|q35), BIOS, TIMEOUT, EXTRA_APPEND, QEMU_EXTRA
set -euo pipefail
ACCEL=auto
while [[ $# -gt 0 && $1 == --* ]]; do
  case $1 in --tcg) ACCEL=tcg ;; --kvm) ACCEL=kvm ;; *) echo "bad opt $1" >&2; exit 2 ;; esac; shift
done
[[ $# -eq 2 ]] || { echo "usage: $0 [--tcg|--kvm] SCRIPT OUTDIR" >&2; exit 2; }
SCRIPT=$(realpath "$1"); OUTDIR=$(realpath "$2")
if [[ $ACCEL == auto ]]; then
  # Real hardware virt only: kvm_pvm (this CI VM's /dev/kvm) cannot run a stock kernel at usable speed.
  if [[ -w /dev/kvm && ( -d /sys/module/kvm_intel || -d /sys/module/kvm_amd ) ]]; then ACCEL=kvm; else ACCEL=tcg; fi
fi
if [[ $ACCEL == kvm ]]; then ACC="-accel kvm -cpu ${CPU:-host}"; else ACC="-accel tcg -cpu ${CPU:-max}"; fi
KERNEL=${KERNEL:?set KERNEL to the extracted vmlinux}   # vmlinux (PVH entry) boots ~3 s faster than bzImage under TCG
INITRD=${INITRD:?set INITRD}
MEM=${MEM:-1G}; SMP=${SMP:-2}; MACHINE=${MACHINE:-pc}
rm -f "$OUTDIR/exit_status" "$OUTDIR/guest.log"
APPEND="console=ttyS0 rdinit=/init panic=-1 oops=panic quiet loglevel=3 8250.nr_uarts=1 i8042.noaux i8042.nokbd i8042.nopnp kil.script=$SCRIPT kil.out=$OUTDIR ${EXTRA_APPEND:-}"
rc=0
timeout --foreground -k 5 "${TIMEOUT:-300}" qemu-system-x86_64 $ACC -M "$MACHINE" -m "$MEM" -smp "$SMP" \
  ${BIOS:+-bios "$BIOS"} -nodefaults -no-user-config -nographic -no-reboot \
  -chardev stdio,id=con,signal=off -serial chardev:con \
  -kernel "$KERNEL" -initrd "$INITRD" -append "$APPEND" \
  -fsdev local,id=hostroot,path=/,security_model=none,readonly=on,multidevs=remap \
  -device virtio-9p-pci,fsdev=hostroot,mount_tag=hostroot \
  -fsdev local,id=kilout,path="$OUTDIR",security_model=none \
  -device virtio-9p-pci,fsdev=kilout,mount_tag=kilout ${QEMU_EXTRA:-} </dev/null || rc=$?
[[ $rc -eq 0 ]] || echo "run-guest: qemu exited with $rc" >&2
if [[ -f $OUTDIR/exit_status ]]; then
  rc=$(cat "$OUTDIR/exit_status"); echo "run-guest: guest script exit status $rc" >&2; exit "$rc"
fi
echo "run-guest: no exit_status (guest crashed or timed out)" >&2; exit 125
