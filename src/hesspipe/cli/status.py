"""``hesspipe status``: each stage fresh or stale, and why."""

from __future__ import annotations

# Imports sit inside the functions: `hesspipe --help` and argument errors load no numpy
# (tests/test_api.py), and each command loads only its own stage.


def register(sub) -> None:
    p = sub.add_parser("status", help="show which pipeline stages are fresh or stale, and why")
    p.add_argument("--config", metavar="FILE", help="TOML configuration merged over pipeline/default.toml")
    p.add_argument("--out", metavar="DIR", default="hesspipe-out", help="output folder (default: %(default)s)")
    p.add_argument("--aircraft", metavar="NAME", help="override flight.aircraft")
    from ._options import add_seed

    add_seed(p, None, "override the pipeline seed")
    p.set_defaults(func=_status)


def _status(args) -> int:
    from ..pipeline.stages import build_pipeline, validate
    from ._options import check_aircraft

    check_aircraft(args.aircraft)  # blamed on the flag: the configuration's file did not name it
    pipe = build_pipeline(args.config, args.out, aircraft=args.aircraft, seed=args.seed)
    # As `run` checks it: a misspelt key said "stale: configuration changed", a missing data
    # folder "input file not found" without the file or the field.
    validate(pipe.config, pipe.source)
    rows = pipe.status()
    width = max(len(r.name) for r in rows)
    for r in rows:
        print(f"{r.name:<{width}}  {r.state:<5}  {r.reason}")
    return 0
