"""``hesspipe fly-pilot``: the Hess pilot model flies the JSBSim aircraft in closed loop."""

from __future__ import annotations

# Imports sit inside the functions: `hesspipe --help` and argument errors load no numpy
# (tests/test_api.py), and each command loads only its own stage.
from pathlib import Path


def register(sub) -> None:
    p = sub.add_parser(
        "fly-pilot", help="let the Hess pilot model fly a JSBSim aircraft in closed loop (SYNTHETIC run)",
        description="Trim a bundled JSBSim transport on the approach and let the Hess structural pilot "
                    "model (original or expanded, with effects) null the roll rate at 120 Hz through "
                    "the paper's side wind plus the identification excitation. Writes DIR/ID.csv "
                    "(measured-run format, marked synthetic), DIR/ID.truth.json and DIR/ID.png.")
    from ..flight.aircraft import DEFAULT_AIRCRAFT
    from ._options import FORCING_CHOICES

    p.add_argument("--aircraft",
                   help=f"aircraft file in aircraft/ to fly; may differ from the plants' aircraft "
                        f"(default: --config's [flight] aircraft, else {DEFAULT_AIRCRAFT})")
    p.add_argument("--plants", required=True, metavar="PLANTS.json",
                   help="plants JSON: sets the pilot's gain scale and optional motion_path")
    p.add_argument("--out", required=True, type=Path, metavar="DIR", help="output folder")
    p.add_argument("--model", default="expanded", choices=("original", "expanded"),
                   help="pilot model (default: %(default)s)")
    p.add_argument("--effects", default="remnant", metavar="LIST",
                   help="comma-separated pilot-side effects added to the model: extra_delay, remnant, "
                        "otoliths, motion_feedback ('' for none; default: %(default)s)")
    p.add_argument("--params", type=Path, metavar="FILE",
                   help="JSON of parameter values (an object, or a truth file with 'parameters'); "
                        "missing ones take Table 1 on the plants' gain scale")
    p.add_argument("--remnant-share", type=float, metavar="X",
                   help="remnant share of the control variance when Kn is not given (default 0.1)")
    p.add_argument("--id", default="pilot", metavar="ID", help="run id / file stem (default: %(default)s)")
    p.add_argument("--actuator-lag", type=float, default=0.0, metavar="S",
                   help="hidden aileron actuator time constant, s (default: none)")
    p.add_argument("--rate-limit", type=float, metavar="R",
                   help="hidden aileron rate limit, normalised command per s (default: none)")
    p.add_argument("--yaw-damper", choices=("on", "off"), default="on",
                   help="'off' removes the aircraft's yaw damper (default: %(default)s)")
    p.add_argument("--max-bank", type=float, default=15.0, metavar="DEG",
                   help="bank limit of the record, deg (default: %(default)s)")
    p.add_argument("--forcing", choices=FORCING_CHOICES, default="paper",
                   help="paper: the side wind and gusts of the identification excitation; two_input: "
                        "wind and roll-rate target multisines on interleaved lines, flown for a 15 s "
                        "run-in plus the duration, no paper's side wind (default: %(default)s)")
    p.add_argument("--config", type=Path, metavar="FILE",
                   help="TOML configuration (as 'hesspipe run --config' takes) whose [flight] table "
                        "sets step, duration, limits and the wind")
    from ._options import add_seed, add_terms

    add_seed(p, None, "seed of the wind excitation and remnant (default: --config's seed, else 0)")
    add_terms(p, {r"(^|: )run_id: ": r"\1--id: "})
    p.set_defaults(func=_run)


def _params(path: Path, model) -> dict:
    import json

    from ..core.errors import HesspipeError

    try:
        obj = json.loads(path.read_text(encoding="utf-8-sig"))
    except FileNotFoundError:
        raise HesspipeError(f"{path}: file not found") from None
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise HesspipeError(f"{path}: not a readable JSON file ({exc})") from None
    if isinstance(obj, dict) and isinstance(obj.get("parameters"), dict):
        obj = obj["parameters"]
    if not isinstance(obj, dict):
        raise HesspipeError(f"{path}: expected a JSON object of parameter values")
    return model.check_values(obj, str(path))


def _run(args) -> int:
    from ..core.errors import HesspipeError
    from ..core.formats import read_plants
    from ..flight.closed_loop import AircraftEffects, fly_pilot
    from ..flight.target import named_forcing
    from ..pilot.hess import model_from_name
    from ..viz.pilotflight import draw_pilot_flight
    from ._options import read_cli_flight

    for flag, value, ok, want in (
            ("--actuator-lag", args.actuator_lag, lambda v: v >= 0, "a time constant >= 0 s"),
            ("--rate-limit", args.rate_limit, lambda v: v > 0, "a rate > 0 (normalised command per s)"),
            ("--max-bank", args.max_bank, lambda v: v > 0, "a bank limit > 0 deg"),
            ("--remnant-share", args.remnant_share, lambda v: 0 < v < 1, "a share in (0, 1)")):
        if value is not None and not (value == value and ok(value)):
            raise HesspipeError(f"{flag}: expected {want}, got {value:g}")
    plants = read_plants(args.plants)
    aircraft, config, seed = read_cli_flight(args)
    effects = [e.strip() for e in args.effects.split(",") if e.strip()]
    model = model_from_name("+".join([args.model] + [e for e in effects if not (
        e == "motion_feedback" and args.model == "expanded")]))
    act = AircraftEffects(actuator_lag_s=args.actuator_lag, rate_limit_per_s=args.rate_limit,
                          yaw_damper=args.yaw_damper == "on")
    params = _params(args.params, model) if args.params is not None else {}
    flight = fly_pilot(aircraft, plants, args.out, model=model, params=params, seed=seed,
                       config=config, aircraft_effects=act, remnant_share=args.remnant_share,
                       max_bank_deg=args.max_bank, run_id=args.id, draw=draw_pilot_flight,
                       target=named_forcing(args.forcing))
    env = flight.truth["envelope"]
    print(f"SYNTHETIC DATA: {flight.truth['model']} pilot flew {flight.truth['aircraft']} for "
          f"{flight.truth['duration_s']:g} s (recorded from {flight.truth['record_start_s']:g} s): airspeed {env['speed_kts'][0]:.1f}-{env['speed_kts'][1]:.1f} kt, "
          f"min {env['min_agl_ft']:.0f} ft AGL, max |bank| {env['max_abs_bank_deg']:.1f} deg")
    print(f"wrote {args.id}.csv, {args.id}.truth.json, {args.id}.png to {args.out}")
    return 0
