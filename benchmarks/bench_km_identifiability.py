"""Benchmark: can Km be identified from JSBSim-flown runs of the disturbance task? (SYNTHETIC DATA)

Pilots of the pipeline's crossover-model cohort (expanded + remnant, cohort draws of seed 1)
fly the JSBSim 737 (hesspipe.flight.closed_loop, 120 Hz, recorded at 40 Hz) and are
identified with the fitted plants (expanded model, `df` criterion) with different sets of
parameters held at their true values (or, for 1/T1, at Hess's rule), to find what Km trades
with. Then a few pilots fly with an 8-line multisine on the reference (the visual path sees r,
the vestibular one does not) and are identified with the `output` criterion, which uses the
measured reference (8-25 s per identification).

Prints, per pilot and set, the relative errors of Ke, Km and K1 K2, then the medians.

Usage::

    nice python benchmarks/bench_km_identifiability.py [--pilots 10] [--reference-pilots 3]
"""

from __future__ import annotations

import argparse
import statistics
import sys
import tempfile
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
import bench_fly_pilot as B  # noqa: E402  (the same plants, draws and helpers)
from hesspipe.flight.approach import FlightConfig  # noqa: E402
from hesspipe.flight.closed_loop import fly_pilot_record  # noqa: E402
from hesspipe.identification.fit import identify  # noqa: E402
from hesspipe.pilot.hess import table1  # noqa: E402
from hesspipe.pilots.cohort import hess_corner  # noqa: E402


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--pilots", type=int, default=10)
    ap.add_argument("--reference-pilots", type=int, default=3)
    ap.add_argument("--reference-rms", type=float, default=0.01, help="rad/s")
    args = ap.parse_args(argv)
    print("SYNTHETIC DATA: Hess pilot models flying the JSBSim 737; identified with the fitted plants")
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        plants = B.fitted_plants(root)
        corner = hess_corner(plants)
        sets = {  # name: (free, fixed from the truth, fixed values)
            "1/T1 by Hess's rule, K1 free": (("Ke", "K1", "Km", "tau0", "wn", "zn"), ("K2",), {"1/T1": corner}),
            "K1, K2, 1/T1 true": (("Ke", "Km", "tau0", "wn", "zn"), ("K1", "K2", "1/T1"), {}),
            "K1 at Table 1, 1/T1 by rule": (("Ke", "Km", "tau0", "wn", "zn"), ("K2",),
                                            {"1/T1": corner, "K1": table1(1)["K1"]}),
        }
        errs = {name: {"Ke": [], "Km": [], "K1K2": []} for name in sets}
        for i in range(args.pilots):
            pid = f"pilot{i + 1:02d}"
            pseed, truth, params = B.draw(plants, pid, 1, ("motion_feedback",))
            f = fly_pilot_record("737", plants, truth["model"], params, seed=pseed, workdir=root / "w",
                                 record_every=B.EVERY, remnant_share=truth["remnant_share"], run_id=pid)
            tp = f.truth["parameters"]
            row = [pid]
            for name, (free, from_truth, values) in sets.items():
                fixed = {**{k: tp[k] for k in from_truth}, **values}
                p = identify(f.run, plants, "expanded", free=free, fixed=fixed, seed=pseed, criterion="df",
                             with_benchmark=False, with_identifiability=False).parameters
                e = errs[name]
                e["Ke"].append(B.rel(p["Ke"], tp["Ke"]))
                e["Km"].append(B.rel(p["Km"], tp["Km"]))
                e["K1K2"].append(B.rel(p["K1"] * p["K2"], tp["K1"] * tp["K2"]))
                row.append(f"{name}: Ke {100 * e['Ke'][-1]:.0f}% Km {100 * e['Km'][-1]:.0f}% "
                           f"K1K2 {100 * e['K1K2'][-1]:.0f}%")
            print(" | ".join(row), flush=True)
        print(f"median |relative error| over {args.pilots} pilots (df criterion, disturbance only):")
        for name, e in errs.items():
            print(f"  {name}: " + ", ".join(f"{k} {100 * statistics.median(v):.0f} %" for k, v in e.items()))

        cfg = FlightConfig()
        n = int(round(cfg.duration_s / cfg.dt_s))
        t = np.arange(n) * cfg.dt_s
        lines = (3, 7, 13, 23, 37, 53, 79, 113)  # cycles per 70 s: 0.04-1.6 Hz
        print(f"\nreference multisine ({len(lines)} lines, {args.reference_rms} rad/s rms) + the wind; "
              "output criterion, default free set:")
        for i in range(args.reference_pilots):
            pid = f"pilot{i + 1:02d}"
            pseed, truth, params = B.draw(plants, pid, 1, ("motion_feedback",))
            rng = np.random.default_rng(pseed)
            r = sum(np.sin(2 * np.pi * k * t / cfg.duration_s + rng.uniform(0, 2 * np.pi)) for k in lines)
            r *= args.reference_rms / np.std(r)
            f = fly_pilot_record("737", plants, truth["model"], params, seed=pseed, workdir=root / "w",
                                 record_every=B.EVERY, remnant_share=truth["remnant_share"], run_id=pid,
                                 reference=r)
            tp = f.truth["parameters"]
            p = identify(f.run, plants, "expanded", seed=pseed, criterion="output", with_benchmark=False,
                         with_identifiability=False).parameters
            print(f"{pid}: Ke {100 * B.rel(p['Ke'], tp['Ke']):.0f}%, Km {100 * B.rel(p['Km'], tp['Km']):.0f}%, "
                  f"K1K2 {100 * B.rel(p['K1'] * p['K2'], tp['K1'] * tp['K2']):.0f}%", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
