"""Reading the text files laboratories write: encodings, delimiters, headers with units.

The measured-run format (SPEC.md) is a comma-separated file with a header row. Files from
recorders and spreadsheets are that format written in other hands: UTF-16 from Excel's
"Unicode text", Windows-1252 from older tools, tab or semicolon separators (the latter
with decimal commas in European locales), capitalised headers, and a unit beside a name
(``Time [s]``, ``roll rate (deg/s)``). They are valid input; this module reads them into
the roles the caller asks for and converts the units it knows to SPEC.md's
(:data:`UNIT_FACTORS`), saying what it did (:attr:`Table.notes`).
"""

from __future__ import annotations

import io as _io
import math
import re
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Mapping

import numpy as np
import pandas as pd

from .errors import HesspipeError
from .io import read_bytes

_DEG = math.pi / 180.0
_FT = 0.3048  # m per ft
_ANGLES = {"rad": 1.0, "rad/s": 1.0, "rad/s2": 1.0, "rad/s^2": 1.0,
           "deg": _DEG, "deg/s": _DEG, "deg/s2": _DEG, "deg/s^2": _DEG, "°": _DEG, "°/s": _DEG}
UNIT_FACTORS: dict[str, dict[str, float]] = {
    "time": {"s": 1.0, "sec": 1.0, "ms": 1e-3},
    "output": dict(_ANGLES),
    "reference": dict(_ANGLES),
    "control": dict(_ANGLES),
    "disturbance": {**_ANGLES, "ft/s": 1.0, "fps": 1.0, "m/s": 1.0 / _FT,
                    "kt": 1852.0 / 3600.0 / _FT, "kn": 1852.0 / 3600.0 / _FT},
}
"""Role → unit written in a header → factor to SPEC.md's unit: time s; angles and their rates
in radians on every signal (hesspipe's convention, as the plants' roll rate in rad/s); a
wind disturbance in ft/s. A unit not listed (a stick's N, a normalised command) is taken as
written, in the plants' units, and noted."""

_DIMENSIONLESS = ("", "-", "1", "none", "n/a", "norm", "normalised", "normalized")
_UNIT = re.compile(r"^(?P<name>.*?)\s*(?:\[(?P<u1>[^\]]*)\]|\((?P<u2>[^)]*)\))\s*$")
_DECIMAL_COMMA = re.compile(r"^\s*[+-]?\d+,\d+(?:[eE][+-]?\d+)?\s*$")


@dataclass(frozen=True)
class Table:
    """Columns read by role.

    Attributes
    ----------
    data : dict of str to ndarray
        Role → float array in SPEC.md's units (all finite).
    comments : tuple of str
        The file's ``#`` comment lines, without the ``#``.
    columns : dict of str to str
        Role → the header the values came from.
    notes : tuple of str
        What reading did beyond the plain format (a delimiter, a unit converted or taken as
        written), one sentence each.
    """

    data: dict
    comments: tuple
    columns: dict
    notes: tuple


def decode(path: str | Path, what: str) -> tuple[str, str]:
    """The text of `path` and the encoding it was read with.

    UTF-8 (with or without a byte-order mark), UTF-16 with a byte-order mark, else
    Windows-1252 (what spreadsheets on Windows write); a file with NUL bytes or other
    control characters after decoding is not text.

    Parameters
    ----------
    path : path
        The file.
    what : str
        What it should be, for messages ("a measured-run CSV").

    Returns
    -------
    text : str
    encoding : str
        The codec that read it ("utf-8-sig", "utf-16" or "cp1252").

    Raises
    ------
    HesspipeError
        Naming the file and what it should be.
    """
    path = Path(path)
    raw = read_bytes(path, what)
    if raw[:2] in (b"\xff\xfe", b"\xfe\xff"):
        candidates = ("utf-16",)
    else:
        candidates = ("utf-8-sig", "cp1252") if b"\x00" not in raw else ()
    for enc in candidates:
        try:
            text = raw.decode(enc)
        except UnicodeDecodeError:
            continue
        # A numeric table is mostly ASCII whatever its comments: bytes that decode to
        # control characters or to mostly other scripts are not one.
        if text and not re.search(r"[\x00-\x08\x0b\x0c\x0e-\x1f\x7f\ufffd]", text) and \
                sum(ord(c) > 127 for c in text) <= 0.3 * len(text):
            return text, enc
        if not text:
            return text, enc
    raise HesspipeError(f"{path}: not a text file (UTF-8, UTF-16 or Windows-1252), expected {what}")


