"""Motion feedback on an ANGLE task with a target (SYNTHETIC data of the independent generator).

The stand-in for real yaw-tracking trials: the display shows the angle, the cab turns at
its rate (plants ``motion_path`` s/(0.01 s + 1)), target and disturbance on interleaved
multisines, disturbance at the plant input. Drawn and simulated by
:mod:`hesspipe.humanlike` (fine-step block simulation, no hesspipe model code).
"""

from __future__ import annotations

import numpy as np
import pytest

from hesspipe.core.formats import read_plants, read_run
from hesspipe.diagnose.workflow import diagnose
from hesspipe.humanlike import draw_trial, simulate_trial, write_trial
from hesspipe.humanlike.plants import ANGLE_MOTION


def _trial(tmp_path, effects, seed=7):
    # km_ratio 1.0: the strongest vestibular path of the generator's range (a share of the
    # visual path at crossover as on a rate display). This is one well-identified trial, a
    # regression check, not a rate: on the benchmark's report seeds only 2 of 10 such roll
    # angle+target runs are named (benchmarks/bench_diagnose.py --km-ratio 1.0,1.0): the
    # canal path on the cab's rate acts on the target lines like the proprioceptive
    # feedback, only the disturbance lines tell them apart.
    spec = draw_trial("roll", seed, task="both", pilot="hess", effects=effects, output="angle",
                      fs=50.0, T_m=70.0, style="plain", name="pilot", km_ratio=1.0)
    path = write_trial(tmp_path, simulate_trial(spec))
    return spec, read_run(path), read_plants(tmp_path / "plants.json")


@pytest.fixture(scope="module")
def twins(tmp_path_factory):
    return (_trial(tmp_path_factory.mktemp("motion"), ("motion_feedback",)),
            _trial(tmp_path_factory.mktemp("static"), ()))


def test_angle_plants_carry_the_cab_rate_path(twins):
    (spec, _, plants), (_, _, plants0) = twins
    assert spec.pilot["Km"] > 0
    for p in (plants, plants0):    # one plants file for both conditions, as a researcher writes it
        assert np.allclose(p.motion_path.num[0][0], ANGLE_MOTION[0])
        assert np.allclose(p.motion_path.den[0][0], ANGLE_MOTION[1])


def test_angle_target_motion_trial_is_named_motion(twins):
    (_, run, plants), _ = twins
    d = diagnose(run, plants, seed=1)
    assert d.motion_verdict is not None and d.motion_verdict["n_lines"] >= 16  # both line sets
    assert "motion_feedback" in d.named_effects, d.motion_verdict


def test_angle_target_static_twin_is_not_named_motion(twins):
    _, (_, run, plants) = twins
    d = diagnose(run, plants, seed=1)
    assert d.motion_verdict is not None
    assert "motion_feedback" not in d.named_effects, d.motion_verdict


def test_interleaved_lines_all_found_when_disturbance_dominates(tmp_path):
    """Target lines one bin above the disturbance's and ~7x weaker (the paper plant's wind):
    the whole record is the analysis window and all 20 lines are found (the purity of the
    sum had picked half records with 2-8 lines)."""
    from hesspipe.identification.motion_test import analysis_window, forcing_lines

    spec = draw_trial("paper", 3, task="both", pilot="hess", output="rate", disturbance="wind",
                      fs=50.0, T_m=70.0, style="plain", name="w")
    run = read_run(write_trial(tmp_path, simulate_trial(spec)))
    start, length = analysis_window(run)
    assert (start, length) == (0, len(run.control))
    assert forcing_lines(run).size == 20


def test_a_bare_differentiator_is_a_valid_angle_motion_path(twins, tmp_path):
    """``"motion_path": {"num": [1, 0], "den": [1]}`` (the cab's rate is s times the angle) is
    what a researcher writes for an angle display: read, not refused, and it gives the
    diagnosis of the proper form s/(0.01 s + 1) on this record."""
    import json

    (_, run, plants), _ = twins
    obj = {"control_to_output": {"num": list(plants.control_to_output.num[0][0]),
                                 "den": list(plants.control_to_output.den[0][0])},
           "disturbance_to_output": {"num": list(plants.disturbance_to_output.num[0][0]),
                                     "den": list(plants.disturbance_to_output.den[0][0])},
           "motion_path": {"num": [1, 0], "den": [1]}}
    path = tmp_path / "bare.json"
    path.write_text(json.dumps(obj, default=float))
    bare = read_plants(path)
    assert np.allclose(bare.motion_path.num[0][0], [1.0, 0.0])
    d = diagnose(run, bare, seed=1)
    assert "motion_feedback" in d.named_effects, d.motion_verdict


def test_expanded_fit_is_not_trapped_in_the_original_models_corner(tmp_path):
    # bench_diagnose's roll angle + target motion trial, development seed 101: started only
    # from the original model's optimum, the expanded fit stayed in that optimum's valley
    # (RSS 60.1 against the original's 68.4, p = 0.27); started from the given start too,
    # it finds the vestibular valley (17.8, p ~ 3e-11). (Paper angle seed 102 was such a
    # corner as well: K1 on its bound, no delay, a 4 rad/s mode.)
    from hesspipe.identification.motion_test import motion_test
    from hesspipe.pilot.hess import PilotModel
    from humanlike_trials import bench_diagnose_trial

    run, plants = bench_diagnose_trial(tmp_path, "roll", "angle", "both", "motion_feedback", 101)
    t = motion_test(run, plants, PilotModel().defaults(k=2), k=2)
    assert t["p_value"] < 0.01 and t["rss_expanded"] < 0.5 * t["rss_original"], t["p_value"]


@pytest.mark.parametrize("effects", [("motion_feedback",), ()])
def test_sparse_two_input_layout_with_a_wandering_gain(tmp_path, effects):
    # Real yaw trials as the stand-in draws them on a layout unlike the generator's default:
    # 81.92 s at 100 Hz, target lines 1-23 bins from the disturbance's (SPARSE_LAYOUT),
    # a precision pilot with a vestibular delay whose visual gain wanders (CV 0.15), logged
    # with ms stamps, a BOM and CRLF. Motion is named only where the pilot has it (seed 101:
    # p ~ 2e-14 with, 0.69 without; benchmarks/bench_diagnose.py --layout sparse: 18/19 and
    # 0/20 over report seeds 0-9).
    from hesspipe.humanlike.forcing import SPARSE_LAYOUT
    from hesspipe.identification.lines import forcing_lines
    from hesspipe.identification.motion_test import motion_test
    from hesspipe.pilot.hess import PilotModel

    spec = draw_trial("K/s2", 101, task="both", pilot="precision", effects=effects, output="angle",
                      tau_m=0.15, gain_drift=0.15, name="s01", **SPARSE_LAYOUT,
                      style={"time": "ms", "bom": True, "newline": "\r\n", "epoch0": 1.7e9})
    path = write_trial(tmp_path, simulate_trial(spec))
    run, plants = read_run(path), read_plants(tmp_path / "plants.json")
    assert len(run.control) == 8192 and forcing_lines(run).size == 20
    t = motion_test(run, plants, PilotModel().defaults(k=2), k=2)
    assert t["significant"] == bool(effects), t["p_value"]
