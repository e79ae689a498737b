"""``hesspipe synth-pilots``: write a synthetic cohort of pilot runs."""

from __future__ import annotations

# Imports sit inside the functions: `hesspipe --help` and argument errors load no numpy
# (tests/test_api.py), and each command loads only its own stage.


def register(sub) -> None:
    p = sub.add_parser("synth-pilots", help="generate a synthetic cohort of pilot runs (marked synthetic)",
                       description="Simulate N pilots (Hess model around Table 1, remnant noise, the "
                                   "paper's side wind plus gusts or a two-input forcing) closed around PLANTS; write <id>.csv "
                                   "in the measured-run format and <id>.truth.json beside each.")
    p.add_argument("--plants", required=True, metavar="PLANTS.json", help="plants JSON (Yc, Yd)")
    p.add_argument("--n", required=True, type=int, metavar="N", help="number of pilots")
    from ._options import FORCING_CHOICES, add_seed, add_terms

    add_seed(p, 0, "base seed")
    add_terms(p, {r"(^|: )effects: ": r"\1--effects: ", r"(^|: )n: ": r"\1--n: "})
    p.add_argument("--effects", default="motion_feedback", metavar="LIST",
                   help="comma-separated effects every pilot has, '' for none (remnant noise is "
                        "always added; default: %(default)s)")
    p.add_argument("--duration", type=float, default=70.0, metavar="S",
                   help="record length in s (default: %(default)s)")
    p.add_argument("--dt", type=float, default=0.02, metavar="S",
                   help="sample interval in s (default: %(default)s)")
    p.add_argument("--cohort", default="table1", choices=("table1", "crossover_model"),
                   help="how pilots are drawn: table1 (around Table 1) or crossover_model (target "
                        "crossover 1.5-4 rad/s, kept within the crossover-model limits; the pipeline's "
                        "default); default: %(default)s")
    p.add_argument("--forcing", choices=FORCING_CHOICES, default="paper",
                   help="paper: the side wind and gusts; two_input: wind and roll-rate target "
                        "multisines on interleaved lines, periodic over the record, no paper's side "
                        "wind (the reference column holds the target; default: %(default)s)")
    p.add_argument("--out", required=True, metavar="DIR", help="output folder")
    p.set_defaults(func=_run)


def _run(args) -> int:
    from ..core.formats import read_plants, record_samples
    from ..core.io import check_output_dir
    from ..flight.target import named_forcing
    from ..pilots.cohort import cohort_spec, synth_cohort

    record_samples(args.duration, args.dt, names=("--duration", "--dt"))  # before any allocation
    check_output_dir(args.out, "cohort")  # before any work: a bad folder loses nothing
    plants = read_plants(args.plants)
    effects = [e for e in args.effects.split(",") if e.strip()]
    paths = synth_cohort(plants, args.n, args.seed, effects, args.out,
                         spec=cohort_spec(args.cohort, duration_s=args.duration, dt_s=args.dt,
                                          target=named_forcing(args.forcing)))
    print(f"SYNTHETIC DATA: wrote {len(paths)} synthetic pilot runs "
          f"(effects: {', '.join(effects) or 'none'} + remnant) to {args.out}")
    return 0
