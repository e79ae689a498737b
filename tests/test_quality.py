"""A record's own faults are noted on read (:mod:`hesspipe.core._quality`; SYNTHETIC data).

Runs of the independent generator (:mod:`hesspipe.humanlike`) written with a lab's faults:
a clipped stick, single-sample spikes, a logger that froze, a stick held still. A newcomer
review found the first two named as aircraft-side effects (a rate limit, a Dutch roll) with
nothing said; clean runs and a quantised stick must stay without a note.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from hesspipe.core.formats import read_plants, read_run, write_run
from hesspipe.diagnose.each import diagnose_each
from hesspipe.humanlike import draw_trial, simulate_trial, write_trial


@pytest.fixture(scope="module")
def trial(tmp_path_factory):
    folder = tmp_path_factory.mktemp("q")
    spec = draw_trial("1/s", 3, task="both", pilot="precision", effects=("motion_feedback",),
                      output="angle", tau_m=0.15, fs=100.0, T_m=40.96)
    return read_run(write_trial(folder, simulate_trial(spec, fine_ratio=2))), read_plants(folder / "plants.json")


def _checks(tmp_path, run, name="r.csv"):
    return [n for n in read_run(write_run(tmp_path / name, run)).notes if n.startswith("data check")]


@pytest.mark.parametrize("plant,task,fs", [("1/s", "both", 100.0), ("paper", "disturbance", 50.0),
                                           ("K/s2", "both", 50.0)])
def test_clean_runs_have_no_data_check(tmp_path, plant, task, fs):
    kw = dict(disturbance="wind") if plant == "paper" else {}
    spec = draw_trial(plant, 5, task=task, pilot="hess", fs=fs, T_m=40.96, **kw)
    run = read_run(write_trial(tmp_path, simulate_trial(spec, fine_ratio=2)))
    assert not [n for n in run.notes if n.startswith("data check")], run.notes


def test_a_quantised_stick_has_no_data_check(tmp_path, trial):
    run, _ = trial
    code = 2.4 * np.max(np.abs(run.control)) / 2 ** 8     # an 8-bit converter over +-1.2 x the range
    assert _checks(tmp_path, replace(run, control=code * np.round(run.control / code))) == []


def test_a_clipped_stick_is_noted_with_its_ends_and_share(tmp_path, trial):
    run, _ = trial
    top = 0.5 * np.max(np.abs(run.control))
    (note,) = _checks(tmp_path, replace(run, control=np.clip(run.control, -top, top)))
    assert "column 'control' (control) sits at its maximum and its minimum value on" in note
    assert "clipped" in note and "a rate limit, a Dutch roll" in note
    share = float(note.split(" on ")[1].split(" %")[0]) / 100
    assert share == pytest.approx(np.mean(np.abs(run.control) >= top), abs=0.002)


def test_spikes_a_frozen_logger_and_a_held_stick_are_noted(tmp_path, trial):
    run, _ = trial
    u = run.control.copy()
    u[[500, 1300, 2100, 2900, 3700]] += 5 * np.std(u)            # single-sample glitches
    (note,) = _checks(tmp_path, replace(run, control=u), "s.csv")
    assert "has 5 single-sample spike(s)" in note
    frozen = {k: getattr(run, k).copy() for k in ("disturbance", "output", "control", "reference")}
    for v in frozen.values():
        v[1000:1200] = v[999]                                     # every channel held 2 s
    notes = _checks(tmp_path, replace(run, **frozen), "f.csv")
    assert any("every column holds its value for 201 samples (2.01 s) from 9.99 s into the record" in n for n in notes), notes
    assert not any("holds one value" in n for n in notes)        # said once, not per column
    held = run.control.copy()
    held[2000:2250] = held[1999]                                  # the stick alone, 2.5 s
    (note,) = _checks(tmp_path, replace(run, control=held), "h.csv")
    assert "column 'control' (control) holds one value for 2.51 s inside the record" in note


def test_a_stick_let_go_is_noted_where_it_rests_for_two_seconds(tmp_path, trial):
    # Let go, a centring spring holds the stick at rest but for its sensor's noise: no value
    # repeats, so the held-value check cannot see it (a review's "passes without a note").
    run, _ = trial
    rng = np.random.default_rng(1)
    notes = {}
    for rest_s in (1.5, 3.0):
        u = run.control.copy()
        n = int(rest_s / run.dt)
        u[1500:1500 + n] = 0.002 * np.std(u) * rng.standard_normal(n)
        notes[rest_s] = _checks(tmp_path, replace(run, control=u), f"go{rest_s}.csv")
    assert notes[1.5] == []
    (note,) = notes[3.0]
    assert "column 'control' (control) barely moves for" in note and "the stick let go?" in note
    span, start = float(note.split("for ")[1].split(" s")[0]), float(note.split("from ")[1].split(" s")[0])
    assert span == pytest.approx(3.0, abs=0.3) and start == pytest.approx(1500 * run.dt, abs=0.3)


def test_a_loop_that_went_unstable_is_noted(tmp_path, trial):
    # A review's run grew to 480,000 deg of yaw and settled again: analysed without a word
    # (named "remnant", and Km/|Ke| of its person moved by a third).
    run, _ = trial
    t = run.time - run.time[0]
    grow = 1.0 + 99.0 * np.exp(-0.5 * ((t - 20.0) / 3.0) ** 2)   # x100 around 20 s
    (note,) = _checks(tmp_path, replace(run, output=run.output * grow, control=run.control * grow), "u.csv")
    assert "column 'output' (output) swings" in note and "the loop went unstable" in note
    ratio, at = float(note.split("swings ")[1].split(" times")[0]), float(note.split("from ")[1].split(" s")[0])
    assert ratio > 100 and 15.0 <= at <= 20.0
    grown = 1.0 + 4.0 * np.exp(-0.5 * ((t - 20.0) / 3.0) ** 2)     # x5: a hard stretch, no note
    assert _checks(tmp_path, replace(run, output=run.output * grown, control=run.control * grown), "g.csv") == []
    # Calm is no smaller swing of a stable loop: a square-wave target the output follows, with
    # rests between its steps (a review: "unstable" at 88 times), and a stick let go for 8 s.
    square = np.where(np.sin(2 * np.pi * t / 30.0) >= 0, 1.0, -1.0) * 5 * np.std(run.output)
    settled = square + 0.05 * (run.output - np.mean(run.output))
    assert not [n for n in _checks(tmp_path, replace(run, reference=square, output=settled), "sq.csv")
                if "unstable" in n]
    u = run.control.copy()
    u[1000:1800] = 0.002 * np.std(u) * np.random.default_rng(2).standard_normal(800)
    notes = _checks(tmp_path, replace(run, control=u), "go8.csv")
    assert [n for n in notes if "let go" in n] and not [n for n in notes if "unstable" in n]


def test_valid_records_a_second_review_found_noted_are_not(tmp_path, trial):
    # A record that starts at rest, a subject holding still 1.2 s, a step target, a target
    # written to whole units: each was told its data was broken (a review of this check).
    run, _ = trial
    rest = {k: getattr(run, k).copy() for k in ("disturbance", "output", "control", "reference")}
    for v in rest.values():
        v[:200] = 0.0                                             # 2 s at rest before the forcing
    assert _checks(tmp_path, replace(run, **rest), "rest.csv") == []
    still = run.control.copy()
    still[2000:2120] = still[1999]                                # 1.2 s held still
    assert _checks(tmp_path, replace(run, control=still), "still.csv") == []
    step = np.where(np.sin(2 * np.pi * run.time / 8.0) >= 0, 1.0, -1.0) * np.max(np.abs(run.reference))
    assert _checks(tmp_path, replace(run, reference=step), "step.csv") == []
    unit = np.max(np.abs(run.reference)) / 60                     # the target to 1/60 of its range
    assert _checks(tmp_path, replace(run, reference=unit * np.round(run.reference / unit)), "int.csv") == []


def test_diagnose_carries_the_data_check_into_its_report_and_run_line(tmp_path, trial):
    run, plants = trial
    top = 0.5 * np.max(np.abs(run.control))
    clipped = read_run(write_run(tmp_path / "c.csv", replace(run, control=np.clip(run.control, -top, top))))
    each = diagnose_each([clipped], plants, seed=1)
    assert any(n.startswith("data check") and "clipped" in n for n in each.diagnoses[0].notes)
    assert each.lines()[-2].endswith("data check: clipped]") and "data check noted on 1 of 1 runs" in each.summary()
