"""The motion verdict says what the record's forcing lets it rest on (SYNTHETIC data from
the independent generator hesspipe.humanlike): with one forcing function the visual and
vestibular paths act on one signal, and a test that finds nothing cannot rule motion out."""

from __future__ import annotations

import pytest

from hesspipe.core.formats import read_plants, read_run
from hesspipe.diagnose.motion import forcing_sets, motion_words
from hesspipe.diagnose.report import format_report
from hesspipe.diagnose.workflow import diagnose
from hesspipe.humanlike import draw_trial, simulate_trial, write_trial


def _run(tmp_path, task):
    spec = draw_trial("roll", 5, task=task, pilot="hess", fs=50.0, T_m=70.0, output="rate")
    path = write_trial(tmp_path / task, simulate_trial(spec))
    return read_run(path), read_plants(tmp_path / task / "plants.json")


@pytest.mark.parametrize("task,expected", [("disturbance", "disturbance only"),
                                           ("tracking", "target only"),
                                           ("both", "disturbance and target")])
def test_forcing_sets_are_read_per_signal(tmp_path, task, expected):
    run, _ = _run(tmp_path, task)
    assert forcing_sets(run) == expected


def test_words_say_when_the_data_cannot_tell():
    assert motion_words(False, "disturbance only").startswith("cannot tell")
    assert motion_words(False, "target only").startswith("cannot tell")
    assert motion_words(False, "target only").endswith("a disturbance on lines of its own would)")
    assert motion_words(False, "disturbance only").endswith("a target on lines of its own would)")
    assert motion_words(False, "disturbance and target").startswith("no evidence")
    assert "shapes of the two paths alone" in motion_words(True, "disturbance only")
    assert motion_words(True, "disturbance and target").startswith("motion feedback named")
    # The form of the path that fitted best, where it is not the paper's.
    assert "proprioceptive loop" not in motion_words(True, "disturbance and target")
    assert "outside the proprioceptive loop" in motion_words(True, "disturbance and target", "multimodal")


def test_disturbance_only_baseline_is_undetermined_not_denied(tmp_path):
    run, plants = _run(tmp_path, "disturbance")
    d = diagnose(run, plants, candidates=("motion_feedback",))
    mv = d.motion_verdict
    assert mv["forcing"] == "disturbance only" and mv["separable"] is False
    assert not mv["named"] and mv["verdict"].startswith("cannot tell"), mv
    assert mv["verdict"] in format_report(d)


def test_every_run_diagnosed_counts_the_runs_that_cannot_tell(tmp_path):
    from hesspipe.diagnose import diagnose_each

    one, plants = _run(tmp_path, "disturbance")
    both, _ = _run(tmp_path, "both")
    each = diagnose_each([one, both], plants, candidates=("motion_feedback",))
    verdicts = [d.motion_verdict for d in each.diagnoses]
    assert [v["separable"] for v in verdicts] == [False, True] and not any(v["named"] for v in verdicts)
    lines = each.lines()
    assert lines[0 if not each.synthetic else 1].endswith("; cannot tell: one forcing function)")
    assert "cannot tell" not in lines[-2]
    assert each.summary().endswith("; motion cannot be told on 1 of 2 runs (one forcing function)")
