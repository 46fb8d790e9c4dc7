#!/bin/bash
# hil.sh - run one guest test script inside Debian's own kernel under QEMU.
#
#   hil.sh GUEST_SCRIPT OUTDIR [NAME=VALUE ...]
#
# The build host's kernel has no AF_CAN and no GPIO character device; Debian's
# kernel has both (+ vcan), and gpio-sim is built here as an out-of-tree module.
# The guest mounts the host's / read-only over 9p (host-built binaries run
# unchanged), OUTDIR writable, runs GUEST_SCRIPT as root with the NAME=VALUE
# pairs exported, and powers off. Exit status = the guest script's.
#
# Never skips: anything that prevents the run (no network for the first
# download, no QEMU, a failed module build, a guest that never reports) is an
# error with a message saying what. Built on a measured kernel-in-the-loop
# recipe (see docs/kernel-harness.md).
#
# Environment: RIG_KERNEL_CACHE (default tests/kernel/work), KVER=... to pin a
# kernel ABI, TIMEOUT (guest seconds, default 600), MEM, SMP.
set -euo pipefail
HERE=$(cd "$(dirname "$0")" && pwd)
KDIR=$(cd "$HERE/.." && pwd)
CACHE=${RIG_KERNEL_CACHE:-$KDIR/work}
[[ $# -ge 2 ]] || { echo "usage: $0 GUEST_SCRIPT OUTDIR [NAME=VALUE ...]" >&2; exit 2; }
SCRIPT=$(realpath "$1"); OUT=$2; shift 2
mkdir -p "$CACHE/debs" "$OUT"
OUT=$(realpath "$OUT")
log() { echo "[hil $(date +%T.%3N)] $*" >&2; }
die() { echo "hil: FAILED: $*" >&2; exit 1; }
export DEBIAN_FRONTEND=noninteractive
[[ -f $SCRIPT ]] || die "guest script $SCRIPT not found"

# One preparation at a time (ctest may start several kernel tests at once).
exec 9>"$CACHE/.lock"
flock 9

# ---- kernel ABI: what linux-image-amd64 points at on first use, then pinned in
#      $CACHE/kernel-version (delete it to follow Debian to a newer kernel) ----
if [[ -z ${KVER:-} && -f $CACHE/kernel-version ]]; then read -r KVER KPKGVER < "$CACHE/kernel-version"; fi
if [[ -z ${KVER:-} ]]; then
  KVER=$(apt-cache depends linux-image-amd64 2>/dev/null | awk '/Depends: linux-image-/{sub("linux-image-","",$2); print $2; exit}')
fi
[[ -n ${KVER:-} ]] || die "cannot resolve the Debian kernel ABI (apt-cache depends linux-image-amd64 gave nothing: run apt-get update)"
KPKGVER=${KPKGVER:-$(apt-cache policy "linux-image-$KVER" | awk '/Candidate:/{print $2}')}
[[ -n $KPKGVER && $KPKGVER != "(none)" ]] || die "no package version for linux-image-$KVER (apt-get update?)"
echo "$KVER $KPKGVER" > "$CACHE/kernel-version"
KSRCPKG=linux-source-${KVER%%-*}     # 6.1.0-56-amd64 -> linux-source-6.1
KSRCPKG=${KSRCPKG%.0}
log "guest kernel $KVER ($KPKGVER)"

# ---- host packages (scripts/setup installs the fixed ones; the headers follow the ABI) ----
PKGS="qemu-system-x86 busybox-static can-utils iproute2 gpiod libgpiod-dev gcc make xz-utils linux-headers-$KVER"
missing=$(for p in $PKGS; do dpkg-query -W -f='${Status}\n' "$p" 2>/dev/null | grep -q '^install ok installed' || echo "$p"; done)
if [[ -n $missing ]]; then
  [[ $(id -u) == 0 ]] || die "missing packages: $missing (as root: apt-get install $missing)"
  log "apt-get install" $missing
  apt-get install -y -qq --no-install-recommends $missing >&2 ||
    { apt-get update -qq >&2 && apt-get install -y -qq --no-install-recommends $missing >&2; } ||
    die "could not install: $missing"
fi

# ---- guest kernel: vmlinuz + the modules we need (no full install, no depmod) ----
KROOT=$CACHE/kroot-$KVER
MODS=$(grep -v '^#' "$HERE/modules.list")
if [[ ! -f $KROOT/.done ]]; then
  log "download + extract linux-image-$KVER"
  (cd "$CACHE/debs" && apt-get download "linux-image-$KVER=$KPKGVER" >&2) || die "apt-get download linux-image-$KVER=$KPKGVER"
  rm -rf "$KROOT"; mkdir -p "$KROOT"
  members="./boot/vmlinuz-$KVER"; for m in $MODS; do members+=" ./lib/modules/$KVER/$m.ko"; done
  dpkg-deb --fsys-tarfile "$CACHE/debs/linux-image-${KVER}_${KPKGVER}_amd64.deb" | tar -x -C "$KROOT" $members ||
    die "extracting the kernel image"
  touch "$KROOT/.done"
fi

# ---- four files of the same kernel's source: gpio-sim, irq_sim, gpiolib.h, extract-vmlinux ----
SRC=$CACHE/src-$KPKGVER
if [[ ! -f $SRC/.done ]]; then
  log "download $KSRCPKG=$KPKGVER, extract 4 files"
  (cd "$CACHE/debs" && apt-get download "$KSRCPKG=$KPKGVER" >&2) || die "apt-get download $KSRCPKG=$KPKGVER"
  mkdir -p "$SRC"
  # tar --occurrence=1 stops early; the upstream stages then die of SIGPIPE, hence '|| true' + the check below.
  (dpkg-deb --fsys-tarfile "$CACHE/debs/${KSRCPKG}_${KPKGVER}_all.deb" | tar -xO "./usr/src/$KSRCPKG.tar.xz" |
     tar -xJ -C "$SRC" --strip-components=1 --occurrence=1 "$KSRCPKG/drivers/gpio/gpio-sim.c" \
       "$KSRCPKG/drivers/gpio/gpiolib.h" "$KSRCPKG/kernel/irq/irq_sim.c" "$KSRCPKG/scripts/extract-vmlinux") 2>/dev/null || true
  for f in drivers/gpio/gpio-sim.c drivers/gpio/gpiolib.h kernel/irq/irq_sim.c scripts/extract-vmlinux; do
    [[ -f $SRC/$f ]] || die "failed to extract $f from $KSRCPKG"; done
  touch "$SRC/.done"
fi

# ---- uncompressed vmlinux: QEMU boots it via the PVH entry, skipping the slow (under TCG) decompressor ----
VMLINUX=$CACHE/vmlinux-$KVER
if [[ ! -s $VMLINUX ]]; then
  log "extract-vmlinux"
  sh "$SRC/scripts/extract-vmlinux" "$KROOT/boot/vmlinuz-$KVER" > "$VMLINUX.tmp" && mv "$VMLINUX.tmp" "$VMLINUX" ||
    die "extract-vmlinux"
fi

# ---- gpio-sim + irq_sim as one out-of-tree module ----
GS=$CACHE/gpiosim-$KVER
if [[ ! -f $GS/gpio_sim_oot.ko ]]; then
  log "build gpio_sim_oot.ko"
  mkdir -p "$GS"
  cp "$SRC/drivers/gpio/gpio-sim.c" "$SRC/drivers/gpio/gpiolib.h" "$SRC/kernel/irq/irq_sim.c" "$GS/"
  # irq_to_desc() is not exported to modules in 6.1; generic_handle_irq() does the same lookup + dispatch.
  sed -i 's/handle_simple_irq(irq_to_desc(irqnum));/generic_handle_irq(irqnum);/' "$GS/irq_sim.c"
  grep -q 'generic_handle_irq(irqnum)' "$GS/irq_sim.c" || die "irq_sim.c patch did not apply (kernel source changed?)"
  printf 'obj-m := gpio_sim_oot.o\ngpio_sim_oot-y := gpio-sim.o irq_sim.o\n' > "$GS/Kbuild"
  make -s -C "/usr/src/linux-headers-$KVER" M="$GS" modules >&2 || die "building gpio_sim_oot.ko"
fi

# ---- initramfs (busybox-static + modules + /init) ----
INITRD=$CACHE/initramfs-$KVER.cpio.gz
if [[ ! -f $INITRD || $HERE/init -nt $INITRD || $HERE/modules.list -nt $INITRD ]]; then
  log "build initramfs"
  "$HERE/build-initramfs.sh" "$KROOT/lib/modules/$KVER" "$INITRD" "$GS/gpio_sim_oot.ko" >&2 || die "building the initramfs"
fi
flock -u 9

# ---- the guest's entry script: the variables, then the test script ----
WRAP=$OUT/guest-entry.sh
{
  echo "#!/bin/sh"
  echo "# generated by hil.sh"
  for kv in "$@"; do printf 'export %q\n' "$kv"; done
  printf 'export KIL_OUT=%q\n' "$OUT"
  printf 'exec /bin/sh %q\n' "$SCRIPT"
} > "$WRAP"

log "boot guest, run $SCRIPT"
rc=0
# The guest gets a private tmpfs on /tmp. A tree that itself lives under /tmp (a CI
# clone, say) would be hidden by it, so init binds those top folders back in (kil.keep).
KIL_KEEP=
for p in "$SCRIPT" "$OUT" "$HERE" "${RIG_BIN:-}"; do
  [[ -n $p ]] || continue
  rp=$(realpath -m "$p")
  if [[ $rp == /tmp/?* ]]; then top=${rp#/tmp/}; top=/tmp/${top%%/*}; [[ ,$KIL_KEEP, == *,$top,* ]] || KIL_KEEP+=${KIL_KEEP:+,}$top; fi
done
KERNEL=$VMLINUX INITRD=$INITRD EXTRA_APPEND="kil.tmp=1 ${KIL_KEEP:+kil.keep=$KIL_KEEP }${EXTRA_APPEND:-}" TIMEOUT=${TIMEOUT:-600} \
  "$HERE/run-guest.sh" "$WRAP" "$OUT" || rc=$?
log "guest exit status $rc"
[[ $rc -ne 125 ]] || die "the guest never reported (crashed or timed out); console output above, log in $OUT"
exit $rc
