"""A run file's columns, read once and picked by role.

:func:`read_frame` reads a file as written: text in any of the shapes :mod:`._csv` knows, a
MATLAB file (:mod:`._mat`), an Excel workbook's sheet as the text it would be saved as
(:mod:`._excel`). :func:`read_table` picks the caller's roles from it, checks them and converts
their units to SPEC.md's (:data:`hesspipe.core._csv.UNIT_FACTORS`), saying what it did
(:attr:`Table.notes`). A frame read once serves several runs of one file.
"""

from __future__ import annotations

import functools
import io as _io
import re
import warnings
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Mapping

import numpy as np
import pandas as pd

from ._csv import (
    _DIMENSIONLESS,
    _TIME_OF_DAY,
    UNIT_FACTORS,
    _long_row,
    _prepare,
    _split_unit,
    decode,
    target_unit,
    written_unit,
)
from ._excel import EXCEL_SUFFIXES, excel_sheets
from ._h5 import h5_frame
from ._mat import mat_frame
from ._tdms import tdms_frame
from .errors import HesspipeError

#: In a mapped column name, the run's number: ``x:*`` is ``x:1``, ``x:2``, ... (one run each;
#: :mod:`._star` reads them).
RUN_NUMBER = "*"


@dataclass(frozen=True)
class Table:
    """Columns read by role.

    Attributes
    ----------
    data : dict of str to ndarray
        Role → float array in SPEC.md's units (all finite, unless the reader was asked to
        keep missing cells: NaN there).
    comments : tuple of str
        The file's ``#`` comment lines, without the ``#``.
    columns : dict of str to str
        Role → the header the values came from.
    notes : tuple of str
        What reading did beyond the plain format (a delimiter, a unit converted or taken as
        written), one sentence each.
    resolution : dict of str to ndarray
        ``"time"`` → the place value of the last digit each time was written with, in
        SPEC.md's unit (1e-5 s for ``30,01000``): how much of an interval's deviation the
        writing explains. Empty without a time role.
    """

    data: dict
    comments: tuple
    columns: dict
    notes: tuple
    resolution: dict = field(default_factory=dict)


def _resolution(cells) -> np.ndarray:
    """Place value of the last digit each cell was written with (``30,01000`` → 1e-5;
    ``20`` → 1; ``1.5e-3`` → 1e-4); NaN where a cell is not a number."""
    out = np.full(len(cells), np.nan)
    for i, cell in enumerate(cells):
        text = str(cell).strip().strip('"').replace(",", ".")
        mant, _, exp = text.lower().partition("e")
        frac = re.match(r"\d*", mant.partition(".")[2]).group()   # a clock's zone ends the digits
        try:
            out[i] = 10.0 ** (int(exp or 0) - len(frac))
        except ValueError:
            pass
    return out


def _match(path, headers: list[str], role: str, name: str, as_written=None,
           hint: str | None = None) -> str | None:
    """The header of `role` (asked for as `name`): the exact name, else the one whose name,
    ignoring case and a unit in brackets, is `name`, or that is `name` but for case and
    spacing (``Yaw[deg]`` asks for ``Yaw [deg]``, ``yaw (deg)`` too; not ``Yaw [rad]``);
    two such headers are an error. Where the
    file names two columns alike (`as_written`, :attr:`Frame.as_written`) a name matching them
    is an error too, and each of them is mapped by its position instead, a number 1 to k
    (`hint`: the setting that maps columns, for the message)."""
    if name in headers:
        found = [name]
    else:
        want = name.strip().lower()

        def bare(text: str) -> tuple[str, str]:   # (name, unit) without case or spaces
            return tuple((v or "").replace(" ", "").lower() for v in _split_unit(text))

        # A name asked for with its unit: a logger's units row makes 'Yaw [deg]' of 'Yaw' over
        # 'deg', and a user reading the file writes 'Yaw[deg]'.
        asked = bare(name)
        found = [h for h in headers if _split_unit(h)[0].lower() == want or h.strip().lower() == want
                 or (asked[1] and bare(h) == asked)]
    if len(found) > 1:
        raise HesspipeError(f"{path}: columns {', '.join(repr(h) for h in found)} all read as "
                            f"'{name}' (role {role}); expected one")
    if as_written is not None and found:
        alike = as_written[headers.index(found[0])]
        at = [str(i) for i, h in enumerate(as_written, 1) if h == alike]
        if len(at) > 1:
            label = f" (role {role})" if role != name else ""
            where = f"{', '.join(at[:-1])} and {at[-1]}"
            how = f" with {hint} " if hint else ", "
            raise HesspipeError(f"{path}: '{name}'{label} matches columns {where}, "
                                f"{'both' if len(at) == 2 else 'all'} headed '{alike}'; expected one: map the "
                                f"one meant by its position{how}{' or '.join(f'{role}={k}' for k in at)}")
    if as_written is not None and not found and name.strip().isdigit() and 1 <= int(name) <= len(headers) \
            and as_written.count(as_written[int(name) - 1]) > 1:
        return headers[int(name) - 1]
    return found[0] if found else None


