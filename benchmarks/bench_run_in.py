"""Benchmark: lab records that hold the whole trial, run-in (and run-out) included (SYNTHETIC DATA).

A laboratory's logger often writes the whole trial: the run-in (the forcing faded in, the
pilot settling into the loop, e.g. 8.08 s) and then the measurement time (81.92 s, one
period of every forcing line). hesspipe analyses the window that puts the lines on exact
bins (`hesspipe.identification.lines.analysis_window`); everything else should say what it
says on the measurement window alone. With ``--run-out S`` the logger also runs on for S s
after the measurement while the forcing fades out (the loop answering).

Each person of the lab stand-in (`bench_lab_experiment.py`: the independent generator's
precision pilots, yaw angle, both forcing functions, files as the lab writes them) flies one
trial with a run-in of ``--run-in`` s; the same trial is written twice, with its run-in
logged and without (the measurement window alone, sample for sample the same), and each
file goes through ``hesspipe diagnose`` as a user types it. Prints per condition: how often
the analysis window is exactly the measurement window, how often the names agree, motion
named on either file, and the largest change of the motion test's F.

    python benchmarks/bench_run_in.py [--persons 6] [--seed 7] [--run-in 8.08] [--run-out 0] [--plants SI,DI]
        [--conditions motion,static] [--out DIR]
"""

from __future__ import annotations

import contextlib
import io
import json
import sys
import tempfile
from pathlib import Path

import numpy as np

import bench_lab_experiment as B
from hesspipe.core.formats import read_run
from hesspipe.core.seeds import derive_seed
from hesspipe.humanlike import simulate_trial
from hesspipe.humanlike.writer import plants_dict
from hesspipe.identification.lines import analysis_window

COLUMNS = dict(item.split("=") for item in B.COLUMNS.split(","))


def trial_pair(tag: str, cond: str, person: int, seed: int, run_in: float, run_out: float = 0.0):
    """(the whole trial, its measurement window alone) of one person: one draw, simulated with
    and without its run-in (and run-out) logged."""
    effects = ("motion_feedback",) if cond == "motion" else ()
    out = []
    for logged in (run_in, 0.0):
        kw = dict(B.TRIAL, name=f"s{person + 1:02d}_{cond}_{'whole' if logged else 'window'}", run_in=run_in)
        if logged:
            kw["logged_run_in"] = logged
            if run_out:
                kw["logged_run_out"] = run_out
        spec = B.draw_person(B.PLANTS[tag], effects, derive_seed(seed, tag, cond, str(person)), **kw)
        out.append((spec, simulate_trial(spec)))
    return out


def main(argv=None) -> int:
    ap = B.experiment_arguments(__doc__, runs=False)
    ap.add_argument("--run-in", type=float, default=8.08, help="run-in, s, logged before the measurement")
    ap.add_argument("--run-out", type=float, default=0.0,
                    help="s logged after the measurement while the forcing fades out (0: none)")
    ap.add_argument("--conditions", default="motion,static", help="the lab's conditions flown, comma-separated")
    ap.add_argument("--out", default=None, help="keep the files here (default: a temporary folder)")
    args = ap.parse_args(argv)
    conditions = args.conditions.split(",")
    if not set(conditions) <= {"motion", "static"}:
        ap.error(f"--conditions: expected motion and/or static, got {args.conditions!r}")
    print(f"SYNTHETIC DATA: independent generator (hesspipe.humanlike), precision pilots, lab files; "
          f"{args.run_in:g} s of run-in logged before {B.TRIAL['T_m']:g} s of measurement"
          + (f", {args.run_out:g} s of fade-out after it" if args.run_out else ""))
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(args.out or tmp)
        for tag in args.plants.split(","):
            for cond in conditions:
                folder = root / f"{tag}_{cond}"
                folder.mkdir(parents=True, exist_ok=True)
                exact = same = 0
                offsets = []
                motion = [0, 0]
                df = []
                for person in range(args.persons):
                    (spec, whole), (_, window) = trial_pair(tag, cond, person, args.seed, args.run_in,
                                                            args.run_out)
                    plants = root / f"plants_{tag}.json"
                    plants.write_text(json.dumps(plants_dict(spec), indent=1))
                    reports = []
                    for trial in (whole, window):
                        path = folder / f"{trial.spec.name}.csv"
                        B.lab_file(trial, path)
                        reports.append(B.diagnose_file(path, plants, path.with_suffix(".diagnosis.json"))[0])
                    n_keep = int(round(args.run_in * B.TRIAL["fs"]))
                    with contextlib.redirect_stderr(io.StringIO()):
                        run = read_run(folder / f"{whole.spec.name}.csv", columns=COLUMNS)
                    start, length = analysis_window(run)
                    exact += (start, length) == (n_keep, window.time.size)
                    offsets.append(abs(start - n_keep) if length == window.time.size else np.inf)
                    names = [r["named_effects"] for r in reports]
                    same += names[0] == names[1]
                    for i, n in enumerate(names):
                        motion[i] += "motion_feedback" in n
                    f = [r["motion_verdict"]["statistic"] for r in reports]
                    df.append(abs(f[0] - f[1]) / max(f[1], 1.0))
                n = args.persons
                print(f"{tag} ({B.PLANTS[tag]}) {cond}: analysis window = the measurement window on {exact}/{n}; "
                      f"the same names {same}/{n}; motion named {motion[0]}/{n} whole trial, {motion[1]}/{n} "
                      f"window alone; largest change of F {max(df):.1%}; one period, at most "
                      f"{max(offsets):g} samples off the measurement: {int(np.sum(np.isfinite(offsets)))}/{n}",
                      flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
