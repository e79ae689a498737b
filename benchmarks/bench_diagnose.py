"""Benchmark of ``diagnose`` on hidden effects from the independent generator (SYNTHETIC DATA).

Every run is drawn by :mod:`hesspipe.humanlike` (fine-step block simulation of a
human-like Hess pilot, literature parameter ranges, multisine forcing, shaped remnant:
no hesspipe model code), written to a temporary folder with its ``plants.json``, read
back and diagnosed with the original model and every registered candidate, 70 s at 50 Hz
(``--fs``, ``--T-m``: another logger and record length, e.g. 100 Hz and 81.92 s).

Cases: hidden effect (none, motion_feedback with Km from weak to strong, extra_delay
0.04-0.1 s, an elevated remnant, dutch_roll, actuator_lag, and two at once:
extra_delay + dutch_roll, motion_feedback + dutch_roll) x plants (``paper``: Table 4 rolling approximation with the
paper's Eq. 16 wind path; ``roll``: Table 4 both paths, plant-input disturbance) x output
(roll rate, roll angle) x task (disturbance only; disturbance and target); ``--plants
1/s,K/s2 --outputs angle --tasks both`` adds the single and double integrator with an
angle display the cab turns with (plant-input disturbance, motion path s/(0.01 s + 1)):
the stand-in for yaw-angle tracking with and without motion. Every
generated baseline carries the generator's ordinary remnant (10-40 % of the control's
variance), so ``remnant`` named on a baseline is not counted as a false pilot-side name;
it is reported apart.

Prints per case, as soon as it is done, one compact confusion row (first named effect)
with the case's target (first-named effect right in >= 90 % of every case; "remnant
aside" also scores the first effect named besides the remnant every generated run
carries; no pilot-side name on baselines; both of two hidden effects named in >= 80 %),
then the whole matrix, how often motion_feedback is named with and without a hidden
motion feedback (>= 70 % / <= 10 %) and the median CPU time per diagnosis
(``time.process_time``: one core's work, independent of how loaded the shared machine is).
The method was developed on seeds 100-104 (``--seed-start 100``; the aircraft-side
evidence test and the Dutch-roll refit on 100-111); the README reports seeds 0-9.

Usage::

    python benchmarks/bench_diagnose.py [--seeds 10] [--seed-start 0] [--quiet] [--plants paper,roll]
                                        [--outputs rate,angle] [--tasks disturbance,both]
                                        [--effects none,dutch_roll,...] [--km-ratio 1.0,1.0]
                                        [--tau-m 0.15] [--fs 100 --T-m 81.92] [--paired] [--repeats 3]
                                        [--pilot precision] [--remnant-at error] [--gain-drift 0.15]
                                        [--layout sparse] [--motion-path NUM;DEN] [--told-motion-path NUM;DEN|none]
                                        [--known-delay 0.03]

``--layout sparse``: the forcing on :data:`hesspipe.humanlike.forcing.SPARSE_LAYOUT` (81.92 s
at 100 Hz, ten lines per set, target lines 1-23 bins from the disturbance's) instead of the
generator's adjacent sets at 70 s and 50 Hz.

``--motion-path NUM;DEN``: the simulator's motion path from the output to the cab's angular
velocity (e.g. a yaw washout), which the generator's pilot feels and plants.json carries,
instead of the plant's own (s/(0.01 s + 1) on an angle display).

``--told-motion-path NUM;DEN`` (or ``none``): the motion path diagnose is told (its
plants.json), where it differs from the simulator's: a user's approximation of the platform
(a lag or a washout left out, a washout's gain or corner misjudged); ``none`` leaves the key
out (the paper's platform and washout on a rate output).

``--gain-drift CV``: the pilot's visual gain wanders within each run (coefficient of
variation CV, correlation time 10 s), as a human's does; the describing function averages
it and its sidebands add to the remnant between the lines.

``--pilot precision`` draws McRuer precision pilots instead of Hess-structured ones (with
motion: the multimodal model of motion experiments, its own canal model; see
``hesspipe.humanlike.pilots``): pilots whose structure is not the one diagnose fits, as
real humans' is not.

``--known-delay MARGIN``: diagnose is told the pilot's own visual delay, as a user who
knows it tells ``hesspipe diagnose --max-pilot-delay`` (the generator pilot's true delay +
MARGIN s): what one record shows of a simulator's extra delay when the pilot's is known.

``--paired`` gives every diagnosis a baseline run of the same pilot (``humanlike.retest``:
the aircraft as drawn, no pilot-side effect, the pilot's run-to-run scatter, its own
remnant and forcing phases): the within-subject design in which a simulator's extra delay
can be told from the pilot's own. ``--repeats N`` flies the condition N times (retests of
the pilot; the runs share the simulator's extra delay): diagnose pools them in the motion
test, and with ``--paired`` (N baseline runs too) the delay test compares the conditions'
mean delays.
"""