def _dialect(text: str) -> tuple[str, str]:
    """(delimiter, decimal) of a table: the separator among comma, tab and semicolon that
    splits the header into the most fields and the first data lines into as many (a
    trailing separator allowed); whitespace when none splits it. A decimal comma is read
    only with tabs or semicolons, when the data show one."""
    lines = [ln for ln in text.splitlines() if ln.strip() and not ln.lstrip().startswith("#")]
    if not lines:
        return ",", "."
    header, body = lines[0], lines[1:50]
    best, width = None, 1
    for sep in (",", "\t", ";"):
        n = len(header.split(sep))
        fits = all(len(ln.split(sep)) in (n, n + 1) for ln in body)
        if n > width and (fits or sep == ","):
            best, width = sep, n
    if best is None:
        return (r"\s+", ".") if len(header.split()) > 1 else (",", ".")
    decimal = "." if best == "," else (
        "," if any(_DECIMAL_COMMA.match(f) for ln in body for f in ln.split(best)) else ".")
    return best, decimal


def _split_unit(header: str) -> tuple[str, str | None]:
    m = _UNIT.match(header)
    if not m:
        return header.strip(), None
    return m.group("name").strip(), (m.group("u1") if m.group("u1") is not None else m.group("u2")).strip()


def _match(path, headers: list[str], role: str, name: str) -> str | None:
    """The header of `role` (asked for as `name`): the exact name, else the one whose name,
    ignoring case and a unit in brackets, is `name`; two such headers are an error."""
    if name in headers:
        return name
    want = name.strip().lower()
    found = [h for h in headers if _split_unit(h)[0].lower() == want or h.strip().lower() == want]
    if len(found) > 1:
        raise HesspipeError(f"{path}: columns {', '.join(repr(h) for h in found)} all read as "
                            f"'{name}' (role {role}); expected one")
    return found[0] if found else None


