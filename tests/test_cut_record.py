"""A run cut short (a logger crash, an aborted trial) says what it could not test (SYNTHETIC).

A yaw-angle trial of the independent generator (:mod:`hesspipe.humanlike`, sparse
line layout, 81.92 s period at 50 Hz) cut to 37 % of one period: few of its lines fall on
the short record's bins. Before, ``frf`` gave a crossover from two lines without a word and
``diagnose`` named only the remnant, with no line about motion.
"""

from __future__ import annotations

import pytest

from hesspipe.core.formats import Run, read_plants, read_run
from hesspipe.diagnose.each import RunDiagnoses
from hesspipe.diagnose.report import format_report
from hesspipe.diagnose.workflow import diagnose
from hesspipe.humanlike import draw_trial, simulate_trial, write_trial
from hesspipe.humanlike.forcing import SPARSE_LAYOUT
from hesspipe.identification import estimate_frf


@pytest.fixture(scope="module")
def cut(tmp_path_factory):
    folder = tmp_path_factory.mktemp("cut")
    spec = draw_trial("1/s", 1, task="both", pilot="hess", effects=("motion_feedback",), output="angle",
                      style="plain", name="pilot", **{**SPARSE_LAYOUT, "fs": 50.0})
    run = read_run(write_trial(folder, simulate_trial(spec)))
    n = int(0.37 * 81.92 / run.dt)
    short = Run(time=run.time[:n], disturbance=run.disturbance[:n], output=run.output[:n],
                control=run.control[:n], reference=run.reference[:n], id="cut", synthetic=True)
    return short, read_plants(folder / "plants.json")


def test_frf_says_its_crossover_rests_on_few_lines(cut):
    run, plants = cut
    frf = estimate_frf(run, plants)
    assert frf.feedback.freq_rad_s.size < 4
    # (Which part of a record without a whole period is analysed is arbitrary; the note is not,
    # and it never claims whole periods.)
    assert not any("whole periods" in n for n in frf.notes), frf.notes
    assert any(n.startswith("only ") and " forcing line(s) found in " in n and
               "shorter than one period" in n for n in frf.notes), frf.notes


def test_diagnose_says_the_describing_function_was_not_tested(cut):
    run, plants = cut
    d = diagnose(run, plants, seed=1)
    assert d.motion_verdict is None and d.untested.startswith("2 multisine forcing lines found (need 4)")
    assert d.to_dict()["describing_function_untested"] == d.untested
    assert "Note: motion feedback, extra delay and remnant not tested on the describing function: 2 " \
           "multisine forcing lines found" in format_report(d)
    each = RunDiagnoses((d,), ())
    assert f"cut: {', '.join(d.named_effects) or 'nothing'} named (motion not tested: {d.untested})" in each.lines()
    assert "motion not tested on 1 of 1 runs (too few forcing lines)" in each.summary()


def test_a_broadband_record_says_why_there_is_no_describing_function():
    # SYNTHETIC (the pilot model's own run): a random wind, as the JSBSim pipeline's cohort
    # flies, has no lines at all; the note must not blame a record cut short.
    import numpy as np

    from hesspipe.core.formats import Plants
    from hesspipe.pilot import synthetic_run

    plants = Plants(([2.0], [1.0, 1.0]), ([1.0], [1.0, 1.0]))
    wind = np.random.default_rng(4).standard_normal(3000)
    run = synthetic_run("original", None, plants, wind, 0.02, seed=1)
    d = diagnose(run, plants, seed=1, candidates="motion_feedback")
    assert d.untested.startswith("0 multisine forcing lines found") and "(a broadband forcing" in d.untested
    assert "shorter than one period" not in d.untested
