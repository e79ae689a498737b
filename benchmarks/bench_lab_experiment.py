"""Benchmark: a motion / no-motion experiment written as a laboratory writes it, run through
``hesspipe pilots`` (SYNTHETIC DATA).

The stand-in for real yaw-tracking trials with and without simulator motion (issue 13):
the independent generator's precision pilots (hesspipe.humanlike; McRuer form with the
multimodal vestibular path, vestibular delay 0.15 s, gain wandering with CV 0.15), a yaw-angle
display the cab turns with, target and disturbance on a sparse two-input layout (81.92 s at
100 Hz), single and double integrator. Each of N persons flies R runs of each condition (one
pilot drawn per person and condition, each run its own forcing phases, remnant and wander).
The files are what a lab's logger writes: degrees, semicolons and decimal commas, CRLF,
Windows-1252, the laboratory's own column names (``Time [s];Target [deg];Disturbance
[deg];Yaw [deg];Stick [deg]``); the plants JSON has the yaw task's ``motion_path``.

Each condition's folder goes through the command line as a user would type it::

    hesspipe pilots FOLDER --plants plants.json --pilot-id '^(s[0-9]+)_' \\
        --columns reference=Target,disturbance=Disturbance,output=Yaw,control=Stick

Prints per condition the verdict, the per-person lines (Km/|Ke| and Km), the wall time, and
for the motion conditions how much one person's Km/|Ke| and Km vary over the runs (median
coefficient of variation). With ``--diagnose`` also every run through ``hesspipe diagnose
RUN --plants plants.json --columns ...`` (one run at a time, as issue 13's real-trial check
counts): how many runs of each condition are named ``motion_feedback``, what else is named,
and the median CPU time per diagnosis.

    python benchmarks/bench_lab_experiment.py [--persons 6] [--runs 3] [--seed 7] [--out DIR] [--diagnose]
        [--style lab|daq|matlab|mat|mat-runs|xlsx|lab-error] [--threshold 0.2] [--cab-washout 1.0 --cab-delay 0.08]
        [--logged-run-in 8.08] [--logged-run-out 3] [--pilot tau=0.35,wn=7,remnant_share=0.4]

``--style`` writes the files otherwise (module ``STYLES``): ``mat-runs`` saves a person's runs of a
condition together in one ``.mat`` (a matrix column per run), read with ``--columns
time=t,reference=ft:*,disturbance=fd:*,output=x:*,control=u:*``; its runs are diagnosed one at
a time (``x:2``).

``--threshold S`` gives every person an indifference threshold on the perceived error, a dead
zone of S times the error's RMS (the generator's ``threshold``; McRuer and Jex's nonlinear
remnant source).

``--cab-washout W --cab-delay T`` make the cab's true path the plants file's times a
first-order washout ``s / (s + W)`` (rad/s) and a platform delay of T s (first-order Padé)
that the plants file does not state: a lab that writes its motion path as the ideal one.

``--logged-run-in S`` makes every file hold the whole trial: a run-in of S s (the forcing faded
in from the record's start) before the measurement; ``--logged-run-out S`` adds S s after it
while the forcing fades out (the generator's ``logged_run_in`` and ``logged_run_out``).

``--pilot KEY=VALUE,...`` holds generator ranges at one value for every person: the literature's
corners, e.g. the slowest, noisiest humans ``tau=0.35,wn=7,remnant_share=0.4`` (visual delay s,
neuromuscular frequency rad/s, remnant share of the control power) or the quickest, cleanest
``tau=0.15,wn=15,remnant_share=0.1``; ``gain_drift`` sets the wander's CV.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import math
import statistics
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from hesspipe.cli import main as hesspipe
from hesspipe.core.errors import HesspipeError
from hesspipe.core.formats import read_file_runs
from hesspipe.core.seeds import derive_seed
from hesspipe.humanlike import csv_bytes, draw_trial, simulate_trial
from hesspipe.humanlike.forcing import SPARSE_LAYOUT
from hesspipe.humanlike.plants import ANGLE_MOTION
from hesspipe.humanlike.writer import DAQ, LAB, MAT_NAMES, MATLAB, mat_bytes, mat_runs_bytes, plants_dict, xlsx_bytes

COLUMNS = ",".join(f"{role}={LAB['names'][role]}" for role in ("reference", "disturbance", "output", "control"))
MAT = {"format": "mat"}
"""A MATLAB workspace saved as ``.mat`` (:func:`~hesspipe.humanlike.writer.mat_bytes`: variables
t, ft, fd, x, u in seconds and degrees)."""
MAT_RUNS = {"format": "mat", "together": True}
"""A person's runs of a condition saved together in one ``.mat`` (:func:`~hesspipe.humanlike.writer.mat_runs_bytes`:
matrices ft, fd, x, u of one column per run, t a vector), read with starred names (``x:*``)."""
XLSX = {"format": "xlsx"}
"""An Excel workbook (:func:`~hesspipe.humanlike.writer.xlsx_bytes`: the LAB columns and names, metadata
above the header)."""
LAB_ERROR = {**LAB, "columns": ["time", "error", "disturbance", "output", "control"],
             "names": {**LAB["names"], "error": "Error"}}
"""The :data:`~hesspipe.humanlike.writer.LAB` files with the displayed error (``Error [deg]``, e = r - y)
logged in place of the target."""
STYLES = {"lab": LAB, "daq": DAQ, "matlab": MATLAB, "mat": MAT, "mat-runs": MAT_RUNS, "xlsx": XLSX,
          "lab-error": LAB_ERROR}


def columns(style) -> str:
    """The ``--columns`` mapping that reads files of `style`: the lab's names, positions (1 =
    first) for a file without a header row (:data:`~hesspipe.humanlike.writer.MATLAB`), or a
    MAT file's variable names (a matrix's columns, one per run, ``x:*``, for :data:`MAT_RUNS`)."""
    if style.get("format") == "mat":
        star = {role: ":*" if style.get("together") and role != "time" else "" for role in MAT_NAMES}
        return ",".join(f"{role}={var}{star[role]}" for role, var in MAT_NAMES.items())
    if "error" in style.get("columns", ()):
        return COLUMNS.replace(f"reference={LAB['names']['reference']}", f"error={style['names']['error']}")
    if style.get("header", True):
        return COLUMNS
    return ",".join(f"{role}={k}" for k, role in enumerate(style["columns"], 1))


def suffix(style) -> str:
    """The file name's suffix a lab gives files of `style` (MATLAB's ``save -ascii``: .txt)."""
    if style.get("format") in ("mat", "xlsx"):
        return "." + style["format"]
    return ".csv" if style.get("header", True) else ".txt"
PLANTS = {"SI": "1/s", "DI": "K/s2"}
TRIAL = dict(task="both", pilot="precision", output="angle", tau_m=0.15, gain_drift=0.15,
             line_bins=SPARSE_LAYOUT["line_bins"], fs=SPARSE_LAYOUT["fs"], T_m=SPARSE_LAYOUT["T_m"])
"""The trials' options (module doc)."""


