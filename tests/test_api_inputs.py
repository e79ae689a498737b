"""A researcher's own arrays and transfer functions through the Python API: valid forms are
taken, mistakes are one-line HesspipeErrors naming the field (a newcomer review found NumPy
tracebacks and silently wrong spectra). Generated trials are SYNTHETIC (hesspipe.humanlike)."""

from __future__ import annotations

import control as ct
import numpy as np
import pandas as pd
import pytest
import scipy.signal

import hesspipe
from hesspipe import HesspipeError, Plants, Run
from hesspipe.humanlike import draw_trial, retest, simulate_trial
from hesspipe.pilot.crossover import gain_scale
from hesspipe.pilot.hess import model_from_name

N = 1000
T = 0.02 * np.arange(N)


def _signals(**over):
    rng = np.random.default_rng(0)
    kw = dict(time=T, disturbance=rng.standard_normal(N), output=rng.standard_normal(N),
              control=rng.standard_normal(N))
    kw.update(over)
    return kw


def test_a_run_takes_what_a_researcher_has_in_memory():
    base = Run(**_signals())
    assert np.array_equal(base.reference, np.zeros(N))   # no target: zeros
    as_series = Run(**{k: pd.Series(v, index=np.arange(N) + 7) for k, v in _signals().items()})
    column = Run(**{k: np.asarray(v, dtype=np.float32).reshape(-1, 1) for k, v in _signals().items()})
    listed = Run(**{k: list(v) for k, v in _signals().items()})
    for run in (as_series, column, listed):
        assert all(getattr(run, k).dtype == np.float64 and getattr(run, k).shape == (N,)
                   for k in ("time", "disturbance", "output", "control", "reference"))
        assert run.dt == pytest.approx(0.02, rel=1e-6)
    # times read back from a text file at 60 Hz, rounded to the millisecond, are uniform
    t60 = np.round(np.arange(N) / 60.0, 3)
    assert Run(**_signals(time=t60)).dt == pytest.approx(1 / 60, rel=1e-4)


@pytest.mark.parametrize("over, words", [
    (dict(time=1000 * T), "field 'time': sample interval 20 s (0.05 Hz) is implausible"),
    (dict(control=np.zeros(N - 1)), "field 'control': expected 1000 samples like time, got 999"),
    (dict(output=np.r_[np.zeros(10), np.nan, np.zeros(N - 11)]), "field 'output': a non-finite value (nan) at t = 0.2 s"),
    (dict(time=np.r_[T[:100], T[101:] + 0.0], disturbance=np.zeros(N - 1), output=np.zeros(N - 1),
          control=np.zeros(N - 1)), "field 'time': an interval of 0.04 s after t = 1.98 s"),
    (dict(control=np.zeros((N, 2))), "field 'control': expected a 1-D array of samples, got shape (1000, 2)"),
    (dict(time=T[::-1]), "field 'time': expected strictly increasing times"),
    (dict(control="stick"), "field 'control': expected an array of numbers, got str"),
])
def test_a_mistake_in_a_runs_arrays_is_named(over, words):
    with pytest.raises(HesspipeError, match="^Run 'x': ") as err:
        Run(**_signals(**over), id="x")
    assert words in str(err.value) and "\n" not in str(err.value)


def test_plants_take_a_transfer_function_in_any_usual_form():
    yc = ct.tf([4.0], [1.0, 2.0, 0.0])
    forms = [yc, ([4.0], [1.0, 2.0, 0.0]), {"num": [4.0], "den": [1.0, 2.0, 0.0]}, ct.ss(yc),
             scipy.signal.lti([4.0], [1.0, 2.0, 0.0])]
    w = np.array([0.5, 2.0, 8.0])
    for form in forms:
        p = Plants(form, form, motion_path=([1.0, 0.0], [1.0]))
        assert np.allclose(p.Yc(1j * w), yc(1j * w)) and np.allclose(p.Yd(1j * w), yc(1j * w))
    assert Plants(yc, yc).Yc is yc   # a control transfer function is kept as given


@pytest.mark.parametrize("yc, words", [
    (ct.tf([1.0, 1.0], [1.0]), "field 'control_to_output': not proper"),
    (ct.tf([1.0], [1.0, 1.0], 0.02), "field 'control_to_output.dt': 0.02 makes it a discrete-time"),
    (ct.tf([[[1.0]], [[1.0]]], [[[1.0, 1.0]], [[1.0, 2.0]]]), "expected a single-input single-output"),
    ("plants.json", "expected a transfer function (control.tf, a (num, den) pair or"),
    (ct.tf([0.0], [1.0]), "field 'control_to_output.num': expected a non-zero polynomial"),
])
def test_a_plant_mistake_is_named(yc, words):
    with pytest.raises(HesspipeError, match="^Plants: ") as err:
        Plants(yc, ct.tf([1.0], [1.0, 1.0]))
    assert words in str(err.value)


