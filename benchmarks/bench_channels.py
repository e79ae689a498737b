"""Benchmark: the pilot's error and output channels apart, without a model, on the lab
stand-in (SYNTHETIC DATA).

The persons, runs and files of ``bench_lab_experiment.py`` (the independent generator's
precision pilots, yaw angle, single and double integrator, the cab turning with the displayed
angle, target and disturbance on the sparse layout of 81.92 s at 100 Hz, the gain wandering
with CV 0.15, remnant 10-40 %, files as the lab writes them, read back with the lab's
columns). For each person and condition, :func:`hesspipe.identification.separate_channels`
on one run and on the person's runs averaged line by line (``average_frf``), against the
generator's truth: the drawn pilot's visual path A and vestibular path B at the same lines
(``hesspipe.humanlike.pilots.parts``; B is zero without motion).

Prints per plant and condition, over persons: the median |Hpy|/|Hpe| between 1 and 5 rad/s
(estimated from one run, from the runs averaged, and the truth's), the median error
|Hpy - B|/|A| there, and how many motion persons' averaged ratio lies above every static
person's of the same plant.

    python benchmarks/bench_channels.py [--persons 6] [--runs 3] [--seed 7]
"""

from __future__ import annotations

import json
import statistics
import sys
import tempfile
from pathlib import Path

import numpy as np

from bench_lab_experiment import COLUMNS, PLANTS, experiment_arguments, write_condition
from hesspipe.core.formats import read_plants, read_run
from hesspipe.humanlike import pilots
from hesspipe.identification import average_frf, estimate_frf
from hesspipe.identification.frf_channels import BAND_RAD_S


def _truth_paths(person: dict, w: np.ndarray, motion_tf) -> tuple[np.ndarray, np.ndarray]:
    return pilots.parts(person, w, motion_tf if "Km" in person else None)


def _row(channels, person: dict, motion_tf) -> tuple[float, float, float]:
    """(estimated ratio, true ratio, median error over |A|) in the band."""
    A, B = _truth_paths(person, channels.freq_rad_s, motion_tf)
    band = (channels.freq_rad_s >= BAND_RAD_S[0]) & (channels.freq_rad_s <= BAND_RAD_S[1])
    return (channels.ratio_median, float(np.median(np.abs(B[band]) / np.abs(A[band]))),
            float(np.median(np.abs(channels.Hpy[band] - B[band]) / np.abs(A[band]))))


def _summary(values) -> str:
    return f"{statistics.median(values):.2f} ({min(values):.2f}-{max(values):.2f})"


def main(argv=None) -> int:
    args = experiment_arguments(__doc__).parse_args(argv)
    print("SYNTHETIC DATA: independent generator (hesspipe.humanlike), precision pilots, files as a lab writes them")
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        for tag in args.plants.split(","):
            averaged = {}
            for cond in ("motion", "static"):
                folder = root / f"{tag}_{cond}"
                truth = write_condition(folder, tag, cond, args.persons, args.runs, args.seed)
                plants = read_plants(root / f"plants_{tag}.json")
                cab = json.loads((root / f"plants_{tag}.json").read_text())["motion_path"]
                motion_tf = (cab["num"], cab["den"])
                one, avg = [], []
                for person, pilot in sorted(truth.items()):
                    runs = [read_run(p, columns=COLUMNS) for p in sorted(folder.glob(f"{person}_*.csv"))]
                    one.append(_row(estimate_frf(runs[0], plants).channels, pilot, motion_tf))
                    avg.append(_row(average_frf(runs, plants).channels, pilot, motion_tf))
                averaged[cond] = [r[0] for r in avg]
                est1, true, err1 = zip(*one)
                estn, _, errn = zip(*avg)
                print(f"{tag} ({PLANTS[tag]}), {cond}, {args.persons} persons: median |Hpy|/|Hpe| at "
                      f"{BAND_RAD_S[0]:g}-{BAND_RAD_S[1]:g} rad/s, median (range) over persons: one run "
                      f"{_summary(est1)}, {args.runs} runs averaged {_summary(estn)}, truth {_summary(true)}; "
                      f"error |Hpy - B|/|A|: one run {_summary(err1)}, averaged {_summary(errn)}", flush=True)
            top = max(averaged["static"])
            above = sum(r > top for r in averaged["motion"])
            print(f"{tag}: {above} of {len(averaged['motion'])} motion persons' averaged ratio above every "
                  f"static person's ({top:.2f})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