def lab_file(trial, path: Path, style=LAB) -> None:
    """`trial` as a lab's logger writes it (the generator's :data:`~hesspipe.humanlike.writer.LAB`
    style, module doc, or another, e.g. :data:`~hesspipe.humanlike.writer.DAQ`), labelled
    synthetic in its comment line (a MAT file's ``note``)."""
    fmt = style.get("format")
    path.write_bytes(mat_bytes(trial) if fmt == "mat" else xlsx_bytes(trial) if fmt == "xlsx" else csv_bytes(trial, style))


def draw_person(plant: str, effects, seed: int, **kw):
    """A trial spec of a person whose pilot meets the generator's crossover ranges (re-drawn
    from derived seeds when one does not)."""
    for attempt in range(20):
        try:
            return draw_trial(plant, derive_seed(seed, "attempt", str(attempt)), **kw, effects=effects)
        except HesspipeError:
            continue
    raise HesspipeError(f"no pilot drawn for {plant} after 20 attempts (seed {seed})")


def cab_path(washout: float, delay: float) -> tuple[list, list]:
    """The generator's angle-output cab path (:data:`~hesspipe.humanlike.plants.ANGLE_MOTION`)
    times a washout ``s / (s + washout)`` (rad/s; 0: none) and a first-order Padé of `delay` (s)."""
    num, den = ANGLE_MOTION
    if washout:
        num, den = np.convolve(num, [1.0, 0.0]), np.convolve(den, [1.0, washout])
    if delay:
        num, den = np.convolve(num, [-delay / 2, 1.0]), np.convolve(den, [delay / 2, 1.0])
    return [float(x) for x in num], [float(x) for x in den]


