"""What a logged record shows of its logger's and its subject's faults (private; the readers
call :func:`quality_notes`).

A lab's files are valid and still hold faults no model of the pilot or the aircraft has: a
stick clipped at its stop or at the converter's range, a logger that froze, single-sample
spikes. Read without a word, a newcomer review found them
named as aircraft-side effects (a clipped stick as a rate limit or a Dutch roll on a yaw
task, spikes as a rate limit on 5 of 6 runs) or moving a person's Km/|Ke| by a factor of 2
(SYNTHETIC: the lab stand-in's runs with the faults written in). The notes say what the
record shows and what it can be taken for; nothing is changed or refused.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from ._time import stretches

#: A column's samples held at its own maximum or minimum, in stretches of at least
#: :data:`HELD` samples: this many stretches, or this share of the samples, reads as
#: clipped. (A quantised signal's peak can sit on its top code for a few samples once; a
#: clipped one sits there at every large excursion.)
CLIPPED_STRETCHES = 3
CLIPPED_SHARE = 0.01
HELD = 3
#: Every signal unchanged for at least this long (s, and :data:`FROZEN_SAMPLES` samples)
#: inside the record reads as a logger that froze (a simulator logged at a multiple of its
#: own rate repeats each value a few times, well below it; a record that starts or ends at
#: rest, before the forcing or after it, is not judged).
FROZEN_S = 0.1
FROZEN_SAMPLES = 5
#: The control or the output alone unchanged for this long inside the record, s: a channel
#: that froze, or a stick let go (a subject holding a digital stick still for 1.2 s was
#: flagged at 1 s by a reviewer).
HELD_ALONE_S = 2.0
#: The stick's activity (its RMS about the local mean over 1 s) below this share of its
#: median over the record, for :data:`HELD_ALONE_S` inside the record while the forcing
#: goes on, reads as a stick let go: a centring spring holds it still but for sensor noise,
#: which no exact repeat shows. (A subject's remnant alone is 10-40 % of the control's power.)
LET_GO_SHARE = 0.1
#: The output's swings (RMS about its median over :data:`SWING_WINDOW_S`) growing to this many
#: times their smallest within the record, while the forcing holds steady, read as a loop
#: that went unstable (control lost, a pilot-induced oscillation). Clean runs: at most 9.2 on
#: 310 (the lab stand-in's, generator trials, flown pilots, a review's design variants), 79
#: with a gain wandering twice as much as the stand-in's (CV 0.3); a generator run that
#: diverged and recovered, 1239. About the median, not each window's mean: the calm between
#: a step target's steps, or a stick let go, is no smaller swing of the output.
SWING_WINDOW_S = 5.0
SWING_LIMIT = 100.0
#: A spike stands this many of the column's smallest steps off its neighbours (a signal
#: written to whole degrees turns by one step, which its robust scale of 0 made a spike).
SPIKE_STEPS = 5.0
#: A sample this many robust standard deviations off the mean of its two neighbours, where
#: the neighbours agree, reads as a spike (the lab stand-in's 72 clean runs: none above 12).
SPIKE_SIGMAS = 30.0


def _inner_longest(mask: np.ndarray) -> tuple[int, int]:
    """(length, start) of the longest stretch of True in `mask` that touches neither end
    (a record's rest before or after the forcing is not a fault); (0, 0) if none."""
    starts, ends = stretches(mask)
    inner = (starts > 0) & (ends < mask.size)
    if not inner.any():
        return 0, 0
    i = int(np.argmax(np.where(inner, ends - starts, -1)))
    return int(ends[i] - starts[i]), int(starts[i])


def _clipped(x: np.ndarray) -> list[tuple[str, float, float]]:
    """(side, value, share of samples) where `x` is held at its maximum or minimum."""
    out = []
    for side, v in (("maximum", float(x.max())), ("minimum", float(x.min()))):
        at = x == v
        starts, ends = stretches(at)
        held = (ends - starts)[ends - starts >= HELD]
        if held.size >= CLIPPED_STRETCHES or held.sum() >= CLIPPED_SHARE * x.size:
            out.append((side, v, float(at.mean())))
    return out


def _moving_rms(x: np.ndarray, w: int, centre: float | None = None) -> np.ndarray:
    """RMS of `x` over each window of `w` samples (``x.size - w + 1`` of them), about the
    window's own mean, or about `centre`."""
    x = x - (x.mean() if centre is None else centre)
    c1 = np.concatenate(([0.0], np.cumsum(x)))
    c2 = np.concatenate(([0.0], np.cumsum(x ** 2)))
    m = (c1[w:] - c1[:-w]) / w if centre is None else 0.0
    return np.sqrt(np.maximum((c2[w:] - c2[:-w]) / w - m * m, 0.0))


def _let_go(x: np.ndarray, forcing: list[np.ndarray], dt: float) -> tuple[float, float]:
    """(length, start), s, of the longest stretch inside the record where `x` barely moves
    while every forcing in `forcing` goes on; (0, 0) if none is as long as :data:`HELD_ALONE_S`."""
    w = max(3, int(round(1.0 / dt)))
    if x.size < 4 * w:
        return 0.0, 0.0
    rms = _moving_rms(x, w)
    quiet = rms < LET_GO_SHARE * float(np.median(rms))
    for f in forcing:
        f_rms = _moving_rms(f, w)
        quiet &= f_rms > LET_GO_SHARE * float(np.median(f_rms))
    starts, ends = stretches(quiet)
    inner = (starts > 0) & (ends < quiet.size)
    if not inner.any():
        return 0.0, 0.0
    # Each window of a stretch lies wholly inside the rest: the rest is the windows' span.
    span = np.where(inner, ends - starts + w - 1, 0)
    i = int(np.argmax(span))
    return (float(span[i] * dt), float(starts[i] * dt)) if span[i] * dt >= HELD_ALONE_S else (0.0, 0.0)


def swing_ratio(x: np.ndarray, forcing: list[np.ndarray], dt: float) -> tuple[float, float]:
    """How far `x`'s swings grow within a record: (largest over smallest RMS about `x`'s
    median over windows of :data:`SWING_WINDOW_S` a second apart, start of the largest
    window, s from the record's start).

    Only windows where every forcing in `forcing` swings (about its own median) at least half
    its median are compared (a record that starts at rest is not a loop that grew). (1, 0)
    for a record shorter than four windows.

    Parameters
    ----------
    x : ndarray
        The output.
    forcing : list of ndarray
        The forcing columns (none: every window compared).
    dt : float
        Sample interval, s.

    Returns
    -------
    ratio : float
    at : float
        Seconds from the record's start to the largest window.
    """
    w, hop = max(3, int(round(SWING_WINDOW_S / dt))), max(1, int(round(1.0 / dt)))
    if x.size < 4 * w:
        return 1.0, 0.0
    rms = _moving_rms(x, w, float(np.median(x)))[::hop]
    keep = np.ones(rms.size, dtype=bool)
    for f in forcing:
        f_rms = _moving_rms(f, w, float(np.median(f)))[::hop]
        keep &= f_rms >= 0.5 * float(np.median(f_rms))
    if keep.sum() < 4:
        return 1.0, 0.0
    i = int(np.flatnonzero(keep)[np.argmax(rms[keep])])
    return float(rms[i] / max(float(rms[keep].min()), 1e-300)), float(i * hop * dt)


def _spikes(x: np.ndarray) -> int:
    """Samples of `x` far off the mean of their two neighbours while those agree."""
    if x.size < 5:
        return 0
    off = x[1:-1] - 0.5 * (x[:-2] + x[2:])
    scale = 1.4826 * float(np.median(np.abs(off - np.median(off))))
    steps = np.abs(np.diff(x))
    step = float(np.min(steps[steps > 1e-9 * float(np.ptp(x))], initial=np.inf))
    if not np.isfinite(step):
        return 0
    big = np.abs(off) > max(SPIKE_SIGMAS * scale, SPIKE_STEPS * step)
    # A spike's neighbours agree with each other; a step's do not.
    agree = np.abs(x[2:] - x[:-2]) < 0.5 * np.abs(off)
    return int(np.sum(big & agree))


#: Each data check's short name (``diagnose --each`` lines) and the words its note holds.
CHECK_NAMES = (("clipped", "clipped"), ("spikes", "spike"), ("logger froze", "logger froze"),
               ("held", "holds one value"), ("let go", "barely moves"), ("unstable", "went unstable"))


def check_names(notes) -> list[str]:
    """The short names of the data checks among a run's `notes`.

    Parameters
    ----------
    notes : sequence of str
        A run's notes (those of :func:`quality_notes` among them).

    Returns
    -------
    list of str
        In :data:`CHECK_NAMES`' order.
    """
    return [name for name, words in CHECK_NAMES if any(n.startswith("data check") and words in n for n in notes)]


def quality_notes(data: Mapping[str, np.ndarray], columns: Mapping[str, str], dt: float) -> tuple[str, ...]:
    """Notes on a record's logging and subject faults: clipped, frozen or spiked columns, a
    stick let go, a loop that went unstable.

    Parameters
    ----------
    data : mapping of str to ndarray
        Role → samples on a uniform grid (``time`` in s among them), in SPEC.md's units.
    columns : mapping of str to str
        Role → the column's name in the file (a role not read from the file is not judged).
    dt : float
        Sample interval, s.

    Returns
    -------
    tuple of str
        Each starting "data check:", empty where the record shows none of them.
    """
    notes = []
    signals = {r: np.asarray(v, dtype=float) for r, v in data.items() if r != "time" and r in columns}
    longest = 0
    if len(signals) >= 2:
        longest, first = _inner_longest(np.all(np.stack([np.diff(x) == 0 for x in signals.values()]), axis=0))
        longest += 1 if longest else 0
        if longest >= max(FROZEN_SAMPLES, FROZEN_S / dt):
            notes.append(f"data check: every column holds its value for {longest} samples "
                         f"({longest * dt:.3g} s) from {first * dt:.6g} s into the record: the logger "
                         "froze? Such a stretch is no pilot's response and moves the fits; leave it out "
                         "(cut the record) if it is not the pilot's")
    forcing = [v for r, v in signals.items() if r in ("disturbance", "reference") and np.ptp(v) > 0]
    unstable = False
    for role, x in signals.items():
        name = columns[role]
        if x.size < 3 or float(np.ptp(x)) == 0.0:
            # A forcing column of zeros is SPEC's way of writing a task without it, and the
            # motion verdict names the one forcing function: no note.
            continue
        # The pilot's and the aircraft's signals only: a designed forcing (a step or a
        # staircase target) sits at its ends by design.
        ends = _clipped(x) if role in ("control", "output") else []
        if ends:
            which = " and its ".join(side for side, _, _ in ends)
            share = sum(sh for _, _, sh in ends)
            notes.append(f"data check: column '{name}' ({role}) sits at its {which} value on "
                         f"{100 * share:.1f} % of the samples, in stretches: clipped at the stick's stop "
                         "or the logger's range? An aircraft-side name on this run (a rate limit, a "
                         "Dutch roll) or a changed delay may come from the clipping")
        if role in ("control", "output"):
            held, _ = _inner_longest(np.diff(x) == 0)
            held += 1 if held else 0
            # Beyond what every column holds (said above): the channel alone.
            if held > longest and held * dt >= HELD_ALONE_S:
                notes.append(f"data check: column '{name}' ({role}) holds one value for {held * dt:.3g} s "
                             "inside the record: a channel that froze, or a stick let go? No pilot "
                             "model here holds such a stretch; leave it out if it is not the pilot's")
            elif role == "control" and longest * dt < HELD_ALONE_S:
                span, start = _let_go(x, forcing, dt)
                if span:
                    notes.append(f"data check: column '{name}' (control) barely moves for {span:.3g} s from "
                                 f"{start:.6g} s into the record while the forcing goes on (below "
                                 f"{100 * LET_GO_SHARE:g} % of its usual activity): the stick let go? No "
                                 "pilot model here rests so; leave the stretch out if the subject let go")
        # The output's: a stick let go or held at a dead zone is calm without the loop growing.
        if role == "output":
            ratio, at = swing_ratio(x, forcing, dt)
            unstable = ratio > SWING_LIMIT
            if unstable:
                notes.append(f"data check: column '{name}' ({role}) swings {ratio:.3g} times wider in the "
                             f"{SWING_WINDOW_S:g} s "
                             f"from {at:.6g} s into the record than where it is calmest, while the forcing holds "
                             "steady: the loop went unstable (control lost, a pilot-induced oscillation)? "
                             "No linear pilot model describes such a run; leave it out")
        # A loop that grew a hundredfold makes its calm stretch the scale every larger sample
        # is a "spike" against: said once, as the growth.
        n = 0 if unstable and role in ("control", "output") else _spikes(x)
        if n:
            notes.append(f"data check: column '{name}' ({role}) has {n} single-sample spike(s) far off "
                         "their neighbours (a logger's glitch?); a rate limit named on this run may be "
                         "theirs")
    return tuple(notes)
