"""Benchmark: CPU time of ``diagnose`` on a folder of recorded runs (yours or a laboratory's).

``bench_diagnose.py`` times the generator's runs (70 s at 50 Hz); this times the files a
laboratory wrote, read as ``hesspipe diagnose FOLDER --each`` reads them (the same
``--columns`` and plants file), one run after another in this one process, and prints each
run's named effects and CPU seconds (``time.process_time``: one core's work, independent of
how loaded a shared machine is), then the median per display. Nothing is written.

Usage::

    python benchmarks/bench_diagnose_folder.py FOLDER [FOLDER ...] --plants PLANTS.json
        [--columns time=t,reference=ft,...] [--display compensatory,either] [--every K] [--seed 0]

``--every K`` takes every K-th run of each folder (natural file order: with five runs per
person, ``--every 5`` is each person's first run). Set ``OPENBLAS_NUM_THREADS=1`` for one
core's figure (NumPy's BLAS threads otherwise spin on the second core and count in the
process's CPU time).
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time

from hesspipe.core.errors import HesspipeError
from hesspipe.core.formats import read_plants
from hesspipe.diagnose import DiagnoseConfig, diagnose
from hesspipe.pilots.compare import list_runs, read_runs


def read_folder(folder, columns=None) -> list:
    """The runs of `folder` (or a file) read as ``hesspipe diagnose FOLDER --each`` reads them;
    each file that cannot be read is printed as one "unread" line."""
    found, failures = read_runs(list_runs(folder), columns=columns)
    for f in failures:
        print(f"  unread: {f.error}")
    return found


def timed_diagnose(run, plants, config: DiagnoseConfig, seed: int = 0):
    """``(diagnosis, CPU seconds)`` of one run (``time.process_time``: one core's work)."""
    t = time.process_time()
    d = diagnose(run, plants, seed=seed, config=config)
    return d, time.process_time() - t


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("folders", nargs="+", help="folders (or files) of runs")
    ap.add_argument("--plants", required=True, help="the task's plants JSON")
    ap.add_argument("--columns", default=None, help="role=column mapping, as for hesspipe diagnose")
    ap.add_argument("--display", default="compensatory,either",
                    help="comma-separated displays to time (DiagnoseConfig.display)")
    ap.add_argument("--every", type=int, default=1, help="every K-th run of each folder (1: all)")
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args(argv)
    try:
        configs = [DiagnoseConfig(display=d) for d in args.display.split(",") if d]
        plants = read_plants(args.plants)
        runs = []
        for folder in args.folders:
            runs += read_folder(folder, args.columns)[::max(args.every, 1)]
    except HesspipeError as exc:
        print(f"bench_diagnose_folder: error: {exc}", file=sys.stderr)
        return 1
    for config in configs:
        display, times = config.display, []
        for run in runs:
            d, cpu = timed_diagnose(run, plants, config, args.seed)
            times.append(cpu)
            print(f"  {display:<13} {run.source}: {list(d.named_effects)} {times[-1]:.2f} s", flush=True)
        if times:
            print(f"{display}: median CPU time per diagnosis {statistics.median(times):.2f} s "
                  f"({len(times)} runs, max {max(times):.1f} s)", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
