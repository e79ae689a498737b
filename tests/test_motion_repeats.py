"""The motion test on repeated runs of one condition (SYNTHETIC: hesspipe.humanlike trials).

With the disturbance alone there is one describing function, and the vestibular path
shows only in its shape: one record often cannot tell. Repeats of the condition (the same
pilot with the generator's run-to-run scatter, its own remnant and forcing phases) are
pooled line by line, each run with its own gain. The runs are drawn and simulated by the
independent generator and read back from the files it writes.
"""

from __future__ import annotations

import json

from hesspipe.cli import main
from hesspipe.identification.criteria import choose_k
from hesspipe.identification.motion_test import motion_test
from hesspipe.pilot.hess import PilotModel
from humanlike_trials import repeated_trials


def _repeats(folder, effect, seed, n=3):
    """n runs of one Hess pilot on the paper's plants, roll rate, disturbance only
    (tests/humanlike_trials.py)."""
    runs, _, plants, _ = repeated_trials(folder, "paper", "rate", "disturbance", effect, seed, n)
    return runs, plants


def test_repeats_name_a_motion_feedback_that_one_run_cannot_tell(tmp_path, capsys):
    # Development seed 101: alone the run's test has p = 0.22; pooled with two repeats
    # p ~ 1e-4.
    runs, plants = _repeats(tmp_path, "motion_feedback", 101)
    k = choose_k(plants)[0]
    start = PilotModel().defaults(k=k)
    one, pooled = motion_test(runs[0], plants, start, k=k), motion_test(runs, plants, start, k=k)
    assert one["p_value"] > 0.05
    assert pooled["p_value"] < 0.001 and pooled["n_lines"] == 3 * one["n_lines"]
    out = tmp_path / "d.json"
    assert main(["diagnose", *(str(r.source) for r in runs), "--plants", str(tmp_path / "run" / "plants.json"),
                 "--candidates", "motion_feedback", "--json", str(out)]) == 0
    assert "lines of 3 runs, each its own gain" in capsys.readouterr().out
    d = json.loads(out.read_text())
    assert d["named_effects"][0] == "motion_feedback" and d["motion_verdict"]["runs"] == 3


def test_repeats_without_motion_name_none(tmp_path):
    runs, plants = _repeats(tmp_path, "none", 100)
    k = choose_k(plants)[0]
    pooled = motion_test(runs, plants, PilotModel().defaults(k=k), k=k)
    assert pooled["p_value"] > 0.05
    # Each later run's gain is a parameter of both fits: the test's degrees of freedom
    # count them.
    single = motion_test(runs[0], plants, PilotModel().defaults(k=k), k=k)
    assert pooled["degrees_of_freedom"] == 2 * pooled["n_lines"] - (2 * single["n_lines"]
                                                                    - single["degrees_of_freedom"]) - 2
