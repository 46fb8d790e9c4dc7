#!/bin/sh
# Issue 17's 50-h figures: a 50-h record (1.8e8 samples at 1 kHz, a 1.44 GB float64 file)
# through the whole `rig analyze` process, streamed from the file (bounded memory, both cores),
# log:100 taus with noise identification and bounds and the noise terms:
#   oadev          OADEV without the PSD   (target: <= 5 s wall, <= 512 MiB)
#   oadev+psd      OADEV with the Welch PSD
#   mdev .. totdev OADEV and that deviation in one pass, no PSD (target: <= 10 s, <= 512 MiB)
#   mdev-only ..   that deviation alone (--no-oadev: no OADEV, no noise terms)
# Prints wall, user and system time and peak RSS (/usr/bin/time) of each; on a machine shared
# with other jobs, user + sys (the CPU the analysis needed) is the figure load disturbs least.
#
#   bench/analysis/bench_50h.sh [BUILD_DIR] [DATA_DIR] [FIGURE...]
#
# The file is generated once (bench/analysis/make_signal.py, about 40 s) and kept in DATA_DIR
# (default /tmp); delete it when done (rm DATA_DIR/rig-bench-50h.f64). It is read into the page
# cache first: the figure is the analysis, not the disk. RIG_BENCH_COLD=1 instead drops the
# file's pages from the cache before each run (posix_fadvise DONTNEED on that file only), which
# adds the disk's read time (about 1.1 s for the 1.44 GB on the 2-core VM of docs/analysis.md).
# Each line ends with the issue's target for that figure and whether this run met it.
set -eu
build=${1:-build}
dir=${2:-/tmp}
[ $# -ge 2 ] && shift 2 || shift $#
figures=${*:-oadev oadev+psd mdev tdev hdev ohdev totdev}
here=$(cd "$(dirname "$0")" && pwd)
file="$dir/rig-bench-50h.f64"
[ -s "$file" ] || /usr/bin/python3 "$here/make_signal.py" "$file" 1.8e8 2
cold=${RIG_BENCH_COLD:-0}
drop() { /usr/bin/python3 -c "import os, sys; fd = os.open(sys.argv[1], os.O_RDONLY); os.posix_fadvise(fd, 0, 0, os.POSIX_FADV_DONTNEED)" "$file"; }
[ "$cold" = 1 ] || cat "$file" > /dev/null
out=$(mktemp -d)
echo "# $(date -u +%Y-%m-%dT%H:%MZ) $(nproc) cores, load $(cut -d' ' -f1 /proc/loadavg); $file; page cache $([ "$cold" = 1 ] && echo cold || echo warm)"
for fig in $figures; do
  case $fig in
    oadev) extra="--no-psd" ;;
    oadev+psd) extra="" ;;
    *-only) extra="--no-psd --dev ${fig%-only} --no-oadev" ;;
    *) extra="--no-psd --dev $fig" ;;
  esac
  case $fig in
    oadev) target=5 ;;
    oadev+psd) target= ;;
    *) target=10 ;;
  esac
  [ "$cold" = 1 ] && drop
  # shellcheck disable=SC2086
  /usr/bin/time -f "wall %e s, user %U s, sys %S s, peak RSS %M KiB" \
    "$build/bin/rig" analyze "$file" --input f64 --rate 1000 --taus log:100 $extra --json "$out/a.json" \
    > "$out/stdout" 2> "$out/time" || {
    cat "$out/stdout" "$out/time"
    exit 1
  }
  line=$(tail -n 1 "$out/time")
  verdict=$(echo "$line" | awk -v t="$target" '{ w = $2; kib = $(NF - 1);
    if (t == "") { print "(no target)"; exit }
    printf "target %s s, 512 MiB: %s", t, (w <= t && kib <= 524288) ? "met" : "not met" }')
  printf '%-11s %s  [%s]\n' "$fig" "$line" "$verdict"
done
/usr/bin/python3 - "$out/a.json" <<'EOF'
import json, sys
a = json.load(open(sys.argv[1]))
if "noise_terms" not in a:
    sys.exit(0)  # the last figure ran without OADEV
nt = a["noise_terms"]
def v(t):
    x = nt[t].get("per_hour", {}).get("value")
    return "null" if x is None else f"{x:.4e}"
print(f"# last run: n = {a['n']}, taus = {len(a['oadev'])}, N = {v('N')} g*h^0.5, K = {v('K')} g/h^0.5, "
      f"R = {v('R')}, B = {nt['B'].get('value')}")
EOF
rm -rf "$out"
