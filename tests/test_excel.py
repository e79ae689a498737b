"""Measured runs kept in Excel workbooks (:mod:`hesspipe.core._excel`): a sheet is read as
the same table saved as text would be; what it cannot read says so. The runs are built
here from known signals (SYNTHETIC)."""

from __future__ import annotations

import datetime

import numpy as np
import openpyxl
import pandas as pd
import pytest

from hesspipe.core.errors import HesspipeError
from hesspipe.core.formats import read_file_runs, read_run
from hesspipe.pilots.compare import list_runs
from known_signals import DT, refused
from known_signals import check as _check
from known_signals import signals as _signals


def _frame(names, degrees=False):
    s = _signals()
    return pd.DataFrame({name: (np.degrees(s[role]) if degrees and role != "time" else s[role])
                         for role, name in names.items()})


def test_a_lab_workbook_reads_as_its_text_would(tmp_path):
    # Metadata above the header, units in the names, another sheet beside it.
    path = tmp_path / "s01_motion_r1.xlsx"
    df = _frame({"time": "Time [s]", "reference": "Target [deg]", "disturbance": "Disturbance [deg]",
                 "output": "Yaw [deg]", "control": "Stick [deg]"}, degrees=True)
    with pd.ExcelWriter(path) as w:
        pd.DataFrame([["Subject: s01"], ["Condition: motion"]]).to_excel(w, sheet_name="run", header=False,
                                                                          index=False)
        df.to_excel(w, sheet_name="run", startrow=3, index=False)
        pd.DataFrame({"remark": ["calibrated 2026-11-02"]}).to_excel(w, sheet_name="notes", index=False)
    run = read_run(path, columns="reference=Target,disturbance=Disturbance,output=Yaw,control=Stick")
    _check(run)
    assert run.dt == pytest.approx(DT, rel=1e-12)
    assert run.comments == ("Subject: s01", "Condition: motion")
    assert any("read sheet 'run' (left out: 'notes')" in n for n in run.notes)
    assert any("'Yaw [deg]' (output): deg converted" in n for n in run.notes)
    assert not any("tab-separated" in n for n in run.notes)   # the tabs are the reader's own


def test_a_units_row_clock_times_and_no_header(tmp_path):
    s = _signals()
    # Units in a row under the names, the time of day in time cells.
    clock = [(datetime.datetime(2026, 11, 2, 14, 3, 5) + datetime.timedelta(seconds=float(x))).time()
             for x in s["time"]]
    path = tmp_path / "units.xlsx"
    book = openpyxl.Workbook()
    sheet = book.active
    sheet.append(["Time", "disturbance", "output", "control", "reference"])
    sheet.append([None, "-", "-", "-", "-"])
    for i, c in enumerate(clock):   # real time cells, as Excel keeps a time column
        sheet.append([c, *(float(s[k][i]) for k in ("disturbance", "output", "control", "reference"))])
    book.save(path)
    run = read_run(path)
    for role in ("disturbance", "output", "control", "reference"):
        np.testing.assert_allclose(getattr(run, role), s[role], rtol=1e-9, atol=1e-12)
    assert run.dt == pytest.approx(DT, rel=1e-6)
    assert any("clock times" in n for n in run.notes) and any("units" in n for n in run.notes)
    # Numbers only: by position, as a text file without a header row.
    bare = tmp_path / "bare.xlsx"
    _frame({k: k for k in s}).to_excel(bare, header=False, index=False)
    _check(read_run(bare, columns="time=1,disturbance=2,output=3,control=4,reference=5"))
    with pytest.raises(HesspipeError, match=r"bare.xlsx: columns 'time', 'output' and 'control' missing; the file "
                                            r"has no header row"):
        read_run(bare)


