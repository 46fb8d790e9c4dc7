#!/usr/bin/env python3
"""Every document the project cites is in it (issue 16).

    check_links.py ROOT          check the tree at ROOT
    check_links.py --self-test   show that each rule catches a planted fault

Rules:
1. Every relative Markdown link in README.md and docs/*.md names a file inside the
   repository that exists, and a `#fragment` names a heading of the target page.
2. No source or document names a place outside the repository: a path above it
   (`../shared/...`), a build machine's folders (`/work/...`, `build-C/...`), or a spec page
   that only existed outside it (the upper-case METHOD / CONTRACTS / ARCHITECTURE pages).
3. A source file a document names in code quotes (`tests/design/test_filter.cpp`) exists: a
   moved test was still cited by its old path (a newcomer's review).
Exit 0 when clean, 1 with one line per fault (FILE:LINE: what).
"""
import os
import re
import sys
import tempfile

LINK = re.compile(r"(?<!\!)\[[^\]]*\]\(([^)\s]+)(?:\s+\"[^\"]*\")?\)")
FENCE = re.compile(r"^\s*(```|~~~)")
# Built from parts so that this file does not trip its own rule.
FOREIGN = [
    (re.compile(r"\.\./" + "shared"), "names a path outside the repository"),
    (re.compile(r"(?<![\w.-])/" + r"work/"), "names a build machine's folder"),
    (re.compile(r"\bbuild-" + r"C/"), "names a build machine's build folder"),
    (re.compile(r"\b(?:" + "METHOD|CONTRACTS|ARCHITECTURE" + r")\.md"),
     "names a page that is not in the repository (docs/method.md, docs/contracts.md, docs/architecture.md)"),
]
# A repository path in code quotes: a top folder of the tree, then a file with a source extension.
CODE_PATH = re.compile(r"`((?:tests|app|rig|analysis|plant|procedures|firmware_link|design|bench|scripts|tools|drives|"
                       r"duts|profiles)/[A-Za-z0-9_./-]+\.(?:cpp|hpp|py|sh|toml|dbc))`")
SKIP_DIRS = {".git", "runs", "__pycache__", "node_modules"}
TEXT_EXT = {".md", ".cpp", ".hpp", ".h", ".c", ".py", ".sh", ".toml", ".txt", ".cmake", ".dbc", ".json", ".html",
            ".in", ""}


def skip_dir(rel):
    name = os.path.basename(rel)
    return (name in SKIP_DIRS or name.startswith("build") or name.startswith("out")
            or rel == os.path.join("tests", "kernel", "work"))


def slug(heading):
    """GitHub's anchor for a heading: lower case, punctuation dropped, spaces to hyphens."""
    s = heading.strip().lower()
    s = re.sub(r"[^\w\- ]", "", s)
    return s.replace(" ", "-")


def anchors(path):
    out, fenced = set(), False
    with open(path, encoding="utf-8") as f:
        for line in f:
            if FENCE.match(line):
                fenced = not fenced
            elif not fenced and line.startswith("#"):
                out.add(slug(line.lstrip("#")))
    return out


def check_links(root, md, faults):
    fenced = False
    with open(md, encoding="utf-8") as f:
        for n, line in enumerate(f, 1):
            if FENCE.match(line):
                fenced = not fenced
                continue
            if fenced:
                continue
            for cited in CODE_PATH.findall(line):
                if not os.path.exists(os.path.join(root, cited)):
                    faults.append(f"{os.path.relpath(md, root)}:{n}: '{cited}': no such file in the repository")
            for target in LINK.findall(line):
                if re.match(r"^[a-z][a-z0-9+.-]*:", target):  # https:, mailto: ...
                    continue
                where = f"{os.path.relpath(md, root)}:{n}"
                path, _, frag = target.partition("#")
                dest = os.path.normpath(os.path.join(os.path.dirname(md), path)) if path else md
                if os.path.commonpath([os.path.abspath(dest), os.path.abspath(root)]) != os.path.abspath(root):
                    faults.append(f"{where}: link '{target}' leaves the repository")
                    continue
                if not os.path.exists(dest):
                    faults.append(f"{where}: link '{target}': no such file {os.path.relpath(dest, root)}")
                    continue
                if frag and dest.endswith(".md") and frag not in anchors(dest):
                    faults.append(f"{where}: link '{target}': no heading '#{frag}' in {os.path.relpath(dest, root)}")


def check_foreign(root, faults):
    me = os.path.abspath(__file__)
    for d, dirs, files in os.walk(root):
        dirs[:] = sorted(x for x in dirs if not skip_dir(os.path.relpath(os.path.join(d, x), root)))
        for name in sorted(files):
            p = os.path.join(d, name)
            if os.path.abspath(p) == me or name == ".git" or os.path.splitext(name)[1] not in TEXT_EXT:
                continue
            try:
                with open(p, encoding="utf-8") as f:
                    lines = f.readlines()
            except (UnicodeDecodeError, OSError):
                continue
            for n, line in enumerate(lines, 1):
                for rx, what in FOREIGN:
                    m = rx.search(line)
                    if m:
                        faults.append(f"{os.path.relpath(p, root)}:{n}: '{m.group(0)}' {what}")


def check(root):
    faults = []
    mds = [os.path.join(root, "README.md")]
    docs = os.path.join(root, "docs")
    if os.path.isdir(docs):
        mds += sorted(os.path.join(docs, f) for f in os.listdir(docs) if f.endswith(".md"))
    for md in mds:
        if os.path.exists(md):
            check_links(root, md, faults)
    check_foreign(root, faults)
    return faults


def self_test():
    planted = {
        "README.md": "# T\n[ok](docs/a.md) [ok](docs/a.md#part-one) [x](docs/missing.md)\n"
                     "[y](../shared/spec/M.md) [z](docs/a.md#nowhere)\n```\n[in code](nope.md)\n```\n",
        "docs/a.md": "# A\n## Part one\n[back](../README.md)\nchecked by `tests/x/gone.cpp`, `src/x.cpp` is not a top folder\n",
        "src/x.cpp": "// see " + "METHOD" + ".md\n// " + "build-" + "C/bin/tool\n",
        "docs/h.md": "# H\nfrom /" + "work/shared/reference\n",
    }
    expected = ["README.md:2: link 'docs/missing.md'", "README.md:3: link '../shared/spec/M.md' leaves",
                "README.md:3: link 'docs/a.md#nowhere': no heading", "README.md:3: '../shared'", "src/x.cpp:1:", "src/x.cpp:2:", "docs/h.md:2:",
                "docs/a.md:4: 'tests/x/gone.cpp': no such file"]
    with tempfile.TemporaryDirectory() as root:
        for rel, text in planted.items():
            os.makedirs(os.path.join(root, os.path.dirname(rel)), exist_ok=True)
            with open(os.path.join(root, rel), "w", encoding="utf-8") as f:
                f.write(text)
        faults = check(root)
    missing = [e for e in expected if not any(f.startswith(e) for f in faults)]
    extra = [f for f in faults if not any(f.startswith(e) for e in expected)]
    if missing or extra:
        print("check_links self-test FAILED\n  not caught: %s\n  unexpected: %s\n  faults: %s" % (missing, extra, faults))
        return 1
    print(f"check_links self-test: {len(expected)} planted faults caught, no false alarm")
    return 0


def main(argv):
    if argv[1:] == ["--self-test"]:
        return self_test()
    if len(argv) != 2:
        print(__doc__)
        return 2
    faults = check(argv[1])
    for f in faults:
        print(f)
    if faults:
        print(f"{len(faults)} reference fault(s)")
        return 1
    print("every reference resolves inside the repository")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
