"""``hesspipe pilots`` (alias ``compare-pilots``): original vs expanded Hess model on a folder of pilot runs."""

from __future__ import annotations

# Imports sit inside the functions: `hesspipe --help` and argument errors load no numpy
# (tests/test_api.py), and each command loads only its own stage.
import sys

from ..core.choices import CRITERIA, DEFAULT_CRITERION, OPTIMIZERS


def register(sub) -> None:
    from ._options import add_display, add_run_options, add_seed, add_terms, field_terms

    # The stage, its package and its command share one name; compare-pilots is kept for old scripts.
    p = sub.add_parser("pilots", aliases=["compare-pilots"],
                       help="identify original / expanded-fixed-Km / expanded models per pilot",
                       description="Does the pilot need motion? For each run in DIR (the file stem is the "
                                   "pilot id; --pilot-id when pilots flew several runs) test motion feedback "
                                   "on the describing function (the motion verdict over the cohort, printed "
                                   "first), and identify the original Hess model, the expanded model with Km "
                                   "fixed, and the expanded model with Km identified; print a table and the "
                                   "mean improvement 1 - expanded/original fitness.")
    p.add_argument("dir", metavar="DIR", help="folder of run files (.csv, .tsv, .mat, .xlsx, .tdms, .h5, ...; or one file)")
    p.add_argument("--plants", required=True, metavar="PLANTS.json", help="plants JSON (Yc, Yd)")
    p.add_argument("--workers", type=int, metavar="N", help="local worker processes (0 or absent: all cores)")
    p.add_argument("--scheduler", metavar="ADDRESS",
                   help="Dask distributed scheduler, e.g. tcp://10.0.0.5:8786 (needs hesspipe[dask])")
    p.add_argument("--json", metavar="OUT.json", help="write the comparison as JSON")
    p.add_argument("--figures", metavar="DIR", help="write a PSD figure per pilot into DIR")
    p.add_argument("--pilot-id", metavar="REGEX",
                   help="when pilots flew several runs: a regular expression that finds the pilot in "
                        "each file name (its group 'pilot', else its first group), e.g. '^(s[0-9]+)_'; "
                        "the motion verdict then combines each pilot's runs and counts pilots "
                        "(default: each file is a pilot)")
    from ._outputs import add_inputs

    add_run_options(p)
    # The library names its settings (workers, scheduler); this command spells them as flags.
    add_terms(p, {r"(^|: )workers: ": r"\1--workers: ", r"(^|: )scheduler ": r"\1--scheduler ",
                  r"pilot_id( pattern)?": "--pilot-id",
                  **field_terms("CompareSettings", {k: "--" + k for k in ("seed", "passes", "restarts", "optimizer",
                                                                        "start", "criterion")})})
    add_seed(p, 0, "base seed")
    p.add_argument("--optimizer", choices=OPTIMIZERS, default="apid",
                   help="identification optimizer (default: %(default)s, the paper's)")
    p.add_argument("--passes", type=int, default=10, help="APID pass budget (default: %(default)s)")
    p.add_argument("--restarts", type=int, default=2, help="APID climbs per identification, best kept "
                                                           "(default: %(default)s)")
    p.add_argument("--benchmark", action="store_true",
                   help="also fit the McRuer precision model per pilot (the paper's benchmark score)")
    p.add_argument("--criterion", choices=CRITERIA, default=DEFAULT_CRITERION,
                   help=f"fit criterion (default {DEFAULT_CRITERION}, as identify): paper = Eq. 10 "
                        "control PSD; df = describing-function error; output = control output error")
    add_display(p, "the pilots")
    p.add_argument("--start", choices=("warm", "random"), default="warm",
                   help="warm (default): the expanded search starts from the original's optimum "
                        "plus fixed Km and the models exchange optima, so improvements measure Km, "
                        "not search luck; random: each model searched from random chromosomes")
    add_inputs(p, "dir", "plants")
    p.set_defaults(func=_run)


def _run(args) -> int:
    from ..core.io import check_output_dir, check_output_file, staged_output
    from ..pilots.batch import check_scheduler_address
    from ..pilots.compare import compare_pilots
    from ..pilots.settings import CompareSettings
    from ._options import cli_message, print_reading, read_cli_plants, run_options
    from ._outputs import write_command_json

    # Every output and the scheduler address are checked before any work.
    if args.json:
        check_output_file(args.json)
    if args.figures:
        check_output_dir(args.figures, "figures")
    if args.scheduler is not None:
        check_scheduler_address(args.scheduler, "--scheduler")
    # The library checks the settings (CompareSettings) and workers (run_batch); cli_message
    # names the flags. Both are checked before any run is read.
    settings = CompareSettings(seed=args.seed, optimizer=args.optimizer, passes=args.passes, start=args.start,
                               restarts=args.restarts, benchmark=args.benchmark, criterion=args.criterion,
                               display=args.display)
    if args.workers is not None:
        from ..pilots.batch import check_workers

        check_workers(args.workers)
    plants = read_cli_plants(args.plants)
    said = set()

    def on_read(reading, unread):
        # What reading found, said before the fits: a folder of 30 runs took three minutes, and
        # a broken file among them was reported only with the table.
        print_reading(reading)
        for f in unread:
            print(f"hesspipe: error: {cli_message(f.error, args)}", file=sys.stderr)
            said.add(id(f))
        sys.stderr.flush()

    result = compare_pilots(args.dir, plants, settings, workers=args.workers, scheduler=args.scheduler,
                            pilot_id=args.pilot_id, on_read=on_read, **run_options(args))
    if result.pilots:   # with none identified: no table, no verdict, no output file
        print(result.table())
        if args.json:
            write_command_json(args.json, result.to_dict())
        if args.figures:
            from ..viz.compare import draw_pilots

            with staged_output(args.figures, kind="figures") as stage:
                draw_pilots(stage, result.pilots)
    for f in result.failures:
        if id(f) not in said:
            print(f"hesspipe: error: {cli_message(f.error, args)}", file=sys.stderr)
    # A file that could not be read is counted as a file: how many runs it holds is unknown.
    files = sum(f.unread for f in result.failures)
    runs = len(result.failures) - files
    failed = f"all {runs}" if not result.pilots else f"{runs} of {runs + len(result.pilots)}"
    what = ", and ".join([f"{failed} run(s) failed"] * bool(runs)
                         + [f"{files} file(s) could not be read"] * bool(files))
    if not result.pilots:
        print(f"hesspipe: error: {what}; nothing to compare", file=sys.stderr)
        return 1
    if result.failures:
        print(f"hesspipe: error: {what}; the others are in the table", file=sys.stderr)
        return 1
    return 0
