"""One describing function from repeated runs of one pilot in one condition.

Human-operator experiments repeat each condition (typically 4-6 runs) and average in the
frequency domain, because one run's remnant leaves the lowest lines uncertain. At each line
the runs' Fourier coefficients of control and error, each divided by the forcing that owns
the line (F = D or R), are averaged before the ratio::

    H = mean_i(U_i / F_i) / mean_i(E_i / F_i)

(the instrumental-variable form; dividing by F lets the runs' forcing phases differ). The
ratio of means, not the mean of the runs' ratios U_i/E_i: in a closed loop the remnant
enters E as well as U, so a line where it dominates E leans towards the inverse plant in
every run, and only averaging before the ratio shrinks that. The error of H follows from
each run's remnant level P_i at the line (the equation error's variance, squared control
units), measured between the lines and smoothed across them
(:func:`hesspipe.identification.lines.line_variances`, the motion test's weights)::

    sigma^2 = sum_i P_i / |F_i|^2 / (N^2 |mean_i(E_i/F_i)|^2)

Not :mod:`.frf`'s own per-line neighbours: at the lowest lines these reach bins several
times the line's frequency, where the remnant is weaker, and the runs' scatter exceeded
them 12-fold in variance (median over 16 runs of a JSBSim-flown cohort pilot at its
0.45 rad/s wind line; 2-fold with the smoothed levels, 0.5-1.6 at the other lines. SYNTHETIC, pilot01 of
``benchmarks/bench_km_identifiability.py --runs``).

A human's describing function also moves between runs (gains by 5-15 %, delays by about
0.01 s), which the remnant-based sigma_i do not hold. So the runs' scatter about the mean
is checked against their sigma_i, per line set, by the Birge ratio
``sum_i sum_k 2 |H_ik - H_k|^2 / sigma_ik^2 / (2 (N - 1) K)`` (about 1 for K lines of
runs that differ only by their remnant); above 1 the set's sigma are widened by its square
root, so a fit's standard errors and tests see the scatter the runs really have.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence

import numpy as np

from ..core.errors import HesspipeError
from ..core.formats import Run
from .frf import Frf, Response, estimate_frf
from .frf_crossover import FrfCrossover, nonparametric_crossover
from .lines import analysis_window, line_variances, windowed


def _where(run, i: int) -> str:
    return getattr(run, "source", "") or getattr(run, "id", "") or f"run {i + 1}"


def check_repeats(runs: Sequence, others: Sequence = ()) -> None:
    """Raise unless `runs` are distinct repeats of one forcing (the same sampling interval
    and analysed length, :func:`hesspipe.identification.lines.analysis_window`) and no record
    among them and `others` (e.g. another condition's runs) appears twice: counted twice, a
    record would shrink the errors and the allowed run-to-run spread for nothing.

    Parameters
    ----------
    runs : sequence of hesspipe.core.formats.Run
        Repeats of one condition.
    others : sequence of hesspipe.core.formats.Run
        Further records that must differ from them and from each other.

    Raises
    ------
    HesspipeError
        Naming the offending record (its file, else its id) and the one it was compared with.
    """
    every = [*runs, *others]
    for i, run in enumerate(every):
        for j in range(i):
            if np.array_equal(np.asarray(run.control), np.asarray(every[j].control)):
                raise HesspipeError(f"{_where(run, i)}: the same record as {_where(every[j], j)}; "
                                    "expected distinct repeated runs")
    if not runs:
        return
    n, dt = analysis_window(runs[0])[1], runs[0].dt
    for i, run in enumerate(runs[1:], start=1):
        m = analysis_window(run)[1]
        if m != n or abs(run.dt - dt) > 1e-6 * dt:
            raise HesspipeError(f"{_where(run, i)}: {m} samples at {run.dt:.6g} s analysed; expected "
                                f"{n} at {dt:.6g} s like {_where(runs[0], 0)}: repeated runs of one forcing")


def _combine(responses: Sequence[Response], names: Sequence[str]) -> tuple[Response, float, int]:
    """Ratio of the runs' mean U/F and E/F at each line of one set, the set's Birge ratio,
    and how many lines some run lacks.

    A line is averaged over the runs that found it: a slow drift can hide a low line in one
    run (:mod:`.frf`), which should not cost the other runs that line.
    """
    for i, r in enumerate(responses):
        if r.error_per_forcing is None:
            raise HesspipeError(f"{names[i]}: the describing function carries no E/F at its "
                                "lines; expected one from estimate_frf")
    bins = np.unique(np.concatenate([np.asarray(r.bins, dtype=int) for r in responses]))
    n, k = len(responses), bins.size
    H = np.full((n, k), np.nan + 0j)
    sig = np.full((n, k), np.nan)
    ef = np.zeros((n, k), dtype=complex)
    freq = np.empty(k)
    for i, r in enumerate(responses):
        j = np.searchsorted(bins, np.asarray(r.bins, dtype=int))
        H[i, j], sig[i, j], ef[i, j], freq[j] = r.H, r.sigma, r.error_per_forcing, r.freq_rad_s
    have = np.isfinite(H.real) & np.isfinite(sig)
    count = have.sum(axis=0)
    # Averaging H itself would keep each run's errors-in-variables bias: where the remnant's
    # share of E is large (the lowest lines, under a high loop gain) U/E leans towards the
    # inverse plant. Averaging U/F and E/F first shrinks that share before the ratio.
    ef = np.where(have, ef, 0.0)
    mean_ef = ef.sum(axis=0) / count
    mean = np.where(have, np.nan_to_num(H) * ef, 0.0).sum(axis=0) / count / mean_ef
    power = np.where(have, np.nan_to_num(sig) ** 2 * np.abs(ef) ** 2, 0.0).sum(axis=0)
    sigma = np.sqrt(power) / (count * np.abs(mean_ef))
    with np.errstate(divide="ignore", invalid="ignore"):
        terms = 2.0 * np.abs(H - mean) ** 2 / sig ** 2
    terms = terms[have & np.isfinite(terms)]
    dof = 2.0 * np.maximum(count - 1, 0).sum()
    birge = float(terms.sum() / dof) if dof > 0 else 1.0
    return (Response(freq, mean, sigma * np.sqrt(max(birge, 1.0)), bins, mean_ef), birge,
            int((count < n).sum()))


def with_remnant_levels(run, frf: Frf) -> Frf:
    """`frf` with each line's sigma from the smoothed remnant levels between the lines
    (:func:`hesspipe.identification.lines.line_variances`; module doc: why).

    Parameters
    ----------
    run : hesspipe.core.formats.Run
        The record `frf` was estimated from.
    frf : Frf
        Its describing function (:func:`~hesspipe.identification.frf.estimate_frf`).

    Returns
    -------
    Frf
        `frf` with each response's ``sigma`` (control units per unit of error) replaced.
    """
    window = windowed(run)
    E = np.fft.rfft(np.asarray(window.reference, dtype=float) - np.asarray(window.output, dtype=float))
    sets = [frf.feedback] + ([frf.reference] if frf.reference is not None else [])
    bins = np.concatenate([np.asarray(r.bins, dtype=int) for r in sets])
    with np.errstate(divide="ignore"):
        sig = np.sqrt(line_variances(window, bins)) / np.abs(E[bins])
    new, i = [], 0
    for r in sets:
        new.append(dataclasses.replace(r, sigma=sig[i:i + r.H.size]))
        i += r.H.size
    return dataclasses.replace(frf, feedback=new[0], reference=new[1] if len(new) > 1 else None)


def average_frf(runs: Sequence, plants=None, *, seed: int = 0) -> Frf:
    """The describing function of repeated runs of one forcing (module doc).

    Parameters
    ----------
    runs : sequence of hesspipe.core.formats.Run
        Runs of one pilot in one condition: the same forcing lines (their phases may
        differ), sampling interval and analysed length.
    plants : Plants or control.TransferFunction, optional
        The control plant Yc, for the crossover of the averaged describing function.
    seed : int
        Seed of the crossover's uncertainty draws.

    Returns
    -------
    Frf
        H (control units per unit of displayed error) and sigma at every line some run
        found; the remnant share is the runs' mean; ``run_id`` joins the runs' ids with ``+``;
        the window is the first run's. One run: its own estimate
        (:func:`~hesspipe.identification.frf.estimate_frf`), so that a person with one run
        reads the same here (``hesspipe conditions``) as ``hesspipe frf`` reads the file.

    Raises
    ------
    HesspipeError
        No runs; a record given twice; of several runs, one without multisine lines (Welch
        estimates are not averaged here);
        runs whose sampling interval, analysed length or reference lines differ (naming
        the run); what :func:`~hesspipe.identification.frf.estimate_frf` raises for a run.
    """
    if isinstance(runs, Run):   # one run is its own average
        runs = [runs]
    if isinstance(runs, (str, bytes)) or not hasattr(runs, "__iter__"):
        raise HesspipeError(f"runs: expected a list of Runs (read_run reads a file), got {type(runs).__name__}")
    runs = list(runs)
    if not runs:
        raise HesspipeError("average_frf: expected at least one run, got none")
    if len(runs) == 1:
        # Averaging one run would only swap its lines' errors for the remnant levels between
        # them: a reviewer's flat-|L| person then crossed at 5.4 rad/s in conditions and at 0.81
        # in frf, on one file.
        return estimate_frf(runs[0], plants, seed=seed)
    frfs, names = [], [_where(r, i) for i, r in enumerate(runs)]
    check_repeats(runs)
    for i, run in enumerate(runs):
        f = estimate_frf(run, seed=seed)
        first = frfs[0] if frfs else f
        if f.method != "multisine":
            raise HesspipeError(f"{names[i]}: no multisine lines (describing function by "
                                f"{f.method!r}); expected lines to average over repeated runs")
        if (f.reference is None) != (first.reference is None):
            raise HesspipeError(f"{names[i]}: reference lines {'absent' if f.reference is None else 'present'}"
                                f"; expected them as in {names[0]}: repeated runs of one forcing")
        frfs.append(with_remnant_levels(run, f))
    feedback, birge_fb, gaps = _combine([f.feedback for f in frfs], names)
    reference, birge_ref = None, None
    if frfs[0].reference is not None:
        reference, birge_ref, more = _combine([f.reference for f in frfs], names)
        gaps += more
    yc = None if plants is None else getattr(plants, "control_to_output", plants)
    cross = (nonparametric_crossover(feedback, yc, seed=seed) if yc is not None else
             FrfCrossover(*(float("nan"),) * 4, "no plants given"))
    scatter = f"feedback lines {birge_fb:.2f}" + (
        "" if birge_ref is None else f", reference lines {birge_ref:.2f}")
    notes = [f"averaged over {len(frfs)} run(s) (mean U/F over mean E/F at each line; each line's "
             f"error from the remnant levels between the lines); the runs' scatter over what their "
             f"remnant explains (Birge ratio; above 1 widens the set's errors): {scatter}"]
    if gaps:
        notes.append(f"{gaps} line(s) found in only some of the runs, averaged over those")
    return Frf("multisine", feedback, reference,
               float(np.mean([f.remnant_share for f in frfs])), cross, frfs[0].window, frfs[0].dt,
               "+".join(f.run_id for f in frfs if f.run_id), any(f.synthetic for f in frfs), tuple(notes),
               {"runs": len(frfs), "feedback": birge_fb, "reference": birge_ref})
