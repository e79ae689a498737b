"""A global smoother of a measured describing function, and the crossover it gives.

All the measured lines (H_k with the standard deviation sigma_k of its complex
error, see :mod:`hesspipe.identification.frf`) are fitted at once by a
low-order describing function of McRuer's precision form::

    H(s) = +-K e^(-tau s) (1 + TL s)/(1 + TI s) * wn^2/(s^2 + 2 zn wn s + wn^2)

by weighted complex least squares: each line's error ``H(j w_k) - H_k``
divided by ``sqrt(sigma_k^2 + (REL_FLOOR |H_k|)^2)``, a Cauchy loss of scale
F_SCALE (one noisy high line does not steer the fit), literature bounds
(tau 0.05-0.5 s, wn 4-25 rad/s, zn 0.05-1, TL and TI 0.01-10 s) and weak
priors worth one line each on the neuromuscular mode (NM_PRIOR, shared with
the df criterion) and on the delay (TAU_PRIOR). Its starts are screened on a grid
(the gain solved in closed form for each) and the best TOP refined. Magnitude
and phase are fitted jointly, so the phase at the crossover draws on every
line instead of the two or three within its octave.

The crossover of ``L = H Yc`` (exact plant) is the first fall of |L| through
1 on a fine grid spanning the lines (the definition the generator's truth and
SPEC's tracking crossover use); its standard deviation is the spread of that
crossing over loops drawn from the fit's linearised covariance (Gauss-Newton,
inflated by the reduced chi-square when above 1), not from refits.
Unlike :func:`hesspipe.pilot.mcruer.fit_precision`, which scores simulated
loops for the benchmark, this fits the points directly and has no loop.

The fit is a smoother, not an identification: it is used as the crossover
estimate only when its residuals are consistent with the lines' variances
(:func:`consistent`); :mod:`.frf_crossover` otherwise keeps the local
regression.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np
from scipy.optimize import least_squares
from scipy.stats import chi2 as chi2_dist

from ..core.seeds import derive_seed
from ..pilot.crossover import flat_band, phase_margin_deg

NAMES = ("K", "tau", "TL", "TI", "wn", "zn")
LOWER = np.array([-np.inf, 0.05, np.log(0.01), np.log(0.01), np.log(4.0), 0.05])
UPPER = np.array([np.inf, 0.5, np.log(10.0), np.log(10.0), np.log(25.0), 1.0])
"""Bounds of the parameter vector (ln K, tau s, ln TL, ln TI, ln wn, zn)."""
NM_PRIOR = {"zn": (0.3, np.log(3.0)), "wn": (10.0, np.log(2.0))}
"""Weak prior on the neuromuscular mode (centre, width in ln units), worth one line's residual
at one width: above the forcing's band the lines are swamped by remnant, and without it a
search bends a lightly damped peak onto a noisy high line. Shared with the df criterion
(:mod:`hesspipe.identification.criteria`)."""
REL_FLOOR = 0.02
"""Relative error floor of a line (a noise-free line still has a model to fit within)."""


def line_scale(sigma, H):
    """A line's error scale with the floor: ``sqrt(sigma^2 + (REL_FLOOR |H|)^2)`` (the df
    criterion's and this smoother's weights).

    Parameters
    ----------
    sigma : array
        The lines' standard errors, H's units.
    H : array
        The lines' complex describing function.

    Returns
    -------
    numpy.ndarray
        In H's units.
    """
    return np.sqrt(sigma ** 2 + (REL_FLOOR * np.abs(H)) ** 2)


F_SCALE = 2.0
"""Cauchy loss scale: a line's error of two standard deviations."""
TAU_PRIOR = (0.2, np.log(2.0))
"""Weak prior on the delay (centre s, width in ln units), worth one line: the lines above the
forcing's corner are swamped by remnant, and without it the phase slope near crossover trades
the delay against the lead-lag on two or three lines."""
TOP = 3
P_CONSISTENT = 1e-4
"""The smooth fit is taken when the chi-square of its residuals has p >= this."""
GRID_POINTS = 600
SPAN = 2.0
"""The crossover is sought from the lowest line / SPAN to the highest line x SPAN."""
_STARTS = tuple(itertools.product(
    (1.0, -1.0), (0.12, 0.22, 0.35), (6.0, 10.0, 16.0), (0.2, 0.5),
    ((0.02, 0.02), (0.02, 0.3), (0.02, 1.5), (0.3, 0.02), (1.5, 0.02), (1.0, 3.0), (3.0, 1.0))))
