"""The McRuer precision model, fitted to measured data as the benchmark score.

Paper: "the benchmark score is produced by executing the precision model,
which is an extension of the McRuer crossover model". Here::

    Y_p = Kp (TL s + 1) / (TI s + 1) exp(-tau s) Y_NM

with the neuromuscular mode of Table 1 (wn = 10 rad/s, zn = 0.707), closed
around the same plants as the Hess model; Kp, TL, TI and tau are fitted to
the measured control PSD with the same fitness, so the benchmark is "what a
classical quasi-linear model achieves on these data".
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import minimize

from .blocks import Block, Loop, delay, gain, tf
from .hess import table1
from .simulation import UNSTABLE_FITNESS

NAMES = ("Kp", "TL", "TI", "tau")
BOUNDS = {"Kp": (0.01, 100.0), "TL": (0.0, 5.0), "TI": (0.0, 20.0), "tau": (0.05, 0.5)}


def precision_loop(p) -> Loop:
    """Loop blocks of the precision model with parameters `p` (Kp, TL, TI, tau).

    Parameters
    ----------
    p : mapping
        Kp (gain, control per output unit), TL and TI (lead and lag time
        constants, s), tau (delay, s).
    """
    t1 = table1()
    wn, zn = t1["wn"], t1["zn"]
    visual = gain(p["Kp"]) * tf([p["TL"], 1.0], [p["TI"], 1.0]) * delay(p["tau"])
    nm = tf([wn * wn], [1.0, 2 * zn * wn, wn * wn])
    return Loop(visual=visual, vestibular=Block(), neuromuscular=nm, proprioceptive=Block())


@dataclass(frozen=True)
class PrecisionFit:
    """A fitted McRuer precision model (the benchmark of Eq. 10's fitness).

    Attributes
    ----------
    parameters : dict
        Kp, TL (s), TI (s), tau (s).
    fitness : float
        Eq. 10 fitness of the fit, control^2/Hz.
    evaluations : int
        Objective evaluations spent.
    """
    parameters: dict
    fitness: float
    evaluations: int


def _to_params(x):
    # Kp on a log scale (its range spans four decades); the rest linear.
    lo_t = {n: BOUNDS[n] for n in NAMES[1:]}
    out = {"Kp": float(10 ** np.clip(x[0], -2, 2))}
    for n, v in zip(NAMES[1:], x[1:]):
        lo, hi = lo_t[n]
        out[n] = float(np.clip(v, lo, hi))
    return out


# Starting points (log10 Kp, TL, TI, tau): the fit has several local minima
# (lead vs lag compensation), so a few spread-out, fixed starts are refined.
STARTS = ((-1.0, 1.0, 0.5, 0.1), (0.0, 0.5, 1.0, 0.15), (1.0, 0.2, 5.0, 0.2))


def fit_precision(score, *, starts=STARTS[:2], maxfev: int = 150) -> PrecisionFit:
    """Fit the precision model by bounded Powell from fixed starts (deterministic).

    Parameters
    ----------
    score : callable
        ``score(loop) -> fitness`` (unstable loops: :data:`UNSTABLE_FITNESS`).
    starts : tuple
        Starting points (log10 Kp, TL, TI, tau).
    maxfev : int
        Evaluation budget of each Powell run.
    """
    count = 0

    def f(x):
        nonlocal count
        count += 1
        return score(precision_loop(_to_params(x)))

    bounds = [(-2.0, 2.0)] + [BOUNDS[n] for n in NAMES[1:]]
    best_x, best_f = None, np.inf
    for x0 in starts:
        x, fun = bounded_powell(f, x0, bounds, maxfev=maxfev, xtol=1e-3, ftol=1e-4)
        if fun < best_f:
            best_x, best_f = x, fun
    fit = float(best_f)
    return PrecisionFit(_to_params(best_x), fit if fit < UNSTABLE_FITNESS else float("nan"), count)


def bounded_powell(f, x0, bounds, **options) -> tuple[np.ndarray, float]:
    """scipy's bounded Powell, returning the best point it ever evaluated.

    Its bounded line search can step onto a plateau (unstable parameter
    sets) without comparing with the point it left, so the final point is
    not always the best one seen.

    Parameters
    ----------
    f : callable
        Objective of a float array.
    x0 : array
        Start.
    bounds : sequence of (float, float)
        Box, per coordinate.
    **options
        Passed to :func:`scipy.optimize.minimize` as ``options``.

    Returns
    -------
    x : ndarray
    value : float
        ``f(x)``.
    """
    seen = [np.inf, None]

    def g(x):
        value = f(x)
        if value < seen[0]:
            seen[0], seen[1] = value, np.array(x, dtype=float)
        return value

    r = minimize(g, np.asarray(x0, dtype=float), method="Powell", bounds=bounds, options=options)
    if seen[1] is not None and seen[0] < r.fun:
        return seen[1], float(seen[0])
    return np.asarray(r.x, dtype=float), float(r.fun)
