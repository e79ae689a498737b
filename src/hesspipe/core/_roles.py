"""What a run's roles say about each other, checked once its columns are read
(:func:`hesspipe.core.formats.read_file_runs`): the displayed error and the target, an angle
logged within one turn, a task without a disturbance, a target the mapping left unread or
a column headed "target".
Each takes the role → values mapping (and the role → column names read) and returns the
notes it adds; those that fill or change a role do so in place."""

from __future__ import annotations

from typing import Mapping

import numpy as np

from ._csv import _split_unit, unwrap_turns
from .errors import HesspipeError

#: The displayed error agrees with reference - output within this fraction of its RMS.
ERROR_AGREES = 0.05

#: Headers (case and a bracketed unit aside) read as the reference where none is mapped or
#: named ``reference``: the manual-control literature's word for it.
TARGET_NAMES = ("target",)


def target_column(headers, mapping: Mapping[str, str]) -> tuple[str | None, tuple[str, ...]]:
    """The column to read as the reference where the file names it the target, and the note.

    Parameters
    ----------
    headers : sequence of str
        The file's columns.
    mapping : mapping
        The caller's role → column mapping.

    Returns
    -------
    (str or None, tuple of str)
        The header, and the note saying so; None where no single column is named the target,
        or where the reference or the error is mapped or a column is named ``reference`` or
        ``error`` (then with a note that the target column is not read, unless the mapping
        reads it). Left unread, a target reads as "no target": its lines are taken for
        remnant and the motion test cannot separate the two paths.
    """
    bare = [_split_unit(str(h))[0].lower() for h in headers]
    found = [h for h, b in zip(headers, bare) if b in TARGET_NAMES]
    if len(found) != 1:
        return None, ()
    mapped = {_split_unit(str(mapping[r]).lstrip("-"))[0].lower() for r in ("reference", "error") if r in mapping}
    if mapped & ({str(found[0]).lower(), *TARGET_NAMES}):
        return None, ()   # the mapping reads it
    if mapped or {"reference", "error"} & set(bare):
        # Said, as a reviewer's zero 'reference' column read beside the real 'Target' was not.
        return None, (f"column '{found[0]}' not read: the {'mapping' if mapped else 'file'} names the "
                      f"reference (or the displayed error); map reference={found[0]} if it is the target",)
    return found[0], (f"column '{found[0]}' read as the target (reference); map reference=NAME to "
                      f"read another",)


def with_error(data: dict, columns: Mapping[str, str]) -> tuple[str, ...]:
    """Take the displayed error out of `data`, in place: where no reference is logged it gives
    the reference (``r = e + y``); beside a logged one it is checked against it and said where
    it disagrees (the reference is used).

    Parameters
    ----------
    data : dict
        Role → values; ``error`` is removed, ``reference`` set where it was not read.
    columns : mapping
        Role → the column read.

    Returns
    -------
    tuple of str
        The notes said.
    """
    if "error" not in data:
        return ()
    e, col = data.pop("error"), columns["error"]
    size = float(np.sqrt(np.mean(e ** 2)))
    if "reference" not in data:
        r = e + data["output"]
        if float(np.sqrt(np.mean(r ** 2))) <= ERROR_AGREES * size:
            # A disturbance task: what is left is rounding, or the output's step between the
            # frames the logger took the two from, not a target's lines.
            data["reference"] = np.zeros_like(r)
            return (f"column '{col}' (error): minus the output within {ERROR_AGREES:.0%} of its RMS: "
                    "no target (reference 0)",)
        data["reference"] = r
        return (f"column '{col}' (error): the reference taken as error + output (the error as "
                "displayed, e = r - y; logged as y - r it maps as error=-NAME)",)
    gap, flipped = (float(np.sqrt(np.mean((data["reference"] - data["output"] - sign * e) ** 2)))
                    for sign in (1.0, -1.0))
    if size == 0.0 or gap <= ERROR_AGREES * size:
        return ()
    what = ("it is output - reference, the opposite sign" if flipped <= ERROR_AGREES * size else
            f"they differ by {gap / size:.0%} of its RMS (a display delay, another scale or another signal?)")
    return (f"column '{col}' (error): not reference - output: {what}; the reference is used",)


def unwrapped(data: dict, columns: Mapping[str, str]) -> tuple[str, ...]:
    """Unwrap, in place, an output or reference angle logged within one turn (a heading), and
    keep the two within half a turn of each other so that the error stays the error.

    Parameters
    ----------
    data : dict
        Role → values.
    columns : mapping
        Role → the column read.

    Returns
    -------
    tuple of str
        A note per role unwrapped.
    """
    notes, turn = [], None
    for role in ("output", "reference"):
        if role in data:
            data[role], period, jumps = unwrap_turns(data[role])
            if period:
                turn = period
                notes.append(f"column '{columns[role]}' ({role}): {jumps} step(s) of one turn "
                             f"({period:.6g}) unwrapped (an angle logged within one turn)")
    if turn and "reference" in data:
        gap = float(np.median(data["reference"] - data["output"]))
        data["output"] = data["output"] + turn * round(gap / turn)
    return tuple(notes)


def without_disturbance(path, data: dict, columns: Mapping[str, str]) -> tuple[str, ...]:
    """Fill, in place, the disturbance of a task without one (0), where no disturbance column
    was read but a target was; a run without any forcing is refused.

    Parameters
    ----------
    path : path
        The run's file, for messages.
    data : dict
        Role → values, the reference already taken from a displayed error.
    columns : mapping
        Role → the column read.

    Returns
    -------
    tuple of str
        The note said (none where a disturbance was read).

    Raises
    ------
    HesspipeError
        When there is no target either (the error was minus the output, or the reference is 0).
    """
    if "disturbance" in data:
        return ()
    if not np.any(data["reference"]):   # no forcing at all
        why = (f"column '{columns['error']}' (error) is minus the output" if "error" in columns
               else f"column '{columns['reference']}' (reference) is 0 throughout")
        raise HesspipeError(f"{path}: no disturbance column, and no target ({why}); expected a "
                            "disturbance column (map it with columns disturbance=NAME)")
    data["disturbance"] = np.zeros(len(data["output"]))
    return ("no disturbance column: a task without a disturbance (target tracking), the disturbance "
            "read as 0 (a disturbance that was flown but not logged shows as the plants' mismatch)",)


def target_unread(headers, used: Mapping[str, str], keys: Mapping[str, str]) -> tuple[str, ...]:
    """A note naming a file's columns left unread where a run was read without a target: a
    target the mapping missed reads as "no target" and changes the answer (its lines taken
    for remnant).

    Parameters
    ----------
    headers : sequence of str
        The file's columns.
    used : mapping
        Role → the column read.
    keys : mapping
        A long table's key roles → their columns (``COLUMN`` or ``COLUMN=VALUE``): read as keys.

    Returns
    -------
    tuple of str
        The note, or nothing where a target was read or no column was left unread.
    """
    if {"reference", "error"} & set(used):
        return ()
    key_names = {k.partition("=")[0].strip().lower() for k in keys.values()}
    unread = [str(h) for h in headers if h not in used.values() and str(h).strip()
              and str(h).strip().lower() not in key_names]
    if not unread:
        return ()
    return (f"no target column (reference): the target read as 0; not read: {', '.join(unread[:6])}"
            + (", ..." if len(unread) > 6 else "") + " (map reference=NAME if one of them is the target)",)
