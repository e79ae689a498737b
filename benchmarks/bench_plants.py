"""Stage two across aircraft, seeds and decimation factors.

Flies each JSBSim transport with the default excitation (several seeds), identifies the
plants with the default configuration and with other decimation factors, and prints the
validation fit, chosen orders, the continuous-vs-discrete frequency check and the wall
time. Also recovers the paper's analytic aircraft from synthetic records (known answer).

    /work/venv/bin/python benchmarks/bench_plants.py [--aircraft 737 B747 ...] [--seeds 1 2 3]

Runs in about two to four minutes on two cores.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

from hesspipe.core.errors import HesspipeError
from hesspipe.flight.approach import FlightConfig, fly
from hesspipe.plants.fit import fit_plants
from hesspipe.plants.settings import PlantsConfig

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--aircraft", nargs="+", default=["737", "B747", "MD11", "global5000"])
    ap.add_argument("--seeds", nargs="+", type=int, default=[1, 2, 3])
    ap.add_argument("--decimate", nargs="+", type=int, default=[4, 6, 8])
    args = ap.parse_args(argv)
    base = PlantsConfig(on_check_failure="warn")
    print("aircraft  seed  dec  channel                ARX(na,nb,nk)  val fit %  cont fit %  "
          "max dB  max deg  time s")
    worst = {}
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        for ac in args.aircraft:
            for seed in args.seeds:
                flight = tmp / f"{ac}-{seed}"
                try:
                    fly(ac, FlightConfig(), flight, seed=seed)
                except HesspipeError as exc:
                    print(f"{ac:8s}  {seed:4d}  flight failed: {exc}")
                    break
                for q in args.decimate:
                    t0 = time.perf_counter()
                    res = fit_plants(flight, tmp / f"p-{ac}-{seed}-{q}", replace(base, decimate=q))
                    wall = time.perf_counter() - t0
                    for key, f in res.fits.items():
                        c = f.check
                        print(f"{ac:8s}  {seed:4d}  {q:3d}  {key:21s}  {str(f.model.orders):13s}  "
                              f"{f.fit_validation:9.2f}  {f.fit_validation_continuous:10.2f}  "
                              f"{c.max_gain_error_db:6.3f}  {c.max_phase_error_deg:7.3f}  {wall:6.2f}")
                        k = (q, key)
                        worst[k] = min(worst.get(k, np.inf), f.fit_validation)
        print("\nworst validation fit per decimation and channel (all aircraft, all seeds):")
        for (q, key), v in sorted(worst.items()):
            print(f"  decimate {q}: {key:21s} {v:6.2f} %")

        # Known answer: the analytic aircraft's full model, synthetic records, several seeds.
        from hesspipe.plants import analytic
        from hesspipe.plants.d2c import frequency_response
        from test_plants import _write_synthetic_flight  # the tests' generator, not duplicated

        truth = analytic.analytic_transfer_functions(analytic.load_analytic("roskam"))
        f = np.logspace(np.log10(0.02), np.log10(2.0), 200)
        print("\nsynthetic roskam (SYNTHETIC DATA): identified continuous plant vs the true one, 0.02-2 Hz")
        for seed in args.seeds:
            folder = _write_synthetic_flight(tmp / f"syn-{seed}", seed=seed)
            res = fit_plants(folder, tmp / f"syn-out-{seed}", base)
            for key, true in (("control_to_output", truth.full_control),
                              ("disturbance_to_output", truth.full_disturbance)):
                r = frequency_response(res.fits[key].continuous, f) / frequency_response(true, f)
                print(f"  seed {seed}  {key:21s} ARX{res.fits[key].model.orders}  val fit "
                      f"{res.fits[key].fit_validation:6.2f} %  max {np.max(np.abs(20 * np.log10(np.abs(r)))):.3f} dB "
                      f"{np.max(np.abs(np.degrees(np.angle(r)))):.2f} deg")
    return 0


if __name__ == "__main__":
    sys.exit(main())
