"""Bounded least squares from several starts and its covariance: the describing-function
fits' shared numerics (:mod:`.motion_test`, :mod:`.paired_delay`)."""

from __future__ import annotations

import math

import numpy as np
from scipy import optimize

from ..core.errors import HesspipeError

SCREEN_NFEV = 30
"""Residual evaluations (least squares' max_nfev) each start gets before a screened search keeps
only its best starts."""

TOLERANCE = 1e-6
"""Each search's ``ftol``, ``xtol`` and ``gtol`` (scipy's default 1e-8): it stops when a step
changes the cost or the parameters by less than this share of themselves. The residuals are
in remnant-variance units, so the RSS (tens) is then known to about 1e-4, far below what the
F tests read; scipy's default spent a third of a laboratory's diagnoses polishing digits no
result shows (p-values on its 32 first runs equal to three digits, median 3.5 -> 2.4 s CPU;
1e-5 moved one p from 0.008 to 0.003)."""


def best_least_squares(resid, starts, lo, hi, failure: str, *, keep: int | None = None, resid_rows=None):
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
    keep : int, optional
        Screen the starts: each is run for :data:`SCREEN_NFEV` evaluations, and only the
        `keep` best go on to convergence, from where they stopped. None: every start to
        convergence.

    Raises
    ------
    HesspipeError
        With `failure` when no start converges.
    """
    def inside(x):
        return np.clip(np.asarray(x, dtype=float), lo + 1e-9 * (hi - lo), hi - 1e-9 * (hi - lo))

    starts = [inside(x0) for x0 in starts]
    if keep is not None and len(starts) > keep:
        screened = sorted((r for r in (_solve(resid, x0, lo, hi, SCREEN_NFEV, resid_rows) for x0 in starts)
                           if r is not None), key=lambda r: r[0])
        # The kept go on from where the screen left them (one that converged there stops
        # again within a few evaluations).
        starts = [inside(sol.x) for _, sol in screened[:keep]]
    best = None
    for x0 in starts:
        r = _solve(resid, x0, lo, hi, 400, resid_rows)
        if r is not None and (best is None or r[0] < best[0]):
            best = r
    if best is None:
        raise HesspipeError(failure)
    return best


_RELATIVE_STEP = float(np.finfo(np.float64).eps) ** 0.5


class _ForwardDifference:
    """`resid` and its forward-difference Jacobian for :func:`scipy.optimize.least_squares`,
    the numbers of scipy's default (``jac="2-point"``) without its per-column overhead.

    scipy's ``approx_derivative`` cost about a tenth of a laboratory's diagnosis in its own
    bookkeeping (the residual is ~100 µs of Python on 14-40 lines). The steps are scipy's:
    sqrt(eps) max(1, |x|) signed as x (+ at 0), turned back where the step would leave the
    bounds and fits on the other side, else the distance to the farther bound; the step is
    read back as (x + h) - x; the Jacobian at x reuses the residual the search just computed
    there. Equal bit for bit to scipy 1.17's (tests/test_lsq.py), so a search follows the
    same path to the same optimum. With `resid_rows` the columns' points are evaluated in one
    call, a row each (the same numbers: tests/test_loop_at_lines.py).
    """

    def __init__(self, resid, lo, hi, resid_rows=None):
        self._resid, self._lo, self._hi = resid, np.asarray(lo, dtype=float), np.asarray(hi, dtype=float)
        self._rows = resid_rows
        self._last = None

    def fun(self, x):
        f = self._resid(x)
        self._last = (np.array(x, dtype=float), f)
        return f

    def jac(self, x):
        x0 = np.asarray(x, dtype=float)
        f0 = self._last[1] if self._last is not None and np.array_equal(self._last[0], x0) \
            else self._resid(x0)
        f0 = np.atleast_1d(f0)
        h = _RELATIVE_STEP * ((x0 >= 0).astype(float) * 2 - 1) * np.maximum(1.0, np.abs(x0))
        below, above = x0 - self._lo, self._hi - x0
        outside = (x0 + h < self._lo) | (x0 + h > self._hi)
        fits = np.abs(h) <= np.maximum(below, above)
        h[outside & fits] *= -1
        up, down = (above >= below) & ~fits, (above < below) & ~fits
        h[up], h[down] = above[up], -below[down]
        if self._rows is not None:
            x1 = np.tile(x0, (x0.size, 1))
            idx = np.arange(x0.size)
            x1[idx, idx] = x0 + h
            return ((np.atleast_2d(self._rows(x1)) - f0) / ((x0 + h) - x0)[:, None]).T
        jt = np.empty((x0.size, f0.size))
        for i in range(x0.size):
            x1 = x0.copy()
            x1[i] = x0[i] + h[i]
            jt[i] = (np.atleast_1d(self._resid(x1)) - f0) / ((x0[i] + h[i]) - x0[i])
        # scipy's layout (the transpose of a C array): the trust region's products then sum
        # in the same order.
        return jt.T


def _solve(resid, x0, lo, hi, max_nfev: int, resid_rows=None):
    fd = _ForwardDifference(resid, lo, hi, resid_rows)
    try:
        sol = optimize.least_squares(fd.fun, x0, jac=fd.jac, bounds=(lo, hi), x_scale="jac",
                                     max_nfev=max_nfev, ftol=TOLERANCE, xtol=TOLERANCE, gtol=TOLERANCE)
    except (ValueError, FloatingPointError):
        return None
    rss = float(np.sum(sol.fun ** 2))
    return (rss, sol) if np.isfinite(rss) else None


def held_covariance(sol, rss: float, dof: int, released=()) -> np.ndarray:
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
    released : sequence of int
        Parameters whose uncertainty is wanted even on a bound: never held (the local
        curvature stands for their error where a NaN would be read as none).
    """
    n = sol.jac.shape[1]
    active = np.asarray(getattr(sol, "active_mask", np.zeros(n)), dtype=int) != 0
    active[np.asarray(released, dtype=int)] = False
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
