"""``hesspipe identify``: identify pilot-model parameters from a measured run (or repeated runs)."""

from __future__ import annotations

# Imports sit inside the functions: `hesspipe --help` and argument errors load no numpy
# (tests/test_api.py), and each command loads only its own stage.
import argparse
import math

from ..core.choices import CRITERIA, DEFAULT_CRITERION, OPTIMIZERS
from ..core.errors import HesspipeError
from ..core.paper import FITNESS_BAND_HZ
from ._options import add_run_options, add_seed, add_terms, read_cli_plants, read_cli_runs
from ._outputs import add_inputs

#: The library's names of identify's settings → this command's options.
TERMS = {r"(^|: )free: ": r"\1--free: ", r"(^|: )fixed: ": r"\1--fix: ",
         r"\bhold it in fixed\b": "hold it with --fix", r"(^|: )band: ": r"\1--band: ",
         r"(^|: )criterion: ": r"\1--criterion: "}


def _fix(text: str) -> tuple[str, float]:
    if "=" not in text:
        raise argparse.ArgumentTypeError(f"expected NAME=VALUE, got {text!r}")
    name, value = (s.strip() for s in text.split("=", 1))
    try:
        number = float(value)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{name}: expected a number, got {value!r}") from None
    if not math.isfinite(number):
        raise argparse.ArgumentTypeError(f"{name}: expected a finite number, got {value!r}")
    return name, number


def _band(text: str) -> tuple[float, float]:
    try:
        lo, hi = (float(v) for v in text.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected LOW,HIGH in Hz, got {text!r}") from None
    if not (math.isfinite(lo) and math.isfinite(hi) and 0 <= lo < hi):
        raise argparse.ArgumentTypeError(f"expected LOW,HIGH in Hz with 0 <= LOW < HIGH, got {text!r}")
    return lo, hi


def _bits(text: str):
    # NAME=BITS[:SCALE[:OFFSET]]
    if "=" not in text:
        raise argparse.ArgumentTypeError(f"expected NAME=BITS[:SCALE[:OFFSET]], got {text!r}")
    name, spec = (s.strip() for s in text.split("=", 1))
    parts = spec.split(":")
    try:
        bits = int(parts[0])
        scale = float(parts[1]) if len(parts) > 1 else 100.0
        offset = float(parts[2]) if len(parts) > 2 else 0.0
    except (ValueError, IndexError):
        raise argparse.ArgumentTypeError(f"expected NAME=BITS[:SCALE[:OFFSET]], got {text!r}") from None
    return name, (bits, scale, offset)


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "identify", help="identify Hess pilot-model parameters from a measured run (APID)",
        description="Fit the Hess structural model (original or expanded with motion feedback) to "
                    "a measured run by matching control power spectra (paper Eqs. 5-10), with the "
                    "bit-climbing GA (APID) or a scipy optimiser.")
    p.add_argument("run", metavar="RUN.csv", nargs="+",
                   help="measured run (time, disturbance, output, control); several runs of one pilot "
                        "in one condition are fitted through their averaged describing function "
                        "(--criterion df)")
    p.add_argument("--plants", required=True, metavar="PLANTS.json", help="fitted plants (Yc, Yd)")
    p.add_argument("--model", default="original",
                   help="original | expanded, optionally +EFFECT (e.g. expanded+remnant)")
    p.add_argument("--fix", action="append", type=_fix, default=[], metavar="NAME=VALUE",
                   help="hold a parameter at a value (repeatable)")
    p.add_argument("--free", metavar="NAME,...", help="parameters to identify "
                   "(default: Ke,K1,K2 and the effects' parameters, e.g. Km)")
    add_seed(p, 0, "random seed")
    add_run_options(p)
    add_terms(p, TERMS)
    p.add_argument("--passes", type=int, default=10, help="APID pass budget (default 10)")
    p.add_argument("--restarts", type=int, default=4,
                   help="APID climbs from random chromosomes, best kept (default 4; paper: 1)")
    p.add_argument("--coding", choices=("gray", "binary"), default="gray",
                   help="APID bit coding (default gray; paper: binary)")
    p.add_argument("--bits", action="append", type=_bits, default=[], metavar="NAME=BITS[:SCALE[:OFFSET]]",
                   help="APID bit field of a free parameter (value = offset + integer/scale)")
    p.add_argument("--optimizer", choices=OPTIMIZERS, default="apid")
    p.add_argument("--k", type=int, choices=(1, 2), default=None,
                   help="Table 1 column: 1 for a rate-like plant (K/s), 2 for K/s^2 "
                        "(default: Hess's rule on the plant's slope around 1-5 rad/s)")
    p.add_argument("--criterion", choices=CRITERIA, default=DEFAULT_CRITERION,
                   help=f"fit criterion (default {DEFAULT_CRITERION}): paper = Eq. 10 control PSD; "
                        "df = describing-function error at the excited lines weighted by their "
                        "uncertainty; output = control output error")
    p.add_argument("--band", type=_band, default=FITNESS_BAND_HZ, metavar="LOW,HIGH",
                   help="fitness band in Hz (default 0,5)")
    p.add_argument("--psd", choices=("paper", "scipy"), default="paper", help="PSD estimate")
    p.add_argument("--no-benchmark", action="store_true", help="skip the McRuer benchmark fit")
    p.add_argument("--json", metavar="OUT.json", help="write the result as JSON")
    p.add_argument("--figure", metavar="OUT.png",
                   help="write a figure: the model's describing function over the measured one "
                        "(criteria df/output), a Fig. 8-style PSD figure (criterion paper)")
    p.add_argument("--df-figure", metavar="OUT.png",
                   help="write the describing-function figure whatever the criterion")
    add_inputs(p, "run", "plants")
    p.set_defaults(func=run)