_BINARY = {".mat": (mat_frame, "variable"), ".npz": (mat_frame, "variable"), ".tdms": (tdms_frame, "channel"),
           ".h5": (h5_frame, "dataset"), ".hdf5": (h5_frame, "dataset")}
#: Files whose columns have no header row (a unit is never written over them).
BINARY_SUFFIXES = tuple(_BINARY)


@dataclass(frozen=True)
class Frame:
    """A file's columns as written, before any is picked by role (:func:`read_frame`).

    Attributes
    ----------
    path : Path
    df : pandas.DataFrame
        The columns under their headers (by position ``1`` to ``k`` without a header row).
    comments : tuple of str
        The file's comment lines (a MAT file's text variables).
    notes : tuple of str
        What reading did so far.
    decimal : str
        The decimal mark of the text.
    written : callable or None
        Header → that column's cells as text (the time column's resolution); None for a
        binary file.
    others : tuple of str or None
        A MAT file's variables (a TDMS file's channels) of another length; None for text.
    positional : bool
        The file has no header row.
    item : str
        What a binary file's columns are called in messages ("variable", "channel").
    as_written : tuple of str or None
        The headers as written where the file names two columns alike (pandas reads the
        second ``Yaw`` as ``Yaw.1``): a role matching them is refused, and each of them is
        mapped by its position, ``1`` to ``k``, instead; None otherwise.
    left_out : str or None
        The header's last name, left out of :attr:`df` because no data row has a value
        under it (LabVIEW's ``Comment``); None otherwise.
    """

    path: Path
    df: pd.DataFrame
    comments: tuple
    notes: tuple
    decimal: str
    written: object = None
    others: tuple | None = None
    positional: bool = False
    item: str = "variable"
    as_written: tuple | None = None
    left_out: str | None = None

    @property
    def headers(self) -> list[str]:
        """The column names."""
        return list(self.df.columns)


def read_frame(path: str | Path, what: str = "a CSV") -> Frame:
    """Read a run file's columns as written: text, a MATLAB file (or NumPy archive), a TDMS file,
    an HDF5 file or a workbook.

    Parameters
    ----------
    path : path
    what : str
        What the file should be, for messages ("a measured-run CSV").

    Returns
    -------
    Frame

    Raises
    ------
    HesspipeError
        Naming the file and the problem.
    """
    path = Path(path)
    if path.suffix.lower() in _BINARY:
        reader, item = _BINARY[path.suffix.lower()]
        df, comments, notes, others = reader(path)
        return Frame(path, df, tuple(comments), tuple(notes), ".", None, tuple(others), item=item)
    if path.suffix.lower() in EXCEL_SUFFIXES:
        sheets, notes = excel_sheets(path)   # each sheet as the text it would be saved as
        frames = [_text_frame(path, text, list(notes), separator_said=False) for _, text in sheets]
        return frames[0] if len(frames) == 1 else _sheets_frame([name for name, _ in sheets], frames)
    text, encoding = decode(path, what)
    return _text_frame(path, text, [] if encoding in ("utf-8-sig",) else [f"read as {encoding} text"])


