#!/usr/bin/env python3
"""The layering rules of docs/architecture.md, checked on the source tree.

Each folder may include only from the folders its row allows (read bottom-up: a layer never
includes a layer above it), and the CMake files of the production layers never name an
emulator library. Exit 0 when every rule holds; otherwise one line per violation
(file:line: what it includes, which rule) and exit 1.
"""
import pathlib
import re
import sys

ROOT = pathlib.Path(sys.argv[1] if len(sys.argv) > 1 else pathlib.Path(__file__).resolve().parents[2])

# folder -> include prefixes it may use (its own folder is always allowed).
RULES = {
    "analysis": ["analysis/"],                                   # the math: nothing else
    "rig/core": ["rig/core/"],                                   # the seams: nothing else
    "design": ["design/", "analysis/", "rig/core/errors.hpp", "rig/core/toml_util.hpp", "rig/core/filter_config.hpp"],
    "rig/capture": ["rig/core/"],
    "rig/executive": ["rig/core/"],
    "rig/modbus": ["rig/core/"],
    "rig/gpio": ["rig/core/"],
    "rig/report": ["rig/core/"],                                  # draws analysis.json; no math
    "rig/seal": ["rig/core/"],
    "firmware_link": ["rig/core/"],
    "procedures": ["procedures/", "analysis/", "design/", "rig/core/", "rig/capture/", "rig/executive/"],
    # The emulated plant runs the rig's own clients on its models: Modbus, CAN, GPIO lines.
    "plant": ["plant/", "analysis/", "design/", "rig/core/", "rig/modbus/", "firmware_link/", "rig/gpio/"],
    "app": None,  # the program wires every layer together
}
# Production layers whose libraries must never link the emulator.
NO_PLANT_LINK = ["analysis", "design", "rig", "firmware_link", "procedures"]

INCLUDE = re.compile(r'^\s*#\s*include\s+"([^"]+)"')


def owner(path: pathlib.Path) -> str | None:
    rel = path.relative_to(ROOT).as_posix()
    best = None
    for folder in RULES:
        if rel.startswith(folder + "/") and (best is None or len(folder) > len(best)):
            best = folder
    return best


def main() -> int:
    bad = []
    for path in sorted(ROOT.rglob("*")):
        if path.suffix not in (".hpp", ".cpp", ".h", ".cc", ".in") or ".git" in path.parts or "build" in path.parts[len(ROOT.parts):len(ROOT.parts) + 1]:
            continue
        folder = owner(path)
        if folder is None or RULES[folder] is None:
            continue
        allowed = [folder + "/"] + RULES[folder]
        for n, line in enumerate(path.read_text(errors="replace").splitlines(), 1):
            m = INCLUDE.match(line)
            if not m or "/" not in m.group(1):
                continue
            inc = m.group(1)
            if not any(inc == a or (a.endswith("/") and inc.startswith(a)) for a in allowed):
                bad.append(f"{path.relative_to(ROOT)}:{n}: includes \"{inc}\" ({folder}/ may include only {', '.join(allowed)})")
    for top in NO_PLANT_LINK:
        for cm in sorted((ROOT / top).rglob("CMakeLists.txt")) if (ROOT / top).exists() else []:
            for n, line in enumerate(cm.read_text().splitlines(), 1):
                code = line.split("#", 1)[0]
                if re.search(r"\brig_plant\w*", code):
                    bad.append(f"{cm.relative_to(ROOT)}:{n}: links the emulator ({top}/ must build without plant/)")
    for b in bad:
        print(b)
    print(f"layers: {len(bad)} violation(s)" if bad else "layers: every rule holds")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