def read_table(path: str | Path, names: Mapping[str, str], *, optional=(), what: str = "a CSV",
               hint: str | None = None) -> Table:
    """Read numeric columns by role from a delimited text file with ``#`` comment lines.

    Parameters
    ----------
    path : path
    names : mapping
        Role → column name (matched exactly, else ignoring case and a unit in brackets; a
        file without that name may use the role's own, e.g. ``time``; ``-NAME`` reads
        NAME with its sign flipped); every role is required unless listed in `optional`.
    optional : sequence of str
        Roles that may be missing (left out of the result); an optional column left empty
        in every row counts as missing.
    what : str
        What the file should be, for messages ("a measured-run CSV").
    hint : str, optional
        Name of the setting that maps other column names (named in the message,
        e.g. "columns": "map other names with columns control=NAME").

    Returns
    -------
    Table

    Raises
    ------
    HesspipeError
        Naming the file, the column and the problem.
    """
    path = Path(path)
    text, encoding = decode(path, what)
    notes = [] if encoding in ("utf-8-sig",) else [f"read as {encoding} text"]
    comments = tuple(line.lstrip()[1:].strip() for line in text.splitlines()
                     if line.lstrip().startswith("#"))
    sep, decimal = _dialect(text)
    if sep != ",":
        notes.append({"\t": "tab-separated", ";": "semicolon-separated"}.get(sep, "whitespace-separated")
                     + (" with decimal commas" if decimal == "," else ""))
    try:
        with warnings.catch_warnings():
            # index_col=False: a separator ending every data line (loggers write one) must not
            # make pandas take the first column as an index and shift the names onto the next.
            # More values than names is then pandas' warning, here an error.
            warnings.simplefilter("error", pd.errors.ParserWarning)
            df = pd.read_csv(_io.StringIO(text), comment="#", skipinitialspace=True, sep=sep,
                             decimal=decimal, index_col=False,
                             engine="python" if sep == r"\s+" else "c")
    except pd.errors.ParserWarning:
        raise HesspipeError(f"{path}: data rows hold more values than the header has names; "
                            "expected one value per named column") from None
    except (pd.errors.ParserError, pd.errors.EmptyDataError) as exc:
        raise HesspipeError(f"{path}: not a readable CSV ({str(exc).splitlines()[0]})") from None
    df.columns = [str(c).strip() for c in df.columns]
    headers = list(df.columns)
    data, used = {}, {}
    flipped = set()
    for role, name in names.items():
        col = _match(path, headers, role, name)
        if col is None and name.startswith("-") and name[1:].strip():
            # "-NAME": the column NAME with its sign flipped (a stick convention opposite
            # to the plants').
            col = _match(path, headers, role, name[1:].strip())
            if col is not None:
                flipped.add(role)
        if col is None and name != role:
            # A mapping written for some files of a folder: the others keep the plain names.
            col = _match(path, headers, role, role)
        if col is not None and role in optional and df[col].isna().all():
            col = None  # a column written but left empty: the default, as if absent
        if col is None:
            if role in optional:
                continue
            tail = f"; map other names with {hint} {role}=NAME" if hint else ""
            label = f" (role {role})" if role != name else ""
            raise HesspipeError(f"{path}: column '{name}' missing{label}; found columns: "
                                f"{', '.join(headers)}{tail}")
        data[role], used[role] = pd.to_numeric(df[col], errors="coerce").to_numpy(dtype=float), col
    first, stop = _complete_rows(data)
    bad = {role: first + int(np.argmax(~np.isfinite(v[first:stop]))) for role, v in data.items()
           if not np.isfinite(v[first:stop]).all()}
    if bad:
        role = min(bad, key=lambda r: bad[r])   # the earliest bad value in the file
        col, row = used[role], bad[role]
        value = df[col].iloc[row]
        got = "an empty or NaN cell" if pd.isna(value) else repr(value)
        raise HesspipeError(f"{path}: column '{col}': expected finite numbers, got {got} "
                            f"in data row {row + 1}")
    if (first, stop) != (0, len(df)):
        notes.append(f"dropped {first} incomplete row(s) at the start and {len(df) - stop} at the end "
                     f"(a value missing or not a number); data rows {first + 1}-{stop} read")
    for role, col in used.items():
        values = data[role][first:stop]
        if role in flipped:
            values = -values
            notes.append(f"column '{col}' ({role}): sign flipped, as mapped")
        unit = _split_unit(col)[1]
        if unit:
            factor = UNIT_FACTORS.get(role, {}).get(unit.lower().replace(" ", ""))
            if factor is None and unit.lower() not in _DIMENSIONLESS:
                notes.append(f"column '{col}' ({role}): unit '{unit}' taken as written")
            elif factor is not None and factor != 1.0:
                values = values * factor
                notes.append(f"column '{col}' ({role}): {unit} converted to SPEC.md's units (x {factor:.6g})")
        data[role] = values
    return Table(data, comments, used, tuple(notes))


def _complete_rows(data: Mapping[str, np.ndarray]) -> tuple[int, int]:
    """(first, stop) of the rows to read: incomplete rows (a value missing or not a number)
    at the start and end of a record are dropped, as a recorder's empty first row or a last
    line cut short leave them, while at least 90 % of the rows remain; otherwise every row.
    A bad value between complete rows stays for the caller to name."""
    if not data:
        return 0, 0
    ok = np.logical_and.reduce([np.isfinite(v) for v in data.values()])
    n = ok.size
    if ok.all() or not ok.any():
        return 0, n
    first = int(np.argmax(ok))
    stop = n - int(np.argmax(ok[::-1]))
    return (first, stop) if stop - first >= 0.9 * n else (0, n)