"""Start grid: sign, tau (s), wn (rad/s), zn, (TL, TI) (s): none, lags, leads, lead-lags."""


def _shape(x, s, sign):
    """The model without its gain at complex `s` (1/s); x = (ln K, tau, ln TL, ln TI, ln wn, zn)."""
    wn = np.exp(x[4])
    return (sign * np.exp(-x[1] * s) * (1 + np.exp(x[2]) * s) / (1 + np.exp(x[3]) * s)
            * wn * wn / (s * s + 2 * x[5] * wn * s + wn * wn))


def _residuals(x, w, H, scale, sign):
    r = (np.exp(x[0]) * _shape(x, 1j * w, sign) - H) / scale
    prior = [np.log(np.exp(x[4]) / NM_PRIOR["wn"][0]) / NM_PRIOR["wn"][1],
             np.log(x[5] / NM_PRIOR["zn"][0]) / NM_PRIOR["zn"][1],
             np.log(x[1] / TAU_PRIOR[0]) / TAU_PRIOR[1]]
    return np.concatenate((r.real, r.imag, prior))


@dataclass(frozen=True)
class SmoothFit:
    """The fitted describing function (see the module doc).

    Attributes
    ----------
    x : ndarray
        (ln K, tau s, ln TL, ln TI, ln wn rad/s, zn).
    sign : float
        +1 or -1 (the sign of the pilot's gain).
    chi2 : float
        Sum over lines of ``|H(j w_k) - H_k|^2 / (scale_k^2 / 2)`` (each of the two components of
        a line's error has variance scale^2 / 2), without the priors.
    dof : int
        Two per line less six parameters.
    cov : ndarray
        Linearised covariance of `x` (6 x 6), inflated by ``max(1, chi2 / dof)``; zero in the
        rows and columns of parameters on a bound (held there).
    """

    x: np.ndarray
    sign: float
    chi2: float
    dof: int
    cov: np.ndarray

    @property
    def params(self) -> dict:
        """K (control per error unit, signed), tau (s), TL, TI (s), wn (rad/s), zn."""
        v = dict(zip(NAMES, (self.sign * np.exp(self.x[0]), self.x[1], np.exp(self.x[2]),
                             np.exp(self.x[3]), np.exp(self.x[4]), self.x[5])))
        return {k: float(val) for k, val in v.items()}

    @property
    def p_value(self) -> float:
        """Chance of a chi-square at least this large if the model held within the lines' errors."""
        return float(chi2_dist.sf(self.chi2, self.dof)) if self.dof > 0 else float("nan")

    def response(self, w) -> np.ndarray:
        """The fitted H(j w) at `w` (rad/s), complex.

        Parameters
        ----------
        w : array
            Angular frequencies, rad/s.
        """
        return np.exp(self.x[0]) * _shape(self.x, 1j * np.asarray(w, dtype=float), self.sign)