def _text_frame(path: Path, text: str, notes: list, separator_said: bool = True) -> Frame:
    """The :class:`Frame` of a table's text (a text file's, or a workbook sheet's)."""
    # A workbook's tabs are ours: not said (separator_said False).
    text, sep, decimal, positional, left_out = _prepare(text, notes, separator_said=separator_said)
    comments = tuple(line.lstrip()[1:].strip() for line in text.splitlines()
                     if line.lstrip().startswith("#"))
    engine = "python" if sep == r"\s+" else "c"
    try:
        with warnings.catch_warnings():
            # index_col=False: a separator ending every data line (loggers write one) must not
            # make pandas take the first column as an index and shift the names onto the next.
            # More values than names is then pandas' warning, here an error.
            warnings.simplefilter("error", pd.errors.ParserWarning)
            df = pd.read_csv(_io.StringIO(text), comment="#", skipinitialspace=True, sep=sep,
                             decimal=decimal, index_col=False, engine=engine)
    except (pd.errors.ParserWarning, pd.errors.ParserError, pd.errors.EmptyDataError) as exc:
        long = _long_row(text, sep)
        if long is not None:
            row, values, names_ = long
            raise HesspipeError(f"{path}: data row {row} holds {values} values where the header "
                                f"names {names_}; expected one value per named column") from None
        if isinstance(exc, pd.errors.ParserWarning):
            raise HesspipeError(f"{path}: data rows hold more values than the header has names; "
                                "expected one value per named column") from None
        if isinstance(exc, pd.errors.EmptyDataError):   # nothing but blank or comment lines
            raise HesspipeError(f"{path}: no header row and no data rows; expected a header naming the "
                                "columns and rows of numbers (an empty export?)") from None
        raise HesspipeError(f"{path}: not a readable CSV ({str(exc).splitlines()[0]})") from None
    df.columns = [str(c).strip() for c in df.columns]
    as_written = None
    if any((m := re.match(r"(.*)\.\d+$", c)) and m.group(1) in df.columns for c in df.columns):
        # pandas renamed a second 'Yaw' to 'Yaw.1': the header row as written tells a name
        # written twice from one that ends in a number.
        head = pd.read_csv(_io.StringIO(text), comment="#", skipinitialspace=True, sep=sep, header=None,
                           nrows=1, dtype=str, index_col=False, engine=engine).iloc[0]
        names = tuple(str(h).strip() for h in head)
        if len(names) == len(df.columns) and len(set(names)) < len(names):
            as_written = names

    @functools.lru_cache(maxsize=None)   # a file of several runs asks once per run
    def written(col: str) -> np.ndarray:
        return pd.read_csv(_io.StringIO(text), comment="#", skipinitialspace=True, sep=sep, index_col=False,
                           usecols=[col], dtype=str, engine=engine)[col].to_numpy()

    return Frame(path, df, comments, tuple(notes), decimal, written, None, positional, as_written=as_written,
                 left_out=left_out)


def _sheets_frame(names: list[str], frames: list[Frame]) -> Frame:
    """A workbook of several sheets of numbers as one frame: the first sheet's columns as
    they are (a run per file), and every sheet's as ``SHEET/COLUMN`` (a sheet per run, read
    with a star: ``Run */Yaw``); sheets of fewer rows padded with empty cells at the end,
    sheets of more rows than the first left out (the first sheet's run stays as it was)."""
    first = frames[0]
    longer = [name for name, fr in zip(names, frames) if len(fr.df) > len(first.df)]
    names, frames = zip(*[(name, fr) for name, fr in zip(names, frames) if name not in longer])
    if len(frames) == 1:
        return replace(first, notes=first.notes + (f"Excel workbook: left out sheet(s) with more rows than "
                                                   f"the first: {', '.join(map(repr, longer))}",))
    parts = [first.df] + [fr.df.add_prefix(f"{name}/") for name, fr in zip(names, frames)]
    df = pd.concat([p.reset_index(drop=True) for p in parts], axis=1)
    n = len(df)
    where = {f"{name}/{col}": (fr, col) for name, fr in zip(names, frames) for col in fr.df.columns}

    def written(col: str) -> np.ndarray:
        fr, own = where.get(col, (first, col))
        cells = fr.written(own)
        return np.concatenate([cells, np.full(n - cells.size, "", dtype=object)]) if cells.size < n else cells

    notes = first.notes + (f"Excel workbook: {len(frames)} sheets of numbers, each sheet's columns also read "
                           "as SHEET/COLUMN (a sheet per run: map them with a star, Run */Yaw)"
                           + (f"; left out, more rows than the first: {', '.join(map(repr, longer))}"
                              if longer else ""),)
    alike = None
    if any(fr.as_written for fr in frames):
        alike = tuple(first.as_written or first.headers) + tuple(
            f"{name}/{h}" for name, fr in zip(names, frames) for h in (fr.as_written or fr.headers))
    return replace(first, df=df, notes=notes, written=written, as_written=alike)


