"""The describing-function test of motion feedback: one implementation for compare-pilots'
per-pilot verdict (:mod:`hesspipe.pilots.verdict`) and diagnose (:mod:`hesspipe.diagnose.motion`).

Per pilot (:func:`motion_test`): a likelihood-ratio test on the pilot's
**describing-function lines**. A multisine experiment forces the loop on a set
of frequency lines (disturbance and/or target); at those lines the Fourier
coefficients of control U, output Y and error E = R − Y are far above the
remnant. The Hess loop (SPEC.md "Stage three", expanded model) holds at every
frequency::

    U (1 + NM PF) = NM (visual E − vestibular Y) + N        (N: remnant)

so each model predicts U from the measured E and Y (an equation-error form:
no closed-loop simulation, target and disturbance lines alike). The residual
at a line is remnant filtered by ``1/(1 + NM PF)``; its variance is measured
at the neighbouring, unforced bins, where the loop runs on remnant alone with
e = −y, so the true pilot's residual there is ``U − H E`` with H the describing
function measured at the nearest disturbance line (:func:`line_variances`, the
same neighbour residual as :mod:`.frf`'s sigma; no model fit enters). (Before,
the residual of a first fit of the original model set it: in closed loop that
fit under-stated the remnant at the low lines, 1.5-7 times on angle tasks, and
several times more on the double integrator.) With residuals
scaled by it (which fixes the misfit's frequency shape; its overall level is
left to the data), the nested-model likelihood-ratio test for the q extra
parameters (the expanded model is the original at Km = 0) is the F test

    F = (RSS_original − RSS_expanded) / q / (RSS_expanded / (2 L − p_expanded))

(L complex lines, 2 L real residuals). Km alone (q = 1) sits on its boundary under
"no motion feedback", so F is 0 half the time (Self & Liang 1987) and
``p = ½ P(F(1, 2L − p) > F)``. With target and disturbance lines a second
alternative adds a vestibular delay tau_m (0-:data:`TAU_M_MAX` s, q = 2,
``p = P(F(2, 2L − p) > F)``, conservative: tau_m is not identified under the null,
Davies 1987). The
delay is the test's, not the paper's model's: human vestibular responses lag by
0.1-0.2 s (SPEC.md "Describing functions"); Km alone lost half its motion runs on angle
tasks of the generator drawn with tau_m = 0.15 s (development seeds 100-111), and the
delayed alternative alone named 9 of 16 JSBSim-flown motion pilots (whose path has no
delay) against 10 of 16 with Km alone or with both (benchmarks/bench_fly_pilot.py).
With both line sets each of these two is also fitted in a second form
(:data:`FORMS_BY_ORDER`): in Hess's order k = 2 the multimodal pilot models', the vestibular
path outside Hess's proprioceptive loop; in order 1 Hess's without the visual lag, nested in
the original fitted without it and admitted only where it fits as well as the original with
it (:data:`UNEQUALISED`). The test's p is the smallest of the alternatives' each divided
by its share of the level (Bonferroni; equal shares within a form, :data:`FORM_SHARES`
between the forms). In order 2 the whole test is also made in McRuer's precision structure
(:data:`PRECISION`, no proprioceptive loop), and the structure whose expanded model scores
better is kept, as the order is.
With one line set only Km in Hess's form is tested. Both models are fitted by bounded least
squares (Ke, K1, 1/T1, tau0, wn, zn, and 1/T2 for k = 2; K2 is held because
only K1 K2 is identifiable; and a visual lag or lead a human adds that Hess's
structure lacks, :data:`VISUAL_EQUALISER`, which the expanded fits hold at the
original's value; the original is fitted without it too), several starts each. The **gain** is
``1 − RSS_expanded / RSS_original``: the share of the describing-function
misfit that the motion path removes.

How strong the motion path is, per pilot, is **Km/|Ke|**, not Km. Where the
proprioceptive lead's corner 1/T1 lies below the lines (as a human's often does), its
feedback is the constant K1 K2 there, and the inner loop ``NM / (1 + NM K1 K2)`` is one
gain ``1/(1 + K1 K2)`` times a neuromuscular mode of frequency ``wn sqrt(1 + K1 K2)`` and
damping ``zn / sqrt(1 + K1 K2)``: Ke and Km scale together along a valley of (K1, wn, zn),
which only the lines near 1/T1 bound. The ratio is the same all along it. On the SYNTHETIC
yaw-angle runs of the independent generator's precision pilots (three runs each of one
person, 1/s, sparse two-input layout) one person's Km came out 2.2, 13.5 and 0.34 with Ke
18.7, 209 and 3.1, while Km/|Ke| came out 0.116, 0.065 and 0.110. The reported Km and
Km/|Ke| are not the test's fit but the estimate of :mod:`._km_estimate` (the equaliser free,
errors-in-variables weights): the test's fit, right for a test, puts Km/|Ke| low by about
a tenth at a typical remnant.

Records without separated multisine lines (random wind or gusts, as in the
JSBSim pipeline's cohort) have no describing function to test: the pilot's
test is "not available" and the verdict says so instead of guessing from
spectra. (Tried and dropped: the same equation error over every forced bin of
a broadband record. There the remnant drives E and Y too, the regression is
biased by the closed loop, and on hesspipe's own cohort with Km = 2-8 it found
motion in 0 of 4 pilots.)
"""

