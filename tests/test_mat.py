"""Measured runs saved from MATLAB (:mod:`hesspipe.core._mat`): variables, a matrix of
columns, a struct; what is left out and why; files that are not readable say so. The runs are
built here from known signals (SYNTHETIC)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.io import savemat

from hesspipe.core.errors import HesspipeError
from hesspipe.core.formats import read_run
from hesspipe.pilots.compare import list_runs
from known_signals import DT, refused
from known_signals import check as _check
from known_signals import signals as _signals


def test_variables_are_columns_and_the_rest_is_said(tmp_path):
    # A workspace: one vector per signal, a sample rate, the forcing's frequencies (another
    # length) and a note saying the data are synthetic.
    s = _signals()
    path = tmp_path / "s01_motion_r1.mat"
    savemat(path, {"t": s["time"], "fd": s["disturbance"], "x": s["output"], "u": s["control"],
                   "ft": s["reference"], "fs": 100.0, "w_d": np.arange(10.0), "note": "synthetic trial"})
    run = read_run(path, columns="time=t,disturbance=fd,output=x,control=u,reference=ft")
    _check(run)
    assert run.dt == pytest.approx(DT, rel=1e-12)
    assert run.synthetic and run.id == "s01_motion_r1"
    assert any("5 variable column(s) of 400 samples" in n and "values as written" in n for n in run.notes)
    assert not any("labelled" in n for n in run.notes)
    assert any("left out 2 variable(s) of another length: fs (1 value), w_d (10 values)" in n for n in run.notes)
    # A role not mapped: the message lists the variables, and those of another length.
    with pytest.raises(HesspipeError, match=r"s01_motion_r1.mat: variable 'control' missing; found variables: "
                                            r"t, fd, x, u, ft \(left out, another length: fs \(1 value\), "
                                            r"w_d \(10 values\)\); map other names with columns control=NAME"):
        read_run(path, columns="time=t,disturbance=fd,output=x")


@pytest.mark.parametrize("rows", [False, True])
def test_a_matrix_is_read_by_its_columns(tmp_path, rows):
    # One matrix, a signal per column (or per row: samples along the longer side).
    s = _signals()
    m = np.column_stack([s[k] for k in ("time", "disturbance", "output", "control", "reference")])
    path = tmp_path / "m.mat"
    savemat(path, {"data": m.T if rows else m})
    _check(read_run(path, columns="time=data:1,disturbance=data:2,output=data:3,control=data:4,"
                                  "reference=data:5"))


def test_a_structs_fields_and_the_plain_names(tmp_path):
    s = _signals()
    path = tmp_path / "st.mat"
    savemat(path, {"trial": {"time": s["time"], "dist": s["disturbance"], "y": s["output"], "stick": s["control"],
                             "target": s["reference"], "subject": "s02"}})
    run = read_run(path, columns="time=trial.time,disturbance=trial.dist,output=trial.y,control=trial.stick,"
                                 "reference=trial.target")
    _check(run)
    assert "trial.subject: s02" in run.comments
    # Variables named as SPEC's columns need no mapping, a sign flip as in a CSV.
    plain = tmp_path / "plain.mat"
    savemat(plain, {**{k: v for k, v in s.items()}, "control": -s["control"]})
    assert np.allclose(read_run(plain, columns="control=-control").control, s["control"])


def test_runs_saved_together_are_read_one_at_a_time(tmp_path):
    # A struct array of runs (data.run(i).u): each element's fields are columns NAME(i).FIELD.
    s = _signals()
    runs = np.zeros((2,), dtype=[("t", object), ("u", object), ("y", object), ("d", object)])
    runs[0] = (s["time"], -s["control"], s["output"], s["disturbance"])
    runs[1] = (s["time"], s["control"], s["output"], s["disturbance"])
    path = tmp_path / "s03_all.mat"
    savemat(path, {"run": runs})
    run = read_run(path, columns="time=run(2).t,control=run(2).u,output=run(2).y,disturbance=run(2).d")
    np.testing.assert_allclose(run.control, s["control"], rtol=1e-12)
    with pytest.raises(HesspipeError, match=r"found variables: run\(1\).t, run\(1\).u, run\(1\).y, run\(1\).d, "
                                            r"run\(2\).t"):
        read_run(path)


def test_labelled_signals_are_named_by_their_labels_with_their_units(tmp_path):
    # dSPACE's export (X and Y(i) with Name, Data, Unit; names are block paths) and Simulink's
    # structure with time (signals(i).label and .values, the unit in the label).
    s = _signals()
    deg = np.degrees
    ys = np.zeros((4,), dtype=[("Name", object), ("Data", object), ("Unit", object)])
    for i, (label, role) in enumerate([('"Model Root"/"Pilot"/"stick"', "control"), ('"Model Root"/"yaw"', "output"),
                                       ('"Model Root"/"fd"', "disturbance"), ('"Model Root"/"ft"', "reference")]):
        ys[i] = (label, deg(s[role]), "deg")
    dspace = tmp_path / "dspace.mat"
    savemat(dspace, {"trial": {"X": {"Name": "Time", "Data": s["time"], "Unit": "s"}, "Y": ys}})
    run = read_run(dspace, columns="time=Time,control=stick,output=yaw,disturbance=fd,reference=ft")
    _check(run)   # degrees converted, as a unit in a CSV header is
    assert any("5 labelled signal(s) also named by their labels" in n for n in run.notes)
    assert any("'yaw [deg]' (output): deg converted" in n for n in run.notes)
    sig = np.zeros((2,), dtype=[("label", object), ("values", object)])
    sig[0] = ("YAW ANGLE (deg)", deg(s["output"]))
    sig[1] = ("STICK (deg)", np.column_stack([deg(s["control"]), deg(s["reference"])]))
    simulink = tmp_path / "simulink.mat"
    savemat(simulink, {"simout": {"time": s["time"], "signals": sig}, "fd": s["disturbance"]})
    run = read_run(simulink, columns="time=simout.time,output=YAW ANGLE,control=STICK:1,reference=STICK:2,"
                                     "disturbance=fd")
    np.testing.assert_allclose(run.output, s["output"], rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(run.reference, s["reference"], rtol=1e-9, atol=1e-12)


def test_files_it_cannot_read_say_why(tmp_path):
    # A text file; a workspace of text only; no file (version 7.3: tests/test_mat73.py).
    refused(tmp_path / "bad.mat", b"time,output\n0,1\n", r"bad.mat: not a readable MATLAB file")
    savemat(tmp_path / "text.mat", {"note": "nothing numeric"})
    refused(tmp_path / "text.mat", None, r"text.mat: no numeric vector or matrix in the MATLAB file")
    refused(tmp_path / "missing.mat", None, r"missing.mat: file not found; expected a MATLAB file")


def test_a_folder_of_mat_files_is_a_set_of_pilots(tmp_path):
    s = _signals()
    for pid in ("p1", "p2"):
        savemat(tmp_path / f"{pid}.mat", s)
    (tmp_path / "notes.txt").write_text("not a run\n")
    assert [p.name for p in list_runs(tmp_path)] == ["p1.mat", "p2.mat"]


def test_a_numpy_archive_is_read_as_a_workspace(tmp_path):
    # numpy.savez of the same variables: the same columns as the MATLAB file's; pickled
    # objects are never loaded (they could run code) and a bare array is no archive.
    s = _signals()
    ws = {"t": s["time"], "fd": s["disturbance"], "x": s["output"], "u": s["control"], "ft": s["reference"],
          "fs": 100.0, "note": "synthetic trial"}
    savemat(tmp_path / "s01.mat", ws)
    np.savez(tmp_path / "s01.npz", **ws, blob=np.array([{"a": 1}], dtype=object))
    cols = "time=t,disturbance=fd,output=x,control=u,reference=ft"
    a, b = read_run(tmp_path / "s01.mat", columns=cols), read_run(tmp_path / "s01.npz", columns=cols)
    for role in ("time", "disturbance", "output", "control", "reference"):
        np.testing.assert_array_equal(getattr(a, role), getattr(b, role))
    assert b.synthetic and any(n.startswith("NumPy archive: 5 variable column(s) of 400 samples") for n in b.notes)
    assert [p.name for p in list_runs(tmp_path)] == ["s01.mat", "s01.npz"]
    np.save(tmp_path / "bare.npy", s["time"])
    (tmp_path / "bare.npz").write_bytes((tmp_path / "bare.npy").read_bytes())
    refused(tmp_path / "bare.npz", None, r"bare.npz: a single NumPy array, not an archive")
    refused(tmp_path / "junk.npz", b"not an archive", r"junk.npz: not a readable NumPy archive")


def test_scalars_never_outvote_the_signals_and_a_cell_of_numbers_is_a_matrix(tmp_path):
    # A workspace with more scalar settings than signals, and num2cell's cell of numbers.
    s = _signals()
    ws = {"t": s["time"], "fd": s["disturbance"], "x": s["output"], "u": s["control"],
          **{f"K{i}": float(i) for i in range(12)}}
    cells = np.empty((2, len(s["time"])), dtype=object)
    cells[0, :], cells[1, :] = list(s["output"]), list(2 * s["output"])
    savemat(tmp_path / "w.mat", {**ws, "c": cells})
    run = read_run(tmp_path / "w.mat", columns="time=t,disturbance=fd,output=c:2,control=u")
    np.testing.assert_array_equal(run.output, 2 * s["output"])
    assert any("left out 12 variable(s) of another length: K0 (1 value)" in n for n in run.notes)
