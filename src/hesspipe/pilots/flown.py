"""The pilots stage's cohort flown in JSBSim (SYNTHETIC): each drawn pilot flies the aircraft.

The draw is :func:`hesspipe.pilots.cohort.synth_pilot`'s; the flight is
:func:`hesspipe.flight.closed_loop.fly_pilot_record`'s.
"""

from __future__ import annotations

import math
import os
import tempfile
from dataclasses import replace
from pathlib import Path
from typing import Sequence

from ..core.errors import HesspipeError
from ..core.formats import Plants, plants_coefficients, write_run
from ..core.io import staged_output, write_json
from ..core.provenance import versions
from ..core.seeds import derive_seed
from ..flight.approach import FlightConfig
from ..flight.closed_loop import fly_pilot_record
from ..flight.target import named_forcing, record_flight
from .cohort import CohortSpec, _check_effects, cohort_spec, pilot_ids, synth_pilot


def fly_cohort(plants: Plants, n: int, seed: int, effects: Sequence[str], out_dir: str | os.PathLike, *,
               aircraft: str = "737", config: FlightConfig = FlightConfig(), record_dt_s: float = 0.02,
               spec=None, target=None) -> list[Path]:
    """The pipeline's cohort, flown in JSBSim: ``<id>.csv``, ``<id>.truth.json``, ``cohort.json``.

    Each pilot is drawn exactly as :func:`hesspipe.pilots.cohort.synth_pilot` draws it
    (same seeds, parameters and remnant share; the frequency-domain run it also
    makes is discarded), then flies `aircraft` at ``config.dt_s``; Kn is
    re-derived for that step from the pilot's remnant share. Records keep every
    ``ceil(record_dt_s / dt_s)``-th step (0.02 s at 1/120 s: every 3rd, 40 Hz, whose
    times are exact in the CSV's decimal digits). `target` (a
    :class:`hesspipe.flight.target.TargetForcing`, optional) replaces the wind excitation
    by its interleaved wind and target multisines.

    Parameters
    ----------
    plants : hesspipe.core.formats.Plants
        The plants the pilots are drawn for (gain scale, corner, remnant level).
    n : int
        Number of pilots (>= 1).
    seed : int
        Base seed; each pilot's seed is derived from it and the pilot id.
    effects : sequence of str
        Pilot-side effects of every pilot.
    out_dir : str or path
        Output folder (written atomically).
    aircraft : str
        JSBSim aircraft.
    config : hesspipe.flight.approach.FlightConfig
        Flight settings (simulation step ``dt_s``, s).
    record_dt_s : float
        Wanted record interval, s (rounded up to whole simulation steps).
    spec : CohortSpec, optional
        How pilots are drawn (default: :class:`CohortSpec` with the flight's duration).
    target : hesspipe.flight.target.TargetForcing, optional
        Wind and roll-rate target multisines replacing the wind excitation.

    Returns
    -------
    list of Path
        The run files, in pilot order.

    Raises
    ------
    HesspipeError
        If `n` is not an integer >= 1, or an effect is unknown or listed twice.
    """
    if isinstance(n, bool) or not isinstance(n, int) or n < 1:
        raise HesspipeError(f"n: expected an integer >= 1, got {n!r}")
    effects = _check_effects(effects)
    spec = spec or CohortSpec(duration_s=config.duration_s)
    every = max(1, int(math.ceil(record_dt_s / config.dt_s - 1e-9)))
    ids = pilot_ids(n)
    out_dir = Path(out_dir)
    summary = []
    with staged_output(out_dir, kind="cohort") as stage:
        with tempfile.TemporaryDirectory(prefix=".jsbsim-", dir=stage) as work:
            for pid in ids:
                pseed = derive_seed(seed, pid)
                _, drawn = synth_pilot(plants, pid, pseed, effects, spec)
                params = {k: v for k, v in drawn["parameters"].items() if k != "Kn"}
                flight = fly_pilot_record(aircraft, plants, drawn["model"], params, seed=pseed,
                                          workdir=Path(work), config=config, record_every=every,
                                          remnant_share=drawn["remnant_share"], run_id=pid,
                                          target=target)
                truth = dict(flight.truth, base_seed=seed, draws=drawn["draws"],
                             distributions=drawn["distributions"],
                             **{k: drawn[k] for k in ("target_crossover_rad_s", "crossover") if k in drawn})
                write_run(stage / f"{pid}.csv", flight.run)
                write_json(stage / f"{pid}.truth.json", truth)
                summary.append({"id": pid, "seed": pseed, "parameters": truth["parameters"],
                                "envelope": truth["envelope"]})
        write_json(stage / "cohort.json", {
            "synthetic": True,
            "simulator": "jsbsim",
            "note": "SYNTHETIC DATA: Hess pilot models flying the JSBSim aircraft in closed loop, "
                    "not measured",
            "target": None if target is None else target.describe(),
            "aircraft": aircraft, "n": n, "seed": seed, "effects": list(summary and truth["effects"]),
            "dt_s": config.dt_s * every, "simulation_dt_s": config.dt_s,
            "plants": plants_coefficients(plants),
            "pilots": summary, "versions": versions()})
    return [out_dir / f"{pid}.csv" for pid in ids]


def fly_pipeline_cohort(config, plants: Plants, ctx):
    """The pilots stage's JSBSim cohort: fly it into ``ctx.out_dir/cohort``.

    `config` is the stage's :class:`hesspipe.pilots.compare.PilotsConfig`; the aircraft and
    the flight settings are the ``[flight]`` table's (the aircraft the plants were
    fitted on, unless the user changes it). Returns `config` pointing at the cohort.

    Parameters
    ----------
    config : hesspipe.pilots.compare.PilotsConfig
        The ``[pilots]`` settings (n, effects, cohort draw, duration, record interval, forcing).
    plants : hesspipe.core.formats.Plants
        The fitted plants.
    ctx
        The pipeline's stage context (its ``config``, ``source``, ``seed`` and
        ``out_dir`` are used).
    """
    table = dict(ctx.config.get("flight", {}))
    aircraft = table.pop("aircraft", "737")
    flight_config = FlightConfig.from_table(table, ctx.source)
    # Two-input: the run-in is flown before the recorded duration_s (see flight.target).
    target = named_forcing(config.forcing)
    flight_config = record_flight(replace(flight_config, duration_s=config.duration_s), target)
    seed = config.seed if config.seed is not None else int(ctx.seed)
    folder = Path(ctx.out_dir) / "cohort"
    fly_cohort(plants, config.n, seed, config.effects, folder, aircraft=aircraft, config=flight_config,
               record_dt_s=config.dt_s, spec=cohort_spec(config.cohort, duration_s=config.duration_s),
               target=target)
    return replace(config, data=str(folder))
