#!/usr/bin/env python3
"""The README's two commands, as a newcomer runs them (issue 16).

    test_scripts.py ROOT BUILD_DIR CASE

ROOT: the checkout; BUILD_DIR: the build folder holding bin/rig (the demo reuses it, so
its cmake configure and build are no-ops). Cases:
  demo_then_test_configure  a build folder configured the demo's way (tests and benches
                            off) and then configured by scripts/test's own cmake line has
                            tests and benches on, and ctest finds tests in it
  no_tests_fails            scripts/test's ctest calls carry --no-tests=error, and ctest
                            with it fails on a build folder that holds no test
  demo_profile_ci           `scripts/demo --profile ci` (its header's usage) runs the ci
                            profile, prints only files it wrote and where it records history;
                            the NumPy loader command it prints works; a rejected run prints no file
  setup_packages            `scripts/setup --runtime` (what the demo runs) installs python3-numpy
                            for the documented loader; every package in the README's table is in
                            scripts/setup and the other way round
"""
import os
import re
import shlex
import subprocess
import sys
import tempfile


def fail(msg):
    print("FAIL: " + msg)
    sys.exit(1)


def cmake_line(script):
    """The `cmake -S . -B "$BUILD" ...` configure line of a script, continuation lines joined."""
    text = open(script).read().replace("\\\n", " ")
    for line in text.splitlines():
        if re.match(r'\s*cmake -S \. -B "\$BUILD"', line):
            return line.split(">/dev/null")[0].strip()
    fail(f"{script}: no `cmake -S . -B \"$BUILD\"` configure line")


def cache_value(build, name):
    for line in open(os.path.join(build, "CMakeCache.txt")):
        if line.startswith(name + ":"):
            return line.split("=", 1)[1].strip()
    return None


def demo_then_test_configure(root, _build):
    with tempfile.TemporaryDirectory(prefix="rig-demo-then-test-") as b:
        # The demo's first configure of a fresh build folder: tests and benches off.
        demo = cmake_line(os.path.join(root, "scripts/demo"))
        if "${switches[@]}" not in demo:
            fail("scripts/demo's configure line no longer takes its switches: " + demo)
        switches = re.search(r"switches=\((-G Ninja [^)]*)\)", open(os.path.join(root, "scripts/demo")).read())
        if not switches or "-DRIG_BUILD_TESTS=OFF" not in switches.group(1):
            fail("scripts/demo's fresh-folder switches changed; update this test")
        subprocess.run(["cmake", "-S", root, "-B", b] + switches.group(1).split(), check=True, stdout=subprocess.DEVNULL)
        if cache_value(b, "RIG_BUILD_TESTS") != "OFF":
            fail("the demo's configure did not switch tests off; the test proves nothing")
        # Then scripts/test's own configure line, verbatim, in the same folder.
        line = cmake_line(os.path.join(root, "scripts/test"))
        args = [a.replace("$BUILD", b) for a in shlex.split(line)]
        subprocess.run(args, cwd=root, check=True, stdout=subprocess.DEVNULL)
        for name in ("RIG_BUILD_TESTS", "RIG_BUILD_BENCH"):
            if cache_value(b, name) != "ON":
                fail(f"after scripts/test's configure {name} = {cache_value(b, name)} (the demo's OFF survived)")
        listed = subprocess.run(["ctest", "--test-dir", b, "-N"], capture_output=True, text=True).stdout
        m = re.search(r"Total Tests: (\d+)", listed)
        # (gtest suites are listed once built; the script-level tests are there at once)
        if not m or int(m.group(1)) == 0 or "arch.layers" not in listed or "docs.links" not in listed:
            fail("ctest lists no tests after scripts/test's configure:\n" + listed[-500:])
        print(f"demo-then-test: tests and benches ON, ctest lists {m.group(1)} tests")


def no_tests_fails(root, _build):
    text = open(os.path.join(root, "scripts/test")).read()
    calls = [l for l in text.replace("\\\n", " ").splitlines() if re.search(r"(^|\s)ctest --test-dir", l)]
    if len(calls) < 2 or not all("--no-tests=error" in c for c in calls):
        fail("every ctest call of scripts/test must carry --no-tests=error:\n" + "\n".join(calls))
    with tempfile.TemporaryDirectory(prefix="rig-no-tests-") as d:
        open(os.path.join(d, "CTestTestfile.cmake"), "w").write("# no tests\n")
        rc = subprocess.run(["ctest", "--test-dir", d, "--no-tests=error"], capture_output=True).returncode
        if rc == 0:
            fail("ctest --no-tests=error passed on a folder without tests")
    print(f"no tests: {len(calls)} ctest calls carry --no-tests=error; it fails on an empty build folder")


