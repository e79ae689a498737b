"""The forcing's lines in a record: where they fall, and how much remnant stands at each.

Shared by the equation-error fits of :mod:`.motion_test` and :mod:`.paired_delay`. A
multisine experiment forces the loop on a set of frequency lines (disturbance and/or
target); over an analysis window holding whole periods (:func:`analysis_window`) each line
falls on one FFT bin. Between the lines the loop runs on remnant alone, which measures the
equation error's variance at each line (:func:`line_variances`) without any pilot model.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from ..core.paper import FITNESS_BAND_HZ
from ._window import MIN_LINES, _lines, _window, period_note
from .frf import NEIGHBOURS, _neighbour_bins, _neighbour_residual_power

SMOOTH_ORDER = 2
"""Order of the polynomial in log frequency that smooths the lines' remnant levels."""
MIN_LINE_SNR = 10.0
"""A disturbance line's U/E measures the pilot's describing function for the remnant levels
(:func:`line_variances`) only when its error power is at least this many times its unforced
neighbours' (then the remnant's share of E there is at most about 30 % in amplitude)."""
MAX_EXTRAPOLATED_RISE = math.log(1e6)
"""Largest rise (natural log) of an extrapolated remnant level over the highest level inside
the usable lines' range (:func:`line_variances`): a line a million times noisier than any
measured one carries no weight in the fits."""


def analysis_window(run) -> tuple[int, int]:
    """(start, length) in samples of the window that puts the forcing's lines on exact bins
    (:func:`hesspipe.identification._window._window`: the record, or a whole number of its periods).

    Parameters
    ----------
    run : hesspipe.core.formats.Run
        Its disturbance and reference are the forcing signals.

    Returns
    -------
    (int, int)
        First sample and number of samples of the window.
    """
    start, length, _ = _run_window(run)[2:]
    return int(start), int(length)


def _run_window(run):
    """(disturbance, reference, start, length, purity) of `run`'s :func:`_window`."""
    d = np.asarray(run.disturbance, dtype=float)
    r = np.asarray(run.reference, dtype=float)
    return (d, r, *_window(d, r if np.any(r) else None))


def window_note(run) -> str | None:
    """What the analysis window did with `run`: the note on a record that holds no whole
    period of its multisine (:func:`hesspipe.identification._window.period_note`); else, where
    the window is not the whole record, which stretch it kept (a lab's logged run-in: a
    reviewer could not confirm it was left out); else None.

    Parameters
    ----------
    run : hesspipe.core.formats.Run
        Its disturbance and reference are the forcing signals.

    Returns
    -------
    str or None
        The note.
    """
    d, r, start, length, purity = _run_window(run)
    leaky = period_note([d, r], purity, run.dt)
    if leaky is not None or (start == 0 and length == d.size):
        return leaky
    left = [f"{n * run.dt:.4g} s {where}" for n, where in ((start, "before it"),
                                                           (d.size - start - length, "after it")) if n]
    return (f"the describing function is taken over whole periods of the forcing, {length * run.dt:.4g} s "
            f"from {start * run.dt:.4g} s into the record ({' and '.join(left)} left out)")


def windowed(run):
    """`run` cut to its :func:`analysis_window` (the forcing's lines on exact bins).

    Parameters
    ----------
    run : hesspipe.core.formats.Run
        A record with multisine forcing.

    Returns
    -------
    hesspipe.core.formats.Run
        The same record over the analysis window (`run` itself when that is all of it).
    """
    start, length = analysis_window(run)
    if start == 0 and length == len(run.control):
        return run
    cut = slice(start, start + length)
    return dataclasses.replace(run, time=run.time[cut], disturbance=run.disturbance[cut],
                               output=run.output[cut], control=run.control[cut],
                               reference=run.reference[cut])


