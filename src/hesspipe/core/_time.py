"""A run's time column: its sample interval, whether it is uniform, and its grid.

Recorders write times rounded to a few digits, as epoch stamps or in milliseconds, with a
little jitter; the interval is estimated over the whole record and "uniform" allows what
the writing explains (SPEC.md "Time").
"""

from __future__ import annotations

import math

import numpy as np
from scipy.optimize import minimize_scalar
from scipy.signal import decimate

from .errors import HesspipeError

#: "Uniform" sampling (SPEC.md "Time"): every interval within this fraction of the
#: interval, beyond what the precision the times are written with explains.
UNIFORM_RTOL = 1e-4
#: Longest sample interval of a plausible tracking run, s (10 Hz: the paper's fitness band
#: reaches 5 Hz). Sample numbers, or milliseconds at 1 kHz, read as seconds give 1 s;
#: milliseconds at 50-100 Hz give 10-20 s.
MAX_INTERVAL_S = 0.1
#: Shortest sample interval of a plausible tracking run, s (10 kHz; seconds labelled as
#: milliseconds give 1e-5 s).
MIN_INTERVAL_S = 1e-4
#: Lowest rate a record too long to analyse at its logged rate is decimated to, Hz: the
#: forcing lines and the neuromuscular mode lie below 4 Hz (25 rad/s), the paper's fitness
#: band below 5 Hz, so 50 Hz (SPEC.md's recording rate) keeps all of them well inside the
#: anti-alias filter's pass band.
MIN_DECIMATED_HZ = 50.0


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


def check_sample_rate(sample_rate) -> float | None:
    """`sample_rate` (Hz) checked: None, or a finite number whose interval a tracking run can
    have (:data:`MIN_INTERVAL_S` to :data:`MAX_INTERVAL_S`).

    Parameters
    ----------
    sample_rate : float or None
        Hz.

    Returns
    -------
    float or None

    Raises
    ------
    HesspipeError
        Naming ``sample_rate`` and what was expected.
    """
    if sample_rate is None:
        return None
    if isinstance(sample_rate, bool) or not isinstance(sample_rate, (int, float)) or not math.isfinite(sample_rate) \
            or sample_rate * MAX_INTERVAL_S < 1.0 or sample_rate * MIN_INTERVAL_S > 1.0:
        raise HesspipeError(f"sample_rate: expected a number of Hz from {1.0 / MAX_INTERVAL_S:g} to "
                            f"{1.0 / MIN_INTERVAL_S:g}, got {sample_rate!r}")
    return float(sample_rate)


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


def coarse_interval(rel: np.ndarray, resolution: np.ndarray) -> float | None:
    """The sample interval of times written more coarsely than they advance, or None.

    A logger at 500 Hz that writes its times to 0.01 s repeats each stamp about five times
    (0.00, 0.00, 0.00, 0.01, ...). Such times are uniform samples rounded: there is a grid
    ``t0 + dt k`` from which every written time lies at most half its last digit away (a
    time exactly between two digits may be rounded either way, so the written times spread
    over a whole digit about the grid). The interval is the one whose grid leaves the
    smallest spread; where even that spread is wider than a digit (samples dropped beyond
    what the rounding hides, a clock that drifts) or a time goes back, None. One sample
    dropped among stamps five samples coarse cannot show and is read as uniform.

    Parameters
    ----------
    rel : ndarray
        Times relative to the first, s.
    resolution : ndarray
        Place value of the last digit each time was written with, s.

    Returns
    -------
    float or None
        The interval, s, or None where the times are not coarsely written uniform samples.
    """
    steps = np.diff(rel)
    res = float(np.median(resolution))
    if rel.size < 3 or np.any(steps < 0) or rel[-1] <= 0:
        return None
    k = np.arange(rel.size, dtype=float)
    kc = k - k.mean()
    ls = float(np.dot(kc, rel - rel.mean()) / np.dot(kc, kc))
    if not 0.0 < ls < res:   # written finely enough to advance: a repeated time is a fault
        return None

    base = rel - ls * k   # searched as a correction to the slope: dt itself has too few digits

    def spread(u: float) -> float:
        off = base - u * k
        return float(off.max() - off.min())

    # The spread is convex in the slope (a maximum of linear functions less a minimum); the
    # least-squares slope is within a digit over the record of its minimum.
    span = 2.0 * res / (rel.size - 1)
    best = minimize_scalar(spread, bounds=(-span, span), method="bounded", options={"xatol": 1e-9 * span})
    u = float(best.x) if spread(float(best.x)) <= spread(0.0) else 0.0
    tol = res * (1.0 + 1e-6) + 8.0 * np.spacing(abs(rel[-1]) + res)
    return ls + u if spread(u) <= tol else None


