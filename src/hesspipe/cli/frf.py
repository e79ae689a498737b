"""``hesspipe frf``: the pilot's nonparametric describing function from a measured run (or
repeated runs, averaged)."""

from __future__ import annotations

# Imports sit inside the functions: `hesspipe --help` and argument errors load no numpy
# (tests/test_api.py), and each command loads only its own stage.


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "frf", help="the pilot's nonparametric describing function H = U/E of a measured run",
        description="Estimate the pilot's describing function from error to control at the lines "
                    "of a multisine disturbance (and, separately, of the reference), or by Welch "
                    "cross-spectra for a broadband disturbance; per-line uncertainty, the remnant "
                    "share of control power, and the crossover and phase margin of L = H Yc. With "
                    "target and disturbance on their own lines, also the response to the error and "
                    "the response to the output itself apart (U = Hpe E - Hpy Y; with a moving cab, "
                    "the vestibular path).")
    p.add_argument("run", metavar="RUN.csv", nargs="+",
                   help="measured run (time, disturbance, output, control); several runs of one pilot "
                        "in one condition (one multisine forcing) are averaged line by line")
    p.add_argument("--plants", required=True, metavar="PLANTS.json", help="plants (Yc is used)")
    from ._options import add_run_options, add_seed
    from ._outputs import add_inputs

    add_run_options(p)
    add_seed(p, 0, "seed of the crossover's uncertainty draws")
    p.add_argument("--json", metavar="OUT.json", help="write the result as JSON")
    p.add_argument("--figure", metavar="OUT.png", help="write a Bode figure")
    p.add_argument("--model", metavar="IDENT.json",
                   help="an identify --json result: its model's describing function is drawn over "
                        "the points")
    add_inputs(p, "run", "plants", "model")
    p.set_defaults(func=run)


def _model_curves(path) -> dict:
    """Label -> H(s) of the model (and benchmark) in an ``identify --json`` result."""
    import json

    from ..core.errors import HesspipeError
    from ..identification.report import model_curves
    from ..pilot.hess import model_from_name

    try:
        obj = json.loads(open(path, encoding="utf-8-sig").read())
        model = model_from_name(obj["model"])
        params = model.complete({k: float(v) for k, v in obj["parameters"].items()},
                                int(obj["parameters"].get("k", 1)))
        return model_curves(obj["model"], params, obj.get("criterion", "paper"), obj.get("benchmark_parameters"))
    except HesspipeError as exc:
        raise HesspipeError(f"{path}: {exc}") from None
    except (OSError, ValueError, KeyError, TypeError, AttributeError) as exc:
        raise HesspipeError(f"{path}: expected an identify --json result with 'model' and "
                            f"'parameters' ({type(exc).__name__}: {exc})") from None


def run(args) -> int:
    from ..core.formats import read_plants
    from ..identification.frf_average import average_frf
    from ..identification.report import format_frf
    from ._options import read_cli_runs
    from ._outputs import check_file_outputs, write_result_json

    check_file_outputs(json=args.json, figure=args.figure)  # before any work
    plants = read_plants(args.plants)
    curves = _model_curves(args.model) if args.model else None  # a bad file fails before any work
    recs = read_cli_runs(args.run, args)
    from ..plants.consistency import check_consistent

    for rec in recs:   # a sign or units mistake, as pilots and identify refuse it
        check_consistent(rec, plants)
    result = average_frf(recs, plants, seed=args.seed)
    print(format_frf(result))
    if args.json:
        write_result_json(args.json, result, run=args.run, plants=args.plants, seed=args.seed)
    if args.figure:
        from ..viz.frf import frf_figure

        frf_figure(args.figure, result, curves)
    return 0