def forcing_lines(run, band_hz: tuple[float, float] = FITNESS_BAND_HZ) -> np.ndarray:
    """Indices (into ``numpy.fft.rfft`` of the run as given) of the multisine forcing lines.

    Parameters
    ----------
    run : hesspipe.core.formats.Run
        Disturbance and reference are the forcing signals; pass the analysis window
        (:func:`analysis_window`) so that the lines fall on exact bins.
    band_hz : (float, float)
        Lines are looked for in this band, Hz (DC excluded).

    Returns
    -------
    ndarray of int
        Sorted bin indices; empty if the forcing has no line structure (lines as in
        :mod:`hesspipe.identification.frf`: a bin standing far above its neighbours).
    """

    d_lines, r_lines = _line_sets(run)
    f = np.fft.rfftfreq(len(run.control), run.dt)
    lines = np.union1d(d_lines, r_lines).astype(int)
    inband = (f[lines] > max(band_hz[0], 0.0)) & (f[lines] <= band_hz[1])
    return lines[inband]


SEPARABLE = "disturbance and target"
""":func:`forcing_sets` of a record whose two line sets separate the visual from the
vestibular path: at disturbance lines e = -y, at target lines y = Yc u, so the sets'
disagreement is the vestibular path's. With one set there is one describing function, in
which the two paths act on one signal; only the model's shapes of the paths tell them apart
(multiloop identification needs as many forcing functions as loops)."""


def forcing_sets(run, band_hz: tuple[float, float] = FITNESS_BAND_HZ) -> str:
    """Which multisine line sets a record has: "disturbance and target" (:data:`SEPARABLE`),
    "disturbance only", "target only" or "none".

    Parameters
    ----------
    run : hesspipe.core.formats.Run
        The measured run (disturbance and reference are the forcing signals), read over its
        analysis window (:func:`windowed`).
    band_hz : (float, float)
        Lines count in this band, Hz (DC excluded), as :func:`forcing_lines`'.

    Returns
    -------
    str
    """
    run = windowed(run)
    f = np.fft.rfftfreq(len(run.control), run.dt)
    has = tuple(bool(np.any((f[s] > max(band_hz[0], 0.0)) & (f[s] <= band_hz[1]))) for s in _line_sets(run))
    return {(True, True): SEPARABLE, (True, False): "disturbance only",
            (False, True): "target only", (False, False): "none"}[has]


def _line_sets(run) -> tuple[np.ndarray, np.ndarray]:
    """Bins of the disturbance's and of the reference's multisine lines (all frequencies)."""
    found = []
    for sig in (run.disturbance, run.reference):
        sig = np.asarray(sig, dtype=float)
        found.append(_lines(np.abs(np.fft.rfft(sig - sig.mean())) ** 2) if np.any(sig)
                     else np.zeros(0, dtype=int))
    return found[0].astype(int), found[1].astype(int)


def line_variances(run, lines) -> np.ndarray:
    """Variance of the equation error at each forcing line, from the measured remnant between
    the lines (:func:`hesspipe.identification.frf._neighbour_residual_power`).

    At an unforced bin j the loop runs on remnant alone with e = −y, so whatever the pilot's
    paths, its equation error there is ``U_j − H E_j`` with H the pilot's response to −y:
    the describing function measured at the disturbance's lines (where e = −y too). A line
    of either set takes H from the nearest disturbance line (a record without disturbance
    lines: its own U/E). The levels are then smoothed across the lines (a quadratic in log
    frequency of their logs). No pilot model enters, so the weights do not lean on the original
    model's fit: fitted first, it can absorb part of the remnant-driven bins and understate
    the remnant at the low lines (bench_motion_limit: 1.5-7x on angle tasks).

    Only levels measured with a usable H enter the smoothing: H's line must stand
    :data:`MIN_LINE_SNR` times above the error power of its unforced neighbours. Where the
    remnant makes up most of E at the line, U/E there is the loop's response to the remnant
    (about the inverse plant, far below the pilot's gain), and ``U_j - H E_j`` at the
    neighbours collapses with it (at high loop gain it scales with ``|H_used / H_true|^2``).
    Lines outside the usable ones' frequency range take the smoothed level, but never less
    than at the nearest usable line: an extrapolated quadratic that falls would over-weight
    exactly the lines the remnant dominates.

    Parameters
    ----------
    run : hesspipe.core.formats.Run
        The analysis window (:func:`analysis_window`).
    lines : ndarray of int
        Bins of the lines to weight (:func:`forcing_lines`).

    Returns
    -------
    ndarray
        One variance per line, squared control units per Fourier coefficient.
    """
    return _levels(run, lines)[0]