@pytest.fixture(scope="module")
def trial():
    return simulate_trial(draw_trial("paper", 5, task="disturbance", pilot="hess", fs=50.0, T_m=81.92,
                                     disturbance="wind"))


def test_a_trial_in_memory_is_labelled_synthetic(trial):
    run = trial.to_run()
    assert run.synthetic and "synthetic data" in run.comments[0] and len(run) == trial.time.size


def test_entry_points_name_a_path_given_for_an_object(trial):
    run = trial.to_run()
    plants = Plants(ct.tf(*trial.spec.plant.nominal_yc), ct.tf(*trial.spec.plant.nominal_yd))
    calls = [(lambda: hesspipe.identify(run, "plants.json"), "plants: expected a Plants (read_plants reads"),
             (lambda: hesspipe.diagnose("run.csv", plants), "run: expected a Run (read_run reads a file), got str"),
             (lambda: hesspipe.estimate_frf("run.csv", plants), "run: expected a Run (read_run reads a file)"),
             (lambda: hesspipe.average_frf("run.csv", plants), "runs: expected a list of Runs"),
             (lambda: hesspipe.compare_conditions([run], ["b.csv"], plants), "expected a Run or a list of Runs"),
             (lambda: hesspipe.compare_pilots([run, 3], plants), "paths_or_dir: expected a folder, run files or Runs"),
             (lambda: hesspipe.simulate("original", None, "plants.json", np.zeros(100), 0.02), "plants: expected"),
             (lambda: hesspipe.simulate("original", None, plants, np.r_[np.zeros(50), np.nan], 0.02),
              "disturbance: a non-finite value at sample 50"),
             (lambda: hesspipe.identify(run, plants, k=3), "k: expected Table 1's column 1"),
             (lambda: hesspipe.identify(run, plants, criterion="df", restarts=0), "restarts: expected an integer >= 1"),
             (lambda: hesspipe.PilotModel("expanded"), "effects: expected a tuple of effect ids")]
    for call, words in calls:
        with pytest.raises(HesspipeError) as err:
            call()
        assert words in str(err.value), str(err.value)


def test_swapped_columns_or_paths_are_named_not_fitted(trial):
    # Before, identify fitted them: crossover 29.7 rad/s, phase margin -80 deg.
    run = trial.to_run()
    yc, yd = ct.tf(*trial.spec.plant.nominal_yc), ct.tf(*trial.spec.plant.nominal_yd)
    plants = Plants(yc, yd)
    swapped = Run(run.time, run.control, run.output, run.disturbance, run.reference)
    for r, p, words in ((swapped, plants, "the control and disturbance columns look swapped"),
                        (run, Plants(yd, yc), "the control and disturbance columns look swapped"),
                        (Run(run.time, run.disturbance, run.control, run.output, run.reference), plants,
                         "the control and output columns look swapped")):
        with pytest.raises(HesspipeError, match=words):
            hesspipe.identify(r, p, criterion="df")


def test_simulate_defaults_follow_the_plants_gain_as_identify_does():
    plants = Plants(ct.tf([2.436], [1.0, 1.05]), ct.tf([1.0], [1.0, 1.0]))
    w = np.random.default_rng(1).standard_normal(2000)
    model = model_from_name("original")
    scaled = model.complete(None, 1, gain=gain_scale(plants, 1))
    assert scaled["Ke"] != model.complete(None, 1)["Ke"]
    a = hesspipe.simulate(model, None, plants, w, 0.02)
    b = hesspipe.simulate(model, scaled, plants, w, 0.02)
    assert a.stable and np.array_equal(a.control, b.control)


def test_a_divergent_generated_loop_is_refused_not_written():
    # A precision pilot with motion feedback re-run without it (humanlike.retest) lost the
    # lead his visual gain relied on; the record grew from 1e5 to 4e19 and was analysed.
    spec = draw_trial("K/s2", seed=103, task="both", pilot="precision", effects=("motion_feedback",),
                      output="angle", fs=60.0, T_m=45.0, name="s04_r1")
    with pytest.raises(HesspipeError, match="the simulated loop diverged"):
        simulate_trial(retest(spec, seed=303, effects=()))