def coarse_note(t: np.ndarray, column: str, dt: float) -> tuple[str, ...]:
    """The note for times :func:`sample_interval` read as coarsely written (repeated), or ().

    Parameters
    ----------
    t : ndarray
        The times as written, s.
    column : str
        The time column's name.
    dt : float
        The sample interval read, s.

    Returns
    -------
    tuple of str
        One note where a time repeats the one before, else empty.
    """
    repeats = int(np.sum(np.diff(np.asarray(t, dtype=float)) <= 0))
    if not repeats:
        return ()
    return (f"column '{column}': {repeats} times repeat the one before (written more coarsely than "
            f"the samples advance): read as uniform samples at {1.0 / dt:.6g} Hz",)


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
    # What writing the times to text explains: half a last digit on each end, plus the
    # float64 spacing of the absolute times (epoch stamps) and of their difference.
    res = _written_resolution(t) if resolution is None else np.asarray(resolution, dtype=float)
    if res.shape != t.shape or not np.all(np.isfinite(res)):
        res = _written_resolution(t)
    if np.any(steps <= 0):
        coarse = coarse_interval(rel, res)
        if coarse is not None:
            return coarse, True
        row = int(np.argmax(steps <= 0)) + 1
        written = float(np.median(res))
        if np.all(steps >= 0) and rel[-1] > 0 and written * (rel.size - 1) > rel[-1]:
            # Repeats of stamps written more coarsely than the samples advance, not a fault
            # of the order: say why they were not read as uniform samples.
            raise HesspipeError(f"{path}: column '{column}': times written to {written:g} s repeat (more "
                                "coarsely than the samples advance), but no uniform sampling explains "
                                "them within that rounding (a sample dropped, or a clock whose rate "
                                "drifts?); expected uniform samples")
        raise HesspipeError(f"{path}: column '{column}': expected strictly increasing time, "
                            f"not at data row {row + 1}")
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


def decimate_signal(x: np.ndarray, q: int) -> np.ndarray:
    """`x` kept at every `q`-th sample through a zero-phase FIR anti-alias filter
    (:func:`scipy.signal.decimate`): no delay is added, sample k of the result stands at
    sample k q of `x`. The one decimation of a record's signals (long records on reading,
    the control-spectrum criteria's fast records).

    Parameters
    ----------
    x : ndarray
        Samples.
    q : int
        Factor (> 1).

    Returns
    -------
    ndarray
        ``ceil(len(x) / q)`` samples.
    """
    return decimate(np.asarray(x, dtype=float), q, ftype="fir", zero_phase=True)


