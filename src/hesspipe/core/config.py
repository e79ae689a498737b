"""Reading TOML configuration with errors that name the file and the field.

Configuration objects elsewhere are small frozen dataclasses; :class:`Fields`
checks type and range of each value and raises
:class:`~hesspipe.core.errors.HesspipeError` with a one-line message such as
``aircraft/737.toml: field 'approach.vc_kts': expected a number > 0, got 'fast'``.

A stage's settings class derives from :class:`Settings`: it is validated on
construction (Python, the command line and TOML all build it the same way, and
all get the same checks: ``FlightConfig: field 'duration_s': expected ...``),
and its ``from_table`` only maps a TOML table onto the constructor, refusing
unknown keys and naming the file and table in the message.
"""

from __future__ import annotations

import dataclasses
import math
import numbers
import tomllib
from pathlib import Path
from typing import Any, Mapping, Sequence

from .errors import HesspipeError
from .io import read_bytes

#: Root of the source tree (holds ``aircraft/`` and ``pipeline/``) when hesspipe runs
#: from a checkout (an editable install); meaningless for an installed wheel.
PROJECT_ROOT = Path(__file__).resolve().parents[3]

#: Where a built package carries copies of ``aircraft/`` and ``pipeline/`` (setup.py).
PACKAGED_DATA = Path(__file__).resolve().parents[1] / "_data"


def data_dir(name: str) -> Path:
    """Return the configuration folder `name` (``"aircraft"`` or ``"pipeline"``).

    From a checkout, the checkout's own folder (the one users edit); from an
    installed package, the copy the build placed in ``hesspipe/_data``.

    Parameters
    ----------
    name : {"aircraft", "pipeline"}
        Which folder.

    Returns
    -------
    Path
        The folder (it exists).
    """
    checkout = PROJECT_ROOT / name
    if (PROJECT_ROOT / "pyproject.toml").is_file() and checkout.is_dir():
        return checkout
    packaged = PACKAGED_DATA / name
    if packaged.is_dir():
        return packaged
    raise HesspipeError(f"{packaged}: folder not found; expected hesspipe's '{name}' folder "
                        "(reinstall hesspipe: the package is incomplete)")


def aircraft_file(name_or_path: str | Path) -> Path:
    """``aircraft/<name>.toml`` for a bare name, else the path itself.

    Parameters
    ----------
    name_or_path : str or Path
        A bare aircraft name (``"b757"``) or a path to a ``.toml`` file.

    Returns
    -------
    Path
        Not checked for existence (:func:`load_toml` reports a missing file).
    """
    p = Path(name_or_path)
    if p.suffix == ".toml" or p.parent != Path("."):
        return p
    return data_dir("aircraft") / f"{name_or_path}.toml"


def load_toml(path: str | Path) -> dict:
    """Load a TOML file, turning I/O and syntax errors into one-line errors.

    Parameters
    ----------
    path : str or Path
        The TOML file (UTF-8, a byte-order mark allowed).

    Returns
    -------
    dict
        Its tables and values.
    """
    path = Path(path)
    data = read_bytes(path, "a TOML file")
    # Editors on Windows start UTF-8 files with a byte-order mark; TOML itself has none.
    data = data.removeprefix(b"\xef\xbb\xbf")
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise HesspipeError(f"{path}: not a TOML text file (not UTF-8 at byte {exc.start}); "
                            "expected a TOML configuration") from None
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise HesspipeError(f"{path}: not valid TOML ({exc})") from None


def merge(base: Mapping, override: Mapping) -> dict:
    """Deep-merge `override` into a copy of `base` (tables merge, values replace).

    Parameters
    ----------
    base, override : mapping
        Nested tables (``override`` wins key by key); neither is modified.

    Returns
    -------
    dict
    """
    out = dict(base)
    for key, value in override.items():
        if isinstance(value, Mapping) and isinstance(out.get(key), Mapping):
            out[key] = merge(out[key], value)
        else:
            out[key] = value
    return out


_MISSING = object()


class FieldError(HesspipeError):
    """A bad value of one configuration field.

    ``field`` is the field's name in its table (or settings class) and
    ``detail`` the rest of the message (``"expected ..., got ..."``), so a
    caller can name the field where it came from (a file's table, a flag).

    Parameters
    ----------
    message : str
        The whole one-line message.
    field : str
        The field's name.
    detail : str
        The message without the field's name.
    """

    def __init__(self, message: str, field: str, detail: str):
        super().__init__(message)
        self.field = field
        self.detail = detail


