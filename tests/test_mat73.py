"""MATLAB version 7.3 files (HDF5; :mod:`hesspipe.core._mat73`) read as the same workspace
saved as version 7 is read. The version 7.3 files are written by hdf5storage, a writer of
MATLAB's HDF5 layout that shares no code with hesspipe, the version 7 ones by scipy; one file
written by MATLAB itself (in scipy's test data) is read too. Signals built here (SYNTHETIC)."""

from __future__ import annotations

from pathlib import Path

import hdf5storage
import numpy as np
import pytest
import scipy
from scipy.io import savemat

from hesspipe.core._mat import mat_frame
from hesspipe.core.errors import HesspipeError
from hesspipe.core.formats import read_file_runs, read_run
from known_signals import refused
from known_signals import signals as _signals


def _both(tmp_path, name: str, workspace: dict, compare: bool = True) -> tuple[Path, Path]:
    """`workspace` saved by scipy (version 7) and by hdf5storage (version 7.3), their columns
    compared."""
    v7, v73 = tmp_path / "v7" / f"{name}.mat", tmp_path / "v73" / f"{name}.mat"
    v7.parent.mkdir(exist_ok=True)
    v73.parent.mkdir(exist_ok=True)
    savemat(v7, workspace)
    hdf5storage.savemat(str(v73), workspace, format="7.3", oned_as="column", truncate_existing=True)
    assert v73.read_bytes()[:19] == b"MATLAB 7.3 MAT-file"
    if compare:
        # Every column under its name with its values, and what was left out, as from version 7
        # (in HDF5's order of names, not MATLAB's of creation).
        a, b = mat_frame(v7), mat_frame(v73)
        assert sorted(a[0].columns) == sorted(b[0].columns)
        for col in a[0].columns:
            np.testing.assert_array_equal(a[0][col], b[0][col])
        assert sorted(a[3]) == sorted(b[3]) and len(a[2]) == len(b[2])
    return v7, v73


def _same(a, b) -> None:
    for role in ("time", "reference", "disturbance", "output", "control"):
        np.testing.assert_array_equal(getattr(a, role), getattr(b, role))
    assert (a.id, a.number, a.synthetic) == (b.id, b.number, b.synthetic)
    assert [_unordered(n) for n in a.notes] == [_unordered(n) for n in b.notes]


def _unordered(note: str):
    """A note whose list of variables may come in HDF5's order of names."""
    head, sep, names = note.partition("of another length: ")
    return (head, sorted(names.split(", "))) if sep else note


def _structs(rows: list[dict]) -> np.ndarray:
    """A 1 x k struct array of `rows` (both writers take a structured array for it)."""
    arr = np.zeros((1, len(rows)), dtype=[(key, object) for key in rows[0]])
    for i, row in enumerate(rows):
        for key, value in row.items():
            arr[0, i][key] = value
    return arr


def test_a_workspace_of_vectors_reads_as_its_version_7_twin(tmp_path):
    s = _signals()
    ws = {"t": s["time"], "fd": s["disturbance"], "x": s["output"], "u": s["control"], "ft": s["reference"],
          "fs": 100.0, "w_d": np.arange(10.0), "note": "synthetic trial",
          "parts": np.empty(2, dtype=object)}   # a cell array of two signals
    ws["parts"][0], ws["parts"][1] = s["output"], 2 * s["output"]
    ws["gains"] = np.empty((1, 3), dtype=object)   # num2cell([1 2 3])
    ws["gains"][0, :] = [1.0, 2.0, 3.0]
    v7, v73 = _both(tmp_path, "s01_motion_r1", ws)
    cols = "time=t,disturbance=fd,output=x,control=u,reference=ft"
    a, b = read_run(v7, columns=cols), read_run(v73, columns=cols)
    _same(a, b)
    np.testing.assert_array_equal(mat_frame(v73)[0]["parts(2)"], 2 * s["output"])
    left = "left out 3 variable(s) of another length: fs (1 value), gains (3 values), w_d (10 values)"
    assert b.synthetic and any(left in n for n in b.notes)


