"""Plants ``motion_path``: read, written, validated, and used by the pilot model.

The angle-task check runs on SYNTHETIC data from the independent generator
(:mod:`hesspipe.humanlike`), which shares no modelling code with the FFT pilot model.
"""

from __future__ import annotations

import dataclasses
import json

import control as ct
import numpy as np
import pytest

from hesspipe.cli import main
from hesspipe.core.errors import HesspipeError
from hesspipe.core.formats import Plants, read_plants, read_run, write_plants
from hesspipe.humanlike import draw_trial, simulate_trial, write_trial
from hesspipe.humanlike.truth import realised_pilot
from hesspipe.pilot.hess import table1
from hesspipe.pilot.motion import ANGLE_NO_WASHOUT, paper_motion_path
from hesspipe.pilot.simulation import simulate

ROLL = Plants(ct.tf([2.436], [1.0, 1.0496]), ct.tf([0.1], [1.0, 1.0496]))


def test_motion_path_roundtrip_and_absent(tmp_path):
    path = write_plants(tmp_path / "p.json", dataclasses.replace(ROLL, motion_path=ct.tf(*ANGLE_NO_WASHOUT)))
    obj = json.loads(path.read_text())
    assert obj["motion_path"] == {"num": [1.0, 0.0], "den": [0.01, 1.0]}
    back = read_plants(path)
    assert "motion_path" not in back.meta
    assert np.allclose(back.motion_path.num[0][0], [1.0, 0.0])
    assert read_plants(write_plants(tmp_path / "q.json", ROLL)).motion_path is None


@pytest.mark.parametrize("value, words", [
    ({"num": [1.0, 0.0, 0.0]}, "motion_path.den"),
    ({"num": [1.0, 0.0, 0.0], "den": [1.0]}, "not proper"),
    ([1, 2], "field 'motion_path'"),
    ({"num": [1.0], "den": [1.0, 1.0], "dt": 0.02}, "motion_path.dt"),
])
def test_bad_motion_path_is_one_line_naming_file_and_field(tmp_path, value, words):
    obj = {"control_to_output": {"num": [1.0], "den": [1.0, 0.0]},
           "disturbance_to_output": {"num": [1.0], "den": [1.0, 0.0]}, "motion_path": value}
    path = tmp_path / "plants.json"
    path.write_text(json.dumps(obj))
    with pytest.raises(HesspipeError) as err:
        read_plants(path)
    msg = str(err.value)
    assert "\n" not in msg and str(path) in msg and words in msg


def _wind(n=3000, seed=0):
    rng = np.random.default_rng(seed)
    return np.convolve(rng.standard_normal(n), np.ones(25) / 25, mode="same")


def test_paper_motion_path_reproduces_default_exactly():
    w = _wind()
    explicit = dataclasses.replace(ROLL, motion_path=paper_motion_path())
    for model, extra in (("expanded", {"Km": 2.0}), ("expanded+otoliths", {"Km": 2.0, "Ko": 1.0})):
        p = {**table1(1), **extra}
        a = simulate(model, p, ROLL, w, 0.02)
        b = simulate(model, p, explicit, w, 0.02)
        assert a.stable and b.stable
        assert np.max(np.abs(a.control - b.control)) <= 1e-9 * np.max(np.abs(a.control))
    # Without a vestibular effect the motion path changes nothing.
    a = simulate("original", table1(1), ROLL, w, 0.02)
    b = simulate("original", table1(1), dataclasses.replace(ROLL, motion_path=ct.tf(*ANGLE_NO_WASHOUT)),
                 w, 0.02)
    assert np.array_equal(a.control, b.control)


def test_another_motion_path_is_the_cab_behind_the_pilots_sensation():
    from hesspipe.pilot.effects import CANALS, OTOLITHS
    from hesspipe.pilot.hess import PilotModel
    from hesspipe.pilot.motion import motion_block, with_motion_path

    cab = ct.tf(*ANGLE_NO_WASHOUT)
    p = PilotModel(("motion_feedback", "otoliths")).complete({"Km": 3.0, "Ko": 0.5})
    loop = with_motion_path(PilotModel(("motion_feedback", "otoliths")).loop(p),
                            motion_block(dataclasses.replace(ROLL, motion_path=cab)))
    s = 1j * np.array([0.1, 1.0, 3.0, 20.0])
    expected = (3.0 * CANALS.response(s) + 0.5 * OTOLITHS.response(s) / s) * cab(s)
    assert np.allclose(loop.vestibular.response(s), expected, rtol=1e-12)
    # s / s cancelled in the otolith term: no marginal pole at the origin.
    assert all(t.den[-1] != 0.0 for t in loop.vestibular.terms)