def _levels(run, lines) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    # line_variances' levels; the H each was measured with; and over the same unforced
    # neighbours the remnant's own U/E at the line, g, and the share of U's power there
    # that E does not explain, c (_remnant_response; LineData.g_remnant, c_remnant).
    d_lines, r_lines = _line_sets(run)
    U = np.fft.rfft(np.asarray(run.control, dtype=float))
    E = np.fft.rfft(np.asarray(run.reference, dtype=float) - np.asarray(run.output, dtype=float))
    src = d_lines[np.isin(d_lines, lines)] if d_lines.size else np.zeros(0, dtype=int)
    if src.size == 0:
        src = np.asarray(lines, dtype=int)
    H_src = U[src] / E[src]
    nearest = np.argmin(np.abs(np.asarray(lines)[:, None] - src[None, :]), axis=1)
    H = H_src[nearest]
    all_lines = np.union1d(d_lines, r_lines).astype(int)
    bins = _neighbour_bins(U.size, lines, all_lines, within=NEIGHBOURS)
    g, c = np.full(len(lines), np.nan, complex), np.full(len(lines), np.nan)
    for i, (k, nb) in enumerate(zip(lines, bins)):
        g[i], c[i] = _remnant_response(U[nb], E[nb], nb / k - 1.0)
    usable = (line_snr(E, src, all_lines) >= MIN_LINE_SNR)[nearest]
    # Only bins within NEIGHBOURS of the line: frf's walk further out reaches, at the lowest
    # lines, bins several times the line's frequency, where the remnant is weaker; the
    # over-weighted low lines then named motion in 3 of 11 static double-integrator runs
    # (bench_motion_calibration, development seeds 100-111; 0 of 11 with this reach).
    raw = _neighbour_residual_power(U, E, H, lines, all_lines, bins=bins)
    ok = np.isfinite(raw) & (raw > 0)
    if ok.sum() < SMOOTH_ORDER + 2:
        return raw, H, g, c
    # JSBSim-flown runs (SYNTHETIC, bench_flown_motion_limit, seeds 0-15): at the lowest
    # 2-6 lines E was 80-90 % remnant and these levels came out 5-50x below the true
    # remnant's; those lines' weight then buried the motion path (ideal weights: 13.4 of 16
    # expected named; these: 9.4).
    if (ok & usable).sum() >= SMOOTH_ORDER + 2:
        ok = ok & usable
    # Between interleaved lines few bins are free, and H at a line carries the line's own
    # remnant: each raw level scatters several-fold. The remnant's spectrum is smooth, so
    # the lines share one: a quadratic in log frequency fitted to the log levels. Against
    # the true remnant of the generator's noise-free twins (development seeds 100-105) the
    # line-to-line scatter of log(true / weight) fell from 1.8 (raw) to 1.3 on roll-angle
    # target runs (1.28 is the scatter of one exponential draw: nothing left to explain).
    x = np.log(np.asarray(lines, dtype=float))
    coef = np.polyfit(x[ok], np.log(raw[ok]), SMOOTH_ORDER)
    level = np.polyval(coef, x)
    lo, hi = x[ok].min(), x[ok].max()
    level[x < lo] = np.maximum(level[x < lo], np.polyval(coef, lo))
    level[x > hi] = np.maximum(level[x > hi], np.polyval(coef, hi))
    # A quadratic through a few usable lines at one end can rise without bound across the
    # rest (4 lines at 2.6-4.4 Hz, extrapolated to 0.03 Hz, overflowed: the test was
    # "unavailable"); such a line weighs nothing at this cap anyway.
    inside = level[(x >= lo) & (x <= hi)]
    return np.exp(np.minimum(level, inside.max() + MAX_EXTRAPOLATED_RISE)), H, g, c