def write_condition(folder: Path, tag: str, cond: str, persons: int, runs: int, seed: int,
                    style=LAB, cab: tuple[float, float] | None = None, **options) -> dict:
    """Write one condition's runs; return person -> the generator's pilot (its truth).
    `options` are further trial options (e.g. ``threshold``) for every run; `cab` (washout
    rad/s, delay s): the cab's true path (:func:`cab_path`), where the plants file states the
    ideal one."""
    folder.mkdir(parents=True, exist_ok=True)
    if cab is not None:
        options = dict(options, motion_path=cab_path(*cab))
    effects = ("motion_feedback",) if cond == "motion" else ()
    truth, spec = {}, None
    for s in range(persons):
        person, session = None, []
        for r in range(runs):
            kw = dict(TRIAL, name=f"s{s + 1:02d}_{cond}_r{r + 1}", **options)
            seed_r = derive_seed(seed, tag, cond, str(s), str(r))
            if person is None:
                spec = draw_person(PLANTS[tag], effects, seed_r, **kw)
                person = spec.pilot
                truth[f"s{s + 1:02d}"] = {k: v for k, v in person.items() if isinstance(v, (int, float, str))}
            else:   # the same person again: only forcing phases, remnant and wander are new
                spec = draw_trial(PLANTS[tag], seed_r, effects=effects, pilot_params=person, **kw)
            trial = simulate_trial(spec)
            if style.get("together"):
                session.append(trial)
            else:
                lab_file(trial, folder / f"{spec.name}{suffix(style)}", style)
        if style.get("together"):   # the person's runs in one file: s01_motion.mat
            (folder / f"s{s + 1:02d}_{cond}{suffix(style)}").write_bytes(mat_runs_bytes(session))
    stated = plants_dict(spec)
    if cab is not None:   # the lab states the ideal path
        stated["motion_path"] = {"num": list(ANGLE_MOTION[0]), "den": list(ANGLE_MOTION[1])}
    (folder.parent / f"plants_{tag}.json").write_text(json.dumps(stated, indent=1))
    return truth


def run_pilots(folder: Path, plants: Path, out_json: Path, cols: str = COLUMNS) -> tuple[int, str, str, float]:
    """``hesspipe pilots`` on `folder` in this process, its files read with the mapping `cols`:
    (exit status, stdout, stderr, wall s)."""
    out, err = io.StringIO(), io.StringIO()
    t0 = time.perf_counter()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = hesspipe(["pilots", str(folder), "--plants", str(plants), "--pilot-id", "^(s[0-9]+)_",
                         "--columns", cols, "--json", str(out_json)])
    return code, out.getvalue(), err.getvalue(), time.perf_counter() - t0


