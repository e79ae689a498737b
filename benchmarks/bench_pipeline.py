"""Wall time of ``hesspipe run`` on the built-in defaults: first run and an immediate re-run.

Issue 7's targets: all stages in under 60 s on the 2-core machine, and a second run
that re-runs nothing in under 3 s. Both are measured as subprocesses (start-up and
imports included), into a fresh temporary folder that is removed afterwards.

Run:  python benchmarks/bench_pipeline.py [--config FILE]
"""

from __future__ import annotations

import argparse
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path


def _timed(cmd: list[str]) -> tuple[float, str]:
    start = time.perf_counter()
    proc = subprocess.run(cmd, capture_output=True, text=True)
    wall = time.perf_counter() - start
    if proc.returncode != 0:
        sys.exit(f"failed ({proc.returncode}): {' '.join(cmd)}\n{proc.stderr}")
    return wall, proc.stderr


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--config", help="configuration file (default: the built-in defaults)")
    args = parser.parse_args()
    out = Path(tempfile.mkdtemp(prefix="hesspipe-bench-"))
    try:
        cmd = [sys.executable, "-m", "hesspipe.cli", "run", "--out", str(out / "run")]
        if args.config:
            cmd += ["--config", args.config]
        first, log = _timed(cmd)
        for line in log.splitlines():
            if "done in" in line:
                print("  " + line.replace("[hesspipe] ", ""))
        second, log = _timed(cmd)
        reran = [line for line in log.splitlines() if "running (" in line]
        print(f"first run (all stages): {first:.1f} s wall   (target < 60 s)")
        print(f"second run:             {second:.2f} s wall  (target < 3 s); stages re-run: {len(reran)}")
    finally:
        shutil.rmtree(out, ignore_errors=True)


if __name__ == "__main__":
    main()
