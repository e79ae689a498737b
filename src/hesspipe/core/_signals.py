"""A run's signals checked where they are built (private; :class:`hesspipe.core.formats.Run`
calls it): what the readers check of a file, for arrays a researcher builds in memory.

A reader's run passes these checks by construction (its time is a uniform grid); arrays built
in memory (a pandas Series, a list, float32, a MATLAB-style column vector) are taken as the
one-dimensional float64 arrays every analysis expects, and a mistake (a sample missing from
one signal, a NaN, time in milliseconds, a gap) is refused here in one line, not deep in an
analysis as a NumPy traceback or a silently wrong spectrum.
"""

from __future__ import annotations

import numpy as np

from ._time import MAX_INTERVAL_S, MIN_INTERVAL_S, UNIFORM_RTOL, sample_interval
from .errors import HesspipeError

#: A run's signals, time first.
SIGNALS = ("time", "disturbance", "output", "control", "reference")


def _vector(where: str, name: str, value) -> np.ndarray:
    """`value` as a 1-D float64 array: a column or row vector (N x 1, 1 x N) is flattened."""
    try:
        x = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise HesspipeError(f"{where}: field '{name}': expected an array of numbers, got "
                            f"{type(value).__name__}") from None
    if x.ndim == 2 and 1 in x.shape:
        x = x.reshape(-1)
    if x.ndim != 1:
        raise HesspipeError(f"{where}: field '{name}': expected a 1-D array of samples, got shape "
                            f"{x.shape}")
    return x


def checked_signals(where: str, signals: dict, interval: float = 0.0) -> dict:
    """The run's signals as 1-D float64 arrays, checked.

    Parameters
    ----------
    where : str
        The run in messages (its file, else ``Run 'id'``).
    signals : dict
        ``time`` (s) and ``disturbance``, ``output``, ``control``, ``reference`` (each an
        array-like of samples; ``reference`` None: zeros, a task without a target).
    interval : float
        The reader's sample interval, s (0: the run was built in memory; its time is then
        checked as a reader checks a file's: uniform, plausible seconds).

    Returns
    -------
    dict
        The same keys, 1-D float64 arrays of one length.

    Raises
    ------
    HesspipeError
        Naming `where` and the field: not numbers, not 1-D, a length unlike time's, fewer
        than 2 samples, a non-finite value, time not increasing, not uniform or not in
        plausible seconds.
    """
    t = _vector(where, "time", signals["time"])
    out = {"time": t}
    for name in SIGNALS[1:]:
        value = signals[name]
        x = np.zeros_like(t) if value is None and name == "reference" else _vector(where, name, value)
        if x.shape != t.shape:
            raise HesspipeError(f"{where}: field '{name}': expected {t.size} samples like time, got {x.size}")
        out[name] = x
    if t.size < 2:
        raise HesspipeError(f"{where}: field 'time': expected a record of at least 2 samples, got {t.size}")
    for name, x in out.items():
        bad = ~np.isfinite(x)
        if bad.any():
            i = int(np.argmax(bad))
            at = f"at t = {t[i]:.6g} s" if name != "time" else f"at sample {i}"
            raise HesspipeError(f"{where}: field '{name}': a non-finite value ({float(x[i])}) {at}; "
                                "expected a continuous record (cut the run or fill its gap first)")
    if interval > 0:
        return out   # a reader's grid, checked against the file's written times
    steps = np.diff(t)
    if not np.all(steps > 0):
        i = int(np.argmax(steps <= 0))
        raise HesspipeError(f"{where}: field 'time': expected strictly increasing times, not after "
                            f"sample {i} (t = {t[i]:.6g} s)")
    slope = (t[-1] - t[0]) / (t.size - 1)
    # Arrays computed as n * dt are uniform to float64 precision; only where they are not
    # (times read from text, rounded) is the reader's rounding-aware rule worth its cost.
    if not np.all(np.abs(steps - slope) <= UNIFORM_RTOL * slope + 4 * np.spacing(np.abs(t[1:]))):
        dt, uniform = sample_interval(where, t)
        if not uniform:
            i = int(np.argmax(np.abs(steps - dt)))
            raise HesspipeError(f"{where}: field 'time': an interval of {steps[i]:.6g} s after t = "
                                f"{t[i]:.6g} s; expected uniform samples every {dt:.6g} s (interpolate "
                                "the record onto a uniform grid first)")
    if not MIN_INTERVAL_S <= slope <= MAX_INTERVAL_S:
        # The readers' bounds (hesspipe.core._time); the remedy is the array's, not a header's.
        hint = (" (milliseconds? divide by 1000; sample numbers? divide by the sample rate)"
                if slope > MAX_INTERVAL_S else " (seconds divided by 1000 twice?)")
        raise HesspipeError(f"{where}: field 'time': sample interval {slope:g} s ({1.0 / slope:.3g} Hz) is "
                            f"implausible for a tracking run; expected seconds with an interval from "
                            f"{MIN_INTERVAL_S:g} to {MAX_INTERVAL_S:g} s{hint}")
    return out