class Fields:
    """Typed access to one TOML table, for building config dataclasses.

    Parameters
    ----------
    table : mapping
        The parsed table.
    source : str or Path
        File the table came from (for messages).
    prefix : str
        Dotted path of the table inside the file (for messages), e.g. ``"flight"``.
    """

    def __init__(self, table: Mapping | None, source: str | Path, prefix: str = ""):
        if table is not None and not isinstance(table, Mapping):
            raise HesspipeError(f"{source}: field '{prefix}': expected a table, got {table!r}")
        self.table = dict(table or {})
        self.source = str(source)
        self.prefix = prefix
        self.used: set[str] = set()

    def _name(self, key: str) -> str:
        return f"{self.prefix}.{key}" if self.prefix else key

    def error(self, key: str, expected: str, got: Any = _MISSING) -> FieldError:
        """Return (not raise) the error for field `key`.

        Parameters
        ----------
        key : str
            Field name inside this table (the message names it with the table's prefix).
        expected : str
            What the field should hold, e.g. ``"a number >= 0"``.
        got : object, optional
            The offending value (left out: the field is missing).
        """
        tail = "missing" if got is _MISSING else f"got {got!r}"
        return self.fail(key, f"expected {expected}, {tail}")

    def fail(self, key: str, detail: str) -> FieldError:
        """Return (not raise) an error for field `key` with a free-form `detail`.

        Parameters
        ----------
        key : str
            Field name inside this table.
        detail : str
            What is wrong, e.g. ``"expected one of a, b, got 'c'"``.
        """
        return FieldError(f"{self.source}: field '{self._name(key)}': {detail}", key, detail)

    def _get(self, key, default):
        self.used.add(key)
        if key in self.table:
            return self.table[key]
        if default is _MISSING:
            return _MISSING
        return default

    def number(self, key: str, default: Any = _MISSING, *, min: float | None = None,
               max: float | None = None, strict_min: bool = False) -> float | None:
        """A finite real number, optionally bounded (``min <= x <= max``, or ``> min``).

        With ``default=None`` the field is optional and None is returned when absent
        (likewise for :meth:`integer` and :meth:`strings`).

        Parameters
        ----------
        key : str
            Field name.
        default : object, optional
            Value when the field is absent (left out: the field is required; None:
            optional).
        min, max : float, optional
            Bounds, in the field's own units.
        strict_min : bool
            True: require ``x > min``.
        """
        what = "a number"
        if min is not None:
            what += f" {'>' if strict_min else '>='} {min:g}"
        if max is not None:
            what += f"{' and' if min is not None else ''} <= {max:g}"
        value = self._get(key, default)
        if value is _MISSING:
            raise self.error(key, what)
        if value is None and default is None:  # optional field left out (TOML has no null)
            return None
        if isinstance(value, bool) or not isinstance(value, numbers.Real) or not math.isfinite(value):
            raise self.error(key, what, value)
        if min is not None and (value <= min if strict_min else value < min):
            raise self.error(key, what, value)
        if max is not None and value > max:
            raise self.error(key, what, value)
        return float(value)

    def integer(self, key: str, default: Any = _MISSING, *, min: int | None = None,
                max: int | None = None) -> int | None:
        """An integer, optionally bounded.

        Parameters
        ----------
        key : str
            Field name.
        default : object, optional
            Value when absent (left out: required; None: optional).
        min, max : int, optional
            Inclusive bounds.
        """
        what = "an integer" + (f" >= {min}" if min is not None else "") + (
            f" <= {max}" if max is not None else "")
        value = self._get(key, default)
        if value is _MISSING:
            raise self.error(key, what)
        if value is None and default is None:  # optional field left out
            return None
        if isinstance(value, bool) or not isinstance(value, numbers.Integral):
            raise self.error(key, what, value)
        if (min is not None and value < min) or (max is not None and value > max):
            raise self.error(key, what, value)
        return int(value)

    def string(self, key: str, default: Any = _MISSING, *, choices: Sequence[str] | None = None) -> str:
        """A string, optionally one of `choices`.

        Parameters
        ----------
        key : str
            Field name.
        default : object, optional
            Value when absent (left out: required).
        choices : sequence of str, optional
            The allowed values.
        """
        what = "one of " + ", ".join(repr(c) for c in choices) if choices else "a string"
        value = self._get(key, default)
        if value is _MISSING:
            raise self.error(key, what)
        if not isinstance(value, str) or (choices and value not in choices):
            raise self.error(key, what, value)
        return value

    def boolean(self, key: str, default: Any = _MISSING) -> bool:
        """true or false.

        Parameters
        ----------
        key : str
            Field name.
        default : object, optional
            Value when absent (left out: required).
        """
        value = self._get(key, default)
        if value is _MISSING:
            raise self.error(key, "true or false")
        if not isinstance(value, bool):
            raise self.error(key, "true or false", value)
        return value

    def numbers(self, key: str, default: Any = _MISSING, *, length: int | None = None) -> tuple[float, ...]:
        """A list of finite numbers, optionally of a fixed length.

        Parameters
        ----------
        key : str
            Field name.
        default : object, optional
            Value when absent (left out: required).
        length : int, optional
            Required number of elements.
        """
        what = f"a list of {length} numbers" if length else "a list of numbers"
        value = self._get(key, default)
        if value is _MISSING:
            raise self.error(key, what)
        if (not isinstance(value, (list, tuple)) or (length and len(value) != length)
                or not all(isinstance(v, numbers.Real) and not isinstance(v, bool)
                           and math.isfinite(v) for v in value)):
            raise self.error(key, what, value)
        return tuple(float(v) for v in value)

    def strings(self, key: str, default: Any = _MISSING, *,
                choices: Sequence[str] | None = None) -> tuple[str, ...] | None:
        """A list of non-empty strings (optionally each one of `choices`); None if
        absent and `default` is None.

        Parameters
        ----------
        key : str
            Field name.
        default : object, optional
            Value when absent (left out: required; None: optional).
        choices : sequence of str, optional
            The allowed values of each element.
        """
        what = "a list of " + ("names from " + ", ".join(repr(c) for c in choices) if choices
                               else "non-empty strings")
        value = self._get(key, default)
        if value is _MISSING:
            raise self.error(key, what)
        if value is None and default is None:
            return None
        if (not isinstance(value, (list, tuple))
                or not all(isinstance(v, str) and v for v in value)
                or (choices and not set(value) <= set(choices))):
            raise self.error(key, what, value)
        return tuple(value)

    def table_(self, key: str) -> "Fields":
        """The sub-table `key` (empty if absent) as a new :class:`Fields`.

        Parameters
        ----------
        key : str
            Name of the sub-table.
        """
        self.used.add(key)
        return Fields(self.table.get(key), self.source, self._name(key))

    def reject_unknown(self) -> None:
        """Raise if the table holds keys no getter asked for (catches typos)."""
        unknown = sorted(set(self.table) - self.used)
        if unknown:
            raise HesspipeError(f"{self.source}: field '{self._name(unknown[0])}': unknown field "
                                f"(known here: {', '.join(sorted(self.used)) or 'none'})")


