"""Diagnose's baseline search on runs where the describing function's dynamics do not
close the loop (SYNTHETIC: hesspipe.humanlike trials, as benchmarks/bench_diagnose.py
draws them).

A double-integrator angle task with a hidden motion feedback and the disturbance alone:
the original model fitted to the motion pilot's lines lands on a ~3 rad/s neuromuscular
mode, and with those dynamics no Ke, K1 closes the loop. Diagnose used to refuse these
runs ("no stable original pilot found"); the defaults with Hess's rule's order close it.
"""

from __future__ import annotations

import pytest

from hesspipe.diagnose.workflow import diagnose
from humanlike_trials import bench_diagnose_trial

PILOT_SIDE = {"motion_feedback", "otoliths", "extra_delay"}


@pytest.mark.slow
@pytest.mark.parametrize("seed", [2, 7])
def test_a_double_integrator_motion_run_is_diagnosed_not_refused(tmp_path, seed):
    run, plants = bench_diagnose_trial(tmp_path, "K/s2", "angle", "disturbance", "motion_feedback", seed)
    d = diagnose(run, plants, seed=seed)
    assert d.plant_finding["verdict"] == "match"
    # Whatever is named, it is not a pilot-side effect the run does not carry.
    assert set(d.named_effects) & PILOT_SIDE <= {"motion_feedback"}
    # The named remnant leaves the fitted spectrum as it was on seed 2 (log-spectral RMS 3.811 dB
    # before and after), and where the fit stops moves the Eq. 10 gap by 0.1 % either way
    # (-0.09 % with one restart of 20 evaluations, +0.14 % with three of 40): not rising by
    # more than 1 % is what the named effects must show here.
    assert d.gap_after <= 1.01 * d.gap_before
