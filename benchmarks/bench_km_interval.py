"""Benchmark: does each pilot's Km interval of the motion verdict cover the truth? (SYNTHETIC DATA)

Hess pilots with motion feedback from the independent generator (hesspipe.humanlike; paper's
and roll plants, rate and angle displays), written as the generator's logger writes them and
read back; compare-pilots' motion test (hesspipe.identification.motion_test) with its 95 %
profile-likelihood intervals of Km and of Km/|Ke| (the vestibular gain relative to the
visual one, which the valley of Ke, Km and the proprioceptive gain leaves identified). Prints
per trial the estimates, the intervals, the generator's values and the delta-method interval
(Km +- 1.96 Km_se), then how often each covers the truth, the intervals' median widths
(upper over lower end) and the profiles' extra CPU time.

    python benchmarks/bench_km_interval.py [--seeds 10] [--seed-start 0] [--tasks both,disturbance]
                                                  [--display either|compensatory|pursuit]
"""

from __future__ import annotations

import argparse
import itertools
import math
import tempfile
import time
from pathlib import Path

from hesspipe.core.choices import DEFAULT_DISPLAY, DISPLAYS
from hesspipe.core.formats import read_plants, read_run
from hesspipe.core.seeds import derive_seed
from hesspipe.humanlike import draw_trial, simulate_trial, write_trial
from hesspipe.identification.criteria import choose_k
from hesspipe.identification.motion_test import motion_test
from hesspipe.pilot.hess import table1


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=10)
    ap.add_argument("--seed-start", type=int, default=0)
    ap.add_argument("--tasks", default="both,disturbance")
    ap.add_argument("--level", type=float, default=0.95)
    ap.add_argument("--display", choices=DISPLAYS, default=DEFAULT_DISPLAY,
                    help="what the motion test is told the pilot saw (the generator's pilots are compensatory)")
    args = ap.parse_args(argv)
    print("SYNTHETIC DATA: independent generator (hesspipe.humanlike), Hess pilots with motion feedback")
    total = {"profile": 0, "delta": 0, "ratio": 0, "n": 0, "extra_cpu": [], "width": [], "ratio_width": []}
    with tempfile.TemporaryDirectory() as tmp:
        for task in args.tasks.split(","):
            cov = {"profile": 0, "delta": 0, "ratio": 0, "n": 0}
            for plant, output, seed in itertools.product(("paper", "roll"), ("rate", "angle"),
                                                         range(args.seed_start, args.seed_start + args.seeds)):
                try:
                    spec = draw_trial(plant, derive_seed(seed, "kmcov", plant, output, task), task=task,
                                      pilot="hess", effects=("motion_feedback",), output=output, name="t")
                except Exception as exc:  # noqa: BLE001 - a draw the generator cannot make is skipped, said
                    print(f"{task} {plant} {output} seed {seed}: no trial ({exc})")
                    continue
                trial = simulate_trial(spec)
                folder = Path(tmp) / f"{task}-{plant}-{output}-{seed}"
                run = read_run(write_trial(folder, trial))
                plants = read_plants(folder / "plants.json")
                k = choose_k(plants)[0]
                t0 = time.process_time()
                motion_test(run, plants, table1(k), k=k, display=args.display)
                t1 = time.process_time()
                r = motion_test(run, plants, table1(k), k=k, interval=args.level, display=args.display)
                t2 = time.process_time()
                total["extra_cpu"].append((t2 - t1) - (t1 - t0))
                km, (lo, hi), se = trial.truth["pilot"]["Km"], r["Km_interval"], r["Km_se"]
                inside = lo <= km <= hi
                delta = math.isfinite(se) and abs(km - r["Km"]) <= 1.96 * se
                ratio = km / abs(trial.truth["pilot"]["Ke"])
                rlo, rhi = r["Km_per_Ke_interval"]
                r_in = rlo <= ratio <= rhi
                cov["n"] += 1
                cov["profile"] += inside
                cov["delta"] += delta
                cov["ratio"] += r_in
                total["width"].append(hi / lo if lo > 0 else math.inf)
                total["ratio_width"].append(rhi / rlo if rlo > 0 else math.inf)
                print(f"{task} {plant} {output} seed {seed}: p {r['p_value']:.2g}, Km {r['Km']:.3g}, "
                      f"profile [{lo:.3g}, {hi:.3g}] {'covers' if inside else 'MISSES'} the truth {km:.3g}; "
                      f"+-1.96 se {1.96 * se:.3g} {'covers' if delta else 'misses'}; Km/|Ke| "
                      f"{r['Km_per_Ke']:.3g} [{rlo:.3g}, {rhi:.3g}] {'covers' if r_in else 'MISSES'} "
                      f"the truth {ratio:.3g}{' (pursuit fit)' if r['feedforward'] else ''}", flush=True)
            print(f"{task}: Km's profile interval covers {cov['profile']}/{cov['n']}, delta method "
                  f"{cov['delta']}/{cov['n']}, Km/|Ke|'s profile interval {cov['ratio']}/{cov['n']} "
                  f"(nominal {100 * args.level:g} %)")
            for key in ("profile", "delta", "ratio", "n"):
                total[key] += cov[key]
    extra = sorted(total["extra_cpu"])
    width, rwidth = sorted(total["width"]), sorted(total["ratio_width"])
    print(f"all: Km's profile {total['profile']}/{total['n']}, delta method {total['delta']}/{total['n']}, "
          f"Km/|Ke|'s profile {total['ratio']}/{total['n']}; median width (upper/lower end) Km "
          f"{width[len(width) // 2]:.3g}, Km/|Ke| {rwidth[len(rwidth) // 2]:.3g}; both profiles' extra CPU "
          f"per test median {extra[len(extra) // 2]:.2f} s, max {extra[-1]:.2f} s")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
