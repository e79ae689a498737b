"""How the cohort's motion verdict answers on cohorts drawn from pools of pilots (SYNTHETIC DATA).

Every pilot is a run of the independent generator :mod:`hesspipe.humanlike` (fine-step
time-domain simulation; no hesspipe pilot code), written by its logger and read back, and
only the per-pilot motion test is run on it
(:func:`hesspipe.identification.motion_test.motion_test`, from the model's default
parameters, as ``bench_motion_calibration.py``). Pools:

- ``standin``, ``standin-motion``: precision (multimodal) pilots, yaw angle, single and
  double integrator, target and disturbance on the sparse layout (81.92 s at 100 Hz),
  vestibular delay 0.15 s, visual gain wandering (CV 0.15): the real-trial stand-in,
  without and with motion (the generator's Km/Ke 0.2-1.0);
- ``weak-motion``: the same with Km/Ke 0.1 (a weak vestibular path);
- ``drift``: Hess pilots (paper and roll plants, rate and angle, target and disturbance,
  adjacent lines, 70 s at 50 Hz) whose visual gain wanders with CV 0.3, no motion;
- ``error-remnant``: precision pilots, remnant injected at the error, CV 0.3, adjacent
  lines, no motion;
- ``pursuit``: precision pilots with a pursuit display's feedforward (0.7), sparse layout,
  no motion, the display not stated (``--display``, default the library's).

Cohorts of n pilots are then drawn from the pools with replacement (the pilots' tests are
computed once), pure or mixed (k motion pilots among n - k without), and each goes
through :func:`hesspipe.pilots.verdict.cohort_verdict`. Printed per cohort kind: how
often the verdict says yes (its median-pilot test), and how often Fisher's combination
and the count of significant pilots (binomial) would have, at the verdict's level.

Usage::

    python benchmarks/bench_cohort_rule.py [--pilots 25] [--n 6,8,10] [--cohorts 2000]
                                           [--workers 2] [--seed 1] [--display either]

``--pilots`` is per plant and pool (pools of 40-60 pilots at the default). About 12 min
on 2 cores.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

from hesspipe.core.choices import DEFAULT_DISPLAY, DISPLAYS
from hesspipe.core.errors import HesspipeError
from hesspipe.core.formats import read_plants, read_run
from hesspipe.core.seeds import derive_seed
from hesspipe.humanlike import draw_trial, simulate_trial, write_trial
from hesspipe.humanlike.forcing import SPARSE_LAYOUT
from hesspipe.identification.criteria import choose_k
from hesspipe.identification.motion_test import ALPHA, motion_test
from hesspipe.pilot.hess import PilotModel
from hesspipe.pilots.verdict import cohort_verdict

_STANDIN = [("1/s", "angle"), ("K/s2", "angle")]
_HESS = [("paper", "angle"), ("roll", "angle"), ("paper", "rate"), ("roll", "rate")]
_SPARSE = dict(SPARSE_LAYOUT)
_ADJACENT = dict(fs=50.0, T_m=70.0)
POOLS = {
    "standin": (_STANDIN, (), dict(pilot="precision", tau_m=0.15, gain_drift=0.15, **_SPARSE)),
    "standin-motion": (_STANDIN, ("motion_feedback",),
                       dict(pilot="precision", tau_m=0.15, gain_drift=0.15, **_SPARSE)),
    "weak-motion": (_STANDIN, ("motion_feedback",),
                    dict(pilot="precision", tau_m=0.15, gain_drift=0.15, km_ratio=(0.1, 0.1), **_SPARSE)),
    "drift": (_HESS, (), dict(pilot="hess", gain_drift=0.3, **_ADJACENT)),
    "error-remnant": (_STANDIN, (), dict(pilot="precision", tau_m=0.15, remnant_at="error",
                                         gain_drift=0.3, **_ADJACENT)),
    "pursuit": (_STANDIN, (), dict(pilot="precision", tau_m=0.15, feedforward=0.7, **_SPARSE)),
}
"""Pool name → (plants and outputs, hidden effects, draw_trial settings)."""


def pilot_test(job) -> dict | None:
    """The motion test of one generated pilot (None: no pilot in the generator's ranges)."""
    pool, plant, output, seed, display = job
    cases, effects, draw = POOLS[pool]
    kw = dict(draw)
    if plant == "paper":
        kw["disturbance"] = "wind"
    s = derive_seed(seed, "bench-cohort-rule", pool, plant, output)
    with tempfile.TemporaryDirectory() as tmp:
        try:
            trial = simulate_trial(draw_trial(plant, s, task="both", effects=effects, output=output,
                                              name="pilot", **kw))
        except HesspipeError:
            return None
        path = write_trial(Path(tmp) / "pilot", trial)
        plants = read_plants(path.parent / "plants.json")
        k = choose_k(plants)[0]
        t = motion_test(read_run(path), plants, PilotModel().complete({}, k), k=k, display=display)
    return t if t.get("available") else None


def rates(pool_a: list, pool_b: list, k: int, n: int, cohorts: int, rng) -> dict:
    """Share of cohorts (k pilots from `pool_a`, n - k from `pool_b`) each rule calls yes."""
    yes = {"verdict": 0, "fisher": 0, "binomial": 0}
    for _ in range(cohorts):
        picks = ([pool_a[i] for i in rng.integers(len(pool_a), size=k)]
                 + [pool_b[i] for i in rng.integers(len(pool_b), size=n - k)])
        v = cohort_verdict({f"p{i}": t for i, t in enumerate(picks)})
        yes["verdict"] += v["answer"] == "yes"
        yes["fisher"] += v["fisher_p"] < ALPHA
        yes["binomial"] += v["binomial_p"] < ALPHA
    return {r: c / cohorts for r, c in yes.items()}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--pilots", type=int, default=25, help="pilots per plant and output in each pool")
    ap.add_argument("--n", default="6,8,10", help="cohort sizes")
    ap.add_argument("--cohorts", type=int, default=2000, help="cohorts drawn per kind and size")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--seed", type=int, default=1, help="seed of the cohort draws")
    ap.add_argument("--display", choices=DISPLAYS, default=DEFAULT_DISPLAY,
                    help="the per-pilot test's display setting (default the library's)")
    args = ap.parse_args(argv)
    print("SYNTHETIC DATA: every pilot below is a run of the independent generator hesspipe.humanlike. "
          f"Per-pilot test display: {args.display}.")
    t0 = time.perf_counter()
    jobs = [(pool, plant, output, seed, args.display) for pool, (cases, _, _) in POOLS.items()
            for plant, output in cases for seed in range(args.pilots)]
    with ProcessPoolExecutor(args.workers) as ex:
        results = list(ex.map(pilot_test, jobs, chunksize=4))
    pools = {name: [] for name in POOLS}
    for (pool, *_), t in zip(jobs, results):
        if t is not None:
            pools[pool].append(t)
    for name, ts in pools.items():
        ps = np.array([t["p_value"] for t in ts])
        print(f"pool {name:<15} {ps.size:3d} pilots: p < {ALPHA:g} in {int(np.sum(ps < ALPHA)):2d}, "
              f"p < 1e-4 in {int(np.sum(ps < 1e-4)):2d}, median p {np.median(ps):.2g}")
    print(f"pools built in {time.perf_counter() - t0:.0f} s\n")
    rng = np.random.default_rng(args.seed)
    kinds = [(name, name, 0) for name in POOLS]
    kinds += [("standin-motion", "standin", 1), ("standin-motion", "drift", 1),
              ("standin-motion", "standin", 2), ("weak-motion", "standin", 1),
              ("weak-motion", "standin", 2)]
    print("share of cohorts called 'yes' (verdict: at least half of the pilots, the median-pilot "
          f"test; Fisher: at least one pilot; binomial: count of pilots at p < {ALPHA:g})")
    for n in (int(x) for x in args.n.split(",")):
        for a, b, k in kinds:
            label = a if k == 0 else f"{k} of {n} from {a}, others {b}"
            r = rates(pools[a], pools[b], k or n, n, args.cohorts, rng)
            print(f"  n {n:2d}  {label:<44} verdict {r['verdict']:.3f}  Fisher {r['fisher']:.3f}  "
                  f"binomial {r['binomial']:.3f}")
    print(f"wall time {time.perf_counter() - t0:.0f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
