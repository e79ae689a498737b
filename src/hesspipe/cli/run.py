"""``hesspipe run``: run every stale stage of the pipeline."""

from __future__ import annotations

# Imports sit inside the functions: `hesspipe --help` and argument errors load no numpy
# (tests/test_api.py), and each command loads only its own stage.
import sys


def register(sub) -> None:
    p = sub.add_parser("run", help="run the pipeline (only the stages that are stale)",
                       description="Run flight → plants → pilots → diagnose and the report, "
                                   "re-running only stages whose inputs, configuration or code changed.")
    p.add_argument("--config", metavar="FILE", help="TOML configuration merged over pipeline/default.toml")
    p.add_argument("--out", metavar="DIR", default="hesspipe-out", help="output folder (default: %(default)s)")
    p.add_argument("--force", metavar="STAGE", action="append", default=[],
                   help="re-run STAGE even if fresh (repeatable)")
    p.add_argument("--from", dest="from_stage", metavar="STAGE",
                   help="re-run STAGE and everything downstream, e.g. --from flight to regenerate the wind model")
    p.add_argument("--aircraft", metavar="NAME", help="override flight.aircraft")
    from ._options import add_seed

    add_seed(p, None, "override the pipeline seed")
    p.set_defaults(func=_run)


def _run(args) -> int:
    from ..pipeline.stages import build_pipeline, validate
    from ._options import check_aircraft

    check_aircraft(args.aircraft)  # blamed on the flag: the configuration's file did not name it
    pipe = build_pipeline(args.config, args.out, aircraft=args.aircraft, seed=args.seed)
    say = (lambda line: print(f"[hesspipe] {line}", file=sys.stderr))
    # Every table is checked before the first stage runs; an up-to-date run skips the
    # check and the heavy imports it needs.
    outcomes = pipe.run(force=args.force, from_stage=args.from_stage, progress=say,
                        before=lambda: validate(pipe.config, pipe.source))
    ran = [o.name for o in outcomes if o.action == "ran"]
    total = sum(o.wall_time_s for o in outcomes)
    print(f"ran {len(ran)} of {len(outcomes)} stages ({', '.join(ran) or 'none'}) in {total:.1f} s; "
          f"report: {pipe.output_folder('report') / 'report.md'}")
    return 0
