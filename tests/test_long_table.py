"""Runs one after another in one long table (:mod:`hesspipe.core._long`): rows keyed by the
columns mapped as ``person`` and ``run``, as shared datasets and statistics packages keep an
experiment. The runs are built here from known signals (SYNTHETIC)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from hesspipe.core.errors import HesspipeError
from hesspipe.core.formats import read_file_runs, read_run
from hesspipe.pilots.verdict import pilot_groups
from test_runs_in_file import signals

ROLES = ("time", "reference", "disturbance", "output", "control")
KEYED = "person=Subject,run=Trial,time=t,reference=ft,disturbance=fd,output=x,control=u"


def _long(path, keys, scale=1.0, sep=";", decimal=","):
    """A long table: per (person, trial) in `keys` the known signals scaled by the trial's
    number (and `scale`), the forcing unscaled, written row after row."""
    s = signals()
    lines = [f"# synthetic long table{sep}", sep.join(("Subject", "Trial", "t", "ft", "fd", "x", "u"))]
    for person, trial in keys:
        k = scale * float(trial)
        for row in zip(s["time"], s["reference"], s["disturbance"], k * s["output"], k * s["control"]):
            lines.append(sep.join([person, str(trial)] + [f"{v:.12g}".replace(".", decimal) for v in row]))
    path.write_text("\r\n".join(lines) + "\r\n", encoding="utf-8")
    return s


def test_a_long_tables_runs_are_read_by_their_keys(tmp_path):
    s = _long(tmp_path / "static.csv", [("s01", 1), ("s01", 2), ("s02", 1), ("s02", 2)])
    runs = read_file_runs(tmp_path / "static.csv", columns=KEYED)
    assert [(r.id, r.number, r.person, r.file_id) for r in runs] == [
        ("static#s01#1", 1, "s01", "s01"), ("static#s01#2", 2, "s01", "s01"),
        ("static#s02#1", 3, "s02", "s02"), ("static#s02#2", 4, "s02", "s02")]
    assert runs[3].source == f"{tmp_path / 'static.csv'}#s02#2" and runs[3].synthetic
    for run, k in zip(runs, (1, 2, 1, 2)):
        np.testing.assert_allclose(run.time, s["time"], atol=1e-12)
        np.testing.assert_allclose(run.control, k * s["control"], rtol=1e-10)
        np.testing.assert_allclose(run.reference, s["reference"], rtol=1e-10)
        assert run.notes[-1] == "4 run(s) in the file, one after another, told apart by person 'Subject', run 'Trial'"
    # Without a pattern the persons are the key's: pilots and conditions group by them.
    ids = [r.id for r in runs]
    assert pilot_groups(ids, None, files={r.id: r.file_id for r in runs}) == {i: i.split("#")[1] for i in ids}
    # One run: its rows picked by their key values, or an error saying how.
    one = read_run(tmp_path / "static.csv", columns=KEYED.replace("Subject", "Subject=s02").replace("Trial", "Trial=2"))
    assert one.id == "static#s02#2" and one.notes[-1].endswith("run 'Trial' = '2'; 6144 other row(s) left out")
    with pytest.raises(HesspipeError, match=r"static.csv: the key columns find 4 runs \(static#s01#1 to "
                                            r"static#s02#2\); "
                                            r"expected one here: keep one run's rows \(run=COLUMN=VALUE\)"):
        read_run(tmp_path / "static.csv", columns=KEYED)
    # A file of one person's runs keyed by trial alone: the file is the person.
    _long(tmp_path / "s03.csv", [("s03", 1), ("s03", 2)])
    one = read_file_runs(tmp_path / "s03.csv", columns=KEYED.replace("person=Subject,", ""))
    assert [(r.id, r.file_id, r.person) for r in one] == [("s03#1", "s03", ""), ("s03#2", "s03", "")]
    # A person's one run keyed by person alone.
    _long(tmp_path / "once.csv", [("s04", 1), ("s05", 1)])
    once = read_file_runs(tmp_path / "once.csv", columns=KEYED.replace(",run=Trial", ""))
    assert [(r.id, r.file_id) for r in once] == [("once#s04#1", "s04"), ("once#s05#1", "s05")]


def test_a_key_that_does_not_tell_runs_apart_and_other_mistakes(tmp_path):
    _long(tmp_path / "all.csv", [("s01", 1), ("s01", 2), ("s02", 1)])
    # Trial 1 of s01 and of s02 read as one run: its rows are in two blocks.
    with pytest.raises(HesspipeError, match=r"all.csv: the rows of run '1' \(run 'Trial'\) are not together: data "
                                            r"rows 1-2048, then from 4097; expected each run's rows in one block "
                                            r"\(map the column that tells its runs apart too: columns person=NAME\)"):
        read_file_runs(tmp_path / "all.csv", columns=KEYED.replace("person=Subject,", ""))
    with pytest.raises(HesspipeError, match=r"all.csv: column 'Session' missing \(role run\); found columns: "
                                            r"Subject, Trial, t"):
        read_file_runs(tmp_path / "all.csv", columns=KEYED.replace("run=Trial", "run=Session"))
    with pytest.raises(HesspipeError, match=r"^columns: person, run with '\*': expected runs side by side "
                                            r"\('\*'\) or one after another \(condition, person, run\)"):
        read_file_runs(tmp_path / "all.csv", columns=KEYED.replace("output=x", "output=x:*"))
    with pytest.raises(HesspipeError, match=r"^columns: role 'run': 'Trial\*': expected the name of the column"):
        read_file_runs(tmp_path / "all.csv", columns=KEYED.replace("run=Trial", "run=Trial*"))


def test_diagnose_takes_one_persons_runs_and_the_pipeline_finds_a_keyed_run(tmp_path, capsys):
    from hesspipe.cli import main
    from hesspipe.core.formats import write_plants
    from hesspipe.pipeline.stages import _diagnose_run
    from test_compare import paper_plants

    _long(tmp_path / "all.csv", [("s01", 1), ("s02", 1)])
    write_plants(tmp_path / "p.json", paper_plants())
    assert main(["diagnose", str(tmp_path / "all.csv"), "--plants", str(tmp_path / "p.json"),
                 "--columns", KEYED]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert err[-1] == (f"hesspipe: error: {tmp_path / 'all.csv'}#s01#1 and its repeats: runs of 2 persons "
                       "(s01, s02); expected one person's runs: diagnose every run alone with --each")
    pilots = tmp_path / "pilots"
    pilots.mkdir()
    (pilots / "comparison.json").write_text(json.dumps({"pilots": [{"id": "all#s02#1",
                                                                   "source": str(tmp_path / "all.csv#s02#1")}]}))

    class Ctx:
        section = {}
        config = {"pilots": {"data": ""}}
        upstream = {"pilots": pilots}

    assert _diagnose_run(Ctx) == (tmp_path / "all.csv", f"{tmp_path / 'all.csv'}#s02#1")


def test_one_table_of_both_conditions_is_read_a_condition_at_a_time(tmp_path):
    from hesspipe.core.formats import columns_for_condition

    s = signals()
    lines = ["Subject,Condition,Trial,t,ft,fd,x,u"]
    for cond, k in (("static", 1.0), ("motion", 2.0)):
        for person in ("s01", "s02"):
            for row in zip(s["time"], s["reference"], s["disturbance"], k * s["output"], k * s["control"]):
                lines.append(",".join([person, cond, "1"] + [f"{v:.12g}" for v in row]))
    (tmp_path / "all.csv").write_text("\n".join(lines) + "\n")
    cols = KEYED + ",condition=Condition"
    with pytest.raises(HesspipeError, match=r"^columns: role 'condition': 'Condition': expected COLUMN=VALUE"):
        read_file_runs(tmp_path / "all.csv", columns=cols)
    motion = read_file_runs(tmp_path / "all.csv", columns=columns_for_condition(cols, "motion"))
    assert [(r.id, r.person) for r in motion] == [("all#motion#s01#1", "s01"), ("all#motion#s02#1", "s02")]
    np.testing.assert_allclose(motion[1].control, 2.0 * s["control"], rtol=1e-10)
    assert motion[0].notes[-1] == ("2 run(s) in the file, one after another, told apart by condition 'Condition' "
                                   "= 'motion', person 'Subject', run 'Trial'; 4096 other row(s) left out")
    with pytest.raises(HesspipeError, match=r"all.csv: no row holds 'moving' in column 'Condition' \(role "
                                            r"condition\); found static, motion$"):
        read_file_runs(tmp_path / "all.csv", columns=cols + "=moving")
    assert columns_for_condition(KEYED, "motion") == KEYED   # no condition mapped: as given


def test_the_library_refuses_repeats_of_another_person_in_its_own_terms(tmp_path):
    # The check lives in diagnose itself, so a script that pools a long table's runs meets it
    # too; the command line only adds its option to the advice.
    from hesspipe.diagnose.workflow import diagnose
    from test_compare import paper_plants

    _long(tmp_path / "all.csv", [("s01", 1), ("s02", 2)])
    first, other = read_file_runs(tmp_path / "all.csv", columns=KEYED)
    with pytest.raises(HesspipeError) as err:
        diagnose(first, paper_plants(), repeat_runs=[other])
    assert str(err.value) == (f"{tmp_path / 'all.csv'}#s01#1 and its repeats: runs of 2 persons (s01, s02); "
                              "expected one person's runs: diagnose every run alone")
