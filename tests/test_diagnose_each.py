"""Every run on its own (:mod:`hesspipe.diagnose.each`, ``hesspipe diagnose --each``): the
per-run diagnoses a motion / no-motion check counts. The runs are SYNTHETIC (hesspipe's own
simulator, :mod:`hesspipe.diagnose.examples`): what is tested is the bookkeeping, each run's
diagnosis being the one ``diagnose`` gives it alone."""

from __future__ import annotations

import dataclasses
import json

import pytest

from hesspipe.cli import main
from hesspipe.core.errors import HesspipeError
from hesspipe.core.formats import write_plants, write_run
from hesspipe.core.io import to_json
from hesspipe.diagnose import diagnose, diagnose_each
from hesspipe.diagnose.examples import hidden_effect_run, validation_plants


@pytest.fixture(scope="module")
def runs():
    plants = validation_plants()
    return plants, [hidden_effect_run(plants, effect, seed=seed, duration=30.0)
                    for effect, seed in ((None, 3), ("remnant", 4))]


@pytest.fixture(scope="module")
def each_seed_5(runs):
    # Computed once: 2 tests compare against it (diagnose alone, worker processes), each
    # computing its own side afresh.
    plants, rs = runs
    return diagnose_each(rs, plants, seed=5)


def test_each_run_is_diagnosed_as_alone_and_the_names_are_tallied(runs, each_seed_5):
    plants, rs = runs
    each = each_seed_5
    alone = [diagnose(r, plants, seed=5) for r in rs]
    assert [to_json(d.to_dict()) for d in each.diagnoses] == [to_json(d.to_dict()) for d in alone]
    names = [n for d in alone for n in d.named_effects]
    assert each.tally() == {n: names.count(n) for n in sorted(set(names), key=lambda n: (-names.count(n), n))}
    assert each.synthetic and each.lines()[0].startswith("*** SYNTHETIC DATA")
    assert each.lines()[-1] == f"SUMMARY: {each.summary()}"
    with pytest.raises(HesspipeError, match="each run is diagnosed alone"):
        diagnose_each(rs, plants, repeat_runs=rs[1:])


def test_the_command_diagnoses_a_folder_run_by_run(runs, tmp_path, capsys):
    plants, rs = runs
    folder = tmp_path / "static"
    for r in rs:
        write_run(folder / f"{r.id}_{id(r) % 1000}.csv", r)
    (folder / "z_cut.csv").write_text("time,disturbance,output\n0,0,0\n")
    write_plants(tmp_path / "p.json", plants)
    code = main(["diagnose", str(folder), "--each", "--plants", str(tmp_path / "p.json"),
                 "--json", str(tmp_path / "each.json")])
    out, err = capsys.readouterr()
    assert code == 1   # a file it could not read
    assert f"hesspipe: error: {folder / 'z_cut.csv'}: column 'control' missing" in err
    report = json.loads((tmp_path / "each.json").read_text())
    assert report["runs"] == 2 and report["failures"][0]["source"] == str(folder / "z_cut.csv")
    assert report["hesspipe_version"] and report["seed"] == 0 and report["plants"].endswith(".json")
    assert report["named"] == diagnose_each(rs, plants).tally()
    assert f"SUMMARY: {report['summary']}" in out and out.count(" named") >= 2
    assert main(["diagnose", str(folder), "--each", "--plants", str(tmp_path / "p.json"),
                 "--figure", str(tmp_path / "x.png")]) == 1
    assert "--figure: not with --each" in capsys.readouterr().err
    assert main(["diagnose", str(folder), "--each", "--plants", str(tmp_path / "p.json"), "--workers", "-1"]) == 1
    assert "--workers: expected an integer >= 0 (0: all cores), got -1" in capsys.readouterr().err
    assert main(["diagnose", str(folder / "z_cut.csv"), "--plants", str(tmp_path / "p.json"), "--workers", "2"]) == 1
    assert "--workers: only with --each" in capsys.readouterr().err


