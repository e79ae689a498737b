"""Several runs in one file (:func:`hesspipe.core.formats.read_file_runs`,
:func:`hesspipe.core._star.run_columns`): a MATLAB session's matrices of one column per run, a
struct array, numbered text columns; a star in the mapped name stands for the run's number.
The runs are built here from known signals (SYNTHETIC)."""

from __future__ import annotations

import json

import numpy as np
import pytest
from scipy.io import savemat

from hesspipe.core.errors import HesspipeError
from hesspipe.core.formats import read_file_runs, read_run
from hesspipe.pilots.verdict import pilot_groups
from known_signals import DT
from known_signals import signals as _short


def signals(n: int = 2048) -> dict:
    """:func:`known_signals.signals` over `n` samples (the pilots' and diagnose's shortest
    record is longer than its 400)."""
    t = DT * np.arange(n)
    short = _short()
    return {role: np.interp(t, short["time"], v, period=short["time"][-1] + DT) if role != "time" else t
            for role, v in short.items()}

STARRED = "time=t,reference=ft:*,disturbance=fd,output=x:*,control=u:*"


def _session(path, runs=3, person=0):
    """A .mat of `runs` runs: x, u and ft one column per run (run k scaled by k + `person`), t and
    fd shared."""
    s = signals()
    k = np.arange(1, runs + 1) + person
    savemat(path, {"t": s["time"], "fd": s["disturbance"], "ft": np.outer(s["reference"], k),
                   "x": np.outer(s["output"], k), "u": np.outer(s["control"], k)})
    return s


def test_a_matrix_column_per_run_is_a_run(tmp_path):
    path = tmp_path / "s01_motion.mat"
    s = _session(path)
    runs = read_file_runs(path, columns=STARRED)
    assert [(r.id, r.number, r.file_id) for r in runs] == [
        ("s01_motion#1", 1, "s01_motion"), ("s01_motion#2", 2, "s01_motion"), ("s01_motion#3", 3, "s01_motion")]
    assert [r.source for r in runs] == [f"{path}#{k}" for k in (1, 2, 3)]
    for k, run in enumerate(runs, 1):
        for role in ("reference", "output", "control"):
            np.testing.assert_allclose(getattr(run, role), k * s[role], rtol=1e-12)
        np.testing.assert_allclose(run.disturbance, s["disturbance"], rtol=1e-12)   # shared
        assert "3 runs in the file, read as PATH#NUMBER" in run.notes[-1]
    # One run at a time: its own column names, or the star refused where one run is read.
    two = read_run(path, columns=STARRED.replace("*", "2"))
    assert (two.id, two.number) == ("s01_motion", 0)
    np.testing.assert_allclose(two.control, runs[1].control)
    with pytest.raises(HesspipeError, match=r"s01_motion.mat: the columns mapped with '\*' find 3 runs "
                                            r"\(s01_motion#1 to s01_motion#3\); expected one here"):
        read_run(path, columns=STARRED)
    # A sign flipped on a starred name, as on a plain one.
    flipped = read_file_runs(path, columns=STARRED.replace("control=u:*", "control=-u:*"))
    np.testing.assert_allclose(flipped[2].control, -3 * s["control"], rtol=1e-12)


def test_a_struct_array_and_numbered_text_columns(tmp_path):
    s = signals()
    trial = np.zeros((2,), dtype=[("t", object), ("u", object), ("y", object), ("d", object)])
    for i in range(2):
        trial[i] = (s["time"], (i + 1) * s["control"], s["output"], s["disturbance"])
    savemat(tmp_path / "all.mat", {"trial": trial})
    runs = read_file_runs(tmp_path / "all.mat",
                          columns="time=trial(*).t,control=trial(*).u,output=trial(*).y,disturbance=trial(*).d")
    assert [r.id for r in runs] == ["all#1", "all#2"]
    np.testing.assert_allclose(runs[1].control, 2 * s["control"], rtol=1e-12)
    # A text file's numbered columns, a unit beside each number (converted as a CSV header's).
    rows = ["time,d,Yaw1 [deg],Yaw2 [deg],u1,u2"] + [
        f"{t:.2f},{d:.9f},{np.degrees(y):.9f},{np.degrees(2 * y):.9f},{u:.9f},{2 * u:.9f}"
        for t, d, y, u in zip(s["time"], s["disturbance"], s["output"], s["control"])]
    (tmp_path / "s02.csv").write_text("\r\n".join(rows) + "\r\n", encoding="utf-8-sig")
    runs = read_file_runs(tmp_path / "s02.csv", columns="disturbance=d,output=yaw*,control=u*")
    assert [r.id for r in runs] == ["s02#1", "s02#2"]
    np.testing.assert_allclose(runs[1].output, 2 * s["output"], atol=1e-9)
    np.testing.assert_allclose(runs[1].control, 2 * s["control"], atol=1e-8)