from __future__ import annotations

from typing import Mapping

import numpy as np

from ..core.choices import DEFAULT_DISPLAY, DISPLAYS
from ..core.errors import HesspipeError
from ..core.formats import as_runs
from ..core.paper import FITNESS_BAND_HZ
from ._line_fit import _nested_f

# The fits live in ._motion_fits; their constants are re-exported here, where the test's
# callers read them (to patch one, patch it in ._motion_fits, where the fits read it).
from ._motion_fits import (  # noqa: F401
    ALPHA,
    EXPANDED_KEEP,
    FEEDFORWARD,
    FORM_SHARES,
    FORMS_BY_ORDER,
    MIN_VISUAL_DELAY,
    PRECISION,
    TAU_M_MAX,
    UNEQUALISED,
    VESTIBULAR_FORMS,
    VISUAL_EQUALISER,
    _either_order,
    finish,
)
from ._path_check import PATH_ADVICE, PATH_VARIANTS  # noqa: F401

# The line data live in .lines; re-exported here, where the test's callers have read them.
from .lines import (  # noqa: F401
    MAX_EXTRAPOLATED_RISE,
    MIN_LINE_SNR,
    MIN_LINES,
    SEPARABLE,
    SMOOTH_ORDER,
    LineData,
    _line_sets,
    analysis_window,
    forcing_lines,
    forcing_sets,
    line_data,
    line_snr,
    line_variances,
    pooled_line_data,
    windowed,
)

EITHER_EXACT = 0.5
"""With display "either" the pursuit test runs where the compensatory p is below this. The
reported p (the larger of the two where the pursuit result counts, :data:`EITHER_FEEDFORWARD`)
is then exact wherever it is below 0.5, and elsewhere the compensatory p, a lower bound of it
that is at least 0.5: every decision at a level below 0.5 is exact - diagnose's, and the
cohort's median-pilot test, whose p is at least 0.5 when its median pilot's is
(:func:`hesspipe.pilots.verdict.median_pilot_p`)."""

ALTERNATIVES_IN_WORDS = ("nested F tests of Km alone, p = 0.5 P(F > f) for Km >= 0, and with target and "
                         "disturbance lines also with a vestibular delay and in a second form (in Hess's "
                         "order 2 the vestibular path outside the proprioceptive loop, the multimodal form; "
                         "in order 1 without the visual lag, the unequalised form), weighted Bonferroni over "
                         "them (FORM_SHARES); in order 2 also in McRuer's precision structure, the structure "
                         "whose expanded model scores better kept")
"""The test's alternatives in words, as diagnose's criterion and pilots' method state them."""