def test_files_it_cannot_read_say_why(tmp_path):
    # Excel 97-2003's compound document, renamed; a text file; a workbook of words only.
    refused(tmp_path / "old.xlsx", bytes.fromhex("d0cf11e0a1b11ae1") + b"\x00" * 504,
            r"old.xlsx: an Excel 97-2003 workbook \(.xls\), which hesspipe does not read; expected .xlsx")
    refused(tmp_path / "text.xlsx", b"time,output\n0,1\n", r"text.xlsx: not an Excel workbook; expected an .xlsx file")
    pd.DataFrame({"a": ["x", "y"], "b": ["z", "w"]}).to_excel(tmp_path / "words.xlsx", index=False)
    refused(tmp_path / "words.xlsx", None, r"words.xlsx: no sheet of the workbook holds a table of numbers")


def test_a_folder_of_workbooks_is_a_set_of_pilots(tmp_path):
    for pid in ("p1", "p2"):
        _frame({k: k for k in _signals()}).to_excel(tmp_path / f"{pid}.xlsx", index=False)
    (tmp_path / "readme.txt").write_text("not a run\n")
    assert [p.name for p in list_runs(tmp_path)] == ["p1.xlsx", "p2.xlsx"]
    _check(read_run(tmp_path / "p1.xlsx"))


def test_a_sheet_per_run(tmp_path):
    # A person's workbook: a sheet per run (metadata above each header), a longer raw sheet
    # and a sheet of text beside them. The first sheet alone still reads as the file's run.
    path = tmp_path / "s02_motion.xlsx"
    names = {"time": "Time [s]", "reference": "Target [deg]", "disturbance": "Disturbance [deg]",
             "output": "Yaw [deg]", "control": "Stick [deg]"}
    base = _frame(names, degrees=True)
    with pd.ExcelWriter(path) as w:
        for k in (1, 2, 3):
            df = base.copy()
            df[["Yaw [deg]", "Stick [deg]"]] *= k
            pd.DataFrame([[f"Run: {k}"]]).to_excel(w, sheet_name=f"Run {k}", header=False, index=False)
            (df if k != 3 else df.iloc[:-5]).to_excel(w, sheet_name=f"Run {k}", startrow=2, index=False)
        pd.concat([base, base]).to_excel(w, sheet_name="raw", index=False)
        pd.DataFrame({"remark": ["ok"]}).to_excel(w, sheet_name="notes", index=False)
    cols = "reference=Run */Target,disturbance=Run */Disturbance,output=Run */Yaw,control=Run */Stick,time=Run */Time"
    runs = read_file_runs(path, columns=cols)
    assert [r.id for r in runs] == ["s02_motion#1", "s02_motion#2", "s02_motion#3"]
    s = _signals()
    for k, run in enumerate(runs, 1):
        n = len(s["time"]) - (5 if k == 3 else 0)
        assert len(run) == n
        np.testing.assert_allclose(run.control, k * s["control"][:n], rtol=1e-12)
        np.testing.assert_allclose(run.time, s["time"][:n], atol=1e-12)
    assert any("3 sheets of numbers" in n_ and "left out, more rows than the first: 'raw'" in n_
               for n_ in runs[0].notes), runs[0].notes
    assert any("left out: 'notes'" in n_ for n_ in runs[0].notes)
    one = read_run(path, columns="reference=Target,disturbance=Disturbance,output=Yaw,control=Stick")
    np.testing.assert_array_equal(one.control, runs[0].control)


def test_a_name_written_twice_in_a_sheet_is_refused_and_mapped_by_position(tmp_path):
    # The sheet is read as its text: the check of a name written twice is the text's.
    s = _signals()
    path = tmp_path / "twice.xlsx"
    book = openpyxl.Workbook()
    sheet = book.active
    sheet.append(["time", "disturbance", "output", "output", "control", "reference"])
    for i in range(s["time"].size):
        sheet.append([float(s["time"][i]), float(s["disturbance"][i]), 0.0, float(s["output"][i]),
                      float(s["control"][i]), float(s["reference"][i])])
    book.save(path)
    refused(path, None, r"twice.xlsx: 'output' matches columns 3 and 4, both headed 'output'; expected one: "
                        r"map the one meant by its position with columns output=3 or output=4")
    _check(read_run(path, columns="output=4"))