def test_plain_names_on_a_file_of_runs_say_the_starred_mapping(tmp_path):
    # A reviewer's struct array of runs mapped as time=t,... failed with the variables found
    # and no word of the star that reads them.
    s = signals()
    trial = np.zeros((2,), dtype=[("t", object), ("u", object), ("y", object), ("d", object)])
    for i in range(2):
        trial[i] = (s["time"], s["control"], s["output"], s["disturbance"])
    savemat(tmp_path / "all.mat", {"trial": trial})
    with pytest.raises(HesspipeError, match=r"all.mat: variables 't' \(role time\).*; if the file holds a run "
                                            r"per number, map each role with '\*' for the run's number, e.g. "
                                            r"time=trial\(\*\).t,disturbance=trial\(\*\).d,output=trial\(\*\).y,"
                                            r"control=trial\(\*\).u$"):
        read_file_runs(tmp_path / "all.mat", columns="time=t,control=u,output=y,disturbance=d")
    _session(tmp_path / "s01.mat")
    with pytest.raises(HesspipeError, match=r"e.g. output=x:\*,control=-u:\*$"):
        read_file_runs(tmp_path / "s01.mat", columns="time=t,reference=ft:*,disturbance=fd,output=x,control=-u")
    # The number beside the name, two runs at least: a person's number is not starred, and one
    # numbered column (an aircraft's name) is no run.
    from hesspipe.core._table import _starred_hint

    assert _starred_hint(["s01_run1.t", "s01_run2.t"], [("time", "t")]).endswith("e.g. time=s01_run*.t")
    assert _starred_hint(["Time", "F16_t"], [("time", "t")]) == ""
    assert _starred_hint(["trial(1).t [s]", "trial(2).t [s]", "u1", "u2"],
                         [("time", "t"), ("control", "u")]).endswith("e.g. time=trial(*).t,control=u*")


def test_starred_names_that_do_not_find_the_same_runs_are_refused(tmp_path):
    path = tmp_path / "s01.mat"
    s = _session(path)
    with pytest.raises(HesspipeError, match=r"s01.mat: no column matches 'y:\*' \(role output, '\*' standing "
                                            r"for a run's number\); found columns: t, fd, ft:1"):
        read_file_runs(path, columns=STARRED.replace("x:*", "y:*"))
    with pytest.raises(HesspipeError, match=r"^columns: role 'output': 'x:\*\*' holds 2 '\*'; expected at most one"):
        read_file_runs(path, columns=STARRED.replace("x:*", "x:**"))
    savemat(path, {"t": s["time"], "fd": s["disturbance"], "ft": np.outer(s["reference"], [1, 2]),
                   "x": np.outer(s["output"], [1, 2, 3]), "u": np.outer(s["control"], [1, 2, 3])})
    with pytest.raises(HesspipeError, match=r"s01.mat: 'x:\*' \(role output\) finds runs 1-3 but 'ft:\*' "
                                            r"\(role reference\) runs 1, 2; expected the same runs"):
        read_file_runs(path, columns=STARRED)
    (tmp_path / "twice.csv").write_text("time,disturbance,output,u1,U1 [deg]\n0,0,0,0,0\n0.01,0,0,0,0\n")
    with pytest.raises(HesspipeError, match=r"columns 'u1' and 'U1 \[deg\]' both read as 'u\*' for run 1"):
        read_file_runs(tmp_path / "twice.csv", columns="control=u*")


def test_a_forcing_saved_once_serves_every_run_a_measured_signal_does_not(tmp_path):
    # One mapping for a folder whose sessions saved the target once (ft) or per run (ft:k).
    path = tmp_path / "s02.mat"
    s = signals()
    savemat(path, {"t": s["time"], "fd": s["disturbance"], "ft": s["reference"],
                   "x": np.outer(s["output"], [1, 2]), "u": np.outer(s["control"], [1, 2])})
    runs = read_file_runs(path, columns=STARRED)
    assert [r.id for r in runs] == ["s02#1", "s02#2"]
    for k, run in enumerate(runs, 1):
        np.testing.assert_allclose(run.reference, s["reference"], rtol=1e-12)
        np.testing.assert_allclose(run.control, k * s["control"], rtol=1e-12)
        assert run.notes[-1].endswith("(output x:*, control u:*); reference 'ft' saved once, the same for "
                                      "every run"), run.notes[-1]
    # The person's own signals are never shared: a control saved once is no run's control.
    savemat(path, {"t": s["time"], "fd": s["disturbance"], "ft": s["reference"],
                   "x": np.outer(s["output"], [1, 2]), "u": s["control"]})
    with pytest.raises(HesspipeError, match=r"s02.mat: no column matches 'u:\*' \(role control"):
        read_file_runs(path, columns=STARRED)