def read_table(path: str | Path | Frame, names: Mapping[str, str], *, optional=(), what: str = "a CSV",
               hint: str | None = None, also: Mapping[str, str] | None = None,
               gaps: bool = False, gaps_hint: str = "") -> Table:
    """Read numeric columns by role from a delimited text file with ``#`` comment lines.

    Parameters
    ----------
    path : path or Frame
        The file, or its columns already read (:func:`read_frame`: several runs in one file).
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
    also : mapping, optional
        Role → what else a missing column's message says (another remedy).
    gaps : bool
        Keep a cell that is empty or not a number between complete rows (a sample the
        logger missed) as NaN for the caller to fill; by default it is an error.
    gaps_hint : str
        What that error says besides (the remedy, e.g. "; set resample to ...").

    Returns
    -------
    Table

    Raises
    ------
    HesspipeError
        Naming the file, the column and the problem.
    """
    frame = path if isinstance(path, Frame) else read_frame(path, what)
    return _by_role(frame, names, optional, hint, also or {}, gaps_hint if not gaps else None)


def _no_number(path, column: str, every_row: bool) -> str:
    """The message for a column without a number in any data row (``every_row`` False: in any
    that has a time)."""
    return (f"{path}: column '{column}': no number in any data row"
            f"{'' if every_row else ' that has a time'}; expected a value in each row")


def _missing(frame: Frame, missing: list[tuple[str, str]], hint: str | None, also: Mapping[str, str]) -> str:
    """:func:`_by_role`'s message for the required columns (role, name asked for) not found."""
    positional, others = frame.positional, frame.others
    item = frame.item if others is not None else "column"
    what = "POSITION" if positional else "NAME"
    names = [f"'{name}'" + (f" (role {role})" if role != name else "") for role, name in missing]
    tail = (f"; map {'them' if positional else 'other names'} with {hint} "
            f"{','.join(f'{role}={what}' for role, _ in missing)}" if hint else "") \
        + "".join(also.get(role, "") for role, _ in missing)
    if len(missing) == 1:
        role, name = missing[0]
        subject = f"{item} '{name}' missing" + (f" (role {role})" if role != name else "")
    else:
        subject = f"{item}s {', '.join(names[:-1])} and {names[-1]} missing"
    headers = ", ".join(frame.headers) + ("" if frame.left_out is None else
                                          f", {frame.left_out} (no number in any data row)")
    tail += _starred_hint(frame.headers, missing)
    if others is not None:
        left = f" (left out, another length: {', '.join(others[:6])})" if others else ""
        return f"{frame.path}: {subject}; found {item}s: {headers}{left}{tail}"
    if positional:
        return (f"{frame.path}: {subject}; the file has no header row, its columns are "
                f"named by position 1-{len(frame.headers)}{tail}")
    return f"{frame.path}: {subject}; found {item}s: {headers}{tail}"


def _starred_hint(headers, missing: list[tuple[str, str]]) -> str:
    """Where a missing name is there once per run (``trial(1).t`` and ``trial(2).t``, ``u1``
    and ``u2``: two numbers at least, the one beside the name), the starred mapping that
    reads them (``time=trial(*).t``): a reviewer's struct array of runs failed on ``time=t``
    with no word of the star."""
    forms = []
    for role, name in missing:
        sign, bare = ("-", name[1:].strip()) if name.startswith("-") else ("", name.strip())
        if not bare:
            continue
        numbers: dict[str, set] = {}
        for h in headers:
            plain = _split_unit(h)[0].strip()
            m = (re.match(rf"^(?:.*\D)?(\d+)\)?[:_. /-]?{re.escape(bare)}$", plain, re.IGNORECASE)
                 or re.match(rf"^{re.escape(bare)}[:_ ]?(\d+)$", plain, re.IGNORECASE))
            if m:
                form = plain[:m.start(1)] + RUN_NUMBER + plain[m.end(1):]
                numbers.setdefault(form, set()).add(int(m.group(1)))
        runs = [form for form, ks in numbers.items() if len(ks) >= 2]
        if runs:
            forms.append(f"{role}={sign}{runs[0]}")
    if not forms:
        return ""
    return (f"; if the file holds a run per number, map each role with '{RUN_NUMBER}' for the "
            f"run's number, e.g. {','.join(forms)}")


