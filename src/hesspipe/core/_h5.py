"""HDF5 files (``.h5``, ``.hdf5``): a trial logged as datasets.

Simulation software writes its logs as HDF5 (DUECA's logger, a group per logged entry with
a ``data`` group of one dataset per member beside the ``tick`` dataset; an experiment script's
``h5py`` or MATLAB's ``h5write``). h5py reads the format; here the datasets become columns as a
MATLAB file's variables do (:mod:`hesspipe.core._mat`):

- a numeric dataset is the column named by its path without the leading ``/``
  (``entry/data/yaw``), with its unit where an attribute ``unit`` or ``units`` gives one
  (``entry/data/yaw [deg]``, converted as a CSV header's unit is), and by its own name too
  where no other dataset has that name (``yaw [deg]``); a group per run (``run1/yaw``,
  ``run2/yaw``) is read with a ``*`` for the run's number (``output=run*/yaw``);
- a matrix's columns are ``PATH:1`` to ``PATH:k``, samples along its longer side (MATLAB's
  ``h5write`` stores a column vector as one row: read as the vector); a compound dataset's
  numeric fields are ``PATH.FIELD``;
- the columns are those of the length most datasets share, the others left out and said;
- text attributes of the file and its groups are the comments (one saying ``synthetic``
  marks the run synthetic); text and other non-numeric datasets are no signal.
"""

from __future__ import annotations

import io as _io
from pathlib import Path

import numpy as np
import pandas as pd

from ._mat import array_columns, left_out, record_columns
from .errors import HesspipeError, reason
from .io import read_bytes

#: Attributes that give a dataset's unit.
_UNITS = ("unit", "units", "Unit", "Units", "unit_string")


def _text(value) -> str | None:
    """An attribute's text, or None for anything else."""
    if isinstance(value, bytes):
        value = value.decode("utf-8", "replace")
    if isinstance(value, np.ndarray) and value.dtype.kind in "SUO" and value.size == 1:
        return _text(value.reshape(-1)[0])
    return value.strip() if isinstance(value, str) and value.strip() else None


def h5_frame(path: str | Path) -> tuple[pd.DataFrame, tuple[str, ...], list[str], list[str]]:
    """The columns of an HDF5 file (:func:`hesspipe.core._mat.record_columns` of its datasets).

    Parameters
    ----------
    path : path
        The ``.h5`` or ``.hdf5`` file.

    Returns
    -------
    frame : pandas.DataFrame
        The datasets' columns that share the record's length (the length most have; the
        longest on a tie), in the file's order, values as written, named with their units.
    comments : tuple of str
        Text attributes, ``NAME: text`` (a group's as ``GROUP: NAME: text``).
    notes : list of str
        What reading did, one sentence each.
    others : list of str
        Datasets left out: another length (``entry/tick (3 values)``).

    Raises
    ------
    HesspipeError
        Naming the file: missing, not an HDF5 file, no numeric dataset in it.
    """
    import h5py  # deferred: only HDF5 files need it (and MATLAB 7.3 files, in _mat73)

    path = Path(path)
    raw = read_bytes(path, "an HDF5 file")
    try:
        h5 = h5py.File(_io.BytesIO(raw), "r")
    except OSError as exc:
        raise HesspipeError(f"{path}: not a readable HDF5 file ({reason(exc)}); expected an HDF5 file") from None
    comments, columns, named, skipped = [], {}, {}, []
    with h5:
        comments += [f"{k}: {t}" for k, v in h5.attrs.items() if (t := _text(v))]

        def visit(name: str, item) -> None:
            if isinstance(item, h5py.Group):
                comments.extend(f"{name}: {k}: {t}" for k, v in item.attrs.items() if (t := _text(v)))
                return
            unit = next((t for k in _UNITS if k in item.attrs and (t := _text(item.attrs[k]))), "")
            tail = f" [{unit}]" if unit else ""
            dtype = item.dtype
            if dtype.names:   # a compound dataset: its numeric fields
                values = item[()]
                parts = {f"{name}.{field}": values[field] for field in dtype.names
                         if dtype[field].kind in "iufb" and dtype[field].shape == ()}
            elif dtype.kind in "iufb":
                parts = {name: item[()]}
            else:
                return   # text, references, opaque data: not a signal
            found = {}
            for key, vals in parts.items():
                found.update(array_columns(key, vals))
            if not found:
                skipped.append(f"{name} ({item.ndim} dimensions)")
            for key, vals in found.items():
                columns[key + tail] = vals
                if "/" in key:   # in a group: its own name is an alias where unique
                    named.setdefault(key.rsplit("/", 1)[-1] + tail, []).append(key + tail)

        h5.visititems(visit)
    if not columns:
        raise HesspipeError(f"{path}: no numeric dataset in the HDF5 file; expected a dataset per signal")
    frame, others = record_columns(columns, named)
    notes = [f"HDF5 file: {len(columns)} column(s) from its datasets, {len(frame)} samples read"]
    others += skipped
    return frame, tuple(comments), notes + left_out("HDF5 file", "dataset", others, "of another length or shape"), \
        others
