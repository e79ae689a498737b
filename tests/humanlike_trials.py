"""Trials of the independent generator (hesspipe.humanlike, SYNTHETIC) as the tests read them.

The generator's truth is computed from the drawn pilot and plant, never from the estimate
under test.
"""

from __future__ import annotations

import control as ct

from hesspipe.core.formats import Plants, Run
from hesspipe.humanlike import draw_trial, plants_dict, simulate_trial


def generated(plant, seed, pilot, **overrides):
    """(run, plants, truth crossover) of one disturbance-task trial at a coarse fine step."""
    spec = draw_trial(plant, seed, task="disturbance", pilot=pilot, **overrides)
    tr = simulate_trial(spec, fine_ratio=10)
    run = Run(time=tr.time, disturbance=tr.disturbance, output=tr.output, control=tr.control,
              reference=tr.reference, id=spec.name, synthetic=True)
    pd = plants_dict(spec)
    plants = Plants(*(ct.tf(pd[k]["num"], pd[k]["den"])
                      for k in ("control_to_output", "disturbance_to_output")))
    return run, plants, tr.truth["crossover"]
