"""Reading MATLAB files (``.mat``, versions 4 to 7): a trial saved as variables.

Laboratories that run their experiments from MATLAB or Simulink keep a trial as the
workspace's variables (``save trial.mat t ft fd e u x``), as one matrix of columns, or as
a struct of signals. Each numeric vector becomes a column named after its variable, each
matrix its columns ``NAME:1`` to ``NAME:k`` (samples along its longer side), a struct's
fields ``STRUCT.FIELD``, the elements of a struct or cell array ``NAME(i).FIELD`` and
``NAME(i)`` (several runs saved together: one is read at a time), and a labelled signal
(dSPACE's ``Y(i).Name``/``.Data``/``.Unit``, Simulink's ``signals(i).label``/``.values``) also
under its label, with its unit; text variables are the file's comments. A MAT file holds no
units of its own: values are read as written, unless a label states one. Version 7.3 files
are HDF5 in MATLAB's layout, which scipy does not read: :mod:`hesspipe.core._mat73` reads
them into the same variables.
"""

from __future__ import annotations

import io as _io
import re
from collections import Counter
from pathlib import Path

import numpy as np
import pandas as pd
from scipy import io as _sio

from ._mat73 import hdf5_content
from .errors import HesspipeError, reason
from .io import read_bytes


def mat_frame(path: str | Path) -> tuple[pd.DataFrame, tuple[str, ...], list[str], list[str]]:
    """The columns of a MAT file (or a NumPy archive, ``.npz``: its named arrays alike).

    Parameters
    ----------
    path : path
        The ``.mat`` file.

    Returns
    -------
    frame : pandas.DataFrame
        The columns that share the record's length (the length most columns have; the
        longest on a tie), in the file's order, values as written.
    comments : tuple of str
        Text variables, ``NAME: text`` (MATLAB's own header line first).
    notes : list of str
        What reading did, one sentence each.
    others : list of str
        Numeric variables left out: another length (``fs (1 value)``).

    Raises
    ------
    HesspipeError
        Naming the file: missing, not a MAT file, no numeric vector in it.
    """
    path = Path(path)
    kind = "NumPy archive" if path.suffix.lower() == ".npz" else "MATLAB file"
    raw = read_bytes(path, f"a {kind}")
    if kind == "NumPy archive":
        content = _npz_content(raw, path)
    else:
        try:
            content = _sio.loadmat(_io.BytesIO(raw), squeeze_me=True, simplify_cells=True)
        except NotImplementedError:   # version 7.3: HDF5
            content = hdf5_content(raw, path)
        except (_sio.matlab.MatReadError, ValueError, TypeError, OSError, EOFError) as exc:
            raise HesspipeError(f"{path}: not a readable MATLAB file ({reason(exc)}); "
                                "expected a MAT file of versions 4 to 7.3") from None
    columns: dict[str, np.ndarray] = {}
    header = content.get("__header__", b"")
    header = header.decode("latin-1") if isinstance(header, bytes) else str(header)
    comments = [header.strip()] if header.strip() else []
    labels: dict = {}
    for name, value in content.items():
        if not name.startswith("__"):
            _collect(name, value, columns, comments, labels)
    named = 0
    for (label, unit), source in labels.items():
        # A matrix's columns keep their number before the unit: 'STICK:2 [deg]'.
        cols = [c for c in columns if c == source or c.startswith(f"{source}:")] if source else []
        names = [label + c[len(source):] + unit for c in cols]
        if cols and not any(n_ in columns for n_ in names):
            named += 1
            columns.update({n_: columns[c] for n_, c in zip(names, cols)})
    if not columns:
        raise HesspipeError(f"{path}: no numeric vector or matrix in the {kind}; expected a "
                            "variable per signal, or a matrix of columns")
    frame, others = record_columns(columns)
    n = len(frame)
    notes = [f"{kind}: {frame.shape[1]} variable column(s) of {n} samples read, values as written "
             f"unless a signal's label states its unit (a {'MAT' if kind == 'MATLAB file' else 'NumPy'} file "
             "holds none of its own)"]
    if named:
        notes.append(f"{kind}: {named} labelled signal(s) also named by their labels")
    return frame, tuple(comments), notes + left_out(kind, "variable", others), others


def _npz_content(raw: bytes, path) -> dict:
    """The arrays of a NumPy archive (``numpy.savez``), as loadmat's variables: numbers as
    arrays, text as str; pickled objects are not loaded (they could run code) and left out."""
    try:
        archive = np.load(_io.BytesIO(raw), allow_pickle=False)
    except (ValueError, OSError, EOFError) as exc:
        raise HesspipeError(f"{path}: not a readable NumPy archive ({reason(exc)}); "
                            "expected a .npz file written by numpy.savez") from None
    if not hasattr(archive, "files"):
        raise HesspipeError(f"{path}: a single NumPy array, not an archive; expected a .npz file of named "
                            "arrays (numpy.savez(path, t=t, u=u, ...))")
    content = {}
    for name in archive.files:
        try:
            value = archive[name]
        except ValueError:   # an object array: would need pickle
            continue
        content[name] = str(value) if value.dtype.kind in "US" else value
    return content


