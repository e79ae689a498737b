"""Reading the text files laboratories write: encodings, delimiters, headers with units.

The measured-run format (SPEC.md) is a comma-separated file with a header row. Files from
recorders and spreadsheets are that format written in other hands: UTF-16 from Excel's
"Unicode text", Windows-1252 from older tools, tab or semicolon separators (the latter
with decimal commas in European locales), capitalised headers, and a unit beside a name
(``Time [s]``, ``roll rate (deg/s)``), or in a row of their own under the names; lines of
metadata above the header (``Subject: s02``); quoted cells; a frame the logger wrote twice;
no header at all (MATLAB's ``save -ascii``: the columns are then named by position, 1 to k).
They are valid input; this module finds the text's shape (encoding, separator, decimal mark,
where the header is) and the units it knows (:data:`UNIT_FACTORS`); :mod:`._table` reads the
columns into the roles the caller asks for, saying what it did.
"""

from __future__ import annotations

import csv as _csvmod
import math
import re
from pathlib import Path

import numpy as np

from .errors import HesspipeError
from .io import read_bytes

_DEG = math.pi / 180.0
_FT = 0.3048  # m per ft
_ANGLES = {"rad": 1.0, "rad/s": 1.0, "rad/s2": 1.0, "rad/s^2": 1.0,
           "deg": _DEG, "deg/s": _DEG, "deg/s2": _DEG, "deg/s^2": _DEG, "°": _DEG, "°/s": _DEG}
UNIT_FACTORS: dict[str, dict[str, float]] = {
    "time": {"s": 1.0, "sec": 1.0, "ms": 1e-3, "msec": 1e-3},
    "output": dict(_ANGLES),
    "reference": dict(_ANGLES),
    "error": dict(_ANGLES),
    "control": dict(_ANGLES),
    "disturbance": {**_ANGLES, "ft/s": 1.0, "fps": 1.0, "m/s": 1.0 / _FT,
                    "kt": 1852.0 / 3600.0 / _FT, "kn": 1852.0 / 3600.0 / _FT},
}
"""Role → unit written in a header → factor to SPEC.md's unit: time s; angles and their rates
in radians on every signal (hesspipe's convention, as the plants' roll rate in rad/s); a
wind disturbance in ft/s. A unit not listed (a stick's N, a normalised command) is taken as
written, in the plants' units, and noted."""



def target_unit(role: str, unit: str) -> str:
    """The unit that :data:`UNIT_FACTORS` converts `unit` of `role` to ("rad/s" for "deg/s").

    Parameters
    ----------
    role : str
        The column's role (time, output, ...).
    unit : str
        The unit written in its header, as listed in :data:`UNIT_FACTORS`.

    Returns
    -------
    str
    """
    u = unit.lower().replace(" ", "")
    if role == "time":
        return "s"
    if u in _ANGLES:
        return "rad" + u.replace("°", "deg")[3:] if u != "°" else "rad"
    return "ft/s"   # the wind's speeds, the only other unit converted


_DIMENSIONLESS = ("", "-", "1", "none", "n/a", "norm", "normalised", "normalized")
_UNIT = re.compile(r"^(?P<name>.*?)\s*(?:\[(?P<u1>[^\]]*)\]|\((?P<u2>[^)]*)\))\s*$")
_TIME_OF_DAY = re.compile(r"^(\d{1,2}):(\d{2}):(\d{2}(?:[.,]\d+)?)$")
_ISO_DATE = re.compile(r"^\d{4}-\d{2}-\d{2}[T ]\d")
_DECIMAL_COMMA = re.compile(r"^\s*[+-]?\d+,\d+(?:[eE][+-]?\d+)?\s*$")


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


def _is_content(line: str) -> bool:
    """A line of the table: neither blank nor a ``#`` comment."""
    return bool(line.strip()) and not line.lstrip().startswith("#")


