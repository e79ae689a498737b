"""Several runs of one file side by side: a star in a mapped name stands for the run's number
(``x:*``, ``trial(*).u``, ``Run */Yaw``), :func:`run_columns` finds the runs it reads."""

from __future__ import annotations

import re
from typing import Mapping

from ._csv import _split_unit
from ._table import RUN_NUMBER, Frame, _match
from .errors import HesspipeError

#: Roles a session's runs may share (the clock, the forcing every run was given): a starred
#: name for one of them that finds no numbered columns reads the column without the star.
SHARED_ROLES = ("time", "reference", "disturbance")
#: The star and what binds it to the name (``x:*``, ``trial(*).u``, ``u_*``): removed, the name a
#: file of one run has.
_UNSTARRED = re.compile(r"\(\*\)|[:_. -]?\*")



def run_columns(frame: Frame, names: Mapping[str, str], *, optional=(),
                hint: str | None = None) -> list[tuple[int, dict[str, str]]]:
    """The runs a file holds, as the names their roles are read under.

    A name holding :data:`RUN_NUMBER` stands for one column per run, the star for the run's
    number (digits; matched as :func:`read_table` matches names: exactly, else ignoring case
    and a unit in brackets); a name without it is shared by every run (the time, the forcing).

    Parameters
    ----------
    frame : Frame
        The file's columns (:func:`read_frame`).
    names : mapping
        Role → column name, possibly with one star (and ``-`` before it: the sign flipped);
        at most one each (:func:`hesspipe.core.formats.parse_columns` checks it).
    optional : sequence of str
        Roles that may be missing in the file.
    hint : str, optional
        Name of the setting that maps other column names (in messages).

    Returns
    -------
    list of (int, dict)
        Per run its number and role → column name, by number; ``[(0, names)]`` when no name
        holds a star, or when none of the starred names is in the file and each is there
        without its star (``x`` for ``x:*``: MATLAB's vector of a session of one run) or under
        its role's own name (a folder's single-run files beside its multi-run ones). A
        starred name of a role in :data:`SHARED_ROLES` that finds no numbered columns while
        the others do reads the name without the star for every run (the forcing saved once).

    Raises
    ------
    HesspipeError
        A starred name matching no column; roles whose starred names find different run
        numbers; two columns one run's role could be.
    """
    starred = {role: name for role, name in names.items() if RUN_NUMBER in name}
    if not starred:
        return [(0, dict(names))]
    headers = frame.headers
    found: dict[str, dict[int, str]] = {}
    for role, name in starred.items():
        sign, body = ("-", name[1:].strip()) if name.startswith("-") else ("", name)
        left, right = body.split(RUN_NUMBER)   # "Run */Yaw": the space before the number is the name's
        head, tail = re.escape(left.lstrip().lower()), re.escape(right.rstrip().lower())
        rx = re.compile(rf"^{head}(\d+){tail}$")
        runs: dict[int, str] = {}
        for h in headers:
            m = rx.match(h.strip().lower()) or rx.match(_split_unit(h)[0].lower())
            if m:
                k = int(m.group(1))
                if k in runs:
                    raise HesspipeError(f"{frame.path}: columns '{runs[k]}' and '{h}' both read as "
                                        f"'{name}' for run {k} (role {role}); expected one")
                runs[k] = sign + h
        found[role] = runs
    if not any(found.values()):
        # A file of one run: MATLAB saves a session of one as vectors (x, not x:1; trial.u,
        # not trial(1).u), or it has the roles' plain columns.
        for plain in ({role: _UNSTARRED.sub("", name) for role, name in starred.items()},
                      {role: role for role in starred}):
            if all(_match(frame.path, headers, role, name.lstrip("-").strip()) is not None or role in optional
                   for role, name in plain.items()):
                return [(0, {**names, **plain})]
    for role, runs in found.items():
        shared = _match(frame.path, headers, role, _UNSTARRED.sub("", starred[role]).lstrip("-").strip())
        if not runs and role in SHARED_ROLES and shared is not None and any(found.values()):
            # The forcing saved once for every run of the session (ft beside x:1..x:5).
            found[role] = {k: ("-" if starred[role].startswith("-") else "") + shared
                           for k in next(r for r in found.values() if r)}
            continue
        if not runs:
            tail = f"; map other names with {hint} {role}=NAME" if hint else ""
            raise HesspipeError(f"{frame.path}: no column matches '{starred[role]}' (role {role}, "
                                f"{RUN_NUMBER!r} standing for a run's number); found columns: "
                                f"{', '.join(headers)}{tail}")
    numbers = {role: sorted(runs) for role, runs in found.items()}
    first = next(iter(numbers))
    for role, ks in numbers.items():
        if ks != numbers[first]:
            raise HesspipeError(f"{frame.path}: '{starred[first]}' (role {first}) finds runs "
                                f"{_numbers(numbers[first])} but '{starred[role]}' (role {role}) runs "
                                f"{_numbers(ks)}; expected the same runs for every starred role")
    return [(k, {**names, **{role: found[role][k] for role in starred}}) for k in numbers[first]]


def _numbers(ks: list[int]) -> str:
    """``1-5`` for consecutive numbers, else ``1, 2, 4``."""
    if ks == list(range(ks[0], ks[-1] + 1)) and len(ks) > 2:
        return f"{ks[0]}-{ks[-1]}"
    return ", ".join(str(k) for k in ks)