def diagnose_file(path: Path, plants: Path, out_json: Path, cols: str = COLUMNS) -> tuple[dict, float]:
    """``hesspipe diagnose PATH --plants PLANTS --columns ... --json OUT_JSON`` in this process, as
    typed: (its JSON report, CPU s of the command)."""
    t0 = time.process_time()
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()) as err:
        code = hesspipe(["diagnose", str(path), "--plants", str(plants), "--columns", cols,
                         "--json", str(out_json)])
    cpu = time.process_time() - t0
    if code != 0:
        raise HesspipeError(f"hesspipe diagnose {path} exited {code}: {err.getvalue().strip()}")
    return json.loads(out_json.read_text()), cpu


def diagnose_runs(folder: Path, plants: Path, cols: str = COLUMNS) -> tuple[int, int, dict, float]:
    """``hesspipe diagnose`` on every run of `folder` (.csv, .txt, .mat, .xlsx), one at a time, read with the
    mapping `cols` (starred: each run of a file on its own, ``x:2``): (runs named motion_feedback,
    runs, other names -> count, median CPU s per diagnosis)."""
    named, others, cpu = 0, {}, []
    paths = sorted(p for p in folder.iterdir() if p.suffix in (".csv", ".txt", ".mat", ".xlsx"))
    each = [(path, cols, path.stem) for path in paths] if "*" not in cols else [
        (path, cols.replace("*", str(r.number)), f"{path.stem}_r{r.number}")
        for path in paths for r in read_file_runs(path, columns=cols)]
    for path, run_cols, name in each:
        report, seconds = diagnose_file(path, plants, folder.parent / f"{folder.name}-{name}.diagnosis.json",
                                        run_cols)
        cpu.append(seconds)
        names = report["named_effects"]
        named += "motion_feedback" in names
        for n in names:
            if n != "motion_feedback":
                others[n] = others.get(n, 0) + 1
    return named, len(each), others, statistics.median(cpu)


def variation(comparison: dict) -> tuple[float, float]:
    """Median over persons of the coefficient of variation of Km/|Ke| and of Km over their runs
    (the motion tests' fits); NaN without a person of two runs or more (``--runs 1``)."""
    by: dict[str, list] = {}
    for p in comparison["pilots"]:
        t = p["motion_test"]
        if t.get("available"):
            by.setdefault(comparison["pilot_of_run"].get(p["id"], p["id"]), []).append((t["Km_per_Ke"], t["Km"]))
    cv = [[np.std(v, ddof=1) / np.mean(v) for v in zip(*runs)] for runs in by.values() if len(runs) > 1]
    if not cv:
        return math.nan, math.nan
    return statistics.median(c[0] for c in cv), statistics.median(c[1] for c in cv)


def experiment_arguments(doc: str, runs: bool = True) -> argparse.ArgumentParser:
    """The experiment's options (persons, runs unless `runs` is False, seed, plants), shared by
    the benchmarks that draw it."""
    ap = argparse.ArgumentParser(description=doc.splitlines()[0])
    ap.add_argument("--persons", type=int, default=6)
    if runs:
        ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--seed", type=int, default=7)
    ap.add_argument("--plants", default="SI,DI", help="comma list of SI (1/s) and DI (K/s2)")
    return ap