def test_a_single_run_file_beside_them_keeps_its_plain_names(tmp_path):
    # A folder's mapping written for its sessions: a file of one run under the roles' own names
    # is that one run, as an unstarred mapping falls back to them.
    s = signals()
    rows = ["time,disturbance,output,control,reference"] + [
        ",".join(f"{v:.12g}" for v in row) for row in zip(*(s[c] for c in ("time", "disturbance", "output",
                                                                           "control", "reference")))]
    (tmp_path / "s09.csv").write_text("\n".join(rows) + "\n")
    (run,) = read_file_runs(tmp_path / "s09.csv", columns="reference=ft:*,output=x:*,control=u:*")
    assert (run.id, run.number, run.source) == ("s09", 0, str(tmp_path / "s09.csv"))
    np.testing.assert_allclose(run.control, s["control"], rtol=1e-10)


def test_a_files_runs_are_one_pilots_unless_a_pattern_says_otherwise(tmp_path):
    from hesspipe.core.formats import write_plants
    from hesspipe.pilots.compare import compare_pilots, read_runs
    from test_compare import fake_job, paper_plants

    for i, name in enumerate(("s01_motion", "s02_motion")):
        _session(tmp_path / f"{name}.mat", runs=2, person=2 * i)
    runs, failures = read_runs(sorted(tmp_path.glob("*.mat")), columns=STARRED, min_samples=2)
    assert not failures and [r.id for r in runs] == ["s01_motion#1", "s01_motion#2", "s02_motion#1", "s02_motion#2"]
    ids, files = [r.id for r in runs], {r.id: r.file_id for r in runs}
    assert pilot_groups(ids, None, files=files) == files
    assert pilot_groups(ids, r"^(s\d+)_", files=files) == {i: i[:3] for i in ids}
    assert pilot_groups(["a", "b"], None, files={"a": "a", "b": "b"}) is None   # a file a run: each its own
    # The folder through compare_pilots: two pilots of two runs each, in file order.
    write_plants(tmp_path / "plants.json", paper_plants())
    result = compare_pilots(tmp_path, paper_plants(), workers=1, job=fake_job, columns=STARRED)
    assert [p.id for p in result.pilots] == ids
    assert result.groups == files


def test_diagnose_reads_its_runs_and_the_baseline_apart(tmp_path, monkeypatch, capsys):
    # A file of several runs among the runs (repeats) and another as the baseline: each list is
    # its own, however many runs a file holds.
    import hesspipe.diagnose.workflow as workflow
    from hesspipe.cli import main
    from hesspipe.core.formats import write_plants
    from test_compare import paper_plants

    _session(tmp_path / "motion.mat", runs=3)
    _session(tmp_path / "static.mat", runs=2, person=3)
    write_plants(tmp_path / "p.json", paper_plants())
    seen = {}

    def fake(run, plants, **kw):
        seen.update(run=run.id, repeats=[r.id for r in kw["repeat_runs"]],
                    baseline=[r.id for r in kw["baseline_run"]])
        raise HesspipeError("stopped here")

    monkeypatch.setattr(workflow, "diagnose", fake)
    code = main(["diagnose", str(tmp_path / "motion.mat"), "--plants", str(tmp_path / "p.json"),
                 "--columns", STARRED, "--baseline-run", str(tmp_path / "static.mat")])
    assert code == 1 and "stopped here" in capsys.readouterr().err
    assert seen == {"run": "motion#1", "repeats": ["motion#2", "motion#3"], "baseline": ["static#1", "static#2"]}


def test_the_pipelines_diagnose_stage_finds_a_run_of_a_file(tmp_path):
    from hesspipe.pipeline.stages import _diagnose_run

    pilots = tmp_path / "pilots"
    pilots.mkdir()
    (tmp_path / "s01.mat").write_bytes(b"x")
    (pilots / "comparison.json").write_text(json.dumps({"pilots": [{"id": "s01#2",
                                                                   "source": str(tmp_path / "s01.mat#2")}]}))

    class Ctx:
        section = {}
        config = {"pilots": {"data": ""}}
        upstream = {"pilots": pilots}

    assert _diagnose_run(Ctx) == (tmp_path / "s01.mat", f"{tmp_path / 's01.mat'}#2")