EITHER_FEEDFORWARD = 0.2
"""With display "either", the pursuit test's result counts only where its feedforward is
needed beside the vestibular path: the nested F test of the two expanded fits (the
feedforward's three parameters, Kff, T_ff and ff_share) gives p below this. Elsewhere the
compensatory result stands. Without it the feedforward of the pursuit fits took part of a compensatory
pilot's vestibular path: on a laboratory's single-integrator motion users (SYNTHETIC), 13 of
32 runs were named against 16 of 32 with the compensatory test alone. The generator's pursuit
pilots still kept the pursuit result (57 of 58 runs), and their no-motion runs stayed unnamed.
A pretest on the same data: the pair's level is no longer bounded by construction whatever the
display, and is measured instead (benchmarks/bench_diagnose.py, bench_cohort_rule.py)."""


def motion_test(run, plants, start: Mapping[str, float], *, k: int = 1,
                band_hz: tuple[float, float] = FITNESS_BAND_HZ, max_delay: float | None = None,
                interval: float | None = None, display: str = DEFAULT_DISPLAY,
                path_check: float | None = None) -> dict:
    """Likelihood-ratio test of motion feedback on one pilot's describing-function lines.

    Parameters
    ----------
    run : hesspipe.core.formats.Run or sequence of Run
        Time (s), disturbance, output, control, reference (e = reference − output).
        Repeated runs of one pilot in one condition are pooled line by line
        (:func:`~hesspipe.identification.lines.pooled_line_data`), the second and later
        each with its own gain (a human's gains move by 5-15 % between runs; one degree
        of freedom each).
    plants : hesspipe.core.formats.Plants
        Only ``motion_path`` is used (output → cab angular velocity; absent: the
        paper's platform × washout).
    start : mapping
        Starting values of the original model's parameters (e.g. compare-pilots'
        spectral optimum); Ke's sign is kept. Where Ke is more than
        :data:`~._line_fit.START_GAIN_RATIO` times off the gain that fits the lines best
        with the other values (:func:`~._line_fit.data_gain`), the original model is
        searched from that gain as well.
    k : int
        Hess model order (1: rate-like controlled element, 2: K/s²).
    band_hz : (float, float)
        Lines are used in this band, Hz.
    max_delay : float, optional
        Also test the original model's visual delay against this bound, s
        (:func:`._motion_fits._delay_bound`; diagnose's extra delay); above
        :data:`MIN_VISUAL_DELAY`, the fits' own lower bound.
    interval : float, optional
        Confidence level (e.g. 0.95) of a profile-likelihood interval of Km
        and of Km/|Ke| (:func:`._km_estimate._km_profile`; about twenty more fits each, so compare-pilots
        asks for them and diagnose does not).
    display : {"compensatory", "pursuit", "either"}
        What the pilot saw. "pursuit" (target and output shown apart) adds the feedforward
        path humans then use on the target (:data:`FEEDFORWARD`), free in both models, on
        records with target lines. "either" (display not known): motion is significant only
        if it is so with and without that path (an intersection-union test; the reported
        result is the one with the larger p, and ``display_p`` gives both), where the
        pursuit fit's feedforward is needed beside the vestibular path
        (:data:`EITHER_FEEDFORWARD`); elsewhere the compensatory result.
    path_check : float, optional
        A level: where the test's p is not below it, the record has target and disturbance
        lines and the plants give a ``motion_path``, the Km alternative is refitted with the path's likely mistakes in its place
        (:data:`PATH_VARIANTS`: negated, differentiated once more, integrated once more),
        and one is reported where its p, times their number, is below the level.

    Returns
    -------
    dict
        ``available`` (bool; False with ``reason`` when the record has too few
        forcing lines), ``n_lines``, ``rss_original``, ``rss_expanded`` (weighted
        residual sums, dimensionless: remnant variance units), ``lr`` (LR
        statistic, the F of the nested test), ``p_value``, ``gain`` (1 − rss_expanded / rss_original),
        ``Km`` and ``Km_se`` (the estimate's, :mod:`._km_estimate`: the expanded model with
        the visual equaliser free and errors-in-variables weights, not the test's fit; its
        standard error from the fit's Jacobian with the residual
        variance rss/dof and parameters on a bound held, same units as the pilot model's
        Km; NaN with Km on its bound of 0), ``Km_per_Ke`` (Km/|Ke|: the vestibular path's
        gain relative to the visual one, output units per rad/s of cab motion, so
        dimensionless on a rate task and seconds on an angle task; unlike Km itself it is
        identified, module doc), ``Km_interval`` and ``Km_per_Ke_interval`` (with
        `interval`: the profile intervals ``[lo, hi]``, ``hi`` inf when unbounded; else
        None), ``significant`` (p < :data:`ALPHA`),
        ``parameters_original`` / ``parameters_expanded`` (the test's two fits' pilot
        parameters), ``parameters_estimate`` (the estimate's), ``standard_errors_original`` and
        ``standard_errors_expanded`` (of the two fits' free parameters; diagnose reads the
        pilot's own delay from the model its verdict keeps),
        ``delay_bound`` and ``delay_bound_expanded`` (None without `max_delay`; else
        :func:`._motion_fits._delay_bound`'s test of that fit's delay against it), ``display``,
        ``target_lines`` (whether the record has a target's lines) and ``feedforward``
        (the fitted ``Kff``, ``T_ff`` and ``tau_ff``, s, ``ff_share`` times tau0; None unless a
        pursuit display with target lines); with display "either" also ``display_p`` (display → p-value; "pursuit"
        only on records with target lines where the compensatory p is below
        :data:`EITHER_EXACT`) and ``feedforward_p`` (the pretest's p of the pursuit
        feedforward, :data:`EITHER_FEEDFORWARD`; None where the pursuit fits were not
        made); ``forcing`` (:func:`~.lines.forcing_sets` of the first run:
        with one forcing function the test rests on the model's shapes of the two paths
        alone, and no motion found is "cannot tell", not "no"); ``path_check`` (None unless
        asked and run; else ``p_values``, variant → p of motion with that path,
        ``named``, the variants whose p times their number is below ``level`` (in
        :data:`PATH_VARIANTS`' order), ``better``, the one of them with the smallest p or None,
        and ``level``); ``k`` (Hess's order the test was made in: `k`, or with both line sets
        the other where its expanded model scores better, RSS + ln(residuals) per parameter)
        and ``dof_expanded`` (the residual degrees of freedom of the alternative kept);
        ``structure`` ("hess" or :data:`PRECISION`, the pilot structure the test was made in)
        and, where it is the precision structure, ``hess`` (Hess's result in the same order,
        this dict's keys without ``hess`` and the intervals, its ``path_check`` None,
        :func:`hess_result`: the pilot's own dynamics in Hess's model; ``Km``,
        ``Km_per_Ke``, ``Km_se``, ``parameters_estimate`` and the intervals are Hess's then).
        Of the up to six tests fitted (display "either", order 2) only the reported one
        gets its Km estimate, intervals and path check (:func:`._motion_fits.finish`).
    """
    if display not in DISPLAYS:
        raise HesspipeError(f"display: expected one of {', '.join(DISPLAYS)}, got {display!r}")
    if max_delay is not None and not max_delay > MIN_VISUAL_DELAY:
        raise HesspipeError(f"max_delay: expected more than the fits' shortest visual delay "
                            f"MIN_VISUAL_DELAY = {MIN_VISUAL_DELAY:g} s, got {max_delay:g} s")
    runs = as_runs(run)
    ld = line_data(runs[0], band_hz) if len(runs) == 1 else pooled_line_data(runs, band_hz)
    forcing = {"forcing": forcing_sets(runs[0], band_hz)}
    if forcing["forcing"] != SEPARABLE:
        # With one forcing function "not named" is "cannot tell", so a variant that names
        # motion says nothing of the path: target-only runs of the generator with the right
        # path were flagged "negated" on 8 of 8 (static pilots, seeds 1-4), and the negated
        # path then named motion on static runs (newcomer review on the lab stand-in).
        path_check = None
    kw = dict(k=k, max_delay=max_delay, path_check=path_check)
    if display != "either":
        return {**finish(*_either_order(ld, plants, start, display=display, **kw), interval), **forcing}
    # An intersection-union test (Berger 1982): significant only if significant with the
    # display's feedforward and without it. Under "no motion" with either display the
    # matching test rejects with probability <= alpha, so the pair does too, whichever
    # display the pilot had. Its p is at least the first, so the pursuit fits are only
    # needed where the first p is below EITHER_EXACT. (Run only where the first test was
    # significant, the reported p of the generator's pursuit no-motion pilots leaned low
    # below it, and the cohort's median-pilot test said yes for 9-11 % of their cohorts.)
    # The pursuit result counts only where its feedforward is needed (EITHER_FEEDFORWARD):
    # a pretest of the display, so that a compensatory pilot's vestibular path is not
    # shared with a feedforward the pilot never had. It trades the bound above for a
    # measured level.
    comp = _either_order(ld, plants, start, display="compensatory", **kw)
    out = {"display": "either", "display_p": {"compensatory": comp[0].get("p_value")}, "feedforward_p": None}
    if comp[0].get("available") and comp[0]["target_lines"] and comp[0]["p_value"] < EITHER_EXACT:
        purs = _either_order(ld, plants, start, display="pursuit", **kw)
        out["display_p"]["pursuit"] = purs[0].get("p_value")
        if purs[0].get("available"):
            out["feedforward_p"] = _feedforward_p(comp[0], purs[0])
            if feedforward_needed(out["feedforward_p"]) and purs[0]["p_value"] >= comp[0]["p_value"]:
                comp = purs
    return {**finish(*comp, interval), **out, **forcing}


