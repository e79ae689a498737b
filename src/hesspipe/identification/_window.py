"""The forcing's lines and the analysis window that puts them on exact bins (private; used by
:mod:`.frf` and :mod:`.lines`).

A multisine's lines fall on exact DFT bins only over a whole number of its periods. Records
are rarely cut so: loggers write both ends, log the run-in, or run on after the forcing
fades out. :func:`_window` finds the window; :func:`_lines` the bins that stand out.
"""

from __future__ import annotations

import numpy as np

LINE_RATIO = 100.0
"""A bin is a line when its power exceeds LINE_RATIO times the median of its NEAR
neighbours each side: a random broadband spectrum does so with probability ~e^-70."""
NEAR = 6
CLEAN = 0.99
"""A window found by exact recurrence is taken when each forcing's purity there is at least
this (the share of its power on its lines)."""
PERIOD_OFF = (0.1, 0.05)
"""A record holds no whole period (:func:`_longer_period`) when its lines lie more than the first
of these, in bins, off those of every window up to its length, and within the second of those
of a longer one. Located lines lay within 0.04 bin of a whole-period window in the records that
hold one (0.17 with a run-in of another phase), within 0.03 of the period beyond the record in
those that do not."""
MIN_LINES = 4
"""Fewest forcing lines a describing function is tested or trusted on: the motion test needs
them (:mod:`.lines`), and ``frf`` says where it found fewer. Half a period of a 10-sine
multisine left 3 on bins, whose crossover came out 14.6 rad/s against the truth's 2.8."""
PURITY_TIE = 1e-9
"""Purities closer than this are equal (floating-point rounding): the longer window stays."""
MIN_PERIOD_LINES = 6
"""Fewest located lines that :func:`_longer_period` judges a period by (with fewer, some longer
window holds them by chance)."""


def _lines(power: np.ndarray) -> np.ndarray:
    """Bins (>= 1) whose power stands LINE_RATIO above their nearest neighbours.

    The reference is the median of the NEAR bins each side: the lines of a sparse
    multisine in a whole-period window sit on an empty floor, while a random
    spectrum (gusts) fluctuates bin to bin like chi-square(2) variates and a
    smooth one (a slow drift) cannot fall by LINE_RATIO within a few bins. A
    multisine exciting every bin of a band has no such contrast and is taken as
    broadband (the Welch estimate serves it).
    """
    p = power.copy()
    p[0] = 0.0
    top = p.max()
    if not top > 0:
        return np.zeros(0, dtype=int)
    n = p.size
    idx = np.arange(n)
    offsets = np.concatenate((np.arange(-NEAR, 0), np.arange(1, NEAR + 1)))
    nb = idx[:, None] + offsets[None, :]
    # Near the ends, take the missing neighbours from further along the other side.
    nb = np.where(nb < 1, nb + 2 * NEAR + 1, nb)
    nb = np.clip(np.where(nb > n - 1, nb - 2 * NEAR - 1, nb), 1, n - 1)
    ref = np.median(p[nb], axis=1)
    ref = np.maximum(ref, 1e-13 * top)  # exact multisines have an empty floor
    ok = p > LINE_RATIO * ref
    ok[0] = False
    cand = np.nonzero(ok)[0]
    if cand.size and cand.max() < 3:
        # Only the record's first one or two bins: a slow drift (the paper's turning side
        # wind), whose steep spectrum clears its neighbours there; a forcing has lines higher up.
        return np.zeros(0, dtype=int)
    if cand.size < 2:
        return cand
    # Leakage (a window that is not a whole number of periods) puts sidebands beside
    # each line that decay like 1/distance^2: a candidate weaker than a neighbour's
    # 1/(10 distance^2) is one of those, not a line of its own.
    keep = np.ones(cand.size, dtype=bool)
    pc = p[cand]
    order = np.argsort(-pc)
    for i in order:
        if not keep[i]:
            continue
        dist = np.abs(cand - cand[i]).astype(float)
        weak = (pc * 10 * np.maximum(dist, 1) ** 2 < pc[i]) & (dist > 0)
        keep &= ~weak
    return cand[keep]


def _purity(x: np.ndarray) -> tuple[float, np.ndarray, np.ndarray]:
    X = np.fft.rfft(x - x.mean())
    p = np.abs(X) ** 2
    lines = _lines(p)
    total = p[1:].sum()
    return (float(p[lines].sum() / total) if total > 0 else 0.0), lines, X


