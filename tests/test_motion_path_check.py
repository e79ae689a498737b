"""A wrong ``motion_path`` is named, not silent (SYNTHETIC data of the independent generator).

A yaw-angle task (1/s, the cab turning with the displayed angle, ``motion_path``
s/(0.01 s + 1)) with target and disturbance lines, drawn and simulated by
:mod:`hesspipe.humanlike` (fine-step block simulation, no hesspipe model code). With the
path negated in the plants file the motion test loses the vestibular path; the path check
refits it with the path's likely mistakes and says which names motion.
"""

from __future__ import annotations

import collections
import dataclasses

import pytest

from hesspipe.core.formats import read_plants, read_run
from hesspipe.diagnose.report import format_report
from hesspipe.diagnose.workflow import diagnose
from hesspipe.humanlike import draw_trial, simulate_trial, write_trial
from hesspipe.identification.motion_test import ALPHA, PATH_VARIANTS, motion_test


def _trial(folder, effects, seed=1):
    spec = draw_trial("1/s", seed, task="both", pilot="hess", effects=effects, output="angle", fs=50.0,
                      T_m=70.0, style="plain", name="pilot")
    path = write_trial(folder, simulate_trial(spec))
    return read_run(path), read_plants(folder / "plants.json")


@pytest.fixture(scope="module")
def twins(tmp_path_factory):
    return (_trial(tmp_path_factory.mktemp("motion"), ("motion_feedback",)),
            _trial(tmp_path_factory.mktemp("static"), ()))


def test_a_negated_motion_path_is_named_by_diagnose(twins):
    (run, plants), _ = twins
    negated = dataclasses.replace(plants, motion_path=-plants.motion_path)
    d = diagnose(run, negated, seed=1)
    mv = d.motion_verdict
    assert "motion_feedback" not in d.named_effects, mv      # the wrong path hides it ...
    assert mv["path_check"]["better"] == "negated", mv["path_check"]   # ... and the check finds it
    assert "negated" in mv["path_check"]["named"]
    assert set(mv["path_check"]["p_values"]) == set(PATH_VARIANTS)
    text = format_report(d)
    assert "CHECK motion_path: motion is not named with the path given, but it is with the path negated (p=" in text
    assert "check motion_path's sign" in text


def test_the_path_check_is_quiet_where_the_path_is_right(twins):
    (run, plants), (run0, _) = twins
    named = motion_test(run, plants, {}, k=1, path_check=ALPHA)
    assert named["p_value"] < ALPHA and named["path_check"] is None    # named: nothing to check
    static = motion_test(run0, plants, {}, k=1, path_check=ALPHA)
    assert static["p_value"] >= ALPHA
    assert static["path_check"] is not None and static["path_check"]["better"] is None, static["path_check"]
    assert motion_test(run0, plants, {}, k=1)["path_check"] is None     # not asked


def test_the_path_check_is_not_run_on_one_forcing_function(tmp_path):
    # Target only: "not named" is "cannot tell", and a negated path fitted such a static
    # run better (p ~ 1e-6): the check flagged it, and the negated path then named motion.
    spec = draw_trial("1/s", 1, task="tracking", pilot="hess", effects=(), output="angle", fs=50.0,
                      T_m=70.0, style="plain", name="pilot")
    run, plants = read_run(write_trial(tmp_path, simulate_trial(spec))), read_plants(tmp_path / "plants.json")
    t = motion_test(run, plants, {}, k=1, path_check=ALPHA)
    assert t["forcing"] == "target only" and t["p_value"] >= ALPHA
    assert t["path_check"] is None, t["path_check"]
    d = diagnose(run, plants, seed=1)
    assert d.motion_verdict["path_check"] is None and "CHECK motion_path" not in format_report(d)
    assert "cannot tell" in d.motion_verdict["verdict"]


