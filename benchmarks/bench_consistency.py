"""Benchmark: are runs with a sign or units mistake named, and are correct runs left alone? (SYNTHETIC DATA)

Trials of the independent generator (hesspipe.humanlike) on the paper's and roll plants (Hess
pilots, rate and angle) and on 1/s and K/s2 (precision pilots, angle), both task types, with
no effect, motion feedback, a Dutch roll (plants miss it) or an actuator lag, written as the
generator's logger writes them and read back. Each run is checked as written, with the
control's sign flipped and with the output in degrees (hesspipe.plants.consistency).

    python benchmarks/bench_consistency.py [--seeds 2]
"""

from __future__ import annotations

import argparse
import itertools
import tempfile
from dataclasses import replace
from pathlib import Path

import numpy as np

from hesspipe.core.formats import read_plants, read_run
from hesspipe.core.seeds import derive_seed
from hesspipe.humanlike import draw_trial, simulate_trial, write_trial
from hesspipe.plants.consistency import consistency

EFFECTS = ((), ("motion_feedback",), ("dutch_roll",), ("actuator_lag",))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=2)
    args = ap.parse_args(argv)
    print("SYNTHETIC DATA: independent generator (hesspipe.humanlike)")
    counts = {"trials": 0, "refused as written": 0, "flip named": 0, "degrees named": 0}
    missed = []
    with tempfile.TemporaryDirectory() as tmp:
        for plant, output, task, eff, seed in itertools.product(("paper", "roll", "1/s", "K/s2"), ("rate", "angle"),
                                                                ("both", "disturbance"), EFFECTS, range(args.seeds)):
            if plant in ("1/s", "K/s2") and (output == "rate" or "dutch_roll" in eff):
                continue
            pilot = "precision" if plant in ("1/s", "K/s2") else "hess"
            name = f"{plant} {output} {task} {'+'.join(eff) or 'none'} seed {seed}"
            try:
                spec = draw_trial(plant, derive_seed(seed, "cons", plant, output, task, ",".join(eff)), task=task,
                                  pilot=pilot, effects=eff, output=output, name="t")
                trial = simulate_trial(spec)
            except Exception as exc:  # noqa: BLE001 - a draw the generator cannot make is skipped, said
                print(f"{name}: no trial ({exc})")
                continue
            folder = Path(tmp) / f"{len(missed)}-{counts['trials']}"
            run = read_run(write_trial(folder, trial))
            plants = read_plants(folder / "plants.json")
            c = consistency(run, plants)
            flip = consistency(replace(run, control=-run.control), plants).problem()
            deg = consistency(replace(run, output=np.degrees(run.output)), plants).problem()
            counts["trials"] += 1
            counts["refused as written"] += c.problem() is not None
            counts["flip named"] += flip is not None
            counts["degrees named"] += deg is not None
            if flip is None or deg is None:
                missed.append(name)
            print(f"{name}: as written {100 * c.unexplained:.1f} % of the output's power unexplained "
                  f"({'REFUSED' if c.problem() else 'accepted'}); flipped control "
                  f"{'named' if flip else 'not named'}; degrees {'named' if deg else 'not named'}", flush=True)
    print(", ".join(f"{k} {v}" for k, v in counts.items()))
    print("not named on: " + ("; ".join(missed) or "none"))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