def _find(path, headers: list[str], role: str, name: str, as_written,
          hint) -> tuple[str | None, bool, tuple[str, ...]]:
    """(header, sign flipped, the other alternatives' headers found) of `role` mapped to
    `name` (:func:`_match`), or (None, False, ()).

    ``-NAME`` is the column NAME with its sign flipped (a stick convention opposite to the
    plants'); ``A|B`` the first of the alternatives A, B found, each with its own sign (a
    logger whose header changed within a study: ``Time [ms]`` in some files, ``t [s]`` in
    others, one mapping ``time=Time|t`` for the folder). A header written with ``-`` or
    ``|`` is matched as written first.
    """
    col = _match(path, headers, role, name, as_written, hint)
    if col is not None:
        return col, False, ()
    found = []
    for alt in (a.strip() for a in name.split("|")):
        col = _match(path, headers, role, alt, as_written, hint) if alt != name else None
        if col is not None:
            found.append((col, False))
        elif alt.startswith("-") and alt[1:].strip():
            col = _match(path, headers, role, alt[1:].strip(), as_written, hint)
            if col is not None:
                found.append((col, True))
    if not found:
        return None, False, ()
    return (*found[0], tuple(c for c, _ in found[1:] if c != found[0][0]))


def _by_role(frame: Frame, names, optional, hint, also: Mapping[str, str], refuse_gaps: str | None) -> Table:
    """:func:`read_table`'s columns found by role in `frame`, checked and converted."""
    path, df, decimal, written = frame.path, frame.df, frame.decimal, frame.written
    comments = frame.comments
    notes = list(frame.notes)   # a frame read once serves several runs: each its own notes
    headers = list(df.columns)
    data, used = {}, {}
    flipped, missing = set(), []
    for role, name in names.items():
        col, flip, also_found = _find(path, headers, role, name, frame.as_written, hint)
        if flip:
            flipped.add(role)
        if also_found:
            notes.append(f"column '{col}' ({role}) read, the first of '{name}' the file has; "
                         f"{', '.join(repr(c) for c in also_found)} left unread")
        if col is None and name != role:
            # A mapping written for some files of a folder: the others keep the plain names.
            col = _match(path, headers, role, role, frame.as_written, hint)
        if col is not None and role in optional and df[col].isna().all():
            col = None  # a column written but left empty: the default, as if absent
        if col is None:
            if role not in optional:
                missing.append((role, name))
            continue
        data[role], used[role] = _numeric(df[col], decimal), col
        if role == "time" and data[role].size and np.mean(np.isfinite(data[role])) < 0.5:
            clock = _clock(df[col])
            if clock is not None:
                data[role] = clock
                notes.append(f"column '{col}' ({role}): clock times read as seconds from the first")
    if frame.left_out is not None:
        # A header naming more columns than the rows hold values: a column asked for may be
        # the header's last, left out for having no values, not a name the file lacks.
        empty = [m for m in missing if _find(path, [frame.left_out], *m, None, hint)[0] is not None]
        if empty and len(empty) == len(missing):
            raise HesspipeError(_no_number(path, frame.left_out, True))
        missing = [m for m in missing if m not in empty]
    if missing:
        # Every missing column in one message: a file from another logger misses several,
        # and naming them one per attempt cost a user as many runs.
        raise HesspipeError(_missing(frame, missing, hint, also))
    timed = np.isfinite(data["time"]) if "time" in data else np.ones(len(df), dtype=bool)
    for role, v in data.items():
        rows = np.ones(v.size, dtype=bool) if role == "time" else timed
        # Nothing to read, nor to interpolate from: a header naming more columns than the rows
        # hold values, not a missed frame. Cells of text are named below.
        if rows.any() and not np.isfinite(v[rows]).any() and _empty(df[used[role]].iloc[rows]).all():
            raise HesspipeError(_no_number(path, used[role], rows.all()))
    first, stop = _complete_rows(data)
    bad = {}
    for role, v in data.items():
        rows = first + np.flatnonzero(~np.isfinite(v[first:stop]))
        if refuse_gaps is None:   # kept: a missed frame's empty cells, never a cell of text
            rows = rows[~_empty(df[used[role]].iloc[rows])]
        if rows.size:
            bad[role] = int(rows[0])
    if bad:
        role = min(bad, key=lambda r: bad[r])   # the earliest bad value in the file
        col, row = used[role], bad[role]
        value = df[col].iloc[row]
        empty = bool(_empty(df[col].iloc[[row]])[0])
        got = "an empty or NaN cell" if empty else repr(value)
        raise HesspipeError(f"{path}: column '{col}': expected finite numbers, got {got} "
                            f"in data row {row + 1}{refuse_gaps if empty else ''}")
    if (first, stop) != (0, len(df)):
        notes.append(f"dropped {first} incomplete row(s) at the start and {len(df) - stop} at the end "
                     f"(a value missing or not a number); data rows {first + 1}-{stop} read")
    keep = np.arange(first, stop)
    if "time" in used and keep.size > 1:
        # A logger that writes a frame twice repeats the whole row, time included: the
        # record holds it once. Rows that share a time but not their values stay, for
        # the caller to refuse.
        block = np.column_stack([data[role][keep] for role in used])
        again = np.all(block[1:] == block[:-1], axis=1)
        if again.any():
            notes.append(f"dropped {int(again.sum())} row(s) repeating the row before in every column "
                         f"(first data row {int(keep[1:][again][0]) + 1}: a frame written twice)")
            keep = keep[np.concatenate(([True], ~again))]
    resolution = {}
    if "time" in used and written is not None:
        resolution["time"] = _resolution(written(used["time"])[keep])
    for role, col in used.items():
        values = data[role][keep]
        if role in flipped:
            values = -values
            notes.append(f"column '{col}' ({role}): sign flipped, as mapped")
        # pandas' name of a second 'Yaw [deg]', 'Yaw [deg].1', hides the unit written over it.
        unit = written_unit(col if frame.as_written is None else frame.as_written[headers.index(col)], role)
        if unit:
            factor = UNIT_FACTORS.get(role, {}).get(unit.lower().replace(" ", ""))
            if factor is None and unit.lower() not in _DIMENSIONLESS:
                notes.append(f"column '{col}' ({role}): unit '{unit}' taken as written")
            elif factor is not None and factor != 1.0:
                values = values * factor
                notes.append(f"column '{col}' ({role}): {unit} converted to {target_unit(role, unit)} "
                             f"(SPEC.md's units, x {factor:.6g})")
                if role in resolution:
                    resolution[role] = resolution[role] * factor
        data[role] = values
    return Table(data, comments, used, tuple(notes), resolution)