def main(argv=None) -> int:
    ap = experiment_arguments(__doc__)
    ap.add_argument("--out", default=None, help="keep the experiment's files here (default: a temporary folder)")
    ap.add_argument("--diagnose", action="store_true", help="also diagnose every run on its own")
    ap.add_argument("--style", choices=tuple(STYLES), default="lab",
                    help="the files' style: lab (LAB: semicolons, decimal commas), daq (DAQ: metadata above "
                         "the header, a units row, clock times across midnight, frames written twice, UTF-16) "
                         "matlab (MATLAB: save -ascii, no header row, read by position), mat (a .mat "
                         "file of variables t, ft, fd, x, u), mat-runs (a person's runs of a condition in one "
                         ".mat, a column per run), xlsx (an Excel workbook, the lab's names) or lab-error (the "
                         "lab's files with the displayed error logged in place of the target)")
    ap.add_argument("--threshold", type=float, default=0.0,
                    help="each person's indifference threshold, share of the error's RMS (0: none)")
    ap.add_argument("--cab-washout", type=float, default=0.0,
                    help="the cab's unstated washout corner, rad/s (0: none)")
    ap.add_argument("--cab-delay", type=float, default=0.0, help="the cab's unstated platform delay, s")
    ap.add_argument("--logged-run-in", type=float, default=0.0,
                    help="s of run-in logged before the measurement, from the forcing's fade-in (0: none)")
    ap.add_argument("--logged-run-out", type=float, default=0.0,
                    help="s logged after the measurement while the forcing fades out (0: none)")
    ap.add_argument("--pilot", default="", metavar="KEY=VALUE,...",
                    help="generator ranges held at one value for every person (the literature's corners), "
                         "e.g. tau=0.35,wn=7,remnant_share=0.4 (hesspipe.humanlike.trial.RANGES), and "
                         "gain_drift (the wander's CV, default 0.15)")
    args = ap.parse_args(argv)
    whole = {}
    for item in filter(None, args.pilot.split(",")):
        key, _, value = item.partition("=")
        whole[key.strip()] = float(value)
    if args.logged_run_in:
        whole.update(run_in=args.logged_run_in, logged_run_in=args.logged_run_in)
    if args.logged_run_out:
        whole.update(logged_run_out=args.logged_run_out)
    cab = (args.cab_washout, args.cab_delay) if args.cab_washout or args.cab_delay else None
    style = STYLES[args.style]
    print("SYNTHETIC DATA: independent generator (hesspipe.humanlike), precision pilots, files as a lab writes them")
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(args.out or tmp)
        for tag in args.plants.split(","):
            for cond in ("motion", "static"):
                folder = root / f"{tag}_{cond}"
                t0 = time.perf_counter()
                truth = write_condition(folder, tag, cond, args.persons, args.runs, args.seed,
                                        style, cab=cab, threshold=args.threshold,
                                        **whole)
                print(f"\n== {tag} ({PLANTS[tag]}), {cond}: {args.persons} persons x {args.runs} runs written "
                      f"in {time.perf_counter() - t0:.0f} s")
                out_json = root / f"{tag}_{cond}.json"
                code, out, err, wall = run_pilots(folder, root / f"plants_{tag}.json", out_json, columns(style))
                if code != 0:
                    print(f"hesspipe pilots exited {code}: {err.strip()}")
                    return 1
                lines = out.splitlines()
                print("\n".join(ln for ln in lines if ln.startswith(("MOTION VERDICT", "  s"))))
                notes = [ln for ln in err.splitlines() if ln.startswith("hesspipe: note:")]
                print(f"hesspipe pilots: {wall:.0f} s wall; {len(notes)} note line(s) on stderr")
                if args.diagnose:
                    named, n, others, cpu = diagnose_runs(folder, root / f"plants_{tag}.json", columns(style))
                    print(f"hesspipe diagnose, run by run: motion_feedback named on {named}/{n} runs; other "
                          f"names: {', '.join(f'{k} {v}/{n}' for k, v in sorted(others.items())) or 'none'}; "
                          f"median CPU {cpu:.2f} s per diagnosis")
                if cond == "motion":
                    cmp = json.loads(out_json.read_text())
                    r, k = variation(cmp)
                    ratio = {s: t.get("km_ratio") for s, t in truth.items()}
                    print(f"one person's runs: median coefficient of variation Km/|Ke| {r:.2f}, Km {k:.2f}; "
                          "the generator's km_ratio per person (its own model's, not Hess's Km/Ke): "
                          + ", ".join(f"{s} {v:.2f}" for s, v in ratio.items()))
    return 0


if __name__ == "__main__":
    sys.exit(main())
