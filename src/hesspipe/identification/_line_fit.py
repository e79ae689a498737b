"""The equation-error fits at the forcing lines that :mod:`.motion_test`, its Km estimate
(:mod:`._km_estimate`) and :mod:`.paired_delay` share: the Hess loop's prediction of the
control from the measured error and output (:func:`_predict`), its bounded least squares
(:func:`_fit`) with fixed or errors-in-variables weights (:func:`sml_weights`), starts and
standard errors.
"""

from __future__ import annotations

import math
from typing import Callable, Mapping, Sequence

import numpy as np
from scipy import stats

from ._loop_at_lines import loop_rows
from ._lsq import best_least_squares, held_covariance
from .lines import LineData, remnant_variance

MULTIMODAL = "multimodal"
"""The held parameter (0 or 1) that selects the vestibular path's form in :func:`_predict`: 0
Hess's (the vestibular sensation joins the visual drive inside the proprioceptive loop, so
the loop's equalisation shapes both), 1 the multimodal pilot models' (Zaal et al. 2009:
the visual and vestibular channels each with their own equalisation, summed at the
neuromuscular system). Only :mod:`.motion_test`'s alternatives set it."""


def feedforward_delay(params) -> float:
    """The pursuit feedforward's delay, s: ``ff_share`` (FEEDFORWARD; 1 where absent) times the
    visual delay ``tau0``.

    Parameters
    ----------
    params : mapping
        A fit's pilot parameters (``tau0`` in s).
    """
    return params.get("ff_share", 1.0) * params["tau0"]


def _predict(params, model, cab, s, E, Y, yc_inv=None, cache: dict | None = None, *, response: bool = False):
    # One parameter set's prediction: :func:`_predict_rows` with one row.
    out = _predict_rows([params], model, cab, s, E, Y, yc_inv, cache, response=response)
    return (out[0][0], out[1][0]) if response else out[0]


def _predict_rows(rows, model, cab, s, E, Y, yc_inv=None, cache: dict | None = None, *, response: bool = False):
    # The Hess loop at the lines for each parameter set of `rows` (arrays: a row each):
    # U (1 + NM PF) = NM (visual E - vestibular Y), the vestibular path delayed by the
    # test's own tau_m (0 when absent: the paper's model), the visual path with the test's
    # equaliser (VISUAL_EQUALISER; 0 when absent); on a pursuit display (yc_inv, the
    # controlled element's inverse at s) also + NM FF R with R = E + Y (FEEDFORWARD). With
    # MULTIMODAL set (the test's other vestibular form) the vestibular path reaches the
    # muscle outside the proprioceptive loop: U = NM (visual E / (1 + NM PF) - vestibular
    # Y). `cache`: the fit's cache for this `s` (loop_rows). With `response`, also the
    # pilot's response to -y (e = -y, r = 0: the remnant's bins). Every operation is
    # elementwise, row by row: a row's numbers are those of the row alone (a Jacobian's
    # columns evaluated at once, _lsq._ForwardDifference).
    nm, ves, vis, rd = loop_rows(rows, model, cab, s, cache)
    names = _TEST_NAMES if yc_inv is None else _TEST_NAMES + _FEEDFORWARD_NAMES
    tau_m, lead, lag, outside, *ff = np.array([[p.get(n, 0.0) for n in names] + (
        [] if yc_inv is None else [feedforward_delay(p)]) for p in rows], dtype=float).T[:, :, None]
    # A factor left out where it is exactly 1 (no vestibular delay, no equaliser): the same
    # numbers, and these were a fifth of the fits' model evaluations.
    on = tau_m[:, 0] != 0
    if on.all():
        ves = ves * np.exp(-s * tau_m)
    elif on.any():
        ves[on] = ves[on] * np.exp(-s * tau_m[on])
    on = (lead[:, 0] != 0) | (lag[:, 0] != 0)
    if on.all():
        vis = vis * (1.0 + s * lead) / (1.0 + s * lag)
    elif on.any():
        vis[on] = vis[on] * (1.0 + s * lead[on]) / (1.0 + s * lag[on])
    drive = vis * E
    if yc_inv is not None:
        kff, t_ff, ff_delay = ff
        drive = drive + kff * yc_inv * np.exp(-s * ff_delay) / (1.0 + s * t_ff) ** 2 * (E + Y)
    # The vestibular term's share of the return difference: 1 / rd in Hess's form, 1 outside it.
    ves_rd = 1.0 / rd
    on = outside[:, 0] != 0
    if on.any():
        ves_rd[on] = 1.0
    u = nm * (drive / rd - ves * ves_rd * Y)
    return (u, nm * (vis / rd + ves * ves_rd)) if response else u


