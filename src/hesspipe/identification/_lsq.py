"""Bounded least squares from several starts and its covariance: the describing-function
fits' shared numerics (:mod:`.motion_test`, :mod:`.paired_delay`)."""

from __future__ import annotations

import math

import numpy as np
from scipy import optimize

from ..core.errors import HesspipeError


def best_least_squares(resid, starts, lo, hi, failure: str):
    """(rss, solution) of bounded least squares of `resid` from the best of `starts`.

    Parameters
    ----------
    resid : callable
        Residual vector of a parameter vector.
    starts : iterable of array
        Starting vectors (clipped just inside the bounds).
    lo, hi : array
        Bounds.
    failure : str
        The error's message when no start converges.

    Raises
    ------
    HesspipeError
        With `failure` when no start converges.
    """
    best = None
    for x0 in starts:
        x0 = np.clip(np.asarray(x0, dtype=float), lo + 1e-9 * (hi - lo), hi - 1e-9 * (hi - lo))
        try:
            sol = optimize.least_squares(resid, x0, bounds=(lo, hi), x_scale="jac", max_nfev=400)
        except (ValueError, FloatingPointError):
            continue
        rss = float(np.sum(sol.fun ** 2))
        if np.isfinite(rss) and (best is None or rss < best[0]):
            best = (rss, sol)
    if best is None:
        raise HesspipeError(failure)
    return best


def held_covariance(sol, rss: float, dof: int) -> np.ndarray:
    """Covariance of a weighted least-squares solution's parameters (the residual variance
    estimated as rss / dof: the lines' common scale is left to the data), with the
    parameters that ended on a bound held there: their rows and columns are NaN.

    Left in, a held parameter's near-flat column (a neuromuscular mode at 60 rad/s, above
    every line) made the delay's error 1-2 s where the delay itself was within 0.01 s of the
    truth (generator runs, development seeds).

    Parameters
    ----------
    sol : scipy.optimize.OptimizeResult
        :func:`scipy.optimize.least_squares`'s result (``jac``, ``active_mask``).
    rss : float
        Its residual sum of squares.
    dof : int
        Degrees of freedom of the residual.
    """
    n = sol.jac.shape[1]
    active = np.asarray(getattr(sol, "active_mask", np.zeros(n)), dtype=int) != 0
    keep = np.flatnonzero(~active)
    cov = np.full((n, n), math.nan)
    if keep.size == 0:
        return cov
    try:
        j = sol.jac[:, keep]
        cov[np.ix_(keep, keep)] = np.linalg.pinv(j.T @ j) * (rss / max(dof, 1))
    except np.linalg.LinAlgError:
        pass
    return cov
