"""Benchmark: is the motion verdict's Km/|Ke| estimate pulled down by the remnant? (SYNTHETIC DATA)

A Hess pilot with motion feedback from the independent generator (hesspipe.humanlike; the
paper's plant, angle display, target and disturbance: the pilot of ``bench_km_interval.py``'s
seed), flown again with its remnant at ``--share`` of the control power and a new remnant
draw each time. Per draw the motion test's own expanded fit's Km/|Ke| (Hess's form, the
estimate's model) and the estimate's (errors-in-variables weights, free equaliser) are
printed as log errors against the generator's value, then their means. The test's fit sits
low at high remnant; the estimate should not.

    python benchmarks/bench_km_remnant.py [--draws 10] [--share 0.4] [--seed 0]
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import tempfile
from pathlib import Path

from hesspipe.core.formats import read_plants, read_run
from hesspipe.core.seeds import derive_seed
from hesspipe.humanlike import draw_trial, simulate_trial, write_trial
from hesspipe.identification.criteria import choose_k
from hesspipe.identification.motion_test import hess_result, motion_test
from hesspipe.pilot.hess import table1


def log_errors(folder, spec, share: float, draw: int) -> tuple[float, float]:
    """(test fit, estimate): log of Km/|Ke| over the generator's, one remnant draw of `spec`."""
    truth = spec.pilot["Km"] / abs(spec.pilot["Ke"])
    remnant = {**spec.remnant, "share": share, "noise_seed": int(derive_seed(draw, "eiv"))}
    run = read_run(write_trial(folder, simulate_trial(dataclasses.replace(spec, remnant=remnant))))
    plants = read_plants(Path(folder) / "plants.json")
    k = choose_k(plants)[0]
    out = motion_test(run, plants, table1(k), k=k)
    pe = hess_result(out)["parameters_expanded"]
    return math.log(pe["Km"] / abs(pe["Ke"]) / truth), math.log(out["Km_per_Ke"] / truth)


def pilot(seed: int):
    """The generator's trial spec of the pilot studied (``bench_km_interval``'s draw)."""
    return draw_trial("paper", derive_seed(seed, "kmcov", "paper", "angle", "both"), task="both", pilot="hess",
                      effects=("motion_feedback",), output="angle", name="t")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--draws", type=int, default=10, help="remnant draws of the one pilot")
    ap.add_argument("--share", type=float, default=0.4, help="remnant's share of the control power")
    ap.add_argument("--seed", type=int, default=0, help="the pilot's seed")
    args = ap.parse_args(argv)
    if args.draws < 1 or not 0.0 < args.share < 1.0:
        ap.error("--draws: expected at least 1; --share: expected a number between 0 and 1")
    print(f"SYNTHETIC DATA: independent generator (hesspipe.humanlike), one Hess pilot with motion "
          f"feedback (paper plant, angle, seed {args.seed}), remnant {100 * args.share:g} % of the control power")
    spec = pilot(args.seed)
    fit, est = [], []
    with tempfile.TemporaryDirectory() as tmp:
        for r in range(args.draws):
            a, b = log_errors(Path(tmp) / str(r), spec, args.share, r)
            fit.append(a)
            est.append(b)
            print(f"draw {r}: log(Km/|Ke| / truth) test fit {a:+.3f}, estimate {b:+.3f}", flush=True)
    n = len(fit)
    print(f"mean over {n} draws: test fit {sum(fit) / n:+.3f} ({sum(a < -0.1 for a in fit)}/{n} low by more "
          f"than 10 %), estimate {sum(est) / n:+.3f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
