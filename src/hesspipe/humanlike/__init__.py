"""Independent generator of human-like manual-control trials (SYNTHETIC data).

It stands in for real human recordings when testing hesspipe's identification
and diagnosis: a fine-step, block-by-block time-domain simulation of
compensatory disturbance-rejection / target-tracking tasks flown by
human-like pilots whose parameters are drawn from literature ranges, with
multisine forcing, shaped remnant, an optional within-run drift of the
visual gain, optional hidden effects (motion feedback,
extra delay, elevated remnant, Dutch roll, actuator lag, rate limit), written
the way real loggers write files, each with a ``*.truth.json``.

It shares no modelling code with the rest of hesspipe (it imports only
``hesspipe.core.errors``, ``hesspipe.core.io``, ``hesspipe.core.seeds`` and the paper's printed
numbers, ``hesspipe.core.paper``), so a result
measured on its output is not a result of the code under test agreeing with
itself.

Example
-------
>>> from hesspipe.humanlike import draw_trial, simulate_trial, write_trial
>>> spec = draw_trial("1/s", seed=3, task="disturbance", pilot="precision")
>>> trial = simulate_trial(spec)                # arrays + trial.truth
>>> path = write_trial("out/", trial)           # out/trial-3.csv, .truth.json, plants.json
"""

from __future__ import annotations

from pathlib import Path

from ..core.seeds import derive_seed
from .plants import Plant, make_plant
from .retest import retest
from .trial import EFFECTS, RANGES, Trial, TrialSpec, draw_trial, simulate_trial
from .truth import GENERATOR, closed_loop, pilot_frf
from .writer import csv_bytes, mat_bytes, mat_runs_bytes, plants_dict, write_trial, xlsx_bytes

__all__ = ["EFFECTS", "GENERATOR", "RANGES", "Plant", "Trial", "TrialSpec", "closed_loop",
           "csv_bytes", "mat_bytes", "mat_runs_bytes", "draw_trial", "make_plant", "make_trials", "pilot_frf", "plants_dict",
           "retest", "simulate_trial", "write_trial", "xlsx_bytes"]


def make_trials(folder, plant, n: int, seed: int, *, task: str = "disturbance",
                pilot: str = "precision", effects=(), prefix: str = "pilot", style=None,
                **overrides) -> list[Path]:
    """Generate and write `n` trials of one plant into `folder`.

    Trial i is named ``f"{prefix}{i+1:02d}"`` (the file stem is the pilot id)
    and drawn with seed ``derive_seed(seed, "trial", str(plant), task, pilot,
    effects, i)``; the folder gets one ``plants.json``. Arguments as
    :func:`draw_trial`; `style` None draws a logger style per trial.

    Parameters
    ----------
    folder : str or Path
        Output folder.
    plant : str, dict, path or Plant
        See :func:`hesspipe.humanlike.plants.make_plant`.
    n : int
        Number of trials.
    seed : int
        Base seed.
    task, pilot, effects, style, **overrides
        As :func:`draw_trial`.
    prefix : str
        Pilot id prefix.

    Returns
    -------
    list of Path
        The CSV files written.
    """
    paths = []
    key = ",".join(effects)
    for i in range(int(n)):
        s = derive_seed(seed, "trial", str(plant), task, pilot, key, str(i))
        spec = draw_trial(plant, s, task=task, pilot=pilot, effects=effects,
                          name=f"{prefix}{i + 1:02d}", style=style, **overrides)
        paths.append(write_trial(folder, simulate_trial(spec)))
    return paths
