"""How strong a pilot's motion path is, as distinct from whether it is there (the test of
:mod:`.motion_test`): the estimate of Km and Km/|Ke| and their profile-likelihood intervals.

The test holds its visual equaliser at the original model's value (the nuisance at its null
estimate, conservative for a test) and weighs each line by the remnant measured with the
nonparametric describing function. Both bias an estimate:

* At the lines E and Y carry the same remnant as U, and least squares with fixed weights
  leans every fit towards the remnant's own U/E (about −1/Yc): on SYNTHETIC generator Hess
  pilots Km/|Ke| came out 0.80 of the truth at 40 % remnant power, 0.93 at 10 % and 0.98
  at 2 % (a paper-angle pilot, four remnant seeds each; a roll-angle one 0.74 at 40 %,
  1.0 at 10 %). The estimate therefore
  refines the fit with the errors-in-variables weights
  (:func:`~hesspipe.identification._line_fit.sml_weights`), each line's variance the
  model's own equation error at the unforced neighbours.
* A lead the original model bought to stand in for the vestibular path stays in the test's
  expanded fit: a roll-angle pilot at 0.1 % remnant came out at 1.2 times its Km/|Ke| with
  it held and within 0.5 % with it free. Where target and disturbance lines separate E
  from Y the estimate frees it.

Both only refine the test's fit: the weights equal the test's at its optimum and follow the
model's response from there (:func:`~hesspipe.identification._line_fit.sml_weights`). On
the generator's Hess motion pilots (``benchmarks/bench_km_interval.py --seeds 10``, 38
trials with a target) the median error of Km/|Ke| fell from 16 % to 7 % and its mean log
error from −0.12 to −0.02; on JSBSim-flown two-input runs identified with the fitted
plants (``bench_km_identifiability.py --levers 10 --levers-designs TWO_INPUT``) Km/Ke stayed
at 17 % and Km fell from 543 % to 51 %.
"""

from __future__ import annotations

import math
from typing import Callable, Mapping, Sequence

import numpy as np
from scipy import stats

from ..pilot.hess import km_per_ke
from ._line_fit import _fit, _predict, _standard_errors, sml_weights
from .lines import LineData


def km_estimate(model, base: dict, free: Sequence[str], lo, hi, test_optimum: Mapping[str, float],
                original_optimum: Mapping[str, float], equaliser: tuple[str, float, float], dof: int,
                km_small: float, data, ld: LineData) -> tuple[dict, Callable[[float], dict]]:
    """Km and Km/|Ke| of the expanded model with the visual equaliser free (with a target), fitted with the
    errors-in-variables weights from the test's optimum, and the function of a confidence
    level that gives their profile-likelihood intervals (:func:`_km_profile`).

    Parameters
    ----------
    model : hesspipe.pilot.hess.PilotModel
        The expanded model.
    base, free, lo, hi
        The test's chosen alternative: parameter values, the free names (the equaliser not
        among them, Km among them) and their bounds.
    test_optimum, original_optimum : mapping
        The test's expanded and original optima (the latter with the equaliser's value).
    equaliser : (str, float, float)
        The visual equaliser's name and bounds, s (freed only where the lines have a target
        and a disturbance set, ``ld.both``).
    dof : int
        Residual degrees of freedom of the test's expanded fit (one fewer here where the
        equaliser is freed).
    km_small : float
        Where a profile's upward steps from Km = 0 start.
    data : tuple
        ``(cab, s, E, Y, U, groups, yc_inv)`` of :func:`~hesspipe.identification._line_fit._fit`.
    ld : LineData
        The lines (their fixed weights and remnant statistics).

    Returns
    -------
    estimate : dict
        ``parameters``, ``Km``, ``Km_per_Ke`` and ``Km_se`` (delta method, NaN on a bound).
    profile : callable
        ``profile(level)`` → ``{"Km_interval": [lo, hi], "Km_per_Ke_interval": [lo, hi]}``.
    """
    if ld.both:
        eq, eq_lo, eq_hi = equaliser
        free_x = [*free, eq]
        lo_x, hi_x = np.append(lo, eq_lo), np.append(hi, eq_hi)
        x_test = [test_optimum[n_] for n_ in free_x]
        _, p_x, _ = _fit(model, base, free_x, lo_x, hi_x, [x_test, [*x_test[:-1], 0.0]], *data, ld.w)
    else:
        # With one line set E = -Y at every line, where a visual lead and the vestibular
        # path differ only by the canals' and the platform's shapes: freed, the lead took
        # Km's place (development run, weights not yet anchored at the test's fit: median
        # error of Km/|Ke| 56 % freed against 44 % held, 38 disturbance-only trials).
        free_x, lo_x, hi_x, p_x = list(free), lo, hi, test_optimum
    cab, s, E, Y, _, _, yc_inv = data
    _, reference = _predict(test_optimum, model, cab, s, E, Y, yc_inv, response=True)
    sml = sml_weights(ld, reference)
    rss, best, sol = _fit(model, base, free_x, lo_x, hi_x, [[p_x[n_] for n_ in free_x]], *data, sml)
    dof_x = dof - (len(free_x) - len(free))
    estimate = {"parameters": {n_: float(v) for n_, v in best.items()}, "Km": float(best["Km"]),
                "Km_per_Ke": km_per_ke(best), "Km_se": _standard_errors(sol, free_x, rss, dof_x)["Km"]}

    def profile(level: float) -> dict:
        # The same criterion at Km = 0, for the lower ends (from the original's optimum and
        # from the estimate's other parameters).
        i = free_x.index("Km")
        rest = free_x[:i] + free_x[i + 1:]
        rss_zero, _, _ = _fit(model, {**base, **best, "Km": 0.0}, rest, np.delete(lo_x, i), np.delete(hi_x, i),
                              [[original_optimum.get(n_, best[n_]) for n_ in rest], [best[n_] for n_ in rest]],
                              *data, sml)
        return {key: list(_km_profile(model, base, free_x, lo_x, hi_x, best, rss, max(rss_zero, rss), dof_x,
                                      float(level), km_small, data, sml, ratio=ratio))
                for key, ratio in (("Km_interval", False), ("Km_per_Ke_interval", True))}

    return estimate, profile