def _period_by_lag(x: np.ndarray) -> int | None:
    """Smallest lag L <= n/2 with x[t+L] ~ x[t] (a periodic forcing), or None."""
    n = x.size
    x = x - x.mean()
    nf = 1 << int(np.ceil(np.log2(2 * n)))
    F = np.fft.rfft(x, nf)
    r = np.fft.irfft(np.abs(F) ** 2, nf)[: n // 2 + 1]
    c = np.concatenate(([0.0], np.cumsum(x * x)))
    lags = np.arange(n // 2 + 1)
    # sum_t (x[t+L] - x[t])^2 over the overlap, relative to the overlap's power.
    s_head = c[n - lags]            # sum x[0:n-L]^2
    s_tail = c[n] - c[lags]         # sum x[L:n]^2
    err = (s_head + s_tail - 2 * r) / np.maximum(s_head + s_tail, 1e-300)
    cand = np.nonzero(err[1:] < 1e-3)[0] + 1
    if cand.size == 0:
        return None
    L = int(cand[0])
    # the first lag under the threshold: walk to its local minimum
    while L + 1 < err.size and err[L + 1] < err[L]:
        L += 1
    return L if L >= 4 else None


def _topk_purity(x: np.ndarray, k: int) -> float:
    p = np.abs(np.fft.rfft(x - x.mean()))[1:] ** 2
    total = p.sum()
    if not total > 0:
        return 0.0
    k = min(k, p.size)
    return float(np.partition(p, p.size - k)[p.size - k:].sum() / total)


def _window(d: np.ndarray, r: np.ndarray | None):
    """Analysis window (start, length, purity) with the forcing's lines on exact bins.

    The purest of the record as written, less its last sample (loggers often write
    both ends) or one sample at each end, a whole number of periods found by lag
    (two or more periods) and one period found by the record's end recurring one
    period earlier (a logged run-in shorter than the period); else the length
    between half the record and all of it whose spectrum concentrates most power in
    as many bins as there are lines (one period of a forcing whose period is not the
    record's length), ending at the record's end or, where purer, starting at its
    beginning. The window ends at the record's end, so a start-up transient
    falls outside it, unless the forcing stops repeating before the end (faded out
    while the logger ran on): then it ends where the forcing last repeats itself.
    A window is judged by the purity of each forcing on its own (the smallest).
    """
    n = d.size
    # Each forcing on its own: interleaved target lines sit one bin above the disturbance's,
    # so in their sum the low lines are neighbours, stand no LINE_RATIO above each other, and
    # the sum's purity is low however exact the window (the search below then picked half
    # records and lost most lines) and peaked one sample past a lab record's period.
    forcings = [x for x in (d, r) if x is not None and np.any(x)]
    x = d if r is None else d + r

    def purity(start: int, length: int) -> float:
        part = slice(start, start + length)
        return min(_purity(f[part])[0] for f in forcings) if forcings else _purity(x[part])[0]

    # The record as written, less its last sample, less one at each end, a whole number of
    # periods found by lag and one found by the end's exact recurrence, judged side by side: a
    # record one sample off two periods passes 0.999 as written (SYNTHETIC lab-layout records:
    # 16383 and 16385 samples for 16384). The recurrence is taken only where the forcings are
    # clean multisines on the window (a broadband record's constant stretch recurs too).
    best = max(((purity(n - m, m), n - m, m) for m in (n, n - 1, n - 2) if m > 0),
               key=lambda b: b[0])
    period = _period_by_lag(x)
    if period is not None:
        length = (n // period) * period
        best = max(best, (purity(n - length, length), n - length, length), key=lambda b: b[0])
    period = _period_by_end(x)
    # A forcing that stops repeating before the record ends: the stretch where it repeats.
    window = (n - period, period) if period else None if best[0] >= 0.999 else _periodic_stretch(x)
    # The stretch found, and as long a window from the record's start (a logger started
    # with the measurement: a 20 s fade-out put the stretch 263 samples in).
    for cand in ((window, (0, window[1])) if window is not None else ()):
        pur = purity(*cand)
        # Purer by more than rounding only: on a 300 s record of an 81.92 s multisine one
        # period found by the end (0.9999999999999996) beat three found by lag
        # (0.9999999999999994) and the analysis lost two periods.
        if pur >= CLEAN and pur > best[0] + PURITY_TIE:
            best = (pur, *cand)
    if best[0] >= 0.999:
        return best[1], best[2], best[0]
    lines = _purity(x)[1]
    if lines.size == 0:   # no lines stand out: broadband forcing, or an exact multisine unfound
        return best[1], best[2], best[0]
    k = int(min(lines.size, 400))
    # About 1024 candidates at most: every 4th sample of a 100 Hz lab record, but each an
    # FFT of up to n samples, so a fixed step made a 1 kHz record of 100 s take 107 s here
    # and one of 262 s over ten minutes (a reviewer's cut records, not whole periods).
    step = max(4, n // 2048)
    coarse = np.arange(n, n // 2, -step)
    for at_end in (True, False):
        # Ending at the record's end (a run-in before the window), and starting at its
        # beginning, taken where purer: a logger started with the measurement and run on
        # while the forcing faded out put the end-anchored window over the fade-out (a
        # reviewer's 7.5 s fade-out: samples 752-8942 of a 8192-sample period).
        part = (lambda m: x[n - m:]) if at_end else (lambda m: x[:m])
        scores = np.array([_topk_purity(part(m), k) for m in coarse])
        m0 = int(coarse[int(np.argmax(scores))])
        # The top-k share of the sum peaked up to 9 samples off a lab record's period (its k
        # from the leaky whole record: 5 of 20 lines); the forcings' own purity is 1 there.
        fine = np.arange(min(n, m0 + max(16, step)), max(n // 2, m0 - max(16, step)) - 1, -1)
        first = (lambda m: n - m) if at_end else (lambda m: 0)
        m = int(fine[int(np.argmax([purity(first(int(m)), int(m)) for m in fine]))])
        pur = purity(first(m), m)
        if pur > best[0] + (0.0 if at_end else PURITY_TIE):
            best = (pur, first(m), m)
    return best[1], best[2], best[0]


def _line_positions(x: np.ndarray, pad: int = 8) -> np.ndarray:
    """The lines of `x` in bins of its record, fractional: the peaks :func:`_lines` finds on
    its Hann-windowed spectrum, each located on that spectrum zero-padded `pad` times (a
    parabola through the log magnitudes at its top). Off the bins the taper keeps each line's
    leakage off the others, so a line's place is read to about 0.02 of a bin."""
    n = x.size
    xw = (x - x.mean()) * np.hanning(n)
    p = np.abs(np.fft.rfft(xw)) ** 2
    peaks = [b for b in _lines(p) if p[b] >= p[max(b - 2, 0):b + 3].max()]   # a lobe spans 2 bins each side
    fine = np.abs(np.fft.rfft(xw, pad * n))
    out = []
    for b in peaks:
        lo = max(pad * (b - 1), 1)
        i = lo + int(np.argmax(fine[lo:min(pad * (b + 1) + 1, fine.size - 1)]))
        a, c, e = np.log(fine[i - 1:i + 2] + 1e-300)
        out.append((i + (0.5 * (a - e) / (a - 2 * c + e) if a - 2 * c + e < 0 else 0.0)) / pad)
    return np.array(out)


def _period_off(lines: np.ndarray, n: int, lo: float, hi: float) -> tuple[float, float]:
    """(m, off): of the windows from `lo` to `hi` samples long, the one whose bins the `lines`
    (in bins of a record of `n` samples) come nearest to together, and the largest distance,
    in bins, of a line from one of them."""
    m = np.arange(lo, hi, 0.02 * n / lines.max())   # a step moves the highest line 0.02 bin
    worst = np.zeros(m.size)
    for b in lines:
        q = m * (b / n)
        worst = np.maximum(worst, np.abs(q - np.round(q)))
    i = int(np.argmin(worst))
    return float(m[i]), float(worst[i])


def _longer_period(forcings) -> float | None:
    """The forcing's period in samples where the record holds no whole one, or None.

    A window of whole periods puts every line on a bin. Where the record is shorter than the
    period, no window does: the lines, located on the record's spectrum (:func:`_line_positions`),
    lie off the bins of every window up to the record's length (by more than PERIOD_OFF[0]),
    and together on the bins of one a little longer (within PERIOD_OFF[1]). Both must hold: a
    run-in of another phase shifts the lines by up to 0.17 bin but puts them on no longer
    window; fewer than MIN_PERIOD_LINES lines tell a period from chance too rarely.

    Parameters
    ----------
    forcings : list of ndarray
        The record's forcing signals (disturbance, target), of one length.

    Returns
    -------
    float or None
        The period, samples; None where a window of whole periods fits in the record, or where
        the lines cannot tell.
    """
    n = forcings[0].size
    lines = np.concatenate([_line_positions(f) for f in forcings])
    if lines.size < MIN_PERIOD_LINES:
        return None
    if _period_off(lines, n, min(n / lines.min(), n), n + 1.0)[1] < PERIOD_OFF[0]:
        return None
    m, off = _period_off(lines, n, n + 1.0, 2.0 * n)
    return m if off < PERIOD_OFF[1] else None


def period_note(forcings, purity: float, dt: float) -> str | None:
    """The note on a record that holds no whole period of its multisine, or None.

    Parameters
    ----------
    forcings : list of ndarray
        The record's forcing signals (disturbance, target), of one length; constant ones are
        left out.
    purity : float
        The chosen window's purity (:func:`_window`); at :data:`CLEAN` or above it holds whole
        periods and nothing is said.
    dt : float
        Sample interval, s.

    Returns
    -------
    str or None
        The note, naming the record's length and the period its lines belong to (s).
    """
    if purity >= CLEAN:
        return None
    moving = [np.asarray(x, dtype=float) for x in forcings if np.ptp(x) > 0]
    period = _longer_period(moving) if moving else None
    if period is None:
        return None
    return (f"no whole period of the forcing repeats in the record ({moving[0].size * dt:.4g} s; its lines "
            f"are those of a period of about {period * dt:.4g} s): the lines leak into their neighbours, "
            "so the describing function and the remnant share are approximate")


def _periodic_stretch(x: np.ndarray, tail: int = 64, steps: int = 16) -> tuple[int, int] | None:
    """(start, length) of the most whole periods inside the stretch where `x` repeats itself,
    found from a segment of `tail` samples stepped back from the record's end over its last
    quarter (a forcing faded out, or stopped, while the logger ran on), or None.

    The period is the shortest lag of at least ``2 tail`` samples at which the segment recurs
    to rounding; the stretch runs on both sides of it while each sample recurs (to 10 times
    the rounding seen there, or 1e-5 of the forcing's RMS).
    """
    n = x.size
    x = x - x.mean()
    c = np.concatenate(([0.0], np.cumsum(x * x)))
    for q in range(n - tail, max(n // 2, 3 * tail) - 1, -max(tail, n // (4 * steps))):
        lags = np.arange(2 * tail, q + 1)
        if lags.size == 0:
            continue
        err, energy = _recurrence(x, c, q, tail, lags)
        if not energy > 0:
            continue
        hit = np.flatnonzero(err < 1e-3 * energy)
        if hit.size == 0:
            continue
        i = int(hit[0])   # to the bottom of that lag's dip
        while i + 1 < err.size and err[i + 1] < err[i]:
            i += 1
        period = int(lags[i])
        # Each sample's recurrence: off where the change over a period exceeds 100 times its
        # mean square in the quieter of this segment and the one a step back (either may lie in
        # a fade's first per cent; a short stretch's step back, in the run-in's fade-in) and
        # persists for 3 samples (a fade's slow start).
        step = max(tail, n // (4 * steps))
        d2 = (x[period:] - x[:-period]) ** 2
        ref = min((r for r in (q, q - step) if r - period >= 0),
                  key=lambda r: float(d2[r - period:r - period + tail].mean()))
        thr = max(100.0 * float(d2[ref - period:ref - period + tail].mean()), 1e-10 * energy / tail)
        off = d2 > thr
        persist = off[:-2] & off[1:-1] & off[2:]
        after = np.flatnonzero(persist[ref - period:])
        end = n if after.size == 0 else ref + int(after[0])
        before = np.flatnonzero(persist[:max(ref - period - 2, 0)])
        first = 0 if before.size == 0 else int(before[-1]) + 3   # x[first:end] repeats
        length = ((end - first) // period) * period
        return (end - length, length) if length else None
    return None


def _period_by_end(x: np.ndarray, tail: int = 64) -> int | None:
    """The lag L from half the record to all of it at which the record's last `tail`
    samples recur (a periodic forcing logged for less than two periods: a run-in before one
    period), or None.

    Only the end is compared: a run-in's start holds the forcing's fade-in.
    """
    n = x.size
    lo, hi = n // 2, n - tail
    if hi < lo:
        return None
    x = x - x.mean()
    c = np.concatenate(([0.0], np.cumsum(x * x)))
    # From a tail below half the record: the minimum must be the bottom of a dip. A slow
    # multisine at 100 Hz recurs to 1e-3 at one sample off its period, so with the range
    # cut at the period (a run-in of exactly one period) its edge passed for it: a window
    # 8193 samples long (SYNTHETIC lab-layout records).
    lags = np.arange(max(lo - tail, tail), hi + 1)
    err, energy = _recurrence(x, c, n - tail, tail, lags)
    if not energy > 0:
        return None
    i = int(np.argmin(err))
    if lags[i] < lo:
        return None
    # A match to rounding only: anything else differs by about twice the end's energy.
    return int(lags[i]) if err[i] < 1e-3 * energy else None


def _recurrence(x: np.ndarray, c: np.ndarray, q: int, tail: int, lags: np.ndarray) -> tuple[np.ndarray, float]:
    """(err, energy): for the segment ``x[q:q + tail]``, ``sum_j (x[q - L + j] - x[q + j])^2``
    at each lag L of `lags` (``tail <= L <= q``), in O(n) memory (`c`: the cumulative sum of
    ``x**2``, a leading 0), and the segment's own energy."""
    seg = x[q:q + tail]
    energy = float(seg @ seg)
    starts = q - lags
    err = (c[starts + tail] - c[starts]) - 2.0 * np.correlate(x[:q], seg, mode="valid")[starts] + energy
    return err, energy
