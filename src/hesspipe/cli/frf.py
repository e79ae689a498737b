"""``hesspipe frf``: the pilot's nonparametric describing function from a measured run (or
repeated runs, averaged)."""

from __future__ import annotations

# Imports sit inside the functions: `hesspipe --help` and argument errors load no numpy
# (tests/test_api.py), and each command loads only its own stage.
import math


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


def format_table(frf) -> str:
    import numpy as np

    tag = "  [SYNTHETIC DATA]" if frf.synthetic else ""
    r = frf.feedback
    lines = [f"run {frf.run_id}: describing function H = U/E, {frf.method} "
             f"({r.freq_rad_s.size} {'lines' if frf.method == 'multisine' else 'Welch bins'}, "
             f"{frf.window[1] * frf.dt:.4g} s analysed){tag}",
             f"{'w rad/s':>9} {'|H| dB':>8} {'+-dB':>6} {'phase deg':>10} {'+-deg':>6}"]
    d = r.to_dict()
    for i in range(r.freq_rad_s.size):
        lines.append(f"{d['frequency_rad_s'][i]:9.3f} {d['magnitude_db'][i]:8.2f} "
                     f"{d['magnitude_db_std'][i]:6.2f} {d['phase_deg'][i]:10.1f} {d['phase_deg_std'][i]:6.1f}")
    if frf.reference is not None:
        lines.append(f"reference lines: {frf.reference.freq_rad_s.size} (their own response, in the JSON)")
    ch = frf.channels
    if ch is not None:
        lines += ["channels at the reference lines, U = Hpe E - Hpy Y (Hpy: the response to the "
                  "output itself; the vestibular path with a compensatory display and motion, minus a "
                  "feedforward on a pursuit display, zero without either):",
                  f"{'w rad/s':>9} {'|Hpe| dB':>9} {'phase deg':>10} {'|Hpy| dB':>9} {'phase deg':>10} "
                  f"{'+-dB':>6} {'|Hpy/Hpe|':>9}"]
        rel = ch.sigma_Hpy / np.abs(ch.Hpy)
        for w, pe, py, r in zip(ch.freq_rad_s, ch.Hpe, ch.Hpy, rel):
            lines.append(f"{w:9.3f} {20 * np.log10(abs(pe)):9.2f} {np.degrees(np.angle(pe)):10.1f} "
                         f"{20 * np.log10(abs(py)):9.2f} {np.degrees(np.angle(py)):10.1f} "
                         f"{20 / np.log(10) * r:6.2f} {abs(py) / abs(pe):9.3f}")
        lines.append(f"median |Hpy|/|Hpe| at {ch.lines_in_band} line(s) between 1 and 5 rad/s: "
                     f"{ch.ratio_median:.3g} (remnant raises it; compare conditions, not zero)")
    lines.append(f"remnant share of control power  {frf.remnant_share:.3f}   (every bin to the Nyquist "
                 f"frequency; diagnose counts its band only)")
    c = frf.crossover
    if math.isfinite(c.frequency_rad_s):
        lines.append(f"crossover (nonparametric)      {c.frequency_rad_s:.3f} +- {c.frequency_std:.3f} "
                     f"rad/s, phase margin {c.phase_margin_deg:.1f} +- {c.phase_margin_std_deg:.1f} deg "
                     f"({c.estimate} estimate; the other in the JSON)")
        if c.note:
            lines.append(f"  {c.note}")
    else:
        lines.append(f"crossover (nonparametric)      not found: {c.note}")
    for n in frf.notes:
        lines.append(f"note: {n}")
    return "\n".join(lines)


def _model_curves(path) -> dict:
    """Label -> H(s) of the model (and benchmark) in an ``identify --json`` result."""
    import json

    from ..core.errors import HesspipeError
    from ..identification.criteria import model_df
    from ..pilot.hess import model_from_name
    from ..pilot.mcruer import precision_loop

    try:
        obj = json.loads(open(path, encoding="utf-8-sig").read())
        model = model_from_name(obj["model"])
        loop = model.loop(model.complete({k: float(v) for k, v in obj["parameters"].items()},
                                         int(obj["parameters"].get("k", 1))))
    except HesspipeError as exc:
        raise HesspipeError(f"{path}: {exc}") from None
    except (OSError, ValueError, KeyError, TypeError, AttributeError) as exc:
        raise HesspipeError(f"{path}: expected an identify --json result with 'model' and "
                            f"'parameters' ({type(exc).__name__}: {exc})") from None
    out = {f"{obj['model']} model ({obj.get('criterion', 'paper')})": lambda s: model_df(loop, s)}
    if obj.get("benchmark_parameters"):
        bench = precision_loop(obj["benchmark_parameters"])
        out["McRuer precision benchmark"] = lambda s: model_df(bench, s)
    return out


def run(args) -> int:
    from ..core.formats import read_plants
    from ..identification.frf_average import average_frf
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
    print(format_table(result))
    if args.json:
        write_result_json(args.json, result, run=args.run, plants=args.plants, seed=args.seed)
    if args.figure:
        from ..viz.frf import frf_figure

        frf_figure(args.figure, result, curves)
    return 0
