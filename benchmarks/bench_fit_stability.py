"""Benchmark: does a diagnosis move with a file's last digits? (SYNTHETIC DATA)

A logger's rounding, a units conversion or another export of the same trial changes a
record's signals in their last digits. The named effects rest on the describing function
and should not move; nor should the control-spectrum fits the report shows (the Eq. 10 gap
and the log-spectral RMS before and after the named effects). Each trial of the independent
generator (hesspipe.humanlike: Hess pilots on the paper's and the roll plants, rate and angle,
with a target and with the disturbance alone, with and without motion feedback, 70 s at
50 Hz; precision pilots of the lab stand-in, yaw angle on 1/s and K/s^2, 81.92 s at 100 Hz)
is written by the generator's logger, read back, and diagnosed as read and with its control
or output multiplied by 1 + 1e-12, 1 - 1e-9 and 1 + 1e-10. Prints per trial the names and
the range of the log-spectral RMS before and after over the four readings, then how many
trials kept their names, the spreads' median and largest, the mean log-spectral RMS after
(lower: the fits found better optima) and the median CPU time per diagnosis.

    python benchmarks/bench_fit_stability.py [--seed 40] [--precision 4]
"""

from __future__ import annotations

import argparse
import dataclasses
import tempfile
import time
from pathlib import Path

import numpy as np

import bench_lab_experiment as B
from hesspipe.core.formats import read_plants, read_run
from hesspipe.core.seeds import derive_seed
from hesspipe.diagnose import diagnose
from hesspipe.humanlike import draw_trial, simulate_trial, write_trial
from hesspipe.humanlike.forcing import SPARSE_LAYOUT

READINGS = {"as written": {}, "u*(1+1e-12)": {"control": 1 + 1e-12}, "u*(1-1e-9)": {"control": 1 - 1e-9},
            "y*(1+1e-10)": {"output": 1 + 1e-10}}


def _trials(folder: Path, seed: int, n_precision: int):
    """(name, run file) of every trial, written into `folder`."""
    out = []
    for plant, output in (("paper", "rate"), ("roll", "angle"), ("paper", "angle"), ("roll", "rate")):
        for task in ("both", "disturbance"):
            for eff in ((), ("motion_feedback",)):
                name = f"hess-{plant}-{output}-{task}-{'motion' if eff else 'none'}"
                spec = draw_trial(plant, derive_seed(seed, plant, output, task, *eff), task=task, pilot="hess",
                                  effects=eff, output=output, fs=50.0, T_m=70.0, name="t")
                out.append((name, write_trial(folder / name, simulate_trial(spec))))
    layout = dict(line_bins=SPARSE_LAYOUT["line_bins"], fs=SPARSE_LAYOUT["fs"], T_m=SPARSE_LAYOUT["T_m"])
    for i in range(n_precision):
        plant, eff = ("1/s", "K/s2")[i % 2], (("motion_feedback",), ())[(i // 2) % 2]
        name = f"precision-{plant.replace('/', '')}-{'motion' if eff else 'static'}-{i}"
        spec = B.draw_person(plant, eff, derive_seed(seed, "precision", str(i)), name="t", task="both",
                             pilot="precision", output="angle", tau_m=0.15, gain_drift=0.15, **layout)
        out.append((name, write_trial(folder / name, simulate_trial(spec))))
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seed", type=int, default=40)
    ap.add_argument("--precision", type=int, default=4, help="precision-pilot trials besides the 16 Hess trials")
    args = ap.parse_args(argv)
    print("SYNTHETIC DATA: independent generator (hesspipe.humanlike); each trial diagnosed as read and "
          "with its last digits changed")
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for name, path in _trials(Path(tmp), args.seed, args.precision):
            run, plants = read_run(path), read_plants(path.parent / "plants.json")
            res = []
            for scale in READINGS.values():
                r = dataclasses.replace(run, **{c: getattr(run, c) * v for c, v in scale.items()})
                t0 = time.process_time()
                d = diagnose(r, plants)
                res.append((d.named_effects, d.log_rms_db_before, d.log_rms_db_after, time.process_time() - t0))
            names = {x[0] for x in res}
            before, after = [x[1] for x in res], [x[2] for x in res]
            rows.append((len(names) == 1, np.ptp(before), np.ptp(after), np.mean(after), [x[3] for x in res]))
            print(f"{name:34s} {','.join(res[0][0]) or '-':32s} {'same' if len(names) == 1 else 'NAMES DIFFER'}"
                  f" | before {min(before):.2f}-{max(before):.2f} dB, after {min(after):.2f}-{max(after):.2f} dB"
                  f" | {np.median([x[3] for x in res]):.2f} s", flush=True)
    sb, sa = [r[1] for r in rows], [r[2] for r in rows]
    print(f"SUMMARY: {len(rows)} trials x {len(READINGS)} readings; names the same on {sum(r[0] for r in rows)}; "
          f"spread of the log-spectral RMS before: median {np.median(sb):.2f} dB, largest {max(sb):.2f} dB; "
          f"after: median {np.median(sa):.2f} dB, largest {max(sa):.2f} dB; mean after {np.mean([r[3] for r in rows]):.3f} dB; "
          f"median CPU {np.median([c for r in rows for c in r[4]]):.2f} s per diagnosis")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
