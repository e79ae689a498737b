"""Compare two `hesspipe run` output folders file by file (a refactor's no-change check).

Files differ only where they should: manifests (timings, code hashes) are skipped, and
each folder's own path, the configuration's path and hesspipe's module names in
provenance text are masked before comparing. Binary files (figures) are compared byte
for byte. Prints one line per differing file and exits 1 if any differ.

    python benchmarks/compare_outputs.py OLD_DIR NEW_DIR [--mask TEXT=TEXT ...]
"""

from __future__ import annotations

import argparse
import re
import sys
from pathlib import Path

SKIP = {"manifest.json", ".hesspipe-output", "pipeline_state.json"}
MODULE = re.compile(r"hesspipe(\.[A-Za-z_][\w]*)+")


def _normal(text: str, root: Path, masks) -> str:
    text = text.replace(str(root), "<OUT>")
    for old, new in masks:
        text = text.replace(old, new)
    text = re.sub(r"Configuration `[^`]*`", "Configuration `<CONFIG>`", text)
    return MODULE.sub("hesspipe.<module>", text)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("old", type=Path)
    ap.add_argument("new", type=Path)
    ap.add_argument("--mask", action="append", default=[], help="OLD=NEW text replaced before comparing")
    args = ap.parse_args(argv)
    masks = [tuple(m.split("=", 1)) for m in args.mask]
    files = {p.relative_to(args.old) for p in args.old.rglob("*") if p.is_file()}
    files_new = {p.relative_to(args.new) for p in args.new.rglob("*") if p.is_file()}
    bad = [f"only in {args.old}: {f}" for f in sorted(files - files_new)]
    bad += [f"only in {args.new}: {f}" for f in sorted(files_new - files)]
    same = 0
    for rel in sorted(files & files_new):
        if rel.name in SKIP:
            continue
        a, b = (args.old / rel).read_bytes(), (args.new / rel).read_bytes()
        if a == b:
            same += 1
            continue
        try:
            ta, tb = a.decode("utf-8"), b.decode("utf-8")
        except UnicodeDecodeError:
            bad.append(f"differs (binary): {rel}")
            continue
        if _normal(ta, args.old.resolve(), masks) == _normal(tb, args.new.resolve(), masks):
            same += 1
        else:
            bad.append(f"differs: {rel}")
    for line in bad:
        print(line)
    print(f"{same} files equal (paths and module names masked), {len(bad)} differ")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
