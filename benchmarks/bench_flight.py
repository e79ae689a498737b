"""Benchmark of stage one: wall time of trim + both records, and excitation strength.

For each aircraft: the wall time of :func:`hesspipe.flight.approach.fly_records` (load,
trim and fly the wind and the aileron record, in memory, no files), the best
of a few repeats; then the RMS roll rate of each record against the RMS roll
rate of a calm-air record with no wind and no excitation (the numerical
noise floor).

Run:  python benchmarks/bench_flight.py [AIRCRAFT ...]   (default: 737 B747)
"""

from __future__ import annotations

import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from hesspipe.flight.approach import FlightConfig, fly_records


def _rms(x) -> float:
    return float(np.sqrt(np.mean(np.asarray(x) ** 2)))


def main(names: list[str]) -> None:
    config = FlightConfig()
    calm = FlightConfig.from_table({"side_wind": {"speed_end_fps": 0.0},
                                    "wind_excitation": {"kind": "none"}}, "bench calm")
    no_excitation = FlightConfig.from_table({"wind_excitation": {"kind": "none"}}, "bench side wind only")
    print(f"stage one: {config.duration_s:g} s records at dt = {config.dt_s:.6g} s; "
          f"wind excitation: {config.wind_excitation.describe('ft/s')}; "
          f"aileron excitation: {config.aileron_excitation.describe('(norm)')}")
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        fly_records(names[0], calm, 0, work / "warm-up")  # imports, caches
        for i, name in enumerate(names):
            times = []
            for r in range(3):
                t0 = time.perf_counter()
                trim, wind, aileron = fly_records(name, config, 0, work / f"{i}-{r}")
                times.append(time.perf_counter() - t0)
            _, quiet, _ = fly_records(name, calm, 0, work / f"{i}-calm")
            _, slow, _ = fly_records(name, no_excitation, 0, work / f"{i}-slow")
            noise = _rms(quiet["roll_rate_rps"])
            p_wind, p_ail, p_slow = (_rms(d["roll_rate_rps"]) for d in (wind, aileron, slow))
            print(f"{name}: trim + both records {min(times):.3f} s wall (best of 3; "
                  f"{', '.join(f'{t:.3f}' for t in times)})")
            print(f"  trim {trim['vc_kts']:.2f} KCAS, gamma {trim['gamma_deg']:.3f} deg, "
                  f"heading {trim['psi_deg']:.2f} deg, alpha {trim['alpha_deg']:.2f} deg")
            print(f"  roll rate rms: calm {noise:.3g} rad/s; side wind only {p_slow:.3g} "
                  f"({p_slow / noise:.3g}x calm); wind record {p_wind:.3g} ({p_wind / noise:.3g}x calm); "
                  f"aileron record {p_ail:.3g} ({p_ail / noise:.3g}x calm)")
            print(f"  airspeed wind record {wind['vc_kts'].min():.1f}-{wind['vc_kts'].max():.1f} kt, "
                  f"aileron record {aileron['vc_kts'].min():.1f}-{aileron['vc_kts'].max():.1f} kt; "
                  f"lowest {min(wind['h_agl_ft'].min(), aileron['h_agl_ft'].min()):.0f} ft AGL; "
                  f"max |bank| {max(wind['bank_deg'].abs().max(), aileron['bank_deg'].abs().max()):.1f} deg")


if __name__ == "__main__":
    main(sys.argv[1:] or ["737", "B747"])