def test_angle_task_motion_feedback_expressed_on_independent_data(tmp_path):
    """Roll-angle task, cab without washout (s/(0.01 s + 1)), hess pilot with motion feedback
    from the independent generator: the FFT model with the generator's true pilot reproduces
    the recorded control only when it reads the plants file's motion_path."""
    spec = draw_trial("roll", 5, task="disturbance", pilot="hess", effects=("motion_feedback",),
                      output="angle", T_m=30.0, fs=50.0, remnant_share=0.02,
                      # the strongest vestibular share of the range (Km/Ke per crossover
                      # frequency on an angle display since the generator's fix)
                      km_ratio=1.0,
                      tau=(0.12, 0.2), style="plain")
    path = write_trial(tmp_path, simulate_trial(spec))
    plants, run = read_plants(tmp_path / "plants.json"), read_run(path)
    assert np.allclose(plants.motion_path.num[0][0], [1.0, 0.0])
    q = realised_pilot(spec, 1.0 / (50.0 * spec.options["fine_ratio"]))
    par = {"Ke": q["Ke"] * spec.options["pilot_sign"], "K1": q["K1"], "K2": q["K2"],
           "1/T1": q["inv_T1"], "1/T2": q["inv_T2"], "k": q["k"], "tau0": q["tau"],
           "zn": q["zn"], "wn": q["wn"], "Km": q["Km"]}
    tail = slice(len(run.control) // 3, None)   # past the FFT model's zero-state start

    def misfit(pl):
        s = simulate("expanded", par, pl, run.disturbance, run.dt, reference=run.reference)
        if not s.stable:
            return np.inf
        return np.std(s.control[tail] - run.control[tail]) / np.std(run.control[tail])

    with_path = misfit(plants)
    without = misfit(dataclasses.replace(plants, motion_path=None))
    assert with_path < 0.3          # remnant share 2 % and the start transient remain
    assert without > 3 * with_path


def test_analytic_plants_write_the_paper_motion_path(tmp_path):
    out = tmp_path / "an"
    assert main(["plants", "--analytic", "roskam", "--out", str(out), "--no-figures"]) == 0
    mp = read_plants(out / "plants.json").motion_path
    ref = paper_motion_path()
    w = np.array([0.3, 1.0, 3.0, 10.0])
    assert np.allclose(mp(1j * w), ref(1j * w), rtol=1e-9)


def test_an_integrating_element_without_a_motion_path_gets_a_note(tmp_path, capsys):
    from hesspipe.cli._options import read_cli_plants
    from hesspipe.pilot.motion import motion_path_note

    yaw = Plants(ct.tf([1.5], [1.0, 0.0]), ct.tf([1.5], [1.0, 0.0]))
    note = motion_path_note(yaw)
    assert "no motion_path" in note and '"motion_path": {"num": [1, 0], "den": [0.01, 1]}' in note
    assert motion_path_note(dataclasses.replace(yaw, motion_path=ct.tf(*ANGLE_NO_WASHOUT))) is None
    assert motion_path_note(ROLL) is None                   # a rate output: the paper's default fits
    path = write_plants(tmp_path / "yaw.json", yaw)
    read_cli_plants(path)
    err = capsys.readouterr().err.splitlines()
    assert len(err) == 1 and err[0].startswith(f"hesspipe: note: {path}: no motion_path")
    read_cli_plants(write_plants(tmp_path / "roll.json", ROLL))
    assert capsys.readouterr().err == ""
    # The pilots' result keeps the note (and the motion path where given) for its record.
    from hesspipe.pilots.compare import plants_record

    assert plants_record(yaw)["motion_path_note"] == note and "motion_path" not in plants_record(yaw)
    kept = plants_record(dataclasses.replace(yaw, motion_path=ct.tf(*ANGLE_NO_WASHOUT)))
    assert kept["motion_path"] == {"num": [1.0, 0.0], "den": [0.01, 1.0]} and "motion_path_note" not in kept
