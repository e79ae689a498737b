"""Runs logged as HDF5 files (:mod:`hesspipe.core._h5`): a simulator's logger (a group per
logged entry, a ``data`` group of one dataset per member, units as attributes), a group per
run, MATLAB's ``h5write`` (vectors as one row, matrices transposed), compound datasets. The
files are written by h5py's writer of the format, laid out here as those programs lay them
out (no hesspipe code writes them); the signals are built here (SYNTHETIC)."""

from __future__ import annotations

import h5py
import numpy as np
import pytest

from hesspipe.core.errors import HesspipeError
from hesspipe.core.formats import read_file_runs, read_run
from hesspipe.pilots.compare import list_runs
from known_signals import refused
from test_runs_in_file import signals

LAB = {"reference": "target", "disturbance": "dist", "output": "yaw", "control": "stick"}
COLS = "time=t," + ",".join(f"{r}={n}" for r, n in LAB.items())


def _entry(group, s, k=1.0, units=True):
    """A logger's entry in `group`: ``data/<member>`` per signal (degrees where `units`), and
    the integer ``tick`` beside it."""
    data = group.create_group("data")
    data["t"] = s["time"]
    for role, name in LAB.items():
        scale = k if role in ("output", "control") else 1.0
        data[name] = (np.degrees(s[role]) if units else s[role]) * scale
        if units:
            data[name].attrs["unit"] = "deg"
    group["tick"] = np.arange(s["time"].size, dtype=np.int64) * 100


def test_a_loggers_hdf5_file_is_read_with_its_units(tmp_path):
    s = signals()
    with h5py.File(tmp_path / "s01_motion_r1.h5", "w") as f:
        f.attrs["description"] = "synthetic trial"
        entry = f.create_group("yawlog")
        entry.attrs["label"] = np.bytes_(b"yaw tracking, subject s01")
        _entry(entry, s)
        f["fs"] = 100.0
        f["notes"] = "a text dataset is no signal"
    run = read_run(tmp_path / "s01_motion_r1.h5", columns=COLS)
    assert run.synthetic and run.id == "s01_motion_r1"
    for role in ("time", "reference", "disturbance", "output", "control"):
        np.testing.assert_allclose(getattr(run, role), s[role], rtol=1e-12, atol=1e-12)
    assert any("column 'yaw [deg]' (output): deg converted" in n for n in run.notes), run.notes
    assert any("left out 1 dataset(s) of another length or shape: fs (1 value)" in n for n in run.notes)
    assert "yawlog: label: yaw tracking, subject s01" in run.comments
    # The full path reads the same column; a folder holds the file as a run.
    full = read_run(tmp_path / "s01_motion_r1.h5", columns=COLS.replace("=", "=yawlog/data/"))
    np.testing.assert_array_equal(full.output, run.output)
    assert any("column 'yawlog/data/yaw [deg]' (output): deg converted" in n for n in full.notes), full.notes
    assert [p.name for p in list_runs(tmp_path)] == ["s01_motion_r1.h5"]


def test_a_group_per_run_and_matlab_h5write(tmp_path):
    s = signals()
    with h5py.File(tmp_path / "s02.hdf5", "w") as f:
        for k in (1, 2, 3):
            _entry(f.create_group(f"run{k}"), s, k=float(k), units=False)
    cols = ",".join(f"{r}=run*/data/{n}" for r, n in {"time": "t", **LAB}.items())
    runs = read_file_runs(tmp_path / "s02.hdf5", columns=cols)
    assert [r.id for r in runs] == ["s02#1", "s02#2", "s02#3"]
    for k, run in enumerate(runs, 1):
        np.testing.assert_allclose(run.control, k * s["control"], rtol=1e-12)
    # A member name in several groups is no column by itself: the message lists the datasets.
    with pytest.raises(HesspipeError, match=r"s02.hdf5: dataset 'yaw' missing \(role output\); found datasets: "
                                            r"run1/data/dist, "):
        read_run(tmp_path / "s02.hdf5", columns=cols.replace("*", "1").replace("run1/data/yaw", "yaw"))
    # MATLAB's h5write stores its column-major arrays as written: a vector as one row, an
    # 8192 x 5 matrix (a column per run) as 5 x 8192.
    with h5py.File(tmp_path / "m.h5", "w") as f:
        f["t"] = s["time"][None, :]
        for role, name in LAB.items():
            f[name] = np.vstack([k * s[role] for k in (1, 2, 3)])
    runs = read_file_runs(tmp_path / "m.h5", columns="time=t," + ",".join(f"{r}={n}:*" for r, n in LAB.items()))
    assert len(runs) == 3
    np.testing.assert_allclose(runs[2].output, 3 * s["output"], rtol=1e-12)
    np.testing.assert_allclose(runs[0].time, s["time"], atol=1e-12)


def test_compound_datasets_and_files_it_cannot_read(tmp_path):
    s = signals()
    table = np.zeros(s["time"].size, dtype=[("t", "f8"), ("yaw", "f4"), ("stick", "f8"), ("target", "f8"),
                                            ("dist", "f8"), ("flag", "S2")])
    for role, name in {"time": "t", **LAB}.items():
        table[name] = s[role]
    with h5py.File(tmp_path / "c.h5", "w") as f:
        f["log"] = table
    run = read_run(tmp_path / "c.h5", columns=",".join(f"{r}=log.{n}" for r, n in {"time": "t", **LAB}.items()))
    np.testing.assert_allclose(run.output, s["output"], rtol=1e-6)   # stored as float32
    np.testing.assert_allclose(run.control, s["control"], rtol=1e-12)
    refused(tmp_path / "bad.h5", b"time,yaw\n0,1\n", r"bad.h5: not a readable HDF5 file \(.*\); expected an HDF5 file")
    refused(tmp_path / "missing.h5", None, r"missing.h5: file not found; expected an HDF5 file")
    with h5py.File(tmp_path / "text.h5", "w") as f:
        f["notes"] = "no numbers here"
    refused(tmp_path / "text.h5", None, r"text.h5: no numeric dataset in the HDF5 file; expected a dataset per signal")


def test_an_unreadable_files_reason_is_one_line_even_without_a_message():
    # The readers name what the library said; an exception without a message was an
    # IndexError (a traceback) in five copies of this line before it was one function.
    from hesspipe.core.errors import reason

    assert reason(ValueError("")) == "ValueError"
    assert reason(OSError("bad magic\nsecond line")) == "bad magic"
    assert reason(KeyError("x" * 200)) == "'" + "x" * 79