class Settings:
    """Base of a stage's frozen settings dataclass: validated on construction.

    A subclass defines ``_checked(self, f: Fields) -> dict``: it reads each field
    with `f` (which holds the instance's own values, so the one set of checks
    serves Python, the command line and TOML) and returns the normalised values
    (floats for numbers, tuples for lists), which are stored. Errors are
    :class:`FieldError` naming the field, e.g. ``DiagnoseConfig: field 'alpha':
    expected a number > 0 and <= 0.5, got 5``.
    """

    def __post_init__(self):
        f = Fields({k.name: getattr(self, k.name) for k in dataclasses.fields(self)}, type(self).__name__)
        for name, value in self._checked(f).items():
            object.__setattr__(self, name, value)  # frozen: normalised once, here

    #: The TOML table the settings come from, named in error messages (a subclass sets it).
    TABLE = ""

    def _checked(self, f: Fields) -> dict:  # pragma: no cover - every subclass defines it
        raise NotImplementedError

    @classmethod
    def from_table(cls, table: Mapping | None, source: str | Path | None = None, prefix: str | None = None):
        """Build from the stage's TOML table: it is only mapped onto the constructor, which
        checks every value; unknown keys are refused.

        Parameters
        ----------
        table : mapping or None
            The table (None: all defaults).
        source : str or Path, optional
            The file it came from, named in error messages (default ``<TABLE defaults>``).
        prefix : str, optional
            The table's name in error messages (default :attr:`TABLE`).
        """
        prefix = cls.TABLE if prefix is None else prefix
        f = Fields(table, f"<{prefix} defaults>" if source is None else source, prefix)
        return cls._from_fields(f, **cls._table_values(f))

    @classmethod
    def _table_values(cls, f: Fields) -> dict:
        """Fields built from sub-tables of `f` (none by default), passed over the table's keys."""
        return {}

    @classmethod
    def _from_fields(cls, f: Fields, **values):
        """``cls(**table keys, **values)``: the table's keys that name fields, `values`
        (already built sub-objects) over them; unknown keys refused; an error names
        the file and the table's field."""
        names = {k.name for k in dataclasses.fields(cls)}
        given = {k: v for k, v in f.table.items() if k in names and k not in values}
        f.used.update(names)  # every field is a key of the table (for the unknown-key message)
        try:
            out = cls(**given, **values)
        except FieldError as exc:
            raise f.fail(exc.field, exc.detail) from None
        f.reject_unknown()
        return out

    def to_dict(self) -> dict:
        """Plain dict (``dataclasses.asdict``), for manifests and reports."""
        return dataclasses.asdict(self)
