"""``hesspipe flight``: trim and fly the approach in JSBSim (stage one)."""

from __future__ import annotations

# Imports sit inside the functions: `hesspipe --help` and argument errors load no numpy
# (tests/test_api.py), and each command loads only its own stage.
from pathlib import Path


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "flight", help="trim a JSBSim transport on the approach and record the side-wind and aileron runs",
        description="Trim a bundled JSBSim transport at the paper's approach condition and fly two "
                    "records (side wind + excitation; aileron excitation in calm air) into DIR.")
    from ..flight.aircraft import DEFAULT_AIRCRAFT

    p.add_argument("--aircraft",
                   help=f"aircraft file in aircraft/ (default: --config's [flight] aircraft, else "
                        f"{DEFAULT_AIRCRAFT})")
    p.add_argument("--out", required=True, type=Path, metavar="DIR", help="output folder")
    p.add_argument("--config", type=Path, metavar="FILE",
                   help="TOML configuration (as 'hesspipe run --config' takes) whose [flight] table "
                        "overrides the defaults")
    from ._options import add_seed

    add_seed(p, None, "seed of the excitation signals (default: --config's seed, else 0)")
    p.set_defaults(func=_run)


def _run(args) -> int:
    from ..core.io import check_output_dir
    from ..flight.approach import fly
    from ..viz.flight import draw_flight
    from ._options import read_cli_flight

    check_output_dir(args.out, "flight")  # before any work: a bad folder loses nothing
    aircraft, config, seed = read_cli_flight(args)
    result = fly(aircraft, config, args.out, seed=seed, draw=draw_flight)
    tr = result.trim
    print(f"{result.aircraft}: trimmed at {tr['vc_kts']:.2f} KCAS, gamma {tr['gamma_deg']:.2f} deg, "
          f"heading {tr['psi_deg']:.1f} deg, alpha {tr['alpha_deg']:.2f} deg, throttle {tr['throttle']:.3f}")
    for name, rec in (("wind", result.wind), ("aileron", result.aileron)):
        print(f"{name} record: {len(rec)} samples, roll rate rms {(rec['roll_rate_rps'] ** 2).mean() ** 0.5:.4g} rad/s, "
              f"airspeed {rec['vc_kts'].min():.1f}-{rec['vc_kts'].max():.1f} kt, "
              f"min {rec['h_agl_ft'].min():.0f} ft AGL")
    print(f"wrote {', '.join(sorted(result.files))} to {args.out}")
    return 0