_TEST_NAMES = ("tau_m", "TL_v", "TI_v", MULTIMODAL)
"""The test's own parameters that :func:`_predict_rows` reads (0 where absent)."""

_FEEDFORWARD_NAMES = ("Kff", "T_ff")
"""The pursuit feedforward's (with its delay, :func:`feedforward_delay`)."""


def _nested_f(rss_restricted: float, rss_full: float, q: int, dof: int) -> tuple[float, float]:
    """(F, p) of a nested least-squares test: `q` parameters, `dof` residual degrees of freedom
    of the full model. With one parameter the restriction is a bound (Km >= 0, a delay at
    most a human's), where F is 0 half the time under H0 (Self & Liang 1987): p is halved."""
    gain = max(rss_restricted - rss_full, 0.0)
    f = gain / q / (rss_full / dof) if rss_full > 0 and dof > 0 else math.inf
    p = float(stats.f.sf(f, q, dof)) * (0.5 if q == 1 else 1.0) if f > 0 else 1.0
    return f, p


def _fit(model, base: dict, free: Sequence[str], lo, hi, starts, cab, s, E, Y, U, groups, yc_inv, w,
         tie: Callable[[dict], None] | None = None, keep: int | None = None):
    """Bounded least squares of the weighted complex residual; best of `starts`.

    With `groups` (the run of each line, repeated runs pooled), the second and later runs'
    predictions are each scaled by their own gain, solved in closed form at every step
    (variable projection): a human's gains move by 5-15 % between runs. `yc_inv` (the
    controlled element's inverse at the lines, or None) adds a pursuit display's feedforward.
    `tie` sets parameters from the others at every step (a profile along Km/Ke). `keep`:
    screen the starts, only that many best go on to convergence (``best_least_squares``). `w`: the
    lines' weights, or a function of the model's response to -y that gives them
    (:func:`sml_weights`; a later run's own gain scales its response too). A Jacobian's
    columns are evaluated together, row by row the numbers of one point alone
    (:func:`_predict_rows`).
    """
    runs = [] if groups is None else [groups == g for g in np.unique(groups)[1:]]
    cache: dict = {}
    fixed = not callable(w)

    def point(x):
        p = dict(base)
        p.update(zip(free, x))
        if tie is not None:
            tie(p)
        return p

    def resid_rows(X):
        # The residual vectors of the parameter vectors X (a row each), row by row as one
        # vector alone would give them (_predict_rows).
        rows = [point(x) for x in X]
        if fixed:
            pred, ws = _predict_rows(rows, model, cab, s, E, Y, yc_inv, cache), w
        else:
            pred, G = _predict_rows(rows, model, cab, s, E, Y, yc_inv, cache, response=True)
            ws = w(G)
        for m in runs:
            ww = ws[..., m] ** 2
            pm = pred[:, m]
            dens, nums = ww * np.abs(pm) ** 2, ww * (np.conj(pm) * U[m]).real
            for i in range(len(rows)):
                # Summed row by row: numpy sums a 2-D array's rows in another order.
                den = float(np.sum(dens[i]))
                if den > 0:
                    gain = max(float(np.sum(nums[i])) / den, 0.0)
                    pred[i, m] = pm[i] * gain
                    if not fixed:
                        G[i, m] = G[i, m] * gain
        if runs and not fixed:
            ws = w(G)
        r = (U - pred) * ws
        return np.concatenate([r.real, r.imag], axis=1)

    def resid(x):
        return resid_rows([x])[0]

    rss, sol = best_least_squares(resid, starts, lo, hi, "motion test: no fit of the describing "
                                  "function converged", keep=keep, resid_rows=resid_rows)
    return rss, point(sol.x), sol


