#!/bin/sh
# Issue 17's procedure figure: the `paper` procedure on the emulated plant (114 min of device
# time: 10 kHz loop model, CAN codec and in-process bus, recording, analysis of both channels),
# whole process. Prints wall, user and system time and peak RSS (/usr/bin/time), the plant's
# own line (real-time factor) and a digest of the passport's values, which must not change
# between builds for the same seed (since 2026-11-25 the build turns FMA contraction off, so one
# build gives one digest on every CPU with AVX2 and FMA and the same glibc: the same on a Zen 3
# and an AVX-512 machine, 2026-11-28; before, the
# Allan kernels' AVX-512 clones used fused multiply-adds: docs/analysis.md "A different machine")
# (target: <= 3 s wall, <= 256 MiB, same passport).
#
#   bench/analysis/bench_paper.sh [BUILD_DIR] [RUNS] [callgrind]
#
# `callgrind` also counts the instructions of one `--profile ci` run (same code paths, about 4
# min of device time) under valgrind: a figure that the machine's load does not disturb, for
# before/after comparisons on a shared machine (wall time there is noise).
#
# Where the time goes (callgrind on the short `ci` profile, same code paths): docs/analysis.md,
# "Speed and memory".
set -eu
build=${1:-build}
runs=${2:-3}
mode=${3:-}
out=$(mktemp -d)
echo "# $(date -u +%Y-%m-%dT%H:%MZ) $(nproc) cores, load $(cut -d' ' -f1 /proc/loadavg)"
i=0
while [ "$i" -lt "$runs" ]; do
  i=$((i + 1))
  rm -rf "$out/run"
  /usr/bin/time -f "wall %e s, user %U s, sys %S s, peak RSS %M KiB" \
    "$build/bin/rig" run --plant emulated --profile paper --yes --quiet --no-history --out "$out/run" \
    > "$out/stdout" 2> "$out/time" || {
    cat "$out/stdout" "$out/time"
    exit 1
  }
  digest=$(/usr/bin/python3 -c "
import hashlib, json, sys
p = json.load(open(sys.argv[1]))
print(hashlib.sha256(json.dumps(p.get('values'), sort_keys=True).encode()).hexdigest()[:16])" "$out/run/passport.json")
  printf 'run %s: %s; passport values sha256 %s\n' "$i" "$(tail -n 1 "$out/time")" "$digest"
  grep -h "emulated plant: [0-9]" "$out/stdout" "$out/time" 2>/dev/null | head -n 1 || true  # the speed line
done
if [ "$mode" = callgrind ]; then
  command -v valgrind > /dev/null || { echo "bench_paper.sh: callgrind needs valgrind (apt-get install valgrind)" >&2; exit 2; }
  valgrind --tool=callgrind --callgrind-out-file="$out/cg.out" \
    "$build/bin/rig" run --plant emulated --profile ci --yes --quiet --no-history --out "$out/ci" \
    > "$out/cg.log" 2>&1 || true
  printf 'callgrind, --profile ci: %s instructions\n' "$(sed -n 's/.*I *refs: *//p' "$out/cg.log" | tr -d ,)"
fi
rm -rf "$out"
