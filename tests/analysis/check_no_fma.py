#!/usr/bin/env python3
"""Fails if a binary holds a fused multiply-add instruction (x86-64 FMA3/FMA4 on float or double).

The project builds with -ffp-contract=off (CMakeLists.txt, rig_options): an FMA rounds a * b + c
once, a multiply and an add round twice, and GCC would otherwise contract them only in the
target_clones whose target has FMA (the AVX-512 ones), so the passport's last bits depended on
the CPU that ran the build. This reads the disassembly (binutils' objdump) and names every
function that still holds one. (An explicit std::fma would be flagged too, though it rounds the
same everywhere; the project has none, and would have to list it here.)

usage: check_no_fma.py FILE...   exit 0: none; 1: found (listed); 2: objdump failed
"""
import re
import subprocess
import sys

# vfmadd132pd, vfnmsub231ss, vfmaddsub213ps, vfmsubadd..., and FMA4's vfmaddpd.
FMA = re.compile(r"\bvfn?m(?:add|sub)(?:sub|add)?(?:\d{3})?[ps][sd]\b")
FUNCTION = re.compile(r"^[0-9a-f]+ <(.+)>:$")


def fma_by_function(path):
    try:
        out = subprocess.run(["objdump", "-d", "--no-show-raw-insn", path], check=True,
                             capture_output=True, text=True).stdout
    except (OSError, subprocess.CalledProcessError) as e:
        print(f"check_no_fma: objdump -d {path}: {e}", file=sys.stderr)
        sys.exit(2)
    counts, function = {}, "?"
    for line in out.splitlines():
        m = FUNCTION.match(line)
        if m:
            function = m.group(1)
        elif FMA.search(re.sub(r"<[^>]*>", "", line)):  # not in a symbol a call names
            counts[function] = counts.get(function, 0) + 1
    return counts


def main(paths):
    if not paths:
        print(__doc__, file=sys.stderr)
        return 2
    found = 0
    for path in paths:
        for function, n in sorted(fma_by_function(path).items(), key=lambda kv: -kv[1]):
            print(f"{path}: {n} FMA instruction(s) in {function}")
            found += n
    if found:
        print(f"check_no_fma: {found} fused multiply-add instruction(s): build with -ffp-contract=off")
        return 1
    print(f"check_no_fma: no fused multiply-add in {' '.join(paths)}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
