"""``hesspipe plants``: identify the plants from a flight folder, or build the analytic ones (stage two)."""

from __future__ import annotations

# Imports sit inside the functions: `hesspipe --help` and argument errors load no numpy
# (tests/test_api.py), and each command loads only its own stage.
from pathlib import Path


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "plants", help="ARX wind -> roll rate and aileron -> roll rate plants, or the paper's analytic aircraft",
        description="Identify ARX models (wind -> roll rate, aileron -> roll rate) from a stage-one flight "
                    "folder, convert them to continuous transfer functions and validate them; or, with "
                    "--analytic, compute the plants of the paper's analytic aircraft (Tables 3-4, Eqs. 11-14).")
    src = p.add_mutually_exclusive_group(required=True)
    src.add_argument("--flight", type=Path, metavar="DIR", help="flight folder (wind.csv, aileron.csv)")
    src.add_argument("--analytic", metavar="NAME", help="analytic aircraft in aircraft/ (e.g. roskam) or a TOML path")
    p.add_argument("--out", required=True, type=Path, metavar="DIR", help="output folder")
    p.add_argument("--config", type=Path, metavar="FILE",
                   help="TOML configuration (as 'hesspipe run --config' takes) whose [plants] (or, with "
                        "--analytic, [analytic]) table overrides the defaults")
    p.add_argument("--no-figures", action="store_true", help="skip the PNG figures")
    p.set_defaults(func=_run)


def _run(args) -> int:
    from ..core.io import check_output_dir
    from ..pipeline.stages import load_config
    from ..plants.fit import analytic_plants, describe_tf, fit_plants
    from ..plants.settings import AnalyticConfig, PlantsConfig

    check_output_dir(args.out, "analytic" if args.analytic else "plants")  # before any work
    # Read as `hesspipe run --config` reads it: a misspelt section or a bad seed is refused.
    table, source = load_config(args.config) if args.config is not None else ({}, "<defaults>")
    if args.analytic:
        cfg = AnalyticConfig.from_table(table.get("analytic", {}), source)
        from ..viz.plants import draw_analytic

        plants = analytic_plants(args.analytic, args.out, cfg, draw=None if args.no_figures else draw_analytic)
        for key, sys in (("control_to_output", plants.Yc), ("disturbance_to_output", plants.Yd)):
            d = describe_tf(sys)
            print(f"{key}: num {[round(v, 6) for v in d['num']]} den {[round(v, 6) for v in d['den']]}")
        print(f"wrote plants.json, plants_report.md, plants_report.json to {args.out}")
        return 0
    cfg = PlantsConfig.from_table(table.get("plants", {}), source)
    from ..viz.plants import draw_plants

    result = fit_plants(args.flight, args.out, cfg, draw=None if args.no_figures else draw_plants)
    for key, ch in result.report["channels"].items():
        o, chk = ch["orders"], ch["conversion"]["check"]
        print(f"{key}: ARX({o['na']},{o['nb']},{o['nk']}) at {ch['model_dt_s']:.4g} s, validation fit "
              f"{ch['fit_percent']['validation']:.1f} %, continuous vs discrete to "
              f"{chk['band_hz'][1]:g} Hz: {chk['max_gain_error_db']:.2f} dB / {chk['max_phase_error_deg']:.2f} deg "
              f"({'pass' if chk['pass'] else 'FAIL'})")
    print(f"wrote {', '.join(sorted(result.files))} to {args.out}")
    return 0