def record_columns(columns: dict, aliases=None) -> tuple[pd.DataFrame, list[str]]:
    """The columns of the record's length, and the others named with their lengths.

    Parameters
    ----------
    columns : dict of str to ndarray
        Name → values of a file's signals, of any lengths (a MAT file's variables, a TDMS
        file's channels).
    aliases : mapping of str to list of str, optional
        A short name (a channel's or dataset's own name) → the columns it names (in their
        groups): a column too where it names one and is no column's name already; never
        listed among the others (their columns are).

    Returns
    -------
    frame : pandas.DataFrame
        The columns of the length most share (the longest on a tie; scalars only where
        nothing is longer), in `columns`' order.
    others : list of str
        ``NAME (k values)`` of the rest: a sample rate, a forcing's frequencies.
    """
    aliases = aliases or {}
    columns = {**columns, **{alias: columns[sources[0]] for alias, sources in aliases.items()
                             if len(sources) == 1 and alias not in columns}}
    # Scalars (a sample rate, a gain, a cell of settings) are no record, however many.
    lengths = Counter(v.size for v in columns.values() if v.size > 1) or Counter(v.size for v in columns.values())
    n = max(lengths, key=lambda k: (lengths[k], k))
    frame = pd.DataFrame({k: v for k, v in columns.items() if v.size == n})
    others = [f"{k} ({v.size} value{'s' if v.size != 1 else ''})" for k, v in columns.items()
              if v.size != n and k not in aliases]
    return frame, others


_LABELS = ("Name", "name", "label", "title", "Label", "Title")
_DATA = ("Data", "data", "values", "Values")
_UNITS = ("Unit", "unit", "Units", "units")


def _collect(name: str, value, columns: dict, comments: list, labels: dict) -> None:
    """Add `value`'s columns (or its text, as a comment) under `name`; a labelled signal's
    label and unit to `labels` ((label, " [unit]") -> the columns' name, or None where two share
    them)."""
    if isinstance(value, dict):
        for key, sub in value.items():
            _collect(f"{name}.{key}", sub, columns, comments, labels)
        # A labelled signal (dSPACE's Y(i).Name/.Data/.Unit, Simulink's signals(i).label/.values,
        # 'YAW ANGLE (deg)'): its label names its columns too, the last part of a block path.
        label = next((value[k] for k in _LABELS if isinstance(value.get(k), str) and value[k].strip()), None)
        data = next((k for k in _DATA if k in value), None)
        if label is not None and data is not None:
            alias = label.strip().split("/")[-1].strip().strip('"').strip()
            m = re.match(r"^(.*?)\s*[\[(]([^\])]*)[\])]\s*$", alias)   # a unit ending the label
            unit = m.group(2).strip() if m else next(
                (value[k].strip() for k in _UNITS if isinstance(value.get(k), str) and value[k].strip()), "")
            alias = (m.group(1) if m else alias, f" [{unit}]" if unit else "")
            labels[alias] = None if alias in labels else f"{name}.{data}"
        return
    if isinstance(value, np.ndarray) and value.dtype == object:
        # A cell array scipy left as objects: of numbers, a matrix (num2cell's); else its cells.
        numbers = all(isinstance(v, (int, float, np.number)) and not isinstance(v, bool) for v in value.flat)
        value = value.astype(float) if numbers and value.size else list(value.ravel(order="F"))
    if isinstance(value, list):   # a struct array or a cell array: NAME(1), NAME(2), ...
        for i, sub in enumerate(value, 1):
            _collect(f"{name}({i})", sub, columns, comments, labels)
        return
    if isinstance(value, str):
        if value.strip():
            comments.append(f"{name}: {value.strip()}")
        return
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        columns[name] = np.array([float(value)])
        return
    if not isinstance(value, np.ndarray) or value.dtype.kind not in "iuf":
        return   # cells, logicals, complex, objects: not a signal
    columns.update(array_columns(name, value))


def array_columns(name: str, values: np.ndarray) -> dict[str, np.ndarray]:
    """A numeric array's columns under `name`: a vector (a matrix of one row or column too) as
    itself, a matrix's columns ``name:1`` to ``name:k`` with the samples along its longer side
    (a row per signal is MATLAB's other habit); nothing for more dimensions.

    Parameters
    ----------
    name : str
        The variable's (or dataset's) name.
    values : ndarray
        Its numbers.

    Returns
    -------
    dict of str to ndarray
        Column name → float values.
    """
    a = np.squeeze(np.asarray(values)).astype(float)
    if a.ndim <= 1:
        return {name: np.atleast_1d(a)}
    if a.ndim > 2:
        return {}
    a = a.T if a.shape[0] < a.shape[1] else a
    return {f"{name}:{j}": a[:, j - 1] for j in range(1, a.shape[1] + 1)}


def left_out(kind: str, item: str, others, why: str = "of another length") -> list[str]:
    """The note of a binary file's columns left out of the record, if any.

    Parameters
    ----------
    kind : str
        The file's kind, the note's head ("TDMS file").
    item : str
        What its columns are ("channel").
    others : sequence of str
        :func:`record_columns`' others.
    why : str
        Why they were left out.

    Returns
    -------
    list of str
        No note or one.
    """
    if not others:
        return []
    return [f"{kind}: left out {len(others)} {item}(s) {why}: {', '.join(others[:6])}"
            + (", ..." if len(others) > 6 else "")]
