#!/bin/bash
# Two builds of rig on the same records of gen.py's seven sets (docs/analysis.md, "Long-end
# misfit, measured"): each record generated once and analysed by both, then tab.py on each.
#   bench/analysis/independent/compare.sh OLD_RIG NEW_RIG FIRST LAST OUT_DIR
# (seeds I = FIRST..LAST of every set; fix them before looking; about 6 min for 20 per set).
set -eu
old=$1 new=$2 first=$3 last=$4 out=$5
here=$(cd "$(dirname "$0")" && pwd)
py=/usr/bin/python3
mkdir -p "$out"
for S in S1_QN S2_B S3_K S4_mixed S5_R1h S6_Nonly S7_QK; do
  fs=$(cd "$here" && $py -c "from gen import SETS; print(SETS['$S']['fs'])")
  psd=--no-psd; case $S in S1_QN|S4_mixed|S6_Nonly) psd="";; esac
  mkdir -p "$out/old/$S" "$out/new/$S"
  for ((i = first; i <= last; i++)); do
    $py "$here/gen.py" $S $i "$out/rec.f64"
    "$old" analyze "$out/rec.f64" --input f64 --rate $fs $psd --json "$out/old/$S/$i.json" > /dev/null 2> "$out/err" || { echo "$S $i: OLD exit $?: $(tail -1 "$out/err")" >&2; }
    "$new" analyze "$out/rec.f64" --input f64 --rate $fs $psd --json "$out/new/$S/$i.json" > /dev/null 2> "$out/err" || { echo "$S $i: NEW exit $?: $(tail -1 "$out/err")" >&2; }
  done
  echo "$S done"
done
rm -f "$out/rec.f64"
for v in old new; do echo "== $v"; $py "$here/tab.py" "$out/$v"; done
