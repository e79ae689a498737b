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


def bench_diagnose_trial(folder, plant, output, task, effect, seed):
    """(run, plants) of the trial benchmarks/bench_diagnose.py draws for this case and seed,
    written as a logger writes it and read back."""
    from hesspipe.core.formats import read_plants, read_run
    from hesspipe.core.seeds import derive_seed
    from hesspipe.humanlike import write_trial

    effects = () if effect == "none" else tuple(effect.split("+"))
    s = derive_seed(seed, "bench-diagnose", plant, output, task, effect)
    kw = dict(disturbance="wind") if plant == "paper" else {}
    spec = draw_trial(plant, s, task=task, pilot="hess", effects=effects, fs=50.0, T_m=70.0,
                      output=output, **kw)
    path = write_trial(folder / "trial", simulate_trial(spec))
    return read_run(path), read_plants(folder / "trial" / "plants.json")


def repeated_trials(folder, plant, output, task, effect, seed, n, *, baselines=False):
    """(runs, baseline runs, plants, drawn trial) of n runs of one Hess pilot's condition and,
    with `baselines`, n of its baseline condition, as benchmarks/bench_diagnose.py
    [--paired] --repeats n draws them (the condition's repeats keep the simulator's extra
    delay; every retest draws the pilot's run-to-run scatter), written as a logger writes
    them and read back."""
    from hesspipe.core.formats import read_plants, read_run
    from hesspipe.core.seeds import derive_seed
    from hesspipe.humanlike import retest, write_trial

    effects = () if effect == "none" else (effect,)
    s = derive_seed(seed, "bench-diagnose", plant, output, task, effect)
    kw = dict(disturbance="wind") if plant == "paper" else {}
    spec = draw_trial(plant, s, task=task, pilot="hess", effects=effects, fs=50.0, T_m=70.0,
                      output=output, name="run", **kw)
    cond = [spec] + [retest(spec, derive_seed(s, "repeat-run", str(j)), name=f"run-{j + 1}")
                     for j in range(1, n)]
    base = [retest(spec, derive_seed(s, "baseline-run", *([str(j)] if j else [])), effects=(),
                   name=f"base-{j + 1}") for j in range(n if baselines else 0)]
    read = [read_run(write_trial(folder / x.name, simulate_trial(x))) for x in cond + base]
    return read[:n], read[n:], read_plants(folder / "run" / "plants.json"), spec