def _remnant_response(U, E, x) -> tuple[complex, float]:
    # U = (a + b x + c x^2) E at unforced bins x = f / f_line - 1, least squares: the
    # remnant's own U/E at the line is a. It is about -1/Yc, a polynomial of degree 2 in s
    # for the textbook plants (exactly so for K/s, K/s^2, K/(s(s + a))). A plain
    # S_ue / S_ee over the neighbours (which reach from 0.2 to 3 times a low line's
    # frequency) is the mean of -1/Yc weighted by |E|^2, i.e. by the lowest bins: 2.3
    # times off at the lowest line of an exact loop (tests/test_motion_weights.py).
    # c: the power E does not explain, over S_ee.
    if x.size < 4:
        return complex(np.nan), float("nan")
    A = E[:, None] * x[:, None] ** np.arange(3)
    coef, *_ = np.linalg.lstsq(A, U, rcond=None)
    rest = U - A @ coef
    return complex(coef[0]), float(np.vdot(rest, rest).real / np.vdot(E, E).real)


def line_snr(E, lines, all_lines) -> np.ndarray:
    """Power of the error at each line over its mean power at the line's unforced neighbours
    (within :data:`~hesspipe.identification.frf.NEIGHBOURS` bins): how far the forcing stands
    above the remnant in E there.

    Parameters
    ----------
    E : ndarray, complex
        Fourier coefficients of the displayed error over the analysis window.
    lines : ndarray of int
        Bins of the lines to rate.
    all_lines : ndarray of int
        Every forcing line's bin (not neighbours).

    Returns
    -------
    ndarray
        One power ratio per line (dimensionless; inf without unforced neighbours).
    """
    lines = np.asarray(lines, dtype=int)
    # frf's neighbour walk with U = E and H = 0: the mean |E_j|^2 at the unforced bins.
    floor = _neighbour_residual_power(E, E, np.zeros(lines.size), lines, np.asarray(all_lines, dtype=int),
                                      within=NEIGHBOURS)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(np.isfinite(floor), np.abs(E[lines]) ** 2 / floor, math.inf)


@dataclass(frozen=True)
class LineData:
    """A record's describing-function lines, as the equation-error fits read them.

    Attributes
    ----------
    lines : ndarray of int
        Bins of the forcing lines (in the analysis window's FFT).
    s : ndarray
        ``j omega`` at the lines, rad/s.
    E, Y, U : ndarray
        Fourier coefficients of the error, output and control at the lines.
    w : ndarray
        Each line's weight, 1 / the measured remnant's standard deviation there.
    both : bool
        The record has disturbance and target lines.
    window_samples : int
        Length of the analysis window, samples.
    reason : str
        Why the lines cannot be used ("" when they can; then the arrays may be empty).
    groups : ndarray of int or None
        The run of each line when repeated runs are pooled (:func:`pooled_line_data`).
    h_level, g_remnant, c_remnant : ndarray or None
        Per line, over its unforced neighbours (:func:`remnant_variance`): the describing
        function the level behind `w` was measured with, the remnant's own U/E there
        (about −1/Yc, control units per error unit) and the share of U's power that E
        does not explain (squared control units per squared error unit).
    """

    lines: np.ndarray
    s: np.ndarray
    E: np.ndarray
    Y: np.ndarray
    U: np.ndarray
    w: np.ndarray
    both: bool
    window_samples: int
    reason: str = ""
    groups: np.ndarray | None = None
    h_level: np.ndarray | None = None
    g_remnant: np.ndarray | None = None
    c_remnant: np.ndarray | None = None


