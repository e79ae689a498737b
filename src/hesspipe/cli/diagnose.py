"""``hesspipe diagnose``: name the effect a pilot model misses in a measured run."""

from __future__ import annotations

# Imports sit inside the functions: `hesspipe --help` and argument errors load no numpy
# (tests/test_api.py), and each command loads only its own stage.
import functools
import sys
from dataclasses import replace
from pathlib import Path


def register(sub) -> None:
    from ._options import add_display, add_run_options, add_seed, add_terms, field_terms

    p = sub.add_parser(
        "diagnose", help="locate model/data disagreement, name missing effects, show the gap shrink",
        description="Check the plants against RUN.csv's output (a failed check is a finding: the "
                    "aircraft-side effect or the file error that closes it is named), judge motion "
                    "feedback on the describing function, identify the baseline pilot model, locate "
                    "where its control PSD disagrees with the measurement, try each candidate effect, "
                    "name the significant ones and report the gap before and after.")
    p.add_argument("run", metavar="RUN.csv", nargs="+",
                   help="measured run (time, disturbance, output, control); more runs of the same pilot "
                        "and condition (the same forcing) are repeats: pooled with it in the motion "
                        "test when the forcing is the disturbance alone, and in the delay test "
                        "against --baseline-run (with --each: runs or folders of runs, each alone)")
    p.add_argument("--plants", metavar="PLANTS.json", required=True, help="plants file (Yc, Yd)")
    p.add_argument("--model", default="original", help="baseline model: original or expanded "
                                                       "(default: %(default)s)")
    p.add_argument("--candidates", metavar="a,b,...",
                   help="effect ids to try (default: every registered effect)")
    p.add_argument("--alpha", type=float, help="significance level per round (default 0.01)")
    p.add_argument("--max-effects", type=int, help="most effects to name (default 3)")
    p.add_argument("--baseline-run", metavar="BASE.csv", nargs="+",
                   help="the same pilot's run(s) in the baseline condition (same aircraft and columns): "
                        "the visual delay is tested against theirs, so a simulator's extra delay can be "
                        "told from the pilot's own")
    p.add_argument("--max-pilot-delay", type=float, metavar="S",
                   help="longest visual delay the pilot alone can have, s (default 0.40, a human's "
                        "longest): one record holds the pilot's and the simulator's delay as one, so "
                        "only delay beyond this is named extra_delay; give the pilot's known delay "
                        "(a model pilot's, or the baseline condition's identified one) plus a margin")
    add_display(p)
    p.add_argument("--each", action="store_true",
                   help="diagnose every run on its own (RUN may then be a folder of runs): a line per "
                        "run and how often each effect was named, as a motion / no-motion check counts")
    p.add_argument("--workers", type=int, metavar="N",
                   help="with --each: local worker processes, a run each at a time (0 or absent: all cores)")
    p.add_argument("--json", metavar="OUT.json", help="write the diagnosis as JSON (with --each: every "
                                                      "run's and the tally, in one file)")
    p.add_argument("--figure", metavar="OUT.png", help="write the PSD figure")
    from ._outputs import add_inputs

    add_run_options(p)
    add_terms(p, field_terms("DiagnoseConfig", {"alpha": "--alpha", "max_effects": "--max-effects",
                                                  "max_pilot_delay": "--max-pilot-delay"}))
    add_terms(p, {r"(^|: )workers: ": r"\1--workers: ",
                  r"diagnose every run alone$": "diagnose every run alone with --each"})
    add_seed(p, 0, "seed of the remnant draws")
    add_inputs(p, "run", "plants", "baseline_run")
    p.set_defaults(func=_diagnose)


