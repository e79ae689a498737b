"""The compare-pilots motion verdict on cohorts from the INDEPENDENT generator.

For each plant and seed, two SYNTHETIC cohorts of human-like pilots (hess-structured, or ``--pilot precision``) are
drawn by :func:`hesspipe.humanlike.draw_trial` (a draw whose pilot misses the
generator's crossover ranges is redrawn with the next sub-seed) (fine-step time-domain simulation that
shares no modelling code with hesspipe's pilot model; multisine disturbance lines,
remnant 10-40 %, tau 0.15-0.35 s): one with motion feedback in every pilot (Km = 0.2-1.0
times Ke), one without. Each cohort goes through ``compare_pilots`` (APID, 2 restarts);
printed: the verdict, its median-pilot p, the binomial p, Fisher's combined p, the per-pilot share of the
describing-function misfit that motion feedback removes with its p-value, and, for
contrast, the PSD-fitness improvement 1 - expanded/original of the paper's criterion.

    python benchmarks/bench_verdict.py [--n 8] [--seeds 1,2,3] [--plants roll,1/s]
                                       [--task disturbance|tracking|both] [--T 45] [--fs 60]
                                       [--output rate|angle] [--km-ratio 0.2,1.0]
                                       [--pilot precision] [--tau-m 0.15]
                                       [--remnant-at error] [--gain-drift 0.15] [--runs 3]
                                       [--layout sparse]

``--runs N``: each pilot flies the condition N times (retests); the verdict combines a
pilot's runs and counts pilots (``compare_pilots(pilot_id=...)``).

``--gain-drift CV``: each pilot's visual gain wanders within its run (CV, correlation
time 10 s).

``--layout sparse``: the forcing on :data:`hesspipe.humanlike.forcing.SPARSE_LAYOUT`
(81.92 s at 100 Hz, target lines 1-23 bins from the disturbance's) instead of the
generator's adjacent sets.

``--pilot precision``: McRuer precision pilots (with motion, the multimodal model's
vestibular path and canals), a structure other than the Hess model compare-pilots fits.

``--output angle``: the display shows the angle and the cab turns at its rate (the
generator's plants carry ``motion_path`` s/(0.01 s + 1)); with ``--task both`` this is the
stand-in for yaw-angle tracking trials with and without motion.
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

import numpy as np

from hesspipe.core.errors import HesspipeError
from hesspipe.core.formats import read_plants
from hesspipe.core.seeds import derive_seed
from hesspipe.humanlike import draw_trial, retest, simulate_trial, write_trial
from hesspipe.humanlike.forcing import SPARSE_LAYOUT
from hesspipe.pilots.compare import compare_pilots


def cohort(folder: Path, plant: str, n: int, seed: int, effects, task: str, T: float, fs: float,
           pilot: str = "hess", runs: int = 1, **draw) -> int:
    """Write `n` trials; a draw with no pilot meeting the generator's crossover/phase-margin
    ranges is redrawn with the next sub-seed. With `runs` > 1 each pilot flies the condition
    that many times (``humanlike.retest``: its run-to-run scatter, its own remnant), files
    ``pilotNN_rJ``. Returns the number of redraws."""
    redraws = 0
    for i in range(n):
        for attempt in range(50):
            s = derive_seed(seed, "bench_verdict", plant, task, ",".join(effects), str(i), str(attempt))
            try:
                name = f"pilot{i + 1:02d}" + ("_r1" if runs > 1 else "")
                spec = draw_trial(plant, s, task=task, pilot=pilot, effects=effects, T_m=T, fs=fs,
                                  name=name, **draw)
            except HesspipeError:
                redraws += 1
                continue
            write_trial(folder, simulate_trial(spec))
            for j in range(1, runs):
                again = retest(spec, derive_seed(s, "repeat-run", str(j)), name=f"pilot{i + 1:02d}_r{j + 1}")
                write_trial(folder, simulate_trial(again))
            break
    return redraws


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=8)
    ap.add_argument("--seeds", default="1,2,3")
    ap.add_argument("--plants", default="roll,1/s")
    ap.add_argument("--task", default="disturbance")
    ap.add_argument("--T", type=float, default=45.0)
    ap.add_argument("--fs", type=float, default=60.0)
    ap.add_argument("--output", default="rate", choices=("rate", "angle"))
    ap.add_argument("--km-ratio", default=None, help="Km/Ke range 'lo,hi' (default the generator's)")
    ap.add_argument("--pilot", choices=("hess", "precision"), default="hess")
    ap.add_argument("--tau-m", type=float, default=None, help="vestibular delay, s (default 0)")
    ap.add_argument("--remnant-at", choices=("control", "error"), default=None,
                    help="where the generator injects the remnant (default control)")
    ap.add_argument("--gain-drift", type=float, default=None,
                    help="the generator's within-run variation of the pilot's visual gain "
                         "(coefficient of variation, correlation time 10 s; default 0: time-invariant)")
    ap.add_argument("--runs", type=int, default=1,
                    help="runs per pilot (retests); the verdict then combines each pilot's runs "
                         "(compare_pilots(pilot_id=...)) and counts pilots")
    ap.add_argument("--layout", choices=("adjacent", "sparse"), default="adjacent",
                    help="sparse: hesspipe.humanlike.forcing.SPARSE_LAYOUT (81.92 s at 100 Hz; "
                         "overrides --T and --fs)")
    args = ap.parse_args(argv)
    if args.layout == "sparse":
        args.T, args.fs = SPARSE_LAYOUT["T_m"], SPARSE_LAYOUT["fs"]
    seeds = [int(s) for s in args.seeds.split(",")]
    print(f"SYNTHETIC data: independent generator hesspipe.humanlike, {args.pilot} pilots, task "
          f"{args.task}, output {args.output}, {args.n} pilots per cohort, {args.T:g} s at {args.fs:g} Hz")
    draw = {"output": args.output}
    if args.layout == "sparse":
        draw["line_bins"] = SPARSE_LAYOUT["line_bins"]
    if args.tau_m is not None:
        draw["tau_m"] = args.tau_m
    if args.gain_drift is not None:
        draw["gain_drift"] = args.gain_drift
    if args.remnant_at is not None:
        draw["remnant_at"] = args.remnant_at
    if args.km_ratio:
        draw["km_ratio"] = tuple(float(x) for x in args.km_ratio.split(","))
    tally = {"motion": {"yes": 0, "no": 0, "undetermined": 0}, "none": {"yes": 0, "no": 0, "undetermined": 0}}
    for plant in args.plants.split(","):
        for seed in seeds:
            for label, effects in (("motion", ("motion_feedback",)), ("none", ())):
                with tempfile.TemporaryDirectory() as tmp:
                    folder = Path(tmp) / "runs"
                    cohort(folder, plant, args.n, seed, effects, args.task, args.T, args.fs, args.pilot,
                           runs=args.runs, **draw)
                    t0 = time.perf_counter()
                    comp = compare_pilots(folder, read_plants(folder / "plants.json"), workers=1,
                                          seed=seed, progress=False,
                                          pilot_id=r"^(pilot\d+)_r" if args.runs > 1 else None)
                    dt = time.perf_counter() - t0
                v = comp.verdict()
                tally[label][v["answer"]] += 1
                print(f"\nplant {plant} seed {seed} cohort {label}: {v['sentence']}")
                print(f"  median-pilot p {v.get('majority_p', float('nan')):.3g} (the verdict's test), "
                      f"binomial p {v.get('binomial_p', float('nan')):.3g}, Fisher p "
                      f"{v.get('fisher_p', float('nan')):.3g}, {dt:.0f} s for {args.n} pilots"
                      + (f" x {args.runs} runs" if args.runs > 1 else ""))
                for p in comp.pilots:
                    t = p.motion_test
                    if t.get("available"):
                        print(f"  {p.id}: DF misfit removed {100 * t['gain']:5.1f} %  p {t['p_value']:.2g}"
                              f"  Km {t['Km']:.3g} +/- {t['Km_se']:.2g}   PSD improvement "
                              f"{100 * p.improvement:5.1f} %")
                    else:
                        print(f"  {p.id}: not tested ({t.get('reason')})")
                imp = comp.improvements
                print(f"  PSD-fitness improvement (paper's criterion): mean {100 * np.nanmean(imp):.1f} %")
                for f in comp.failures:
                    print(f"  FAILED {f.id}: {f.error}")
    # With one forcing function a cohort that is not "yes" is "undetermined" (cannot tell):
    # right for neither kind of cohort, wrong for neither.
    said = {k: ", ".join(f"{n} {a}" for a, n in v.items()) for k, v in tally.items()}
    print(f"\nright verdicts: motion cohorts {tally['motion']['yes']}/{sum(tally['motion'].values())} said yes; "
          f"no-motion cohorts {tally['none']['no']}/{sum(tally['none'].values())} said no "
          f"(motion cohorts: {said['motion']}; no-motion cohorts: {said['none']})")


if __name__ == "__main__":
    main()