def test_the_report_says_which_fit_holds_the_named_motion_gain(twins):
    # A reader took the final model's Km (parameters_after, the control-spectrum refit) for the
    # describing function's: 0.03 against 0.17 in Km/|Ke| on a lab stand-in run.
    (run, plants), _ = twins
    d = diagnose(run, plants, seed=1)
    assert "motion_feedback" in d.named_effects and d.motion_verdict["path_check"] is None
    km = next(s for s in d.steps if s.accepted and s.candidate == "motion_feedback").parameters["Km"]
    assert d.parameters_after["Km"] != pytest.approx(km, rel=1e-6)
    assert (f"fitted Km={km:.4g} on the describing function (the final model's control-spectrum refit: "
            f"Km={d.parameters_after['Km']:.4g})") in format_report(d)
    assert d.to_dict()["parameters_fitted_on"].startswith("control spectrum")


def test_a_cohort_flown_with_a_negated_path_is_told_to_check_it(tmp_path):
    # pilots' cohort verdict with the path's likely mistakes (verdict.path_verdict): a negated
    # path made an independent lab's motion cohort a plain "no" (median-pilot p = 1) that only
    # diagnose, run by run, flagged. The static cohort with the right path gets no line.
    from hesspipe.core.errors import HesspipeError
    from hesspipe.pilots.compare import pilot_motion_test
    from hesspipe.pilots.settings import CompareSettings
    from hesspipe.pilots.verdict import cohort_verdict, verdict_lines

    def cohort(folder, effects, negate):
        paths, seed = [], 0
        while len(paths) < 3:   # the first three pilots the generator's draw budget finds
            seed += 1
            try:
                spec = draw_trial("1/s", seed, task="both", pilot="hess", effects=effects, output="angle",
                                  fs=50.0, T_m=70.0, style="plain", name=f"pilot{seed:02d}")
            except HesspipeError:
                continue
            paths.append(write_trial(folder, simulate_trial(spec)))
        plants = read_plants(folder / "plants.json")
        if negate:
            plants = dataclasses.replace(plants, motion_path=-plants.motion_path)
        # The test as compare_pilots runs it for each pilot.
        return cohort_verdict({p.stem: pilot_motion_test(read_run(p), plants, {}, CompareSettings(k=1))
                               for p in paths})

    wrong = cohort(tmp_path / "m", ("motion_feedback",), True)
    assert wrong["answer"] == "no" and wrong["path_check"]["named"][:1] == ["negated"], wrong["path_check"]
    assert wrong["path_check"]["variants"]["negated"]["n_significant"] >= 2
    lines = verdict_lines(wrong)
    assert lines[1].startswith("  CHECK motion_path: motion feedback would improve the fit for at least half "
                               "of the pilots with the path negated (")
    static = cohort(tmp_path / "s", (), False)
    assert static["answer"] == "no" and static["path_check"] is not None and static["path_check"]["named"] == []
    assert not any("CHECK motion_path" in line for line in verdict_lines(static))


def test_only_the_reported_test_gets_its_path_check_and_km_estimate(twins, monkeypatch):
    # Display "either" fits the test for each display and pilot structure; the path check and
    # the Km estimate are made once, for the test reported (made for each, they were a fifth
    # of a laboratory's diagnosis time).
    import hesspipe.identification._motion_fits as fits

    calls = collections.Counter()

    def counted(name, f):
        def wrapper(*args, **kwargs):
            calls[name] += 1
            return f(*args, **kwargs)
        return wrapper

    for name in ("_one_display", "_path_check", "km_estimate"):
        monkeypatch.setattr(fits, name, counted(name, getattr(fits, name)))
    _, (run0, plants) = twins
    # Order 2: Hess's structure and the precision one are both fitted.
    t = motion_test(run0, plants, {}, k=2, path_check=ALPHA, display="either")
    assert calls["_one_display"] >= 2, calls
    assert calls["_path_check"] == 1 and calls["km_estimate"] == 1, calls
    assert t["p_value"] >= ALPHA and t["path_check"]["better"] is None
    assert t["Km"] == t["parameters_estimate"]["Km"]
