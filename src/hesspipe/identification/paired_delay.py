"""The difference of one pilot's visual delay between two runs, on their describing functions.

A simulator's extra delay and the pilot's own visual delay are one delay in a single
record. A within-subject design separates them: the same pilot flies a baseline run, and
the delay that grew is the simulator's. Fitting each run alone, the delay trades with the
neuromuscular mode and the lag (a light, slow mode adds phase like a delay), so each
run's delay scatters by 0.01-0.06 s around the truth and their difference by as much (the
independent generator's runs, development seeds 100-104). Here both runs' lines are fitted
together by the equation error of :mod:`.motion_test` (each line weighted by its measured
remnant): the pilot's dynamics (neuromuscular mode, lead-lag, proprioceptive gain) are
shared, the gain Ke and the delay are each run's own, so the trade is common to both runs
and the difference of the delays is measured by the phase the two runs do not share.

Repeated runs of either condition join the same fit, each with its own gain and delay (a
human's delay scatters from run to run); the difference is that of the conditions' mean
delays, whose run-to-run spread shrinks with the number of runs
(:func:`hesspipe.diagnose.motion.paired_delay_test`).
"""

from __future__ import annotations

import math
from typing import Mapping

import numpy as np

from ..core.errors import HesspipeError
from ..core.formats import as_runs
from ..core.paper import FITNESS_BAND_HZ
from ..pilot.hess import PilotModel
from ..pilot.motion import motion_block
from ._line_fit import _predict_rows, pilot_start
from ._lsq import best_least_squares, held_covariance
from .lines import line_data

SHARED = ("K1", "1/T1", "wn", "zn", "1/T2")
"""Pilot parameters common to the two runs (1/T2 for k = 2 only). (K1 each run's own too
named fewer extra delays and no fewer false ones: development seeds 100-104.)"""
OWN = ("Ke", "tau0")
"""Pilot parameters each run has its own."""
TAU0_BOX = (0.0, 0.6)
"""Bounds of each run's visual delay in the joint fit, s."""


def _lines(run, band_hz):
    ld = line_data(run, band_hz)
    if ld.reason:
        raise HesspipeError(f"{run.source or run.id}: {ld.reason}")
    return ld.s, ld.E, ld.Y, ld.U, ld.w