def _diagnose(args) -> int:
    from ..core.errors import HesspipeError
    from ..core.paper import WELCH_SEGMENT
    from ..diagnose.report import format_report
    from ..diagnose.settings import DiagnoseConfig
    from ..diagnose.workflow import diagnose
    from ._outputs import check_file_outputs, write_command_json

    check_file_outputs(json=args.json, figure=args.figure)  # before any work
    # The library checks its settings (DiagnoseConfig); cli_message names the flags.
    cfg = replace(DiagnoseConfig(), display=args.display,
                  **{k: v for k, v in (("alpha", args.alpha), ("max_effects", args.max_effects),
                                       ("max_pilot_delay", args.max_pilot_delay)) if v is not None})
    candidates = None
    if args.candidates is not None:
        candidates = [c.strip() for c in args.candidates.split(",") if c.strip()]
        if not candidates:
            raise HesspipeError("--candidates: expected effect ids separated by commas, got nothing")
    from ._options import read_cli_plants, read_cli_runs

    if args.each:
        return _each(args, cfg, candidates)
    if args.workers is not None:
        raise HesspipeError("--workers: only with --each (one run's diagnosis runs in one process)")
    plants = read_cli_plants(args.plants)

    # A file may hold several runs (a starred column name): the two lists are read apart.
    run, *repeats = read_cli_runs(args.run, args, min_samples=WELCH_SEGMENT)
    base = None if args.baseline_run is None else read_cli_runs(args.baseline_run, args, min_samples=WELCH_SEGMENT)
    result = diagnose(run, plants, model=args.model, candidates=candidates, seed=args.seed, config=cfg,
                      baseline_run=base, repeat_runs=repeats)
    print(format_report(result))
    if args.json:
        write_command_json(args.json, result.to_dict(), plants=args.plants, seed=args.seed)
        print(f"wrote {args.json}")
    if args.figure:
        from ..viz.diagnose import plot_diagnosis

        plot_diagnosis(result, args.figure)
        print(f"wrote {args.figure}")
    return 0


def _each(args, cfg, candidates) -> int:
    # Every run alone: a folder's runs (or the files given, each file's runs), read as
    # `pilots` reads them (a file it cannot read is a failure, not the end), then tallied.
    from ..core.errors import HesspipeError
    from ..core.paper import WELCH_SEGMENT
    from ..diagnose.each import RunDiagnoses, diagnose_each
    from ..pilots.batch import check_workers, run_batch
    from ..pilots.compare import list_runs, read_runs
    from ._options import cli_message, print_reading, read_cli_plants, run_options
    from ._outputs import write_command_json

    if args.baseline_run or args.figure:
        raise HesspipeError(f"{'--baseline-run' if args.baseline_run else '--figure'}: not with --each, which "
                            "diagnoses every run alone (one figure per run: diagnose the run without --each)")
    if args.workers is not None:
        check_workers(args.workers)   # before any work
    plants = read_cli_plants(args.plants)
    listed = [(arg, list_runs(arg)) for arg in args.run]
    paths = [path for _, files in listed for path in files]
    runs, unread = read_runs(paths, min_samples=WELCH_SEGMENT, **run_options(args))
    print_reading({run.source: run.notes for run in runs})
    result = diagnose_each(runs, plants, model=args.model, candidates=candidates, seed=args.seed, config=cfg,
                           mapper=functools.partial(run_batch, workers=args.workers, desc="diagnose", unit="run"))
    unread = tuple((f.source, f.error.removeprefix(f"{f.source}: ")) for f in unread)
    result = RunDiagnoses(result.diagnoses, unread + result.failures)
    print("\n".join(result.lines(failures=False)))
    # Several folders are several conditions (motion/ static/): a tally each, as well as the pooled one.
    # Files listed one by one (a shell's motion/*.csv) are not conditions: a tally each was a
    # "1 of 1 runs" line per file.
    apart = ({arg: result.of_files(files) for arg, files in listed if Path(arg).is_dir()}
             if len(listed) > 1 else {})
    for arg, sub in apart.items():
        print(f"SUMMARY of {arg}: {sub.summary()}")
    if args.json:
        write_command_json(args.json, {**result.to_dict(), **({"by_input": {
            arg: {"runs": len(sub.diagnoses), "named": sub.tally(), "summary": sub.summary()}
            for arg, sub in apart.items()}} if apart else {})}, plants=args.plants, seed=args.seed)
        print(f"wrote {args.json}")
    for where, message in result.failures:
        print(f"hesspipe: error: {where}: {cli_message(message, args)}", file=sys.stderr)
    return 1 if result.failures else 0