def _km_profile(model, base, free, lo, hi, best: Mapping[str, float], rss_best: float, rss_zero: float,
                dof: int, level: float, km_small: float, data, w, *, ratio: bool = False) -> tuple[float, float]:
    """Profile-likelihood interval of Km (or, with `ratio`, of Km/|Ke|) at confidence `level`:
    the values whose best fit of the other parameters stays within the F test's critical
    value of the optimum.

    Consistent with its criterion (the lower end is above 0 exactly when the nested F at
    Km = 0, from ``rss_zero`` under the same weights, exceeds the critical value; the
    test's own F, with fixed weights and the lead held, can fall on the other side of it near
    the threshold), and honest in a valley: where Km trades
    with the proprioceptive loop or the delay the curvature at the optimum gives standard
    errors of 10^3-10^4 for a Km significant at p ~ 1e-25 (generator trials), while the
    profile follows the valley. Along that valley Ke and Km scale together with the
    proprioceptive gain (1 + K1 K2 where 1/T1 lies below the lines; module doc), so the
    ratio's profile is narrow where Km's spans decades. The upper end is ``inf`` when Km's
    search bound (for the ratio: that bound over the optimum's |Ke|) is reached.
    """
    i = free.index("Km")
    names = free[:i] + free[i + 1:]
    lo_r, hi_r = np.delete(lo, i), np.delete(hi, i)
    crit = float(stats.f.ppf(level, 1, dof))
    scale = rss_best / dof
    ke_hat = max(abs(float(best["Ke"])), 1e-12)

    def f_at(v, start):
        if ratio:
            rss, p, _ = _fit(model, {**base, **best}, names, lo_r, hi_r, [start], *data, w,
                             tie=lambda q: q.__setitem__("Km", v * abs(q["Ke"])))
        else:
            rss, p, _ = _fit(model, {**base, **best, "Km": v}, names, lo_r, hi_r, [start], *data, w)
        return (max(rss, rss_best) - rss_best) / scale, [p[n] for n in names]

    hat = float(best["Km"]) / ke_hat if ratio else float(best["Km"])
    small, top = (km_small / ke_hat, float(hi[i]) / ke_hat) if ratio else (km_small, float(hi[i]))
    start = [best[n] for n in names]
    ends = []
    for factor, limit in ((1 / 3, None), (3.0, top)):
        if factor < 1 and ((rss_zero - rss_best) / scale <= crit or hat <= 0):
            ends.append(0.0)
            continue
        inside, x_in, outside = hat, start, None
        for _ in range(24):   # bracket: geometric steps until the fit is worse than crit
            # From Km on its bound of 0 the upward steps start at km_small.
            v = inside * factor if inside > 0 else small
            if limit is not None and v >= limit:
                f, x = f_at(limit, x_in)
                if f <= crit:
                    break
                v = limit
            else:
                f, x = f_at(v, x_in)
            if f > crit:
                outside = v
                break
            inside, x_in = v, x
        if outside is None:
            ends.append(0.0 if factor < 1 else math.inf)
            continue
        for _ in range(6):    # bisection in the logarithm: about 2 % of the value
            mid = math.sqrt(inside * outside) if inside > 0 else 0.5 * outside
            f, x = f_at(mid, x_in)
            if f > crit:
                outside = mid
            else:
                inside, x_in = mid, x
        ends.append(inside)
    return float(ends[0]), float(ends[1])