def paired_delay(run, baseline_run, plants, starts: tuple[Mapping[str, float], Mapping[str, float]], *,
                 k: int = 1, band_hz: tuple[float, float] = FITNESS_BAND_HZ) -> dict:
    """Visual delay of `run` minus that of `baseline_run` (s), one pilot's shared dynamics.

    Parameters
    ----------
    run, baseline_run : hesspipe.core.formats.Run or sequence of Run
        Records of one pilot with multisine forcing (either line set or both): the
        condition under test and the baseline condition. Several runs of a condition
        (repeats) each keep their own gain and delay; the difference is then that of the
        conditions' mean delays.
    plants : hesspipe.core.formats.Plants
        Only the motion path is used (the original model has none; kept for the API).
    starts : (mapping, mapping)
        Starting pilot parameters of the condition and of the baseline (e.g. their first
        runs' own describing-function fits,
        :func:`hesspipe.identification.motion_test.motion_test`'s ``parameters_original``);
        the fit starts from each condition's dynamics in turn.
    k : int
        Hess model order (1 or 2).
    band_hz : (float, float)
        Lines are used in this band, Hz.

    Returns
    -------
    dict
        ``difference_s`` and ``se_s`` (its standard error from the joint fit, s),
        ``delay_s`` and ``baseline_delay_s`` (each condition's mean delay in the joint fit,
        s), ``runs`` and ``baseline_runs`` (how many of each), ``run_delays_s`` and
        ``baseline_run_delays_s`` (each run's own delay, s), ``shared`` (the shared
        parameters), ``n_lines`` (all runs), ``degrees_of_freedom``.

    Raises
    ------
    HesspipeError
        When a run has too few forcing lines or no unforced bins between them (naming it).
    """
    runs, base_runs = as_runs(run), as_runs(baseline_run)
    data = [_lines(r, band_hz) for r in runs + base_runs]
    side = [0] * len(runs) + [1] * len(base_runs)      # which start each run takes
    model = PilotModel()
    cab = motion_block(plants)
    shared = [n for n in SHARED if n != "1/T2" or k == 2]
    own = list(OWN)
    bases = [pilot_start(model, st, k) for st in starts]
    big = 1e3 * max(abs(bases[0]["Ke"]), abs(bases[1]["Ke"]), 1.0)
    box = {"K1": (1e-3, 100.0), "1/T1": (1e-4, 10.0), "wn": (1.0, 60.0), "zn": (0.02, 2.0),
           "1/T2": (1e-3, 20.0), "tau0": TAU0_BOX,
           "Ke": (0.0, big) if bases[0]["Ke"] >= 0 else (-big, 0.0)}
    names = shared + own * len(data)    # x = [shared..., each run's own...]
    lo = np.array([box[n][0] for n in names])
    hi = np.array([box[n][1] for n in names])
    taus = np.array([len(shared) + len(own) * i + own.index("tau0") for i in range(len(data))])
    # The difference of the conditions' mean delays, as a weight on each run's delay.
    g = np.array([1.0 / len(runs) if sd == 0 else -1.0 / len(base_runs) for sd in side])

    def params(x, i):
        p = dict(bases[side[i]])
        p.update(zip(shared, x[:len(shared)]))
        j = len(shared) + len(own) * i
        p.update(zip(own, x[j:j + len(own)]))
        return p

    caches = [{} for _ in data]   # each run's cache, tied to its lines (_line_fit._predict_rows)

    def resid_rows(X):
        # The residual vectors of the parameter vectors X (a row each; a Jacobian's columns):
        # each run's lines predicted for every row at once, row by row the numbers of one.
        out = []
        for i, (s, E, Y, U, w) in enumerate(data):
            r = (U - _predict_rows([params(x, i) for x in X], model, cab, s, E, Y, cache=caches[i])) * w
            out += [r.real, r.imag]
        return np.concatenate(out, axis=1)

    def resid(x):
        return resid_rows([x])[0]

    mid = 0.5 * (bases[0]["tau0"] + bases[1]["tau0"])
    # From each condition's dynamics, with each condition's own delay and with no
    # difference at all (one start's valley of the delay-mode trade can hold the
    # difference away from 0).
    x_starts = []
    for src in bases:
        for same in (False, True):
            x0 = np.array([src[n] for n in shared]
                          + [v for i in range(len(data)) for v in (bases[side[i]][n] for n in own)],
                          dtype=float)
            if same:
                x0[taus] = mid
            x_starts.append(x0)
    rss, sol = best_least_squares(resid, x_starts, lo, hi, "paired delay: no joint fit of the "
                                  "describing functions converged", resid_rows=resid_rows)
    dof = max(sol.fun.size - sol.x.size, 1)
    # The delays' curvature even where one ended on its bound: held there, its error was NaN
    # and the test counted it as none (with the box's floor at 0.1 s, three generator
    # baseline runs of roll-rate pairs, disturbance alone, ended on it and a 0.06 s
    # difference was named at p 0.0009; with the error measured there, 0.067, as with the
    # floor at 0).
    cov = held_covariance(sol, rss, dof, released=taus)
    var = float(g @ cov[np.ix_(taus, taus)] @ g)
    se = float(math.sqrt(max(var, 0.0))) if math.isfinite(var) else math.nan
    t = sol.x[taus]
    mine, theirs = float(t[:len(runs)].mean()), float(t[len(runs):].mean())
    return {"difference_s": mine - theirs, "se_s": se, "delay_s": mine,
            "baseline_delay_s": theirs, "runs": len(runs), "baseline_runs": len(base_runs),
            "run_delays_s": [float(v) for v in t[:len(runs)]],
            "baseline_run_delays_s": [float(v) for v in t[len(runs):]],
            "shared": {n: float(v) for n, v in zip(shared, sol.x[:len(shared)])},
            "n_lines": int(sum(d[0].size for d in data)), "degrees_of_freedom": int(dof)}