def fit_smooth(w, H, sigma) -> SmoothFit | None:
    """Fit the smoother to measured lines (None with fewer than four lines).

    Parameters
    ----------
    w : array
        Line frequencies, rad/s.
    H : array of complex
        Measured describing function (control per unit error).
    sigma : array
        Standard deviation of each line's complex error (``E|dH|^2``), same units as H.

    Returns
    -------
    SmoothFit or None
    """
    w, H, sigma = (np.asarray(a) for a in (w, H, sigma))
    if w.size < 4:
        return None
    scale = line_scale(sigma, H)
    wt = 1.0 / scale ** 2
    cands = []
    for sign, tau, wn, zn, (tl, ti) in _STARTS:
        x = np.array([0.0, tau, np.log(tl), np.log(ti), np.log(wn), zn])
        S = _shape(x, 1j * w, sign)
        k = np.sum(wt * (np.conj(S) * H).real) / np.sum(wt * np.abs(S) ** 2)
        if k > 0:  # the best real gain for this shape; a negative one is the other sign's start
            x[0] = np.log(k)
            cands.append((float(np.sum(wt * np.abs(k * S - H) ** 2)), sign, x))
    if not cands:
        return None
    cands.sort(key=lambda c: c[0])
    best = None
    for _, sign, x0 in cands[:TOP]:
        r = least_squares(_residuals, x0, bounds=(LOWER, UPPER), args=(w, H, scale, sign),
                          method="trf", loss="cauchy", f_scale=F_SCALE)
        if best is None or r.cost < best[0].cost:
            best = (r, sign)
    r, sign = best
    err = np.exp(r.x[0]) * _shape(r.x, 1j * w, sign) - H
    chi2 = float(2 * np.sum(np.abs(err) ** 2 / scale ** 2))
    dof = 2 * w.size - len(NAMES)
    # A parameter on its bound (active_mask) is held there, not estimated: its column of the
    # Jacobian says nothing of its spread (a lag TI on its 0.01 s bound read a standard
    # deviation of 19.5 in ln TI, whose draws moved a double integrator's crossover to 10 rad/s).
    free = r.active_mask == 0
    J = r.jac[:, free]
    cov = np.zeros((r.x.size, r.x.size))
    cov[np.ix_(free, free)] = np.linalg.pinv(J.T @ J) * max(1.0, chi2 / dof if dof > 0 else 1.0)
    return SmoothFit(r.x, float(sign), chi2, dof, cov)


def consistent(fit: SmoothFit | None) -> bool:
    """Whether the fit's residuals are consistent with the lines' variances (p >= P_CONSISTENT).

    Parameters
    ----------
    fit : SmoothFit or None
    """
    return fit is not None and fit.dof > 0 and fit.p_value >= P_CONSISTENT


def _first_falls(m, grid):
    """The first fall through 0 of each row of `m` (D, G), ln|L| on `grid`: wc (D,) rad/s, NaN
    without one; the grid index just below it and the fraction of the step."""
    down = (m[:, :-1] >= 0) & (m[:, 1:] < 0)
    i = np.argmax(down, axis=1)
    rows = np.arange(m.shape[0])
    has = down.any(axis=1)
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.where(has, m[rows, i] / (m[rows, i] - m[rows, i + 1]), 0.0)   # no fall: no step
    lg = np.log(grid)
    wc = np.where(has, np.exp(lg[i] + t * (lg[i + 1] - lg[i])), np.nan)
    return wc, i, t


DRAWS = 2000
"""Loops drawn for the smoothed crossover's spread. They are the same draws on every call (a
fixed seed), so the spread, and whether a crossover is ill-defined, is a function of the
lines alone: with 400 draws seeded from the user's seed, a reviewer's flat-loop persons came
out ill-defined in 5-9 of 10 seeds. 2000 draws cost about 10 ms."""


LOST_MAX = 0.975
"""Share of the draws that must cross for a finite spread (:func:`_spread` drops 2.5 % each side)."""