def _clock(column: pd.Series) -> np.ndarray | None:
    """Seconds from the first row of a column of clock times (``14:03:05.120``, a day
    rolled over at midnight, or ISO 8601 ``2026-11-01T14:03:05.120``), NaN where a cell is
    not one; None unless at least 90 % of the cells are."""
    cells = column.astype(str).str.strip().str.strip('"')
    parts = cells.str.extract(_TIME_OF_DAY)
    if parts.notna().all(axis=1).mean() >= 0.9:
        sec = (parts[0].astype(float) * 3600 + parts[1].astype(float) * 60
               + parts[2].str.replace(",", ".", regex=False).astype(float)).to_numpy()
        held = pd.Series(sec).ffill().bfill().to_numpy()   # a cell that is not a time counts no day
        days = np.concatenate(([0], np.cumsum(np.diff(held) < -43200)))
        sec = sec + 86400.0 * days
    else:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            stamps = pd.to_datetime(cells.str.replace(",", ".", regex=False), errors="coerce",
                                    format="ISO8601")
        if stamps.notna().mean() < 0.9:
            return None
        if getattr(stamps.dt, "tz", None) is not None:
            stamps = stamps.dt.tz_convert(None)
        sec = (stamps - stamps[stamps.notna()].iloc[0]).dt.total_seconds().to_numpy(dtype=float)
    first = sec[np.isfinite(sec)][0]
    return sec - first


#: Cells a logger writes for a sample it has not got (lower case, stripped).
_EMPTY_CELLS = frozenset({"", "nan", "-nan", "na", "n/a", "null", "none"})


def _empty(cells: pd.Series) -> np.ndarray:
    """True where a cell is empty or says not-a-number (a missed sample), not text."""
    text = cells.astype(str).str.strip().str.strip('"').str.lower()
    return (cells.isna() | text.isin(_EMPTY_CELLS)).to_numpy(dtype=bool)


def _numeric(column: pd.Series, decimal: str) -> np.ndarray:
    """Floats of a column, NaN where a cell is not a number. pandas applies a decimal comma
    only to columns it reads as numbers: one text cell (``---``, a units row) leaves the
    whole column as text, whose commas are converted here."""
    if decimal == "," and not pd.api.types.is_numeric_dtype(column):
        column = column.astype(str).str.strip().str.strip('"').str.replace(",", ".", regex=False)
    return pd.to_numeric(column, errors="coerce").to_numpy(dtype=float)


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

