"""The role -> column mapping of a measured run's file, parsed and checked once
(re-exported by :mod:`hesspipe.core.formats`, whose readers take it)."""

from __future__ import annotations

from typing import Mapping

from ._long import KEY_COLUMNS
from ._table import RUN_NUMBER
from .errors import HesspipeError

#: Columns every run has (SPEC.md "Data formats").
RUN_COLUMNS = ("time", "disturbance", "output", "control")
#: Columns a run may have: the target, and the displayed error e = reference - output (the
#: reference where a laboratory logged the error and not the target).
OPTIONAL_COLUMNS = ("reference", "error")


def parse_columns(spec: str | Mapping[str, str] | None) -> dict[str, str]:
    """A column mapping, checked: ``"control=stick,output=p"`` (or a mapping) into ``{"control":
    "stick", ...}``.

    Parameters
    ----------
    spec : str, mapping or None
        ROLE=NAME pairs separated by commas, or role -> column name; None or "" for none.

    Returns
    -------
    dict
        Role -> column name.

    Raises
    ------
    HesspipeError
        A pair without ``=``, an unknown role, an empty name, a key column with ``*``.
    """
    if not spec:
        return {}
    if isinstance(spec, Mapping):
        pairs = dict(spec)
    else:
        pairs = {}
        for item in str(spec).split(","):
            if not item.strip():
                continue
            if "=" not in item:
                raise HesspipeError(f"columns: expected ROLE=NAME pairs separated by commas, got {item!r}")
            role, name = (s.strip() for s in item.split("=", 1))
            pairs[role] = name
    for role in pairs:
        if role not in RUN_COLUMNS + OPTIONAL_COLUMNS + KEY_COLUMNS:
            raise HesspipeError(f"columns: unknown role {role!r}; expected one of "
                                f"{', '.join(RUN_COLUMNS + OPTIONAL_COLUMNS + KEY_COLUMNS)}")
        if not isinstance(pairs[role], str) or not pairs[role].strip():
            raise HesspipeError(f"columns: role {role!r}: expected a column name, got {pairs[role]!r}")
        if role in KEY_COLUMNS and RUN_NUMBER in pairs[role]:
            raise HesspipeError(f"columns: role {role!r}: {pairs[role]!r}: expected the name of the column "
                                "whose values tell runs apart, without '*'")
        if "|" in pairs[role] and not all(alt.strip().lstrip("-").strip() for alt in pairs[role].split("|")):
            raise HesspipeError(f"columns: role {role!r}: {pairs[role]!r}: expected column names separated by "
                                "'|', got an empty one")
        if pairs[role].count(RUN_NUMBER) > 1:
            raise HesspipeError(f"columns: role {role!r}: {pairs[role]!r} holds {pairs[role].count(RUN_NUMBER)} "
                                f"'{RUN_NUMBER}'; expected at most one, standing for a run's number")
    return pairs


def columns_for_condition(columns: str | Mapping[str, str] | None, value: str) -> str | dict | None:
    """`columns` reading one condition of a long table that holds several.

    Parameters
    ----------
    columns : str or mapping or None
        A role → column mapping (:func:`~hesspipe.core.formats.read_file_runs`).
    value : str
        The condition to read, e.g. ``"motion"``.

    Returns
    -------
    str or dict or None
        `columns` itself, unless it maps ``condition`` to a column without a value: then
        the mapping with ``condition=COLUMN=value``.
    """
    mapping = parse_columns(columns)
    name = mapping.get("condition")
    if name is None or "=" in name:
        return columns
    return {**mapping, "condition": f"{name}={value}"}
