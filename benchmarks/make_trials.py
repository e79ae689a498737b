"""Write folders of SYNTHETIC human-like trials from the independent generator.

One folder per plant (``OUT/<plant-tag>/pilotNN.csv`` + ``.truth.json`` +
``plants.json``), N trials each, for benchmarks of the describing-function
identification (issue 12) and of diagnose (issue 13). Prints what it wrote:
per trial the true crossover, phase margin, delay and remnant share.

    python benchmarks/make_trials.py OUT --n 20 --seed 1
    python benchmarks/make_trials.py OUT --plants roll --pilot hess \\
        --effects motion_feedback --task both --n 10
    python benchmarks/make_trials.py OUT --plants path/to/plants.json --n 5
"""

from __future__ import annotations

import argparse
import json
import re
import sys
import time

from hesspipe.core.errors import HesspipeError
from hesspipe.humanlike import EFFECTS, make_trials

DEFAULT_PLANTS = ("1/s", "1/(s(s+1))", "K/s2")


def tag(plant: str, effects) -> str:
    base = re.sub(r"[^A-Za-z0-9]+", "_", plant.split("/")[-1] if plant.endswith(".json")
                  else plant).strip("_") or "plant"
    return "-".join([base, *effects]) if effects else base


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("out", help="output folder (one sub-folder per plant)")
    ap.add_argument("--plants", default=",".join(DEFAULT_PLANTS),
                    help="comma-separated: 1/s, 1/(s(s+1)), K/s2, roll, paper or a plants.json")
    ap.add_argument("--n", type=int, default=20, help="trials per plant")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--task", default="disturbance", choices=["disturbance", "tracking", "both"])
    ap.add_argument("--pilot", default="precision", choices=["precision", "hess"])
    ap.add_argument("--effects", default="", help=f"comma-separated of {', '.join(EFFECTS)}")
    ap.add_argument("--output", default="rate", choices=["rate", "angle"],
                    help="roll/paper plants: roll rate or roll angle task")
    ap.add_argument("--disturbance", default=None, choices=["input", "wind"])
    ap.add_argument("--style", default=None, help="CSV style: plain, g9, ms, epoch_ms, epoch_us, "
                    "g17 (default: drawn per trial)")
    a = ap.parse_args(argv)
    effects = tuple(e for e in a.effects.split(",") if e)
    plants = [p.strip() for p in a.plants.split(",") if p.strip()]
    try:
        for plant in plants:
            folder = f"{a.out}/{tag(plant, effects)}"
            t0 = time.perf_counter()
            paths = make_trials(folder, plant, a.n, a.seed, task=a.task, pilot=a.pilot,
                                effects=effects, style=a.style, output=a.output,
                                disturbance=a.disturbance)
            dt = time.perf_counter() - t0
            print(f"{folder}: {len(paths)} SYNTHETIC trials of {plant} ({a.task}, {a.pilot} pilot"
                  f"{', effects ' + ','.join(effects) if effects else ''}) in {dt:.1f} s")
            for p in paths:
                t = json.loads(p.with_suffix(".truth.json").read_text())
                c = t["crossover"]
                print(f"  {p.name}: wc {c['frequency_rad_s']:.2f} rad/s, PM {c['phase_margin_deg']:.1f} deg,"
                      f" delay {t['pilot']['tau_realised']:.3f} s, remnant "
                      f"{100 * t['remnant']['share_realised']:.0f} %, time style {t['style']['time']}")
    except HesspipeError as exc:
        print(f"make_trials: error: {exc}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
