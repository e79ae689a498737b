"""Reading Excel workbooks (``.xlsx``, ``.xlsm``): a run kept in a spreadsheet.

A laboratory that passes its trials around as workbooks keeps a run on a sheet, a header
row (perhaps with units, perhaps a units row under it, perhaps lines of metadata above it),
one run per file or a sheet per run. Each sheet of numbers is turned into the
tab-separated text the CSV reader takes (:mod:`hesspipe.core._csv`), so a sheet is read
exactly as the same table saved as text would be: its header, units, metadata and clock
times alike. Numbers keep their full
precision (written as the shortest text that reads back as the same float).
"""

from __future__ import annotations

import io as _io
import math
import numbers
import zipfile
from pathlib import Path

import pandas as pd

from .errors import HesspipeError, reason
from .io import read_bytes

EXCEL_SUFFIXES = (".xlsx", ".xlsm")
"""Workbook file endings read (Office Open XML; the binary ``.xls`` of Excel 97-2003 is not)."""


def excel_sheets(path: str | Path) -> tuple[list[tuple[str, str]], list[str]]:
    """The sheets holding numbers, each as tab-separated text, and what reading did.

    Parameters
    ----------
    path : path
        The workbook.

    Returns
    -------
    sheets : list of (str, str)
        Per sheet of numbers, in the workbook's order: its name and its text, one line per
        row, cells separated by tabs, empty cells empty.
    notes : list of str
        The sheets read (and the others left out).

    Raises
    ------
    HesspipeError
        Naming the file: missing, not a workbook, no sheet with numbers.
    """
    path = Path(path)
    raw = read_bytes(path, "an Excel workbook")
    if not zipfile.is_zipfile(_io.BytesIO(raw)):
        old = raw[:8] == bytes.fromhex("d0cf11e0a1b11ae1")
        raise HesspipeError(f"{path}: " + ("an Excel 97-2003 workbook (.xls), which hesspipe does not read; "
                                          "expected .xlsx: save it as an Excel workbook or as text" if old else
                                          "not an Excel workbook; expected an .xlsx file"))
    try:
        sheets = pd.read_excel(_io.BytesIO(raw), sheet_name=None, header=None, engine="openpyxl")
    except (ValueError, KeyError, OSError, zipfile.BadZipFile) as exc:
        raise HesspipeError(f"{path}: not a readable Excel workbook ({reason(exc)}); "
                            "expected an .xlsx file") from None
    numeric = [name for name, df in sheets.items() if _numbers(df) >= 2]
    if not numeric:
        raise HesspipeError(f"{path}: no sheet of the workbook holds a table of numbers; expected a run's "
                            "columns on its first sheet")
    left = [repr(str(n)) for n in sheets if n not in numeric]
    notes = [f"Excel workbook: read sheet{'s' if len(numeric) > 1 else ''} "
             f"{', '.join(repr(str(n)) for n in numeric)}" + (f" (left out: {', '.join(left)})" if left else "")]
    # Each row as far as its last filled cell: the sheet's width padded a metadata line
    # ("Subject: s02") into as many cells as the header has, and it passed for the header.
    texts = [(str(name), "\n".join("\t".join(_cell(v) for v in row).rstrip("\t")
                                  for row in sheets[name].itertuples(index=False)) + "\n")
             for name in numeric]
    return texts, notes


def _numbers(df: pd.DataFrame) -> int:
    """Rows of `df` with at least two numbers (a time of day, as a time or as text, beside them)."""
    return sum(sum(isinstance(v, numbers.Real) and not isinstance(v, bool) and not _empty(v) for v in row) >= 2
               for row in df.itertuples(index=False))


def _empty(value) -> bool:
    return value is None or (isinstance(value, float) and math.isnan(value)) or \
        (isinstance(value, str) and not value.strip())


def _cell(value) -> str:
    """A cell as the text a logger would have written: numbers exactly, times of day as
    ``HH:MM:SS.ffffff``, text without tabs or line breaks."""
    if _empty(value):
        return ""
    if isinstance(value, float):
        return repr(float(value))
    return " ".join(str(value).split())
