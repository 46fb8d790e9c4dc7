#!/bin/sh
# The issue's speed target, part 2: a 50-h capture (1.8e8 samples at 1 kHz, a 1.44 GB float64
# file) through `rig analyze`: OADEV on log:100 with noise identification and bounds, the noise
# terms and the Welch PSD, streamed from the file. Prints wall time, CPU time and peak RSS.
#
#   bench/analysis/bench_50h.sh [BUILD_DIR] [DATA_DIR]
#
# The file is generated once (bench/analysis/make_signal.py, about 40 s) and kept in DATA_DIR
# (default /tmp). The first run after generating it reads from the page cache like the rest.
set -eu
build=${1:-build}
dir=${2:-/tmp}
here=$(cd "$(dirname "$0")" && pwd)
file="$dir/rig-bench-50h.f64"
[ -s "$file" ] || /usr/bin/python3 "$here/make_signal.py" "$file" 1.8e8 2
cat "$file" > /dev/null  # into the page cache: the figure is the analysis, not the disk
out=$(mktemp -d)
/usr/bin/time -f 'wall %e s, user %U s, sys %S s, peak RSS %M KiB' \
  "$build/bin/rig" analyze "$file" --input f64 --rate 1000 --taus log:100 --json "$out/analysis.json" > "$out/stdout" 2> "$out/time" || {
  cat "$out/stdout" "$out/time"
  exit 1
}
tail -n 1 "$out/time"
/usr/bin/python3 - "$out/analysis.json" <<'EOF'
import json, sys
a = json.load(open(sys.argv[1]))
nt = a["noise_terms"]
def v(t):
    x = nt[t].get("per_hour", {}).get("value")
    return "null" if x is None else f"{x:.4e}"
print(f"n = {a['n']}, taus = {len(a['oadev'])}, N = {v('N')} g*h^0.5, K = {v('K')} g/h^0.5, "
      f"R = {v('R')}, B = {nt['B'].get('value')}")
EOF
rm -rf "$out"