def run(args) -> int:
    from ..core.formats import read_plants
    from ..identification.fit import identify
    from ..identification.report import format_identification
    from ..identification.spectra import PaperWelch
    from ..pilot.hess import model_from_name
    from ._outputs import check_file_outputs, write_result_json

    check_file_outputs(json=args.json, figure=args.figure)  # before any work
    check_file_outputs(figure=args.df_figure)
    # The motion path's note only where the model feels the cab (vestibular or otolith path).
    cab = {"motion_feedback", "otoliths"} & set(model_from_name(args.model).effects)
    plants = read_cli_plants(args.plants) if cab else read_plants(args.plants)
    recs = read_cli_runs(args.run, args, min_samples=PaperWelch().nperseg)
    rec = recs[0]
    free = None
    if args.free is not None:
        free = [n.strip() for n in args.free.split(",") if n.strip()]
        if not free:
            raise HesspipeError("--free: expected NAME,... with at least one parameter")
    fixed = dict(args.fix)
    if free is None:
        from ..identification.problem import default_free

        defaults = default_free(model_from_name(args.model))
        if all(n in fixed for n in defaults):
            raise HesspipeError(f"--fix: every parameter identified by default ({', '.join(defaults)}) "
                                "is fixed: nothing to identify; name the parameters to identify with --free")
    result = identify(recs if len(recs) > 1 else rec, plants, args.model, free=free, fixed=fixed, seed=args.seed,
                      passes=args.passes, optimizer=args.optimizer, band=args.band, k=args.k,
                      fields=dict(args.bits) or None, psd_method=args.psd,
                      with_benchmark=not args.no_benchmark, restarts=args.restarts, coding=args.coding,
                      criterion=args.criterion)
    print(format_identification(result))
    if args.json:
        write_result_json(args.json, result, run=args.run, plants=args.plants)
    if args.figure and result.criterion == "paper":
        from ..viz.pilots import identification_figure

        identification_figure(args.figure, [result])
    for path in ([args.figure] if args.figure and result.criterion != "paper" else []) + (
            [args.df_figure] if args.df_figure else []):
        df_figure(path, result, rec.source)
    return 0


def df_figure(path, result, where: str = "") -> None:
    """The model's (and the precision benchmark's) describing function over the measured one."""
    from ..identification.report import model_curves
    from ..viz.frf import frf_figure

    if result.frf is None or isinstance(result.frf, str):
        raise HesspipeError(f"{where or result.run_id}: no describing-function figure: "
                            f"{result.frf or 'no nonparametric estimate'}")
    frf_figure(path, result.frf, model_curves(result.model, result.parameters, result.criterion,
                                              result.benchmark_parameters))