def line_data(run, band_hz: tuple[float, float] = FITNESS_BAND_HZ) -> LineData:
    """The lines of `run` in `band_hz` (Hz) over its analysis window, with their weights
    (:func:`line_variances`), or the reason they cannot be used (``LineData.reason``).

    Parameters
    ----------
    run : hesspipe.core.formats.Run
        A record with multisine forcing (e = reference − output).
    band_hz : (float, float)
        Lines are used in this band, Hz.
    """
    run = windowed(run)
    n = len(run.control)
    lines = forcing_lines(run, band_hz)
    d_lines, r_lines = _line_sets(run)
    empty = np.zeros(0)
    unusable = dict(lines=lines, s=empty, E=empty, Y=empty, U=empty, w=empty,
                    both=bool(d_lines.size and r_lines.size), window_samples=n)
    if lines.size < MIN_LINES:
        return LineData(**unusable, reason=f"{lines.size} multisine forcing lines found (need {MIN_LINES}): "
                                           "no describing function to test")
    var, h_level, g_remnant, c_remnant = _levels(run, lines)
    if not np.all(np.isfinite(var)) or not np.max(var) > 0:
        return LineData(**unusable, reason="no unforced bins between the forcing lines to measure the remnant")
    U = np.fft.rfft(np.asarray(run.control, dtype=float))
    Y = np.fft.rfft(np.asarray(run.output, dtype=float))
    E = np.fft.rfft(np.asarray(run.reference, dtype=float) - np.asarray(run.output, dtype=float))
    return LineData(lines=lines, s=1j * 2.0 * np.pi * np.fft.rfftfreq(n, run.dt)[lines], E=E[lines],
                    Y=Y[lines], U=U[lines], w=1.0 / np.sqrt(np.maximum(var, np.max(var) * 1e-12)),
                    both=unusable["both"], window_samples=n, h_level=h_level, g_remnant=g_remnant,
                    c_remnant=c_remnant)


def pooled_line_data(runs, band_hz: tuple[float, float] = FITNESS_BAND_HZ) -> LineData:
    """The lines of repeated runs of one pilot in one condition, side by side, each line
    weighted by its own run's remnant (:func:`line_data`).

    Parameters
    ----------
    runs : sequence of hesspipe.core.formats.Run
        Records with multisine forcing (e = reference − output).
    band_hz : (float, float)
        Lines are used in this band, Hz.

    Returns
    -------
    LineData
        Arrays concatenated run after run (``lines`` are each run's own bins, ``groups``
        the run's index); ``both`` only if every run has both line sets; the first
        unusable run's reason, naming it.
    """
    parts = [line_data(r, band_hz) for r in runs]
    for r, ld in zip(runs, parts):
        if ld.reason:
            return dataclasses.replace(ld, reason=f"{r.source or r.id}: {ld.reason}")
    cat = {name: np.concatenate([getattr(ld, name) for ld in parts])
           for name in ("lines", "s", "E", "Y", "U", "w", "h_level", "g_remnant", "c_remnant")}
    groups = np.concatenate([np.full(ld.lines.size, i) for i, ld in enumerate(parts)])
    return LineData(**cat, both=all(ld.both for ld in parts), window_samples=parts[0].window_samples,
                    groups=groups)


def remnant_variance(ld: LineData, G: np.ndarray, reference: np.ndarray | None = None) -> np.ndarray:
    """Each line's equation-error variance for a pilot whose response to −y is `G`, relative
    to that of a pilot whose response is `reference` (default: the describing function the
    level behind ``ld.w`` was measured with, ``ld.h_level``).

    At the unforced neighbours the loop runs on remnant alone, E = −Y there, and a model's
    equation error is ``U_j − G E_j``; its mean power is ``S_ee (|G − g|^2 + c)`` with
    ``g`` the remnant's own U/E (the loop closes it through the plant, about −1/Yc) and
    ``c`` the part of U that E does not explain (LineData). Dividing each residual by this
    variance, not by the level at the measured H, is the errors-in-variables (sample
    maximum-likelihood) criterion: at the lines E and Y carry the same remnant as U, and
    least squares with fixed weights leans every fit towards g, the remnant's own response
    (SYNTHETIC generator Hess pilots: Km/|Ke| 0.74-0.80 of the truth at 40 % remnant
    power, 0.93-1.0 at 10 %).

    Parameters
    ----------
    ld : LineData
        With ``h_level``, ``g_remnant`` and ``c_remnant``.
    G, reference : ndarray, complex
        Responses to −y at each line (control units per output unit).

    Returns
    -------
    ndarray
        One factor per line (dimensionless, > 0).
    """
    num = np.abs(G - ld.g_remnant) ** 2 + ld.c_remnant
    den = np.abs((ld.h_level if reference is None else reference) - ld.g_remnant) ** 2 + ld.c_remnant
    ok = np.isfinite(num) & np.isfinite(den) & (den > 0)
    return np.where(ok, num / np.where(ok, den, 1.0), 1.0)