def run_demo(root, build, args):
    env = dict(os.environ, BUILD_DIR=build)
    p = subprocess.run([os.path.join(root, "scripts/demo")] + args, cwd=root, env=env, capture_output=True,
                       text=True, timeout=600)
    return p.returncode, p.stdout, p.stderr


def demo_profile_ci(root, build):
    with tempfile.TemporaryDirectory(prefix="rig-demo-ci-") as d:
        out, db = os.path.join(d, "run"), "sqlite:" + os.path.join(d, "history.sqlite")
        rc, so, se = run_demo(root, build, ["--profile", "ci", "--out", out, "--db", db])
        if rc != 0:
            fail(f"scripts/demo --profile ci exited {rc}:\n{se[-2000:]}")
        import json
        profile = json.load(open(os.path.join(out, "passport.json")))["profile"]
        if profile != "ci":
            fail(f"the run was profile '{profile}', not ci")
        written = re.search(r"^written: (.*)$", se, re.M)
        if not written:
            fail("scripts/demo did not list the files it wrote:\n" + se[-1000:])
        files = written.group(1).split()
        for f in files:
            if not os.path.isfile(f):
                fail(f"scripts/demo lists {f}, which does not exist")
        for want in ("passport.json", "report.html", "junit.xml"):
            if not any(f.endswith("/" + want) for f in files):
                fail(f"scripts/demo did not list {want}")
        if f"history: recorded in {db}" not in se:
            fail("scripts/demo did not say where it records history:\n" + se[-1000:])
        if not os.path.isfile(db[len("sqlite:"):]):
            fail("the history database the demo names was not written")
        loader = re.search(r"(\S*python3) (tools/rigcap\.py \S+)$", se, re.M)
        if not loader:
            fail("scripts/demo did not print the NumPy loader command for its capture:\n" + se[-1000:])
        # The command exactly as printed, interpreter included (a pyenv python3 may lack NumPy).
        p = subprocess.run([loader.group(1)] + loader.group(2).split(), cwd=root, capture_output=True, text=True)
        if p.returncode != 0 or '"serial"' not in p.stdout:
            fail(f"the loader command the demo printed failed ({p.returncode}):\n{p.stderr[-1000:]}")
        # A run rejected at its command line writes nothing, and the demo lists nothing.
        bad = os.path.join(d, "bad")
        rc, so, se = run_demo(root, build, ["--profile", "no-such-profile", "--out", bad, "--no-history"])
        if rc != 2:
            fail(f"a bad profile should exit 2, got {rc}:\n{se[-1000:]}")
        if "written:" in se or "wrote no files" not in se:
            fail("for a run that wrote nothing the demo must list no file:\n" + se[-1000:])
        # The finished run's folder again: refused (exit 2), and its earlier files are not listed as
        # this run's, nor is a history record claimed (a newcomer's review).
        rc, so, se = run_demo(root, build, ["--profile", "ci", "--out", out, "--db", db])
        if rc != 2:
            fail(f"a finished run's folder should exit 2, got {rc}:\n{se[-1000:]}")
        if "written:" in se or "history: recorded" in se or "wrote no files" not in se:
            fail("a refused run listed files or a history record it did not write:\n" + se[-1000:])
    print("demo --profile ci: exit 0, lists only written files and the history database; bad profile and a "
          "finished folder: no file listed")


def packages(root, *args):
    out = subprocess.run([os.path.join(root, "scripts/setup"), *args, "--print"], capture_output=True, text=True,
                         check=True).stdout
    return set(out.split())


def setup_packages(root, _build):
    runtime, full = packages(root, "--runtime"), packages(root)
    if "python3-numpy" not in runtime:
        fail("scripts/setup --runtime does not install python3-numpy (README: the NumPy loader tools/rigcap.py)")
    if not runtime <= full:
        fail(f"--runtime installs packages the full set-up does not: {sorted(runtime - full)}")
    readme = open(os.path.join(root, "README.md")).read()
    table = readme.split("## Set-up and dependencies", 1)[1].split("\n## ", 1)[0]
    listed = set()
    for row in re.findall(r"^\| ([^|]+) \|", table, re.M):
        listed |= {p.strip() for p in row.split(",") if p.strip() and p.strip() != "package" and "---" not in p}
    if listed - full or full - listed - {"pkg-config"}:
        fail(f"README's dependency table and scripts/setup differ: only in README {sorted(listed - full)}, "
             f"only in setup {sorted(full - listed - {'pkg-config'})}")
    print(f"setup: --runtime {len(runtime)} packages incl. python3-numpy; README table matches {len(full)} packages")


CASES = {"setup_packages": setup_packages, "demo_then_test_configure": demo_then_test_configure, "no_tests_fails": no_tests_fails,
         "demo_profile_ci": demo_profile_ci}

if __name__ == "__main__":
    if len(sys.argv) != 4 or sys.argv[3] not in CASES:
        print(__doc__)
        sys.exit(2)
    CASES[sys.argv[3]](os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2]))