def test_two_folders_are_tallied_apart_as_well_as_together(runs, tmp_path, capsys):
    # `diagnose motion/ static/ --each`: the README's use; one pooled tally mixed the conditions
    plants, rs = runs
    for r, name in zip(rs, ("a", "b")):
        write_run(tmp_path / name / f"{name}_r1.csv", r)
    write_plants(tmp_path / "p.json", plants)
    assert main(["diagnose", str(tmp_path / "a"), str(tmp_path / "b"), "--each", "--workers", "1",
                 "--plants", str(tmp_path / "p.json"), "--json", str(tmp_path / "each.json")]) == 0
    out = capsys.readouterr().out
    report = json.loads((tmp_path / "each.json").read_text())
    assert report["runs"] == 2 and set(report["by_input"]) == {str(tmp_path / "a"), str(tmp_path / "b")}
    for r, name in zip(rs, ("a", "b")):
        alone = diagnose_each([r], plants)
        apart = report["by_input"][str(tmp_path / name)]
        assert apart["runs"] == 1 and apart["named"] == alone.tally()
        assert f"SUMMARY of {tmp_path / name}: {alone.summary()}" in out
    # Files listed one by one (a shell's glob) are not conditions: no "1 of 1" tally per file.
    assert main(["diagnose", str(tmp_path / "a" / "a_r1.csv"), str(tmp_path / "b" / "b_r1.csv"), "--each",
                 "--workers", "1", "--plants", str(tmp_path / "p.json")]) == 0
    out = capsys.readouterr().out
    assert "SUMMARY: " in out and "SUMMARY of" not in out


def test_runs_diagnosed_in_worker_processes_are_the_same(runs, each_seed_5):
    from hesspipe.pilots.batch import run_batch

    plants, rs = runs
    one = each_seed_5   # in this process
    two = diagnose_each(rs, plants, seed=5, mapper=lambda f, items: run_batch(f, items, workers=2))
    assert [to_json(d.to_dict()) for d in two.diagnoses] == [to_json(d.to_dict()) for d in one.diagnoses]
    assert two.tally() == one.tally()


def test_a_failed_plant_check_and_a_flagged_motion_path_show_on_the_run_line(runs):
    # A reviewer's --each lines said only the names; the failed plant check and the
    # CHECK motion_path line were in the single-run report and the JSON alone.
    plants, rs = runs
    each = diagnose_each(rs[:1], plants, seed=5)
    d = each.diagnoses[0]
    assert not any("[" in line for line in each.lines()[1:-1])          # nothing to flag
    failing = dataclasses.replace(
        d, plant_finding={"verdict": "unexplained", "fit_percent": -159.0, "named": None},
        motion_verdict={**(d.motion_verdict or {}), "path_check": {"named": ["negated"], "p_values": {}}})
    flagged = dataclasses.replace(each, diagnoses=[failing, d])
    line = flagged.lines()[1]
    assert line.endswith("[plant check fails: fit -159.0 %; CHECK motion_path: motion is named with it negated]")
    assert "plant check failed on 1 of 2 runs; CHECK motion_path flagged on 1 of 2 runs (a flag may be the " \
           "model's misfit, not a wrong path, and on a run whose cab did not move it is" in flagged.summary()


def test_runs_the_unstated_display_kept_unnamed_are_counted_and_said(each_seed_5):
    # With the display not stated a run is named only if the tests with and without a pursuit
    # display's feedforward both name it; a run the compensatory test alone names is left
    # unnamed, and only its own report said so. The tally says it too.
    d = each_seed_5.diagnoses[0]
    mv = {**(d.motion_verdict or {}), "named": False, "alpha": 0.01, "p_value": 0.13}
    decided = dataclasses.replace(d, motion_verdict={**mv, "display_p": {"compensatory": 0.004, "pursuit": 0.13}})
    neither = dataclasses.replace(d, motion_verdict={**mv, "display_p": {"compensatory": 0.02, "pursuit": 0.13}})
    stated = dataclasses.replace(d, motion_verdict={**mv, "display_p": None})
    each = dataclasses.replace(each_seed_5, diagnoses=[decided, neither, stated])
    lines = each.lines()
    assert "(motion test p = 0.13; the compensatory test alone p = 0.004)" in lines[-4]
    assert "compensatory test alone" not in lines[-3] + lines[-2]
    assert ("; the display decided on 1 of 3 runs (the compensatory test alone names motion there, the test "
            "with a pursuit display's feedforward does not: where the display is known, state it)") in each.summary()
    # Named runs, and runs the compensatory test did not name, are not counted.
    named = dataclasses.replace(d, motion_verdict={**decided.motion_verdict, "named": True})
    assert "the display decided" not in dataclasses.replace(each_seed_5, diagnoses=[named, neither]).summary()
    assert "the display decided" not in each_seed_5.summary()
