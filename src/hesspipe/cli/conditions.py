"""``hesspipe conditions``: two conditions flown by the same persons (e.g. without and with
motion), compared person by person (:mod:`hesspipe.pilots.conditions`)."""

from __future__ import annotations


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "conditions", help="compare two conditions flown by the same persons (e.g. static and motion)",
        description="For each person, from their runs in each condition: the crossover and phase margin "
                    "of the loop the disturbance sees (nonparametric, runs averaged line by line), the "
                    "error and control variances and the remnant share; then a paired t test per metric "
                    "across the persons who flew both, Holm-adjusted, and a verdict in words. No pilot "
                    "model is fitted (for the model's motion verdict run `hesspipe pilots` on each folder).")
    p.add_argument("first", metavar="DIR_A", help="the first condition's runs (a folder of CSVs or one CSV)")
    p.add_argument("second", metavar="DIR_B", help="the second condition's runs; differences are B minus A")
    p.add_argument("--plants", required=True, metavar="PLANTS.json", help="plants (Yc is used)")
    p.add_argument("--labels", metavar="A,B", default=None,
                   help="the conditions' names, e.g. static,motion (default: the folders' names); "
                        "with --columns condition=COLUMN (one long table for both), the values read")
    p.add_argument("--pilot-id", metavar="REGEX",
                   help="a regular expression that finds the person in each file name (its group 'pilot', "
                        "else its first group), e.g. '^(s[0-9]+)_' (default: the file name, the same in both "
                        "folders)")
    from ._options import add_run_options, add_seed, add_terms
    from ._outputs import add_inputs

    add_run_options(p)
    add_seed(p, 0, "seed of the crossovers' uncertainty draws")
    p.add_argument("--json", metavar="OUT.json", help="write the comparison as JSON")
    p.add_argument("--figure", metavar="OUT.png", help="write a figure: each person's metrics in both conditions")
    add_terms(p, {r"pilot_id( pattern)?": "--pilot-id", r"(^|: )labels: ": r"\1--labels: "})
    add_inputs(p, "first", "second", "plants")
    p.set_defaults(func=run)


def run(args) -> int:
    from pathlib import Path

    from ..core.formats import columns_for_condition, read_plants
    from ..pilots.compare import list_runs
    from ..pilots.conditions import check_labels, compare_conditions, format_conditions
    from ._options import read_cli_runs
    from ._outputs import check_file_outputs, write_result_json

    check_file_outputs(json=args.json, figure=args.figure)  # before any work
    labels = (tuple(x.strip() for x in args.labels.split(",")) if args.labels is not None
              else (Path(args.first).resolve().name or "A", Path(args.second).resolve().name or "B"))
    if args.labels is None and labels[0] == labels[1]:
        labels = (f"{labels[0]} (A)", f"{labels[1]} (B)")
    labels = check_labels(labels)   # before the runs are read by them
    plants = read_plants(args.plants)
    files = [list_runs(args.first), list_runs(args.second)]
    # One long table holding both conditions: a condition column mapped without a value
    # reads each side's rows by its label.
    runs_a, runs_b = (read_cli_runs(f, args, columns=columns_for_condition(args.columns, label))
                      for f, label in zip(files, labels))
    result = compare_conditions(runs_a, runs_b, plants, labels=labels, pilot_id=args.pilot_id, seed=args.seed)
    print(format_conditions(result))
    if args.json:
        write_result_json(args.json, result, first=[str(f) for f in files[0]],
                          second=[str(f) for f in files[1]], plants=args.plants, seed=args.seed)
    if args.figure:
        from ..viz.conditions import conditions_figure

        conditions_figure(args.figure, result)
    return 0