def _dialect(text: str) -> tuple[str, str]:
    """(delimiter, decimal) of a table: the separator among comma, tab and semicolon that
    splits the header into the most fields and the first data lines into as many (a
    trailing separator allowed; one line in ten may not, so that a row run together is
    refused by its row rather than the file misread); whitespace when none splits it. A
    decimal comma is read only with tabs or semicolons, when the data show one."""
    lines = [ln for ln in text.splitlines() if _is_content(ln)]
    if not lines:
        return ",", "."
    header, body = lines[0], lines[1:50]
    best, width = None, 1
    # A file without a header row: only a separator that splits its first line into numbers
    # (a decimal comma splits "0,01;2,5" into more fields than the semicolon does).
    numeric = not re.search(r"[A-DF-Za-df-z]", header)
    for sep in (",", "\t", ";"):
        if numeric and not all(_number(c) for c in header.split(sep) if c.strip()):
            continue
        n = len(header.split(sep))
        # n + 1: a separator ending each data line; n - 1: a last name over no values
        # (LabVIEW's "Comment" column).
        misfits = sum(len(ln.split(sep)) not in (n - 1, n, n + 1) for ln in body)
        fits = misfits <= max(1, len(body) // 10) and (misfits < len(body) or not body)
        if n > width and (fits or sep == ","):
            best, width = sep, n
    if best is None:
        return (r"\s+", ".") if len(header.split()) > 1 else (",", ".")
    decimal = "." if best == "," else (
        "," if any(_DECIMAL_COMMA.match(f.strip().strip('"')) for ln in body for f in ln.split(best))
        else ".")
    return best, decimal


def _number(cell: str) -> bool:
    try:
        float(cell.strip().strip('"').replace(",", "."))
    except ValueError:
        return False
    return True


def _cells(line: str, sep: str) -> list[str]:
    return [c.strip().strip('"').strip() for c in line.split(sep)]


_UNIT_WORDS = {u for units in UNIT_FACTORS.values() for u in units} | {u for u in _DIMENSIONLESS if u}


def _layout(lines: list[str]) -> tuple[int, bool]:
    """(header, units) of a table's non-comment lines: the index of the header (lines above
    it are metadata a logger writes, ``Subject: s02``) and whether the line under it holds
    units rather than values (``s;deg;deg``).

    The header is the first line that splits like the middle of the file (a separator
    ending the data lines allowed, or a last name over no values: LabVIEW's ``Comment``),
    is not all numbers, and has the data under it (or a units row, then the data), under
    the separator that finds it earliest (a decimal comma splits data lines into cells
    that are not numbers); a file whose first line is one is left to the plain reading."""
    header = 0
    if len(lines) > 2:
        mid = lines[len(lines) // 2: len(lines) // 2 + 50]
        found = []
        for sep in (",", "\t", ";"):
            counts = sorted(len(ln.split(sep)) for ln in mid)
            n = counts[len(counts) // 2]
            if n < 2 or any(c not in (n - 1, n) for c in counts):
                continue
            if not _values(mid[0], sep):
                continue   # a decimal comma's split of semicolon data ("0,02;0,5" at ",")
            # The data under it: a LabVIEW file's header block has lines that split like the
            # data ("Samples\t400\t400\t400\t400") and passed for the header.
            i = next((i for i, ln in enumerate(lines[:len(lines) // 2])
                      if len(ln.split(sep)) in (n - 1, n, n + 1)
                      and not all(_number(c) for c in ln.split(sep) if c.strip())
                      and (_values(lines[i + 1], sep) or (_unit_row(lines[i + 1], sep) and i + 2 < len(lines)
                                                          and _values(lines[i + 2], sep)))), None)
            if i is not None:
                found.append(i)
        header = min(found, default=0)
    units = False
    if header + 1 < len(lines):
        sep = next((c for c in (",", "\t", ";") if c in lines[header]), None)
        units = _unit_row(lines[header + 1], sep)
    return header, units


def _values(line: str, sep: str | None) -> bool:
    """Every cell of `line` is a number or a time stamp (``14:03:05.120``, ``2026-11-01T…``):
    a data line, not a logger's ``Samples\t400\t400``."""
    cells = [c for c in (_cells(line, sep) if sep else line.split()) if c]
    return bool(cells) and all(_number(c) or _TIME_OF_DAY.match(c) or _ISO_DATE.match(c) for c in cells)


def _unit_row(line: str, sep: str | None) -> bool:
    """`line` holds units (``s;deg;deg;-``), no numbers."""
    cells = _cells(line, sep) if sep else line.split()
    words = [c.strip("[]()").lower().replace(" ", "") for c in cells if c]
    return bool(words) and not any(_number(c) for c in cells if c) and any(w in _UNIT_WORDS for w in words)


def _long_row(text: str, sep: str) -> tuple[int, int, int] | None:
    """(data row, values, names) of the first data row holding more values than the header
    names (counted as the reader counts them: quotes kept together, a separator ending a
    line not a value), or None."""
    rows = [ln for ln in text.splitlines() if _is_content(ln)]
    if len(rows) < 2:
        return None

    def count(line: str) -> int:
        cells = line.split() if sep == r"\s+" else next(_csvmod.reader([line], delimiter=sep))
        while cells and not cells[-1].strip():
            cells.pop()
        return len(cells)

    names = count(rows[0])
    return next(((i, n, names) for i, n in ((i, count(ln)) for i, ln in enumerate(rows[1:], 1))
                 if n > names), None)


def _with_units(header: str, units_row: str, sep: str) -> str:
    """`header` with each name lacking a unit given the one written under it."""
    names = header.split(sep) if sep != r"\s+" else header.split()
    units = _cells(units_row, sep) if sep != r"\s+" else units_row.split()
    # Between spaces-aligned names a space would split 'Yaw [deg]' into two names.
    gap = " " if sep != r"\s+" else ""
    out = []
    for i, name in enumerate(names):
        unit = units[i].strip("[]()").strip() if i < len(units) else ""
        bare = name.strip().strip('"')
        out.append(f"{bare}{gap}[{unit}]" if unit and _split_unit(bare)[1] is None else name)
    return (sep if sep != r"\s+" else " ").join(out)


def _split_unit(header: str) -> tuple[str, str | None]:
    m = _UNIT.match(header)
    if not m:
        return header.strip(), None
    return m.group("name").strip(), (m.group("u1") if m.group("u1") is not None else m.group("u2")).strip()


_TIME_SUFFIX = re.compile(r"[_ ](?P<unit>ms|msec|s|sec)$", re.IGNORECASE)


def written_unit(header: str, role: str) -> str | None:
    """The unit a column's header states: in brackets or parentheses (``Time [ms]``), and for
    the time also as the name's last word after an underscore or a space (``time_ms``,
    ``t_s``), as loggers name it; None where the header states none.

    Parameters
    ----------
    header : str
        The column's name as written.
    role : str
        Its role (time, output, ...). Only the time's suffix is read: milliseconds read as
        seconds spoil the record, where an angle named ``yaw_deg`` is read as written, in the
        plants' units, as it always was.

    Returns
    -------
    str or None
    """
    unit = _split_unit(header)[1]
    if unit is None and role == "time":
        m = _TIME_SUFFIX.search(header.strip())
        unit = m.group("unit") if m else None
    return unit


def _prepare(text: str, notes: list, *, separator_said: bool = True) -> tuple[str, str, str, bool, str | None]:
    """(text, delimiter, decimal, positional, left_out) for pandas: metadata lines above the
    header turned into comments, a units row merged into the header's names, a header of
    positions (``1`` to ``k``; `positional` True) given to a file without one, the header's
    last name left out where no data row has a value under it (`left_out`, else None); what
    was done appended to `notes` (the separator too when `separator_said`)."""
    # A line of whitespace (LabVIEW writes a tab) is blank to pandas only when empty.
    lines = [ln if ln.strip() else "" for ln in text.splitlines()]
    content = [i for i, ln in enumerate(lines) if _is_content(ln)]
    header, units = _layout([lines[i] for i in content])
    if header:
        above = content[:header]
        notes.append(f"read {len(above)} line(s) above the header as comments "
                     f"(from {lines[above[0]].strip()[:40]!r})")
        for i in above:
            lines[i] = "# " + lines[i]
    units_row = None
    if units:
        units_row = lines[content[header + 1]]
        lines[content[header + 1]] = ""
    text = "\n".join(lines)
    sep, decimal = _dialect(text)
    if units_row is not None:
        h = content[header]
        lines[h] = _with_units(lines[h], units_row, sep)
        text = "\n".join(lines)
        notes.append(f"read the row under the header as the columns' units ({units_row.strip()[:40]!r})")
    if sep != "," and separator_said:
        notes.append({"\t": "tab-separated", ";": "semicolon-separated"}.get(sep, "whitespace-separated")
                     + (" with decimal commas" if decimal == "," else ""))
    rows = [i for i, ln in enumerate(lines) if _is_content(ln)]
    left_out = None
    if sep != r"\s+" and len(rows) > 1:
        # A last name over no values (LabVIEW's "Comment"): pandas took the data for a row
        # short of a value, and the file for one with more values than names.
        head = lines[rows[0]].split(sep)
        widths = sorted(len(lines[i].rstrip(sep).split(sep)) for i in rows[1:51])
        if head[-1].strip() and len(head) == widths[len(widths) // 2] + 1 == widths[-1] + 1:
            lines[rows[0]] = sep.join(head[:-1])
            text = "\n".join(lines)
            left_out = head[-1].strip()
            notes.append(f"left out the header's last name {left_out!r}: no data row has a value under it")
    positional = False
    first = rows[0] if rows else None
    cells = None if first is None else [c for c in (lines[first].split() if sep == r"\s+"
                                                    else _cells(lines[first], sep)) if c]
    if cells and all(_number(c) for c in cells):
        # No header row. A comment right above the data naming as many columns is one
        # (``# time disturbance output control``, gnuplot's habit); else (MATLAB's save
        # -ascii, dlmwrite) the columns are named by their position, 1 to k.
        above = lines[first - 1].strip().lstrip("#%").strip() if first and lines[first - 1].lstrip()[:1] == "#" else ""
        names = [c for c in (above.split() if sep == r"\s+" else _cells(above, sep)) if c]
        # Names, not prose: no number, no word ending a clause ("# subject: s02, motion").
        if len(names) == len(cells) and not any(_number(c) or c[-1] in ":,;" for c in names):
            notes.append("read the comment line above the data as the header")
        else:
            names = [str(k) for k in range(1, len(cells) + 1)]
            positional = True
            notes.append(f"no header row: columns named by position, 1 to {len(cells)}")
        lines.insert(first, (" " if sep == r"\s+" else sep).join(names))
        text = "\n".join(lines)
    return text, sep, decimal, positional, left_out


def unwrap_turns(values: np.ndarray) -> tuple[np.ndarray, float | None, int]:
    """An angle logged within one turn (a heading from 0 to 360 deg), unwrapped.

    A step of about one turn (2 pi, or 360 in a column without a unit) between samples whose
    other steps are all below a quarter turn, in a column whose values span at most one
    turn, is the logger wrapping the angle, not motion.

    Parameters
    ----------
    values : ndarray
        The column as read (radians if its unit was given).

    Returns
    -------
    values : ndarray
        Unwrapped (`values` itself when nothing wrapped).
    period : float or None
        The turn found (2 pi or 360), None when nothing wrapped.
    jumps : int
        How many wraps were undone.
    """
    steps = np.diff(values)
    for period in (2.0 * math.pi, 360.0):
        wrap = np.abs(np.abs(steps) - period) < 0.1 * period
        rest = np.abs(steps[~wrap])
        if wrap.any() and (rest.size == 0 or rest.max() < 0.25 * period) and \
                np.ptp(values) <= 1.001 * period:
            return np.unwrap(values, period=period), period, int(wrap.sum())
    return values, None, 0