from __future__ import annotations

import argparse
import itertools
import sys
import tempfile
import time
from collections import Counter
from dataclasses import replace
from pathlib import Path

import numpy as np

from hesspipe.core.choices import DEFAULT_DISPLAY, DISPLAYS
from hesspipe.core.errors import HesspipeError
from hesspipe.core.formats import read_plants, read_run
from hesspipe.core.seeds import derive_seed
from hesspipe.diagnose.settings import DiagnoseConfig
from hesspipe.diagnose.workflow import diagnose
from hesspipe.humanlike import draw_trial, retest, simulate_trial, write_trial
from hesspipe.humanlike.forcing import SPARSE_LAYOUT

EFFECTS = ("none", "motion_feedback", "extra_delay", "remnant", "dutch_roll", "actuator_lag",
           "extra_delay+dutch_roll", "motion_feedback+dutch_roll")
PILOT_SIDE = ("motion_feedback", "otoliths", "extra_delay")


def run_case(folder, plant, output, task, effect, seed, paired=False, pilot="hess", repeats=1, config=None,
             known_delay=None, told_path=False, **draw):
    effects = () if effect == "none" else tuple(effect.split("+"))
    s = derive_seed(seed, "bench-diagnose", plant, output, task, effect)
    kw = dict(disturbance="wind", fs=50.0, T_m=70.0) if plant == "paper" else dict(fs=50.0, T_m=70.0)
    kw.update(draw)
    name = f"{plant}-{output}-{task}-{effect}-{seed}".replace("/", "_")   # "1/s", "K/s2"
    if pilot != "hess":
        name += f"-{pilot}"
    try:
        spec = draw_trial(plant, s, task=task, pilot=pilot, effects=effects, output=output, name=name, **kw)
    except HesspipeError as exc:  # the generator found no pilot in its ranges: not diagnose's doing
        return None, str(exc)
    try:
        trial = simulate_trial(spec)
    except HesspipeError as exc:  # a drawn loop that diverges (seen with a vestibular delay)
        return None, str(exc)
    path = write_trial(Path(folder) / name, trial)
    run = read_run(path)
    plants = read_plants(path.parent / "plants.json")
    if told_path is not False:   # None: the key left out; (num, den): another path than the simulator's
        plants = replace(plants, motion_path=told_path)
    base, more = [], []
    # With repeats, more runs of the condition (retests of the pilot: its run-to-run
    # scatter, its own remnant and forcing phases; the simulator's extra delay kept) and,
    # paired, as many of the baseline condition (the same aircraft, no pilot-side effect).
    for j in range(1, repeats):
        try:
            rspec = retest(spec, derive_seed(s, "repeat-run", str(j)), name=f"{name}-{j + 1}")
            more.append(read_run(write_trial(Path(folder) / rspec.name, simulate_trial(rspec))))
        except HesspipeError as exc:
            return None, f"repeat run: {exc}"
    for j in range(repeats if paired else 0):
        try:
            bspec = retest(spec, derive_seed(s, "baseline-run", *([str(j)] if j else [])), effects=(),
                           name=name + "-baseline" + ("" if j == 0 else f"-{j + 1}"))
            base.append(read_run(write_trial(Path(folder) / bspec.name, simulate_trial(bspec))))
        except HesspipeError as exc:
            return None, f"baseline run: {exc}"
    if known_delay is not None:   # the user knows the pilot's own delay (a model pilot's)
        config = replace(config or DiagnoseConfig(), max_pilot_delay=spec.pilot["tau_v"] + known_delay)
    t = time.process_time()
    d = diagnose(run, plants, seed=seed, baseline_run=base or None, repeat_runs=more, config=config)
    return d, time.process_time() - t


def _coefficients(ap, flag: str, text: str) -> tuple[list, list]:
    """A transfer function's 'NUM;DEN' (comma-separated, highest power first), or the parser's error."""
    try:
        num, den = ([float(x) for x in part.split(",")] for part in text.split(";"))
    except ValueError:
        ap.error(f"{flag}: expected 'NUM;DEN' (comma-separated coefficients), got {text!r}")
    return num, den


