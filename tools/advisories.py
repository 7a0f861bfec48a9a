#!/usr/bin/env python3
"""Cargo.lock against a local copy of the RustSec advisory database (standard library only).

`cargo audit` needs the network to fetch the database; CI has none. With a clone of
https://github.com/rustsec/advisory-db anywhere on disk:

  python3 tools/advisories.py PATH/TO/advisory-db [Cargo.lock]

lists every advisory on a crate in the lock file whose version is neither patched nor
unaffected (withdrawn advisories skipped), with its kind (vulnerability, unmaintained,
unsound, ...), and exits 1 when there is one.
"""

import os
import re
import sys


def version(text):
    """(major, minor, patch) of a version, build metadata and pre-release dropped."""
    core = re.split(r"[+-]", text.strip())[0]
    parts = [int(p) for p in core.split(".")] + [0, 0]
    return tuple(parts[:3])


def matches(req, v):
    """Whether version `v` meets one requirement: comparators joined by commas."""
    for comp in req.split(","):
        comp = comp.strip()
        if not comp:
            continue
        m = re.match(r"(>=|<=|>|<|=|\^|~)?\s*(.+)", comp)
        op, want = m.group(1) or "^", m.group(2)
        w = version(want)
        if op == ">=" and not v >= w:
            return False
        if op == "<=" and not v <= w:
            return False
        if op == ">" and not v > w:
            return False
        if op == "<" and not v < w:
            return False
        if op == "=" and v != w:
            return False
        if op == "~" and not (w <= v < (w[0], w[1] + 1, 0)):
            return False
        if op == "^":
            if w[0] > 0:
                upper = (w[0] + 1, 0, 0)
            elif w[1] > 0:
                upper = (0, w[1] + 1, 0)
            else:
                upper = (0, 0, w[2] + 1)
            if not (w <= v < upper):
                return False
    return True


def field(header, name):
    """The requirements of a `name = [...]` list in an advisory's TOML header."""
    m = re.search(rf"^{name}\s*=\s*\[(.*?)\]", header, re.S | re.M)
    return re.findall(r'"([^"]*)"', m.group(1)) if m else []


def main():
    if len(sys.argv) < 2:
        print(__doc__)
        return 2
    db = sys.argv[1]
    lock = sys.argv[2] if len(sys.argv) > 2 else os.path.join(os.path.dirname(__file__), "..", "Cargo.lock")
    text = open(lock, encoding="utf-8").read()
    packages = re.findall(r'\[\[package\]\]\nname = "([^"]+)"\nversion = "([^"]+)"', text)
    found = 0
    for name, ver in sorted(set(packages)):
        folder = os.path.join(db, "crates", name)
        if not os.path.isdir(folder):
            continue
        v = version(ver)
        for f in sorted(os.listdir(folder)):
            body = open(os.path.join(folder, f), encoding="utf-8").read()
            header = body.split("```toml", 1)[-1].split("```", 1)[0]
            if re.search(r"^withdrawn\s*=", header, re.M):
                continue
            if any(matches(r, v) for r in field(header, "patched") + field(header, "unaffected")):
                continue
            kind = re.search(r'^informational\s*=\s*"([^"]+)"', header, re.M)
            title = re.search(r"^# (.+)$", body, re.M)
            print(f"{name} {ver}: {f[:-3]} ({kind.group(1) if kind else 'vulnerability'}): "
                  f"{title.group(1) if title else ''}")
            found += 1
    print(f"{len(set(packages))} packages, {found} open advisories")
    return 1 if found else 0


if __name__ == "__main__":
    sys.exit(main())
