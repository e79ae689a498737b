"""Calibration and power of the describing-function motion test (SYNTHETIC DATA).

Every run is drawn by the independent generator :mod:`hesspipe.humanlike` exactly as
``benchmarks/bench_diagnose.py`` draws it (same cases, same seeds, 70 s at 50 Hz), and
only :func:`hesspipe.identification.motion_test.motion_test` is run on it (from the
model's default parameters, as ``bench_motion_limit.py`` does), which is much faster than
a whole diagnosis.

Under "no motion feedback" Km sits on its boundary and the test's vestibular delay is not
identified; the F(2, dof) reference is conservative for that case, so a calibrated test
names motion in at most about 1 % of the runs without it at diagnose's level 0.01. The
script prints, per case and effect, how often p < 0.01 and p < 0.05, and the totals.
``--tau-m`` sets the generator's vestibular delay (s; the literature's 0.1-0.2 s, SPEC.md
"Describing functions"); the generator's default is 0.

Usage::

    python benchmarks/bench_motion_calibration.py [--seeds 10] [--seed-start 0]
        [--cases paper:rate:disturbance,...] [--effects none,motion_feedback] [--tau-m 0.15] [--pilot precision]
        [--gain-drift 0.15] [--layout sparse|sparse-70s] [--threshold 0.2]

``--gain-drift CV`` lets the pilot's visual gain wander within each run (the generator's
``gain_drift``, correlation time 10 s). ``--layout sparse`` draws the forcing on a sparser
two-input layout (81.92 s at 100 Hz; :data:`LAYOUTS`) instead of the generator's default.
``--threshold S`` gives the pilot an indifference threshold, a dead zone on the perceived
error whose half-width is S times the error's RMS (the generator's ``threshold``).
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from hesspipe.core.errors import HesspipeError
from hesspipe.core.formats import read_plants, read_run
from hesspipe.core.seeds import derive_seed
from hesspipe.humanlike import draw_trial, simulate_trial, write_trial
from hesspipe.humanlike.forcing import SPARSE_LAYOUT
from hesspipe.identification.criteria import choose_k
from hesspipe.identification.motion_test import motion_test
from hesspipe.pilot.hess import PilotModel

CASES = ",".join([f"{p}:{o}:{t}" for p in ("paper", "roll") for o in ("rate", "angle")
                  for t in ("disturbance", "both")] + ["1/s:angle:both", "K/s2:angle:both"])


LAYOUTS = {"adjacent": dict(fs=50.0, T_m=70.0), "sparse": SPARSE_LAYOUT,
           "sparse-70s": dict(fs=50.0, T_m=70.0, line_bins=SPARSE_LAYOUT["line_bins"])}
"""Forcing layouts: the generator's default (each target line one bin above a disturbance
line, 70 s at 50 Hz, as ``bench_diagnose.py``), a sparser one
(:data:`hesspipe.humanlike.forcing.SPARSE_LAYOUT`, 81.92 s at 100 Hz) and the sparser
line numbers at the default's length and rate (the spacing alone)."""


def p_value(folder, plant, output, task, effect, seed, tau_m=0.0, pilot="hess", gain_drift=0.0,
            layout="adjacent", threshold=0.0):
    """The motion test's p-value on one generated run, or None (not generated / no lines)."""
    effects = () if effect == "none" else tuple(effect.split("+"))
    s = derive_seed(seed, "bench-diagnose", plant, output, task, effect)
    kw = dict(disturbance="wind") if plant == "paper" else {}
    name = f"{plant}-{output}-{task}-{effect}-{seed}".replace("/", "_")
    try:
        spec = draw_trial(plant, s, task=task, pilot=pilot, effects=effects, **LAYOUTS[layout],
                          output=output, name=name, tau_m=tau_m,
                          gain_drift=gain_drift, threshold=threshold, **kw)
    except HesspipeError:
        return None
    try:
        trial = simulate_trial(spec)
    except HesspipeError as exc:   # a drawn pilot whose loop diverges (seen with tau_m > 0)
        print(f"  not generated: {exc}")
        return None
    path = write_trial(Path(folder) / name, trial)
    plants = read_plants(path.parent / "plants.json")
    k = choose_k(plants)[0]
    t = motion_test(read_run(path), plants, PilotModel().complete({}, k), k=k)
    return t["p_value"] if t.get("available") else None


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=10)
    ap.add_argument("--seed-start", type=int, default=0)
    ap.add_argument("--cases", default=CASES, help="plant:output:task, comma-separated")
    ap.add_argument("--effects", default="none,motion_feedback")
    ap.add_argument("--tau-m", type=float, default=0.0, help="generator's vestibular delay, s")
    ap.add_argument("--pilot", choices=("hess", "precision"), default="hess",
                    help="generator pilot structure (precision: McRuer's, not the one fitted)")
    ap.add_argument("--gain-drift", type=float, default=0.0,
                    help="coefficient of variation of the pilot's wandering visual gain (0: steady)")
    ap.add_argument("--layout", choices=tuple(LAYOUTS), default="adjacent",
                    help="forcing layout (sparse: 81.92 s at 100 Hz, lines 1-23 bins apart; "
                         "sparse-70s: the same line numbers at 70 s and 50 Hz)")
    ap.add_argument("--threshold", type=float, default=0.0,
                    help="pilot's indifference threshold, share of the error's RMS (0: none)")
    args = ap.parse_args(argv)
    print("SYNTHETIC DATA: every run below is drawn by the independent generator hesspipe.humanlike.")
    total = {}
    t0 = time.perf_counter()
    with tempfile.TemporaryDirectory() as tmp:
        for case in args.cases.split(","):
            plant, output, task = case.split(":")
            for effect in args.effects.split(","):
                ps = [p for p in (p_value(tmp, plant, output, task, effect, seed, args.tau_m, args.pilot,
                                                  args.gain_drift, args.layout, args.threshold)
                                  for seed in range(args.seed_start, args.seed_start + args.seeds))
                      if p is not None]
                total.setdefault(effect, []).extend(ps)
                ps = np.array(ps)
                print(f"  {case:<24} {effect:<16} {ps.size:3d} runs: p<0.01 {int(np.sum(ps < 0.01)):3d}, "
                      f"p<0.05 {int(np.sum(ps < 0.05)):3d}, p<0.2 {int(np.sum(ps < 0.2)):3d}; "
                      f"p = {' '.join(f'{p:.2g}' for p in np.sort(ps)[:5])} ...", flush=True)
    for effect, ps in total.items():
        ps = np.array(ps)
        line = (f"{effect}: {ps.size} runs, p < 0.01 in {int(np.sum(ps < 0.01))} "
                f"({100 * np.mean(ps < 0.01):.1f} %), p < 0.05 in {int(np.sum(ps < 0.05))} "
                f"({100 * np.mean(ps < 0.05):.1f} %), p < 0.2 in {int(np.sum(ps < 0.2))}")
        print(line)
    print(f"wall time {time.perf_counter() - t0:.0f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