def test_conditions_take_a_files_runs_as_one_persons(tmp_path):
    # Without a pattern the person is the file: s01's three runs in one condition, s02's in the
    # other, are two persons (not six), and none flew both.
    from hesspipe.pilots.conditions import compare_conditions
    from test_compare import paper_plants

    _session(tmp_path / "s01.mat")
    _session(tmp_path / "s02.mat", person=3)
    a, b = (read_file_runs(tmp_path / f"{p}.mat", columns=STARRED) for p in ("s01", "s02"))
    with pytest.raises(HesspipeError, match=r"no person flew both 'static' and 'motion': the persons \(a run's "
                                            r"file name\) are s01 and s02"):
        compare_conditions(a, b, paper_plants(), labels=("static", "motion"))


def test_a_session_of_one_run_saved_as_vectors_is_that_run(tmp_path):
    # MATLAB saves a matrix of one column as a vector (x, not x:1) and a struct array of one
    # element as a struct (trial.u): the starred mapping reads it as the file's one run.
    s = signals()
    savemat(tmp_path / "s04.mat", {"t": s["time"], "fd": s["disturbance"], "ft": s["reference"],
                                   "x": s["output"], "u": s["control"]})
    (run,) = read_file_runs(tmp_path / "s04.mat", columns=STARRED.replace("control=u:*", "control=-u:*"))
    assert (run.id, run.number) == ("s04", 0)
    np.testing.assert_allclose(run.control, -s["control"], rtol=1e-12)
    savemat(tmp_path / "s05.mat", {"trial": {"t": s["time"], "u": s["control"], "y": s["output"], "d": s["disturbance"]}})
    (run,) = read_file_runs(tmp_path / "s05.mat",
                            columns="time=trial(*).t,control=trial(*).u,output=trial(*).y,disturbance=trial(*).d")
    np.testing.assert_allclose(run.output, s["output"], rtol=1e-12)


def test_a_file_without_times_is_read_at_the_sample_rate_given(tmp_path, capsys):
    # A MATLAB workspace saved without its time vector (the rate a scalar beside the signals).
    from hesspipe.cli import main

    s = signals()
    savemat(tmp_path / "s06.mat", {"fs": 100.0, "fd": s["disturbance"], "x": s["output"], "u": s["control"]})
    cols = "disturbance=fd,output=x,control=u"
    with pytest.raises(HesspipeError, match=r"s06.mat: variable 'time' missing; found variables: fd, x, u "
                                            r"\(left out, another length: fs \(1 value\)\); map other names with "
                                            r"columns time=NAME, or give the sample rate \(sample_rate\)"):
        read_run(tmp_path / "s06.mat", columns=cols)
    run = read_run(tmp_path / "s06.mat", columns=cols, sample_rate=100)
    np.testing.assert_allclose(run.time, s["time"], rtol=0, atol=1e-12)
    assert run.dt == pytest.approx(0.01) and "no time column: sample k at k / 100 Hz" in run.notes
    # A file with times keeps them, and they must agree with the rate given.
    savemat(tmp_path / "s07.mat", {"t": s["time"], "fd": s["disturbance"], "x": s["output"], "u": s["control"]})
    timed = "time=t," + cols
    assert np.array_equal(read_run(tmp_path / "s07.mat", columns=timed, sample_rate=100).time,
                          read_run(tmp_path / "s07.mat", columns=timed).time)
    with pytest.raises(HesspipeError, match=r"s07.mat: column 't': samples at 100 Hz; expected the sample rate "
                                            r"given, 60 Hz"):
        read_run(tmp_path / "s07.mat", columns=timed, sample_rate=60)
    for bad in (0.5, float("nan"), "100", True):
        with pytest.raises(HesspipeError, match=r"^sample_rate: expected a number of Hz from 10 to 10000"):
            read_run(tmp_path / "s07.mat", columns=timed, sample_rate=bad)
    # The command line names its own option.
    from hesspipe.core.formats import write_plants
    from test_compare import paper_plants

    write_plants(tmp_path / "p.json", paper_plants())
    assert main(["frf", str(tmp_path / "s06.mat"), "--plants", str(tmp_path / "p.json"), "--columns", cols]) == 1
    assert "give the sample rate (--sample-rate HZ)" in capsys.readouterr().err


def test_the_pilots_table_takes_a_sample_rate():
    from hesspipe.pilots.settings import PilotsConfig

    assert PilotsConfig.from_table({"data": "runs/", "sample_rate": 100}, "c.toml").sample_rate == 100.0
    assert PilotsConfig.from_table({}, "c.toml").sample_rate is None
    with pytest.raises(HesspipeError, match=r"c.toml: field 'pilots.sample_rate'"):
        PilotsConfig.from_table({"sample_rate": 0.2}, "c.toml")