def decimated(path, data: dict, dt: float, limit: int) -> tuple[dict, float, tuple[str, ...]]:
    """A run's signals with at most `limit` samples: a longer record decimated by the
    smallest whole factor that fits, through a zero-phase anti-alias filter.

    A laboratory logging at 500-1000 Hz writes 300,000 samples in five to ten minutes, more
    than the analyses hold (:data:`hesspipe.core.formats.MAX_SAMPLES`); nothing a pilot
    model or a describing function uses lies above a few hertz. The filter is a symmetric
    FIR (:func:`decimate_signal`), so the decimated signals keep their timing
    (a delay a filter with phase lag added would be identified as the pilot's), and each
    kept sample stands at its original time.

    Parameters
    ----------
    path : str or Path
        The file the run comes from (for messages).
    data : dict of str to ndarray
        Role → samples on a uniform grid, ``"time"`` in s among them.
    dt : float
        Sample interval, s.
    limit : int
        Most samples kept.

    Returns
    -------
    data : dict of str to ndarray
        At most `limit` samples each (`data` itself when it holds no more).
    dt : float
        Sample interval of the result, s.
    notes : tuple of str
        What was done (empty when nothing was).

    Raises
    ------
    HesspipeError
        When the factor needed would take the rate below :data:`MIN_DECIMATED_HZ`.
    """
    n = data["time"].size
    if n <= limit:
        return data, dt, ()
    q = -(-n // limit)
    if q * dt * MIN_DECIMATED_HZ > 1.0 + 1e-9:
        # The longest record this rate allows: the limit at the largest factor that keeps
        # the rate at MIN_DECIMATED_HZ or more (1 below 100 Hz: no decimation at all).
        most = max(1, int(math.floor(1.0 / (dt * MIN_DECIMATED_HZ) + 1e-9)))
        raise HesspipeError(f"{path}: {n} samples at {1.0 / dt:.6g} Hz ({n * dt:.6g} s); expected at most "
                            f"{limit * most * dt:.6g} s at this rate ({limit} samples analysed, decimated "
                            f"to no less than {MIN_DECIMATED_HZ:g} Hz); split the record")
    out = {role: (v[::q] if role == "time" else decimate_signal(v, q)) for role, v in data.items()}
    note = (f"{n} samples at {1.0 / dt:.6g} Hz decimated by {q} to {1.0 / (q * dt):.6g} Hz through a "
            f"zero-phase anti-alias filter (at most {limit} samples per run are analysed)")
    return out, q * dt, (note,)


def advancing(data: dict, resolution: np.ndarray | None, column: str
              ) -> tuple[dict, np.ndarray | None, tuple[str, ...]] | None:
    """A run's rows with those whose time does not pass every earlier one left out, for a
    record that is to be resampled; None where that is no logger's stall.

    A logger whose clock missed a tick writes a row with the time of the one before (or a
    hair earlier); the samples are sound, only the stamp is not, and resampling onto the
    uniform grid fills the row left out. A time that goes back by more than an interval
    (two logs joined, a clock reset), or stalls on more than 1 % of the rows, is no such
    stall: None, and the caller refuses the record.

    Parameters
    ----------
    data : dict of str to ndarray
        Role → values, ``"time"`` (s) among them.
    resolution : ndarray or None
        Place value of each time's last written digit, s (kept in step with the rows).
    column : str
        The time column's name (for the note).

    Returns
    -------
    (data, resolution, notes) or None
    """
    t = np.asarray(data["time"], dtype=float)
    ahead = np.maximum.accumulate(t)
    stalled = np.zeros(t.size, dtype=bool)
    stalled[1:] = t[1:] <= ahead[:-1]
    steps = np.diff(t)
    if not stalled.any() or not (steps > 0).any() or stalled.sum() > 0.01 * t.size:
        return None
    if float(np.max(ahead[:-1][stalled[1:]] - t[1:][stalled[1:]])) > float(np.median(steps[steps > 0])):
        return None
    keep = ~stalled
    first = int(np.argmax(stalled))
    note = (f"column '{column}': {int(stalled.sum())} row(s) whose time does not pass the one before "
            f"left out (the first at data row {first + 1}), then resampled")
    return ({role: v[keep] for role, v in data.items()},
            None if resolution is None else resolution[keep], (note,))


def stretches(mask: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(starts, ends) of the stretches of consecutive True in `mask`: indices, end exclusive.

    Parameters
    ----------
    mask : ndarray of bool

    Returns
    -------
    starts, ends : ndarray of int
    """
    edges = np.flatnonzero(np.diff(np.concatenate(([0], np.asarray(mask).astype(np.int8), [0]))))
    return edges[::2], edges[1::2]


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
        starts, ends = stretches(~ok)
        longest = max(longest, int(np.max(ends - starts)))
    if filled:
        notes.append(f"cells empty or not a number between complete rows interpolated linearly "
                     f"({', '.join(filled)}; at most {longest} in a row)")
    return data, ("missing samples: " + "; ".join(notes),)
