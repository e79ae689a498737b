"""Does motion feedback improve the fit? A per-pilot test and a cohort verdict.

Per pilot: :func:`hesspipe.identification.motion_test.motion_test` (shared with
diagnose), the likelihood-ratio (F) test of Km on the pilot's describing-function lines;
its module docstring gives the equation and the test. Its **gain** is the share of the
describing-function misfit that the motion path removes.

Across pilots (:func:`cohort_verdict`): under "no pilot uses motion" the
per-pilot p-values are independent and (super-)uniform, so Fisher's
combination ``-2 Σ log p ~ χ²(2n)`` tests that null for the cohort; the verdict
is "yes" when it is significant at alpha. Beside it: the count of individually
significant pilots, tested against Binomial(n, alpha). (The first benchmark run
used the binomial count as the rule; it said "no" for one of six motion
cohorts of 8 pilots whose weak-motion pilots were each just short of
significance, where Fisher's p was 1e-4. Fisher's rule, tried on three more
seeds, gave one false "yes" from a pilot whose original fit had stopped in a
local optimum: hence the exchange of optima in :func:`motion_test`. See
benchmarks/bench_verdict.py and the README for the numbers.)

A pilot whose record has no separated multisine lines (gusts, as in the JSBSim
pipeline's cohort) has no test ("not available", see the motion test), and the
verdict says so instead of guessing from spectra.
"""

from __future__ import annotations

import math
from typing import Mapping

import numpy as np
from scipy import stats

# The per-pilot test lives with identification so that diagnose uses the very same one.
from ..identification.motion_test import ALPHA, analysis_window, forcing_lines, motion_test, safe_motion_test  # noqa: F401


def cohort_verdict(tests: Mapping[str, Mapping], *, alpha: float = ALPHA) -> dict:
    """Paired verdict across pilots from their :func:`motion_test` results.

    Parameters
    ----------
    tests : mapping
        Pilot id → :func:`motion_test` dict.
    alpha : float
        Significance level of the per-pilot tests and of the cohort test.

    Returns
    -------
    dict
        ``answer`` ("yes", "no" or "undetermined"), ``sentence`` (the verdict in
        words), ``fisher_p`` (Fisher's combination of the per-pilot p-values: the
        cohort test), ``n_tested``, ``n_significant``, ``binomial_p`` (P[X ≥
        n_significant] for X ~ Binomial(n_tested, alpha)), ``median_gain``, ``per_pilot``
        (id → gain, p_value, significant), ``method``.
    """
    done = {pid: t for pid, t in tests.items() if t.get("available")}
    method = ("per pilot: likelihood-ratio test of Km on the describing-function lines "
              "(equation error U(1+NM PF) = NM(visual E - vestibular Y), residuals scaled by the "
              "remnant level of neighbouring unforced bins; nested F test, p = 0.5 P(F > f), "
              "Km >= 0); "
              f"cohort: Fisher's combination of the pilots' p-values, yes if p < {alpha:g}")
    if not done:
        return {"answer": "undetermined", "n_tested": 0, "n_significant": 0, "method": method,
                "sentence": "undetermined: no pilot's record has multisine forcing lines, so no "
                            "describing function could be tested for motion feedback",
                "per_pilot": {pid: {"available": False} for pid in tests}}
    n = len(done)
    sig = sum(1 for t in done.values() if t["p_value"] < alpha)
    binom_p = float(stats.binom.sf(sig - 1, n, alpha)) if sig > 0 else 1.0
    fisher_p = float(stats.combine_pvalues([t["p_value"] for t in done.values()],
                                           method="fisher").pvalue)
    gains = np.array([t["gain"] for t in done.values()])
    yes = fisher_p < alpha
    skipped = len(tests) - n
    tail = f" ({skipped} pilot(s) without forcing lines not tested)" if skipped else ""
    claim = "improves" if yes else "does not significantly improve"
    sentence = (f"{'yes' if yes else 'no'}: motion feedback {claim} the describing-function "
                f"fit across the {n} pilots (Fisher's combined p = {fisher_p:.2g}); individually "
                f"significant for {sig} of {n} pilots (p < {alpha:g}; binomial p = {binom_p:.2g}); "
                f"median share of the misfit removed {100 * float(np.median(gains)):.0f} %{tail}")
    return {"answer": "yes" if yes else "no", "sentence": sentence, "n_tested": n,
            "n_significant": sig, "binomial_p": binom_p, "fisher_p": fisher_p, "median_gain": float(np.median(gains)), "alpha": alpha,
            "method": method,
            "per_pilot": {pid: ({"gain": t["gain"], "p_value": t["p_value"], "lr": t["lr"],
                                 "Km": t["Km"], "Km_se": t["Km_se"], "significant": t["significant"]}
                                if t.get("available") else {"available": False,
                                                            "reason": t.get("reason", "")})
                          for pid, t in tests.items()}}


def verdict_lines(verdict: Mapping) -> list[str]:
    """Plain-text lines of a :func:`cohort_verdict`: the sentence, then one line per pilot.

    Parameters
    ----------
    verdict : mapping
        A :func:`cohort_verdict` result (``sentence``, ``per_pilot``, ``method``).
    """
    out = [f"MOTION VERDICT: {verdict['sentence']}"]
    for pid, t in verdict.get("per_pilot", {}).items():
        if t.get("available", True) is False:
            out.append(f"  {pid}: not tested ({t.get('reason', 'no forcing lines')})")
            continue
        se = t.get("Km_se")
        km = f"Km {t['Km']:.3g}" + (f" +/- {se:.2g}" if se is not None and math.isfinite(se) else "")
        out.append(f"  {pid}: misfit removed {100 * t['gain']:.1f} %, F = {t['lr']:.3g}, "
                   f"p = {t['p_value']:.2g}{' *' if t['significant'] else ''}, {km}")
    out.append(f"  ({verdict['method']})")
    return out