def test_a_session_matrix_a_struct_array_and_labelled_signals(tmp_path):
    s = _signals()
    k = np.array([1.0, 2.0, 3.0])
    # A matrix column per run, the target saved once (8192 x 5 in MATLAB: here 400 x 3).
    v7, v73 = _both(tmp_path, "s02", {"t": s["time"], "ft": s["reference"], "fd": s["disturbance"],
                                      "x": np.outer(s["output"], k), "u": np.outer(s["control"], k)})
    cols = "time=t,reference=ft:*,disturbance=fd,output=x:*,control=u:*"
    a, b = read_file_runs(v7, columns=cols), read_file_runs(v73, columns=cols)
    assert [r.id for r in b] == ["s02#1", "s02#2", "s02#3"]
    for x, y in zip(a, b):
        _same(x, y)
    np.testing.assert_array_equal(b[2].control, 3.0 * s["control"])
    # A struct array, trial(k).u, beside a scalar struct of the shared signals.
    trials = _structs([{"x": j * s["output"], "u": j * s["control"]} for j in k])
    v7, v73 = _both(tmp_path, "s03", {"trial": trials, "common": {"t": s["time"], "fd": s["disturbance"],
                                                                 "ft": s["reference"], "who": "s03"}})
    cols = "time=common.t,reference=common.ft,disturbance=common.fd,output=trial(*).x,control=trial(*).u"
    a, b = read_file_runs(v7, columns=cols), read_file_runs(v73, columns=cols)
    assert [r.id for r in b] == ["s03#1", "s03#2", "s03#3"]
    for x, y in zip(a, b):
        _same(x, y)
    # dSPACE's labelled signals, Y(i).Name / .Data / .Unit.
    deg = np.degrees
    sig = _structs([{"Name": "Yaw", "Data": deg(s["output"]), "Unit": "deg"},
                    {"Name": "Stick", "Data": deg(s["control"]), "Unit": "deg"},
                    {"Name": "Target", "Data": deg(s["reference"]), "Unit": "deg"},
                    {"Name": "Disturbance", "Data": deg(s["disturbance"]), "Unit": "deg"}])
    v7, v73 = _both(tmp_path, "s04", {"t": s["time"], "Y": sig})
    cols = "time=t,output=Yaw,control=Stick,reference=Target,disturbance=Disturbance"
    a, b = read_run(v7, columns=cols), read_run(v73, columns=cols)
    _same(a, b)
    np.testing.assert_allclose(b.output, s["output"], rtol=1e-12)


def test_a_file_matlab_wrote_and_files_it_cannot_read(tmp_path):
    # MATLAB 7.4 saved 'testdouble' (0:pi/4:2*pi) with -v7.3 and as version 7 (scipy's test data).
    data = Path(scipy.__file__).parent / "io" / "matlab" / "tests" / "data"
    if (data / "testhdf5_7.4_GLNX86.mat").exists():
        v73, v7 = (mat_frame(data / name)[0] for name in ("testhdf5_7.4_GLNX86.mat", "testdouble_7.4_GLNX86.mat"))
        assert list(v73.columns) == list(v7.columns) == ["testdouble"]
        np.testing.assert_array_equal(v73["testdouble"], v7["testdouble"])
        np.testing.assert_allclose(v73["testdouble"], np.arange(9) * np.pi / 4, rtol=1e-15)
    refused(tmp_path / "v73.mat", b"MATLAB 7.3 MAT-file, Platform: GLNXA64, HDF5 schema 1.00 .".ljust(116, b" ")
            + b"\x00" * 8 + b"\x00\x02IM" + b"\x00" * 512,
            r"v73.mat: not a readable MATLAB 7.3 \(HDF5\) file")
    # Text only, or values that are no signal (complex, a cell of text): said.
    v7, v73 = _both(tmp_path, "empty", {"z": np.array([1 + 2j, 3j]), "c": np.array(["a", "bc"], dtype=object),
                                        "note": "nothing numeric"}, compare=False)
    for path in (v7, v73):
        with pytest.raises(HesspipeError, match=r"empty.mat: no numeric vector or matrix in the MATLAB file"):
            read_run(path)
