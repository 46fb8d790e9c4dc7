#!/bin/bash
# (rig: adapted from a kernel-in-the-loop QEMU recipe, docs/kernel-harness.md)
# Build a tiny initramfs: busybox-static + the listed kernel modules + /init.
# usage: build-initramfs.sh <kernel-modules-dir> <out.cpio.gz> [extra .ko files...]
set -euo pipefail
KMOD=$1; OUTF=$2; shift 2
HERE=$(cd "$(dirname "$0")" && pwd)
# insmod order matters (dependencies first; no modprobe/modules.dep needed): modules.list
MODS=$(grep -v '^#' "$HERE/modules.list")
W=$(mktemp -d); trap 'rm -rf "$W"' EXIT
mkdir -p "$W"/{bin,proc,sys,dev,modules,newroot}
cp /bin/busybox "$W/bin/busybox"
for a in $(/bin/busybox --list); do [ "$a" = busybox ] || ln -s busybox "$W/bin/$a"; done
: > "$W/modules.list"
for m in $MODS; do
  b=$(basename "$m"); cp "$KMOD/$m.ko" "$W/modules/$b.ko"; echo "$b" >> "$W/modules.list"
done
for extra in "$@"; do   # extra out-of-tree modules, loaded last, in the given order
  b=$(basename "$extra" .ko); cp "$extra" "$W/modules/$b.ko"; echo "$b" >> "$W/modules.list"
done
cp "$HERE/init" "$W/init"; chmod 755 "$W/init"
(cd "$W" && find . | busybox cpio -o -H newc 2>/dev/null | gzip -1) > "$OUTF"
ls -l "$OUTF"