def _row(plant, output, task, effect, row, n) -> tuple[str, bool]:
    """One compact confusion line and whether the case meets its target."""
    firsts, both, false_pilot, remnant_named, aside = row
    conf = ", ".join(f"{k} {v}" for k, v in firsts.most_common())
    if effect == "none":
        verdict = f"pilot-side {false_pilot}/{n}; remnant named {remnant_named}/{n}"
        ok = false_pilot == 0
    elif "+" in effect:
        verdict = f"both named {100 * both / n:.0f} % (>= 80)"
        ok = both >= 0.8 * n
    else:
        right = firsts[effect]
        verdict = f"first right {100 * right / n:.0f} %, remnant aside {100 * aside / n:.0f} % (>= 90)"
        ok = right >= 0.9 * n
    return (f"  {plant:>5}/{output:<5}/{task:<11} {effect:<22} {conf:<48} {verdict} "
            f"{'ok' if ok else 'MISSED'}"), ok


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=10)
    ap.add_argument("--seed-start", type=int, default=0,
                    help="first seed (reported figures: 0..; development used 100..)")
    ap.add_argument("--quiet", action="store_true", help="no per-run lines")
    ap.add_argument("--plants", default="paper,roll")
    ap.add_argument("--outputs", default="rate,angle")
    ap.add_argument("--tasks", default="disturbance,both")
    ap.add_argument("--effects", default=",".join(EFFECTS))
    ap.add_argument("--km-ratio", default=None,
                    help="the generator's Km/Ke range 'lo,hi' (default its literature range)")
    ap.add_argument("--tau-m", type=float, default=None,
                    help="the generator's vestibular delay, s (default its own, 0)")
    ap.add_argument("--fs", type=float, default=None, help="logged rate, Hz (default 50)")
    ap.add_argument("--T-m", type=float, default=None,
                    help="measured length, s (default 70; fs*T_m whole, e.g. 100 Hz and 81.92 s)")
    ap.add_argument("--pilot", choices=("hess", "precision"), default="hess",
                    help="the generator's pilot structure (precision: McRuer's, with the "
                         "multimodal model's vestibular path under motion)")
    ap.add_argument("--remnant-at", choices=("control", "error"), default=None,
                    help="where the generator injects the remnant (default control; error: "
                         "perceptual noise shaped by the pilot's own dynamics, as Levison's)")
    ap.add_argument("--gain-drift", type=float, default=None,
                    help="the generator's within-run variation of the pilot's visual gain "
                         "(coefficient of variation, correlation time 10 s; default 0: time-invariant)")
    ap.add_argument("--paired", action="store_true",
                    help="give diagnose a baseline run of the same pilot (humanlike.retest: no "
                         "pilot-side effect, the pilot's run-to-run scatter, another remnant)")
    ap.add_argument("--repeats", type=int, default=1,
                    help="runs of the condition (pooled by the motion test; with --paired also of the "
                         "baseline, and the delay test compares their means)")
    ap.add_argument("--layout", choices=("adjacent", "sparse"), default="adjacent",
                    help="sparse: hesspipe.humanlike.forcing.SPARSE_LAYOUT (81.92 s at 100 Hz, "
                         "target lines 1-23 bins from the disturbance's; overrides --fs and --T-m)")
    ap.add_argument("--motion-path", default=None, metavar="NUM;DEN",
                    help="the simulator's motion path (output -> cab angular velocity), polynomial "
                         "coefficients, highest power first, e.g. a washout; written to plants.json")
    ap.add_argument("--told-motion-path", default=None, metavar="NUM;DEN|none",
                    help="the motion path diagnose is told, where it differs from the simulator's "
                         "(--motion-path): a user's approximation; none: the key left out")
    ap.add_argument("--feedforward", type=float, default=None, metavar="KFF",
                    help="a pursuit display: the generator's precision pilots add a feedforward path on "
                         "the target, KFF times the controlled element's inverse (tasks with a target)")
    ap.add_argument("--ff-delay", type=float, default=None, metavar="S",
                    help="the feedforward's own delay, s (with --feedforward; default: the visual delay)")
    ap.add_argument("--known-delay", type=float, default=None, metavar="MARGIN",
                    help="tell diagnose the pilot's own visual delay: max_pilot_delay = the generator "
                         "pilot's true delay + MARGIN s (hesspipe diagnose --max-pilot-delay)")
    ap.add_argument("--display", choices=DISPLAYS, default=DEFAULT_DISPLAY,
                    help="what diagnose is told the pilot saw (DiagnoseConfig.display)")
    args = ap.parse_args(argv)
    split = (lambda s: [x for x in s.split(",") if x])
    draw = {"km_ratio": tuple(float(x) for x in split(args.km_ratio))} if args.km_ratio else {}
    if args.tau_m is not None:
        draw["tau_m"] = args.tau_m
    if args.fs is not None:
        draw["fs"] = args.fs
    if args.T_m is not None:
        draw["T_m"] = args.T_m
    if args.gain_drift is not None:
        draw["gain_drift"] = args.gain_drift
    if args.remnant_at is not None:
        draw["remnant_at"] = args.remnant_at
    if args.feedforward is not None:
        draw["feedforward"] = args.feedforward
    if args.ff_delay is not None:
        draw["ff_delay"] = args.ff_delay
    if args.layout == "sparse":
        draw.update(SPARSE_LAYOUT)
    if args.motion_path:
        draw["motion_path"] = _coefficients(ap, "--motion-path", args.motion_path)
    told = False
    if args.told_motion_path:
        told = None if args.told_motion_path == "none" else _coefficients(ap, "--told-motion-path",
                                                                            args.told_motion_path)
    print("SYNTHETIC DATA: every run below is drawn by the independent generator hesspipe.humanlike "
          f"({args.pilot} pilots).")
    rows, times, failures, skipped = {}, [], [], []
    motion = {True: [0, 0], False: [0, 0]}  # hidden motion? -> [runs naming it, runs]
    # (hidden motion?, one forcing function?) -> [named, "cannot tell", runs]
    words = {(h, o): [0, 0, 0] for h in (True, False) for o in (True, False)}
    t0 = time.perf_counter()
    with tempfile.TemporaryDirectory() as tmp:
        for plant, output, task, effect in itertools.product(split(args.plants), split(args.outputs),
                                                             split(args.tasks), split(args.effects)):
            firsts, both, false_pilot, remnant_named, aside = Counter(), 0, 0, 0, 0
            for seed in range(args.seed_start, args.seed_start + args.seeds):
                try:
                    d, cpu = run_case(tmp, plant, output, task, effect, seed, args.paired,
                                      args.pilot, args.repeats, DiagnoseConfig(display=args.display),
                                      args.known_delay, told, **draw)
                except HesspipeError as exc:
                    failures.append(f"{plant}/{output}/{task}/{effect}/{seed}: {exc}")
                    print("  REFUSED", failures[-1], flush=True)
                    firsts["REFUSED"] += 1
                    continue
                if d is None:
                    skipped.append(f"{plant}/{output}/{task}/{effect}/{seed}: {cpu}")
                    firsts["not generated"] += 1
                    continue
                times.append(cpu)
                named = list(d.named_effects)
                firsts[named[0] if named else "none"] += 1
                # Every generated run carries the generator's ordinary remnant, so naming it
                # is not wrong: "remnant aside" scores the first effect named besides it.
                hidden_motion = "motion_feedback" in effect
                motion[hidden_motion][0] += "motion_feedback" in named
                motion[hidden_motion][1] += 1
                mv = d.motion_verdict or {}
                if mv.get("forcing"):
                    cell = words[(hidden_motion, not mv.get("separable", True))]
                    cell[0] += bool(mv.get("named"))
                    cell[1] += mv.get("verdict", "").startswith("cannot tell")
                    cell[2] += 1
                rest = [e for e in named if e != "remnant"] if effect != "remnant" else named
                aside += bool(rest) and rest[0] == effect.split("+")[0]
                if "+" in effect:
                    both += set(effect.split("+")) <= set(named)
                if effect == "none":
                    false_pilot += bool(set(named) & set(PILOT_SIDE))
                    remnant_named += "remnant" in named
                if not args.quiet:
                    print(f"  {plant}/{output}/{task} hidden={effect:<22} seed={seed} -> {named} "
                          f"[plant check {d.plant_finding['verdict']}] {cpu:.1f} s", flush=True)
            rows[(plant, output, task, effect)] = (firsts, both, false_pilot, remnant_named, aside)
            print(_row(plant, output, task, effect, rows[(plant, output, task, effect)], args.seeds)[0],
                  flush=True)
    n = args.seeds
    print(f"\nConfusion (first named effect; {n} seeds per case, seeds {args.seed_start}.."
          f"{args.seed_start + n - 1})")
    ok_all = True
    for key, row in rows.items():
        line, ok = _row(*key, row, n)
        ok_all &= ok
        print(line)
    for hidden, (k, m) in motion.items():
        if m:
            print(f"motion_feedback named in {k}/{m} = {100 * k / m:.0f} % of runs "
                  f"{'with' if hidden else 'without'} hidden motion feedback "
                  f"(target {'>= 70' if hidden else '<= 10'} %)")
    for (hidden, one), (k, c, m) in words.items():
        if m:
            print(f"  {'with' if hidden else 'without'} hidden motion, "
                  f"{'one forcing function' if one else 'target and disturbance'}: named {k}/{m}, "
                  f"'cannot tell' {c}/{m}, 'no evidence' {m - k - c}/{m}")
    med = float(np.median(times)) if times else float("nan")
    print(f"\nmedian CPU time per diagnosis: {med:.2f} s (target < 3 s; {len(times)} diagnoses, "
          f"max {max(times, default=float('nan')):.1f} s); wall time {time.perf_counter() - t0:.0f} s")
    if skipped:
        print(f"not generated ({len(skipped)}; the generator's draw budget found no pilot in its "
              "ranges; counted as misses):\n  " + "\n  ".join(skipped))
    if failures:
        print("refused:\n  " + "\n  ".join(failures))
    print("all targets met" if ok_all and med < 3.0 else "targets MISSED (see above)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