def smooth_crossover(fit: SmoothFit, block, w_lines, *, draws: int = DRAWS):
    """Crossover of ``L = H_fit Yc``, its standard deviations and the band where |L| stays near 1.

    The standard deviations are the spread (:func:`_spread`: the central 95 % of the draws
    over 2 x 1.96) of the same crossing over `draws` loops drawn from the fit's covariance,
    linearised: ``ln L(j w) + G(w) dx`` with ``G`` the gradient of
    ``ln L`` at each frequency and ``dx`` drawn from the covariance. Near a well-defined
    crossing this is the usual propagation; where |L| stays near 1 over a wide band a draw's
    crossing can jump along it, which a derivative at the crossing does not see.

    Parameters
    ----------
    fit : SmoothFit
    block : hesspipe.pilot.blocks.Block
        The control plant.
    w_lines : array
        The fitted lines' frequencies (rad/s): the search spans them (times SPAN each side).
    draws : int
        Loops drawn for the standard deviations (always the same ones: :data:`DRAWS`).

    Returns
    -------
    wc, pm, wc_std, pm_std : float
        rad/s and deg; NaN when |L| does not fall through 1 in the span (std inf when more
        than 2.5 % of the draws find no crossing).
    band : hesspipe.pilot.crossover.FlatBand or None
        :func:`hesspipe.pilot.crossover.flat_band` of the fitted loop.
    """
    grid = np.logspace(np.log10(np.min(w_lines) / SPAN), np.log10(np.max(w_lines) * SPAN),
                       GRID_POINTS)
    yc_grid = block.response(1j * grid)

    def loop(x):
        return np.exp(x[0]) * _shape(x, 1j * grid, fit.sign) * yc_grid

    L = loop(fit.x)
    ln = np.log(np.abs(L)) + 1j * np.unwrap(np.angle(L))
    G = np.empty((grid.size, fit.x.size), complex)
    for j in range(fit.x.size):
        h = 1e-5 * max(1.0, abs(fit.x[j]))
        xp, xm = fit.x.copy(), fit.x.copy()
        xp[j] += h
        xm[j] -= h
        G[:, j] = np.log(loop(xp) / loop(xm)) / (2 * h)   # d ln L / dx_j, phase unwrapped by the ratio
    vals, vecs = np.linalg.eigh(fit.cov)
    root = vecs * np.sqrt(np.clip(vals, 0.0, None))
    dx = np.random.default_rng(derive_seed(0, "frf-smooth-crossover")).standard_normal((draws, fit.x.size)) @ root.T
    # row 0 the fitted loop itself, then the draws
    lns = ln[None, :] + np.vstack((np.zeros(fit.x.size), dx)) @ G.T
    wcs, i, t = _first_falls(lns.real, grid)
    nan = float("nan")
    if not np.isfinite(wcs[0]):
        return nan, nan, nan, nan, None
    rows = np.nonzero(np.isfinite(wcs))[0]
    ph = lns.imag[rows[:, None], i[rows, None] + [0, 1]]
    pms = phase_margin_deg(np.degrees(ph[:, 0] + t[rows] * (ph[:, 1] - ph[:, 0])))
    wc, pm = float(wcs[0]), float(pms[0])
    band = flat_band(grid, L, wc)
    if rows.size - 1 < LOST_MAX * draws:
        # More draws lose the crossing than the spread's central 95 % leaves out: it lies
        # beyond the span as often as not within it, so the spread is unbounded.
        return wc, pm, float("inf"), float("inf"), band
    dpm = (pms[1:] - pm + 180.0) % 360.0 - 180.0
    return wc, pm, _spread(wcs[rows[1:]]), _spread(dpm), band


def _spread(x) -> float:
    """A standard deviation from the draws' central 95 % (their width over 2 x 1.96): a second
    crossing that a few per cent of the draws reach counts, a rare far tail does not (1 % of
    draws at 10 rad/s, where a poorly determined neuromuscular mode lifted |L|, doubled a plain
    standard deviation of 0.6)."""
    lo, hi = np.percentile(x, [2.5, 97.5])
    return float((hi - lo) / (2 * 1.959964))


def describing_function(params: dict):
    """The smoother's H(s) from its :attr:`SmoothFit.params` (e.g. a JSON's ``smooth_fit``).

    Parameters
    ----------
    params : dict
        ``K`` (signed), ``tau``, ``TL``, ``TI`` (s), ``wn`` (rad/s), ``zn``.

    Returns
    -------
    callable
        ``H(s)`` for complex `s` (1/s), control per unit error.
    """
    p = {k: float(params[k]) for k in NAMES}
    x = np.array([np.log(abs(p["K"])), p["tau"], np.log(p["TL"]), np.log(p["TI"]),
                  np.log(p["wn"]), p["zn"]])
    sign = 1.0 if p["K"] >= 0 else -1.0

    def H(s):
        return np.exp(x[0]) * _shape(x, np.asarray(s), sign)
    return H