def sml_weights(ld: LineData, reference: np.ndarray) -> Callable[[np.ndarray], np.ndarray]:
    """The lines' weights as a function of the model's response G to −y: ``ld.w`` over the
    square root of :func:`~hesspipe.identification.lines.remnant_variance` relative to
    `reference`, the errors-in-variables (sample maximum-likelihood) criterion.

    The weights are ``ld.w`` where G is `reference` (the response of the fit they refine),
    not where G is the describing function measured at the line: at lines where the remnant
    makes up most of E that measurement is about the remnant's own U/E, and the levels
    there come from the other lines (:func:`~hesspipe.identification.lines.line_variances`).
    Relative to it, a JSBSim-flown Hess pilot's own response weighed 44 times less at the
    lowest two lines (SYNTHETIC, cohort pilot01, two-input forcing).

    Parameters
    ----------
    ld : LineData
        The lines, with their remnant statistics.
    reference : ndarray, complex
        The response to −y at which the weights are ``ld.w`` (control units per output unit).

    Returns
    -------
    callable
        ``weights(G)``: G the model's response to −y at each line (control units per
        output unit) → one weight per line (1 / control units).
    """
    return lambda G: ld.w / np.sqrt(remnant_variance(ld, G, reference))


def pilot_start(model, start: Mapping[str, float], k: int) -> dict:
    """The starting pilot parameters of a describing-function fit: `start` completed for order
    `k`, K2 held at its default and the start's K1 K2 carried by K1 (only the product is
    identifiable).

    Parameters
    ----------
    model : hesspipe.pilot.hess.PilotModel
        The model fitted.
    start : mapping
        Starting values (missing ones: the model's defaults).
    k : int
        Hess model order (1 or 2).
    """
    base = model.complete({key: v for key, v in start.items() if key in model.parameter_names()}, k)
    base["k"] = float(k)
    k2 = model.defaults(k)["K2"]
    base["K1"], base["K2"] = float(np.clip(base["K1"] * base["K2"] / k2, 1e-3, 100.0)), k2
    return base


START_GAIN_RATIO = 4.0
"""A describing-function fit's start whose visual gain Ke is more than this factor from the
data's (:func:`data_gain`) is searched from the data's gain as well
(:func:`hesspipe.identification._motion_fits._null_fit`). From starts 0.85-3.3 times the
data's gain (diagnose's, on three laboratories' 208 double-integrator and 80
single-integrator runs) a start at the data's gain moved no fit by 0.1 %; from starts 5-10
times it (the model's defaults on a plant of gain 5) the fit ended more than 1 % worse on 6
of 80 runs (docs/status.md, lab12)."""


def data_gain(model, params: Mapping[str, float], data, w) -> float | None:
    """The visual gain Ke that fits the lines best with `params`' other parameters held, or
    None where it comes out with the opposite sign to ``params["Ke"]``.

    The prediction of the control is affine in Ke (U = Ke A + B, the vestibular path and a
    pursuit feedforward in B), so this is a weighted linear least squares. The later runs'
    own gains of pooled records are left out (a start needs no more).

    Parameters
    ----------
    model : hesspipe.pilot.hess.PilotModel
        The model fitted.
    params : mapping
        Its complete parameters (Ke in control units per output unit).
    data : tuple
        The fit's ``(cab, s, E, Y, U, groups, yc_inv)`` (:func:`_fit`'s).
    w : ndarray
        The lines' weights (1 / control units).
    """
    cab, s, E, Y, U, _, yc_inv = data
    b = _predict(dict(params, Ke=0.0), model, cab, s, E, Y, yc_inv)
    a = _predict(dict(params, Ke=1.0), model, cab, s, E, Y, yc_inv) - b
    den = float(np.sum(w ** 2 * np.abs(a) ** 2))
    ke = float(np.sum(w ** 2 * (np.conj(a) * (U - b)).real)) / den if den > 0 else 0.0
    return ke if ke * params["Ke"] > 0 else None


def _standard_errors(sol, free: Sequence[str], rss: float, dof: int) -> dict:
    """Standard errors of the `free` parameters (:func:`held_covariance`; NaN for one held
    on its bound)."""
    cov = held_covariance(sol, rss, dof)
    return {n_: float(math.sqrt(max(cov[i, i], 0.0))) if math.isfinite(cov[i, i]) else math.nan
            for i, n_ in enumerate(free)}
