"""A run whose column signs or units are at odds with its plants is refused before a fit
(SYNTHETIC: independent generator trials, read back from the files its logger writes).

A sign-flipped control had compare-pilots fit Ke on its lower bound and say "yes" to motion
for two pilots; nothing warned.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from hesspipe.cli import main
from hesspipe.core.errors import HesspipeError
from hesspipe.core.formats import read_plants, read_run, write_run
from hesspipe.core.seeds import derive_seed
from hesspipe.humanlike import draw_trial, simulate_trial, write_trial
from hesspipe.identification.fit import identify
from hesspipe.plants.consistency import check_consistent, consistency

CASES = [("roll", "rate", "both", ()), ("paper", "angle", "disturbance", ("motion_feedback",)),
         ("K/s2", "angle", "both", ())]


def _trial(folder, plant, output, task, effects, seed=0):
    pilot = "precision" if plant.startswith(("1/s", "K/s")) else "hess"
    spec = draw_trial(plant, derive_seed(seed, "cons", plant, output, task, ",".join(effects)), task=task,
                      pilot=pilot, effects=effects, output=output, name="t")
    run = read_run(write_trial(folder, simulate_trial(spec)))
    return run, read_plants(folder / "plants.json")


@pytest.mark.parametrize("plant, output, task, effects", CASES)
def test_as_written_passes_and_mistakes_are_named(tmp_path, plant, output, task, effects):
    run, plants = _trial(tmp_path, plant, output, task, effects)
    c = check_consistent(run, plants)
    assert c.unexplained < 0.05 and c.problem() is None
    for column, words in (("control", "control's sign is opposite"),
                          ("disturbance", "disturbance's sign is opposite"),
                          ("output", "output's sign is opposite")):
        bad = replace(run, **{column: -getattr(run, column)})
        with pytest.raises(HesspipeError, match=f"{words}.*map it with columns {column}=-NAME"):
            check_consistent(bad, plants)
    degrees = replace(run, output=np.degrees(run.output))
    with pytest.raises(HesspipeError, match=r"output is 5\d\.\d times .*degrees against radians"):
        check_consistent(degrees, plants)


@pytest.mark.parametrize("plant, output, task, effects", CASES)
def test_one_column_in_another_unit_is_named(tmp_path, plant, output, task, effects):
    # A stick logged in per cent where the plants take degrees, or one input left in degrees
    # beside radians: the joint factor of both predictions stays near 1 or explains nothing,
    # so only each path's own factor shows it.
    run, plants = _trial(tmp_path, plant, output, task, effects)
    for column, factor, words in (("control", 0.1 * 180 / np.pi, r"control's units differ .* times 0\.1[6-8]"),
                                  ("control", np.pi / 180, r"control times 5\d\.\d \(degrees against radians"),
                                  ("disturbance", 180 / np.pi, r"disturbance times 0\.017.*radians against degrees")):
        bad = replace(run, **{column: getattr(run, column) * factor})
        with pytest.raises(HesspipeError, match=words):
            check_consistent(bad, plants)


def test_a_column_of_zeros_has_no_scale_to_judge(tmp_path):
    run, plants = _trial(tmp_path, "1/s", "angle", "tracking", ())
    c = check_consistent(replace(run, disturbance=np.zeros(len(run))), plants)
    assert np.isnan(c.path_scales[1]) and abs(c.path_scales[0] - 1) < 0.05


def test_plants_that_miss_dynamics_are_not_a_file_mistake(tmp_path):
    # A Dutch roll behind rolling-approximation plants: the plants explain little, but no
    # sign or scale would make them; diagnose's finding, not the reader's.
    for seed in range(3):
        for task in ("both", "disturbance"):
            run, plants = _trial(tmp_path / f"{seed}{task}", "roll", "rate", task, ("dutch_roll",), seed=seed)
            c = consistency(run, plants)
            assert c.problem() is None, (seed, task, c)
    assert c.unexplained > 0.5


def test_identify_and_pilots_refuse_a_flipped_stick_and_read_it_mapped(tmp_path, capsys):
    run, plants = _trial(tmp_path / "g", "roll", "rate", "both", ("motion_feedback",))
    folder = tmp_path / "runs"
    folder.mkdir()
    write_run(folder / "p1.csv", replace(run, control=-run.control))
    with pytest.raises(HesspipeError, match="p1.csv: the control's sign is opposite"):
        identify(read_run(folder / "p1.csv"), plants, criterion="df", with_benchmark=False,
                 with_identifiability=False)
    pj = str(tmp_path / "g" / "plants.json")
    assert main(["pilots", str(folder), "--plants", pj, "--passes", "2", "--restarts", "1"]) == 1
    err = capsys.readouterr().err
    assert "map it with --columns control=-NAME" in err
    assert main(["pilots", str(folder), "--plants", pj, "--passes", "2", "--restarts", "1",
                 "--columns", "control=-control"]) == 0
    out = capsys.readouterr()
    assert "sign flipped, as mapped" in out.err and "MOTION VERDICT: yes" in out.out
