"""Runs one after another in one table: a long (tidy) file, rows keyed by person and run.

Shared datasets and statistics packages keep an experiment as one long table, a row per
sample, with columns that say whose run a row belongs to (``Subject``, ``Trial``) beside
the signals. The key columns' values cut the table into runs, each then read as a file of
one run is (:func:`hesspipe.core._table.read_table` on its rows).
"""

from __future__ import annotations

import re
from dataclasses import replace
from typing import Mapping

import numpy as np
import pandas as pd

from ._table import Frame, _match
from .errors import HesspipeError

#: Roles that name a row's owner, not a signal, in the order they key a run. Mapped as
#: ``ROLE=COLUMN``, or ``ROLE=COLUMN=VALUE`` to keep only the rows holding VALUE there (a
#: condition always so: one condition's runs are read at a time).
KEY_COLUMNS = ("condition", "person", "run")


def row_groups(frame: Frame, keys: Mapping[str, str]) -> list[tuple[tuple[str, ...], Frame, str]]:
    """The runs of a long table: the rows that share their key columns' values.

    Parameters
    ----------
    frame : Frame
        The file's columns (:func:`hesspipe.core._table.read_frame`).
    keys : mapping
        Key role (:data:`KEY_COLUMNS`) → column name, matched as a signal's name is, or
        ``COLUMN=VALUE``: only the rows whose value there is VALUE (``condition`` needs one).

    Returns
    -------
    list of (labels, Frame, note)
        In the order the runs start in the file: the run's labels, key role → value (the
        condition's, the person's, then the run's, as written, ``#`` and path separators
        replaced; a run key not mapped is ``1``), its rows as a frame of their own, and a
        note of what was read.

    Raises
    ------
    HesspipeError
        A key column missing; a condition without a value; a value no row holds; a run whose
        rows are not together (a key left out that tells two runs apart).
    """
    path, df = frame.path, frame.df
    cols, wanted = {}, {}
    for role in KEY_COLUMNS:
        if role in keys:
            name, _, value = keys[role].partition("=")
            if role == "condition" and not value.strip():
                raise HesspipeError(f"columns: role 'condition': {keys[role]!r}: expected COLUMN=VALUE, the "
                                    "condition whose rows to read (one condition at a time)")
            col = _match(path, frame.headers, role, name.strip(), frame.as_written)
            if col is None:
                raise HesspipeError(f"{path}: column '{name.strip()}' missing (role {role}); found columns: "
                                    f"{', '.join(frame.headers)}")
            cols[role] = col
            if value.strip():
                wanted[role] = _labels(pd.Series([value.strip()]))[0]
    text = {role: _labels(df[col]) for role, col in cols.items()}
    keyed = np.logical_and.reduce([t != "" for t in text.values()])
    for role, value in wanted.items():
        if not np.any(text[role] == value):
            found = list(dict.fromkeys(t for t in text[role] if t))
            raise HesspipeError(f"{path}: no row holds {value!r} in column '{cols[role]}' (role {role}); found "
                                f"{', '.join(found[:8])}{', ...' if len(found) > 8 else ''}")
        keyed &= text[role] == value
    left = int((~keyed).sum())
    label = pd.Series(["\x1f".join(parts) for parts in zip(*text.values())])
    label[~keyed] = ""
    groups = []
    # The rows of each key value at once, in the order the values first appear.
    kept = label[keyed]
    where = kept.index.to_numpy()
    for value, rows in kept.groupby(kept, sort=False).indices.items():
        rows = where[rows]
        if rows[-1] - rows[0] + 1 != rows.size:
            gap = int(rows[np.argmax(np.diff(rows) > 1)])
            names = ", ".join(f"{role} '{cols[role]}'" for role in cols)
            raise HesspipeError(f"{path}: the rows of run {value.replace(chr(31), ' ')!r} ({names}) are not "
                                f"together: data rows {rows[0] + 1}-{gap + 1}, then from "
                                f"{int(rows[rows > gap + 1][0]) + 1}; expected each run's rows in one "
                                f"block (map the column that tells its runs apart too: columns "
                                f"{'run' if 'run' not in cols else 'person'}=NAME)")
        labels = {"run": "1", **dict(zip(cols, value.split("\x1f")))}
        groups.append(({role: labels[role] for role in KEY_COLUMNS if role in labels}, _rows(frame, rows)))
    if not groups:
        raise HesspipeError(f"{path}: no row has a value in {', '.join(repr(c) for c in cols.values())}; "
                            "expected the key columns filled on every row of a run")
    said = ", ".join(f"{role} '{col}'" + (f" = {wanted[role]!r}" if role in wanted else "")
                     for role, col in cols.items())
    note = (f"{len(groups)} run(s) in the file, one after another, told apart by {said}"
            + (f"; {left} other row(s) left out" if left else ""))
    return [(labels, sub, note) for labels, sub in groups]


def _labels(column: pd.Series) -> np.ndarray:
    """A key column's values as text for ids: ``3.0`` as ``3``, blanks as ``""``; ``#``, path
    separators and spaces as ``_``."""
    def one(value) -> str:
        if isinstance(value, float) and value.is_integer():
            return str(int(value))
        return re.sub(r"[#/\\\s]+", "_", str(value).strip().strip('"'))

    codes, uniques = pd.factorize(column)   # each distinct value once: a table has millions of rows
    text = np.array([one(v) for v in uniques] + [""], dtype=object)
    return text[codes]   # code -1 (a blank cell) is the last, ""


def _rows(frame: Frame, rows: np.ndarray) -> Frame:
    """`frame` cut to `rows` (the cells as written cut alike)."""
    written = frame.written
    cut = None if written is None else (lambda col: written(col)[rows])
    return replace(frame, df=frame.df.iloc[rows].reset_index(drop=True), written=cut)
