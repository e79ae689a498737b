"""A run's time column: its sample interval, whether it is uniform, and its grid.

Recorders write times rounded to a few digits, as epoch stamps or in milliseconds, with a
little jitter; the interval is estimated over the whole record and "uniform" allows what
the writing explains (SPEC.md "Time").
"""

from __future__ import annotations

import numpy as np

from .errors import HesspipeError

#: "Uniform" sampling (SPEC.md "Time"): every interval within this fraction of the
#: interval, beyond what the precision the times are written with explains.
UNIFORM_RTOL = 1e-4
#: Longest sample interval of a plausible tracking run, s (10 Hz: the paper's fitness band
#: reaches 5 Hz). Sample numbers, or milliseconds at 1 kHz, read as seconds give 1 s;
#: milliseconds at 50-100 Hz give 10-20 s.
MAX_INTERVAL_S = 0.1
#: Shortest sample interval of a plausible tracking run, s (10 kHz; seconds labelled as
#: milliseconds give 1e-5 s). A run of the longest length accepted lasts 26 s there.
MIN_INTERVAL_S = 1e-4


def _check_plausible(path, column: str, dt: float, t: np.ndarray | None = None, *, headed: bool = True) -> None:
    """Refuse sample intervals no tracking run has (usually times in milliseconds read as
    seconds, sample numbers, or seconds labelled as milliseconds); `t`, the times read,
    tells whole numbers apart; `headed`: the column has a header a unit can be written in."""
    if dt < MIN_INTERVAL_S:
        hint = (" (the column says milliseconds: are its values seconds?)"
                if "ms" in column.lower().replace(" ", "") else "")
        raise HesspipeError(f"{path}: column '{column}': sample interval {dt:g} s "
                            f"({1.0 / dt:.3g} Hz) is implausible for a tracking run; expected "
                            f"an interval of at least {MIN_INTERVAL_S:g} s{hint}")
    if dt > MAX_INTERVAL_S:
        whole = t is not None and bool(np.all(t == np.round(t)))
        # A unit in the header is converted ('Time [ms]'): the remedy that leaves a logger's
        # file as it is, and the one a newcomer looks for.
        head = f"head the column '{column} [ms]'" if headed else ""
        hint = (" (the times are whole numbers, one apart: sample numbers, or milliseconds? write "
                f"seconds, {head + ', ' if head else ''}or map no time column and give the sample "
                "rate (sample_rate))" if whole and dt == 1.0
                else f" (the time column looks like milliseconds: {head + ' or ' if head else ''}write seconds)"
                if 1.0 < dt <= 100.0 else "")
        raise HesspipeError(f"{path}: column '{column}': sample interval {dt:g} s "
                            f"({1.0 / dt:.3g} Hz) is implausible for a tracking run; expected "
                            f"seconds with an interval of at most {MAX_INTERVAL_S:g} s{hint}")


def _written_resolution(t: np.ndarray) -> np.ndarray:
    """Place value of the last digit each time was written with (from the shortest text
    that reads back as the same float): 1e-7 for ``60.0166667``, 1e-3 for ms stamps."""
    out = np.empty(t.size)
    for i, v in enumerate(t.tolist()):
        mant, _, exp = repr(float(v)).partition("e")
        whole, _, frac = mant.partition(".")
        digits = 0 if frac in ("", "0") else len(frac)
        out[i] = 10.0 ** (int(exp or 0) - digits)
    return out


def _intercept(t: np.ndarray, dt: float) -> float:
    """Offset from ``t[0]`` of the uniform grid with interval `dt` closest to `t`."""
    rel = t - t[0]
    return float(np.mean(rel - dt * np.arange(t.size)))


