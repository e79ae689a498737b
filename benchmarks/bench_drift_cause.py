"""Why a double integrator's plants drift when fed the logged control (SYNTHETIC DATA).

Every run is drawn by the independent generator :mod:`hesspipe.humanlike` exactly as
``bench_diagnose.py`` draws it. The generator simulates the loop at 20x the logging rate
and logs *samples* of the fine-step signals (a logger samples; it does not average). This
script keeps the fine-step control and drives the run's plants, through the refit of
:func:`hesspipe.diagnose.aircraft.plant_finding` (initial state and disturbance gain
refitted, no drift columns), with three versions of the control:

* ``sampled``: the logged control (asserted equal to the fine control's sample at each
  logging instant);
* ``block-mean``: the fine control averaged over each logging interval;
* ``lowpass+sample``: the fine control with everything above the logging Nyquist removed,
  then sampled.

If the drift is the control's content above the Nyquist folded down and integrated, the
last two fit the output and the first leaves a residual mostly below 0.1 Hz. Prints per
run: the fine control's power share above the Nyquist, and for each version the refit
(percent), the residual RMS over the output's standard deviation and the residual's power
share below 0.1 Hz.

Usage::

    python benchmarks/bench_drift_cause.py [--runs K/s2:angle:both:none:9,...]
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from dataclasses import replace
from pathlib import Path

import numpy as np

import hesspipe.diagnose._refit as refit
import hesspipe.diagnose.aircraft as aircraft
import hesspipe.humanlike.trial as trial
from hesspipe.core.formats import read_plants, read_run
from hesspipe.core.seeds import derive_seed
from hesspipe.humanlike import write_trial

#: The reported runs (seeds 0-9) that named an aircraft effect before the drift columns:
#: the double integrator's two, the paper plants' two elevated-remnant runs, and one
#: double-integrator baseline left "unexplained".
RUNS = ("K/s2:angle:both:none:9,K/s2:angle:both:motion_feedback:0,K/s2:angle:both:none:0,"
        "paper:angle:both:remnant:0,paper:angle:disturbance:remnant:0")


def fine_trial(plant, output, task, effect, seed):
    """The bench_diagnose run and its fine-step control (captured from the stepper)."""
    calls, info = [], {}
    compile_loop, build_truth = trial.compile_loop, trial.build_truth

    def spy_compile(wiring):
        fn = compile_loop(wiring)
        return lambda *a: calls.append(fn(*a)) or calls[-1]

    def spy_truth(spec, sim_info):
        info.update(sim_info)
        return build_truth(spec, sim_info)

    effects = () if effect == "none" else tuple(effect.split("+"))
    s = derive_seed(seed, "bench-diagnose", plant, output, task, effect)
    kw = dict(disturbance="wind") if plant == "paper" else {}
    spec = trial.draw_trial(plant, s, task=task, pilot="hess", effects=effects, fs=50.0, T_m=70.0,
                            output=output, **kw)
    trial.compile_loop, trial.build_truth = spy_compile, spy_truth
    try:
        tr = trial.simulate_trial(spec)
    finally:
        trial.compile_loop, trial.build_truth = compile_loop, build_truth
    if info["rate_limit_per_s"] is not None:
        raise SystemExit("a rate-limited run is not superposed; pick another run")
    (_, u_f, _), (_, u_n, _) = calls[-2], calls[-1]   # forcing, then remnant (linear loop)
    u_fine = np.asarray(u_f) + info["remnant_gain"] * np.asarray(u_n)
    with tempfile.TemporaryDirectory() as d:
        path = write_trial(Path(d) / "t", tr)
        run, plants = read_run(path), read_plants(Path(d) / "t" / "plants.json")
    i0 = int(round(spec.options["run_in"] * 50.0)) * info["ratio"]
    return run, plants, u_fine[i0:i0 + len(run) * info["ratio"]], info["ratio"]


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", default=RUNS, help="plant:output:task:effect:seed, comma-separated")
    args = ap.parse_args(argv)
    print("SYNTHETIC DATA: every run below is drawn by the independent generator hesspipe.humanlike.")
    for item in args.runs.split(","):
        plant, output, task, effect, seed = item.split(":")
        run, plants, u_fine, ratio = fine_trial(plant, output, task, effect, int(seed))
        n, fs = len(run), 1.0 / run.dt
        blocks = u_fine.reshape(n, ratio)
        assert np.allclose(blocks[:, 0], run.control, rtol=0, atol=1e-6 * np.ptp(run.control)), \
            "the logged control is not the fine control's sample"
        U = np.fft.rfft(u_fine)
        f = np.fft.rfftfreq(u_fine.size, run.dt / ratio)
        above = float(np.sum(np.abs(U[f > fs / 2]) ** 2) / np.sum(np.abs(U[1:]) ** 2))
        U[f >= fs / 2] = 0.0
        versions = {"sampled": run.control, "block-mean": blocks.mean(axis=1),
                    "lowpass+sample": np.fft.irfft(U, u_fine.size)[::ratio]}
        print(f"{item}: fine control's power above {fs / 2:.0f} Hz {100 * above:.2f} %")
        band, refit.DRIFT_HZ = refit.DRIFT_HZ, 0.0   # the refit without drift columns (read by _refit)
        try:
            for name, u in versions.items():
                p = aircraft._Paths(replace(run, control=u), plants)
                r = p.residual(p.time(p.yc * p.spec["control"]), p.time(p.yd * p.spec["disturbance"]),
                               aircraft._poles(plants.control_to_output, plants.disturbance_to_output))
                R = np.abs(np.fft.rfft(r)) ** 2
                low = float(R[np.fft.rfftfreq(r.size, run.dt) < 0.1].sum() / R.sum())
                print(f"  {name:<15} refit {p.fit_of(r):6.1f} %, residual RMS / output std "
                      f"{100 * np.std(r) / np.std(p.cols['output'][p.sl]):5.1f} %, residual power "
                      f"below 0.1 Hz {100 * low:5.1f} %")
        finally:
            refit.DRIFT_HZ = band
    return 0


if __name__ == "__main__":
    sys.exit(main())