def hess_result(result: dict) -> dict:
    """The motion test's result in Hess's structure.

    Parameters
    ----------
    result : dict
        :func:`motion_test`'s result.

    Returns
    -------
    dict
        `result` itself, or where the test kept the precision structure (:data:`PRECISION`)
        the Hess result it carries under ``hess``: the pilot's own dynamics in Hess's model.
    """
    return result.get("hess", result)


def feedforward_needed(feedforward_p: float | None) -> bool:
    """Whether display "either" counts the pursuit test: its feedforward's p (the result's
    ``feedforward_p``; None where the pursuit fits were not made) is below
    :data:`EITHER_FEEDFORWARD`. Then the test's p is the larger of the two displays'; else
    the compensatory test's.

    Parameters
    ----------
    feedforward_p : float or None
        :func:`motion_test`'s ``feedforward_p``.
    """
    return feedforward_p is not None and feedforward_p < EITHER_FEEDFORWARD


def _feedforward_p(comp: dict, purs: dict) -> float:
    # The nested F test of the pursuit display's feedforward (its parameters) between
    # the two expanded fits, each with its own vestibular path; nested only within one
    # pilot structure, so where the two displays kept different ones, between Hess's.
    if comp.get("structure") != purs.get("structure"):
        comp, purs = hess_result(comp), hess_result(purs)
    return _nested_f(comp["rss_expanded"], purs["rss_expanded"], len(FEEDFORWARD), purs["dof_expanded"])[1]


def safe_motion_test(run, plants, start: Mapping[str, float], *, k: int = 1,
                     band_hz: tuple[float, float] = FITNESS_BAND_HZ, max_delay: float | None = None,
                     interval: float | None = None, display: str = DEFAULT_DISPLAY,
                     path_check: float | None = None) -> dict:
    """:func:`motion_test`, with a failure of the test reported in the result, not raised
    (a pilot's identification stays valid when its describing function cannot be tested).

    Parameters
    ----------
    run, plants, start, k, band_hz, max_delay, interval, display, path_check
        As :func:`motion_test`.

    Returns
    -------
    dict
        :func:`motion_test`'s result, or ``{"available": False, "reason": ...}``.
    """
    try:
        return motion_test(run, plants, start, k=k, band_hz=band_hz, max_delay=max_delay,
                           interval=interval, display=display, path_check=path_check)
    except (HesspipeError, ValueError, np.linalg.LinAlgError) as exc:
        return {"available": False, "reason": f"motion test failed: {exc}"}