def sample_interval(path, t: np.ndarray, column: str = "time", *,
                    rtol: float = UNIFORM_RTOL, resolution=None) -> tuple[float, bool]:
    """Sample interval of `t` and whether the sampling is uniform.

    Times are taken relative to the first (Unix-epoch stamps keep their
    precision). The interval is the least-squares slope of time against
    sample number over the whole record (rounding averages out). Uniform
    means every interval is within `rtol` of it plus what the rounding of the
    two written times explains (SPEC.md "Time"). For non-uniform times the grid of a
    resampling is returned: the span over its intervals, each step counted as the whole
    number of median intervals nearest to it (dropped samples and quantised stamps alike).

    Parameters
    ----------
    path : str or Path
        The file `t` comes from (for messages).
    t : array
        Sample times, s.
    column : str
        Name of the time column (for messages).
    rtol : float
        Relative tolerance of a uniform interval.
    resolution : array, optional
        Place value of the last digit each time was written with, s
        (:attr:`hesspipe.core._table.Table.resolution`); by default inferred from the floats,
        which cannot see written trailing zeros (``30.01000`` reads as ``30.01``: a whole
        interval of tolerance at 100 Hz, where a missing sample would pass).

    Returns
    -------
    dt : float
        Sample interval, s (> 0).
    uniform : bool

    Raises
    ------
    HesspipeError
        If `t` is not strictly increasing (naming the file, the column and the row).
    """
    t = np.asarray(t, dtype=float)
    rel = t - t[0]
    steps = np.diff(rel)
    if np.any(steps <= 0):
        row = int(np.argmax(steps <= 0)) + 1
        raise HesspipeError(f"{path}: column '{column}': expected strictly increasing time, "
                            f"not at data row {row + 1}")
    # What writing the times to text explains: half a last digit on each end, plus the
    # float64 spacing of the absolute times (epoch stamps) and of their difference.
    res = _written_resolution(t) if resolution is None else np.asarray(resolution, dtype=float)
    if res.shape != t.shape or not np.all(np.isfinite(res)):
        res = _written_resolution(t)
    rounding = 0.5 * (res[1:] + res[:-1]) + 2.0 * np.spacing(np.abs(t[1:]) + np.abs(t[:-1]))
    # The interval over the whole record (rounded intervals are biased: with 6 digits most
    # 1/60 s steps read 0.0167, so their median is not the interval).
    i = np.arange(t.size, dtype=float)
    i -= i.mean()
    slope = float(np.dot(i, rel - rel.mean()) / np.dot(i, i))
    if slope > 0 and np.all(np.abs(steps - slope) <= rtol * slope + rounding):
        return slope, True
    # The grid of a resampling: the span over the number of intervals it holds, each step
    # counted as the whole number of median steps nearest to it. The median alone is the
    # interval where samples were dropped, but not where stamps are quantised: float32 times
    # 1000 s after a logger's start gave 0.98 ms for 1 ms, and 34 spurious lines.
    med = float(np.median(steps))
    return float(rel[-1] / np.sum(np.maximum(1.0, np.round(steps / med)))), False


def fill_missing(data: dict, columns: dict) -> tuple[dict, tuple[str, ...]]:
    """A run's missing samples filled, and what was done, in a note.

    A logger that misses a frame leaves an empty cell or ``NaN`` between complete rows. A
    row whose time is missing is left out (the uniform grid is then resampled over it); a
    signal's missing cell is interpolated linearly between its neighbours in time (in
    sample number without a time column).

    Parameters
    ----------
    data : dict of str to ndarray
        Role → values, NaN where a cell was missing; complete first and last rows.
    columns : dict of str to str
        Role → the header the values came from (for the note).

    Returns
    -------
    data : dict of str to ndarray
        Finite everywhere.
    notes : tuple of str
        Empty when nothing was missing.
    """
    if all(np.isfinite(v).all() for v in data.values()):
        return data, ()
    notes = []
    if "time" in data and not np.isfinite(data["time"]).all():
        keep = np.isfinite(data["time"])
        data = {role: v[keep] for role, v in data.items()}
        notes.append(f"{int((~keep).sum())} row(s) without a time left out")
    x = data["time"] if "time" in data else np.arange(len(next(iter(data.values()))), dtype=float)
    filled, longest = [], 0
    for role, v in list(data.items()):
        ok = np.isfinite(v)
        if ok.all():
            continue
        data[role] = v.copy()
        data[role][~ok] = np.interp(x[~ok], x[ok], v[ok])
        filled.append(f"'{columns[role]}' {int((~ok).sum())}")
        edges = np.flatnonzero(np.diff(np.concatenate(([0], (~ok).astype(int), [0]))))
        longest = max(longest, int(np.max(edges[1::2] - edges[::2])))
    if filled:
        notes.append(f"cells empty or not a number between complete rows interpolated linearly "
                     f"({', '.join(filled)}; at most {longest} in a row)")
    return data, ("missing samples: " + "; ".join(notes),)
