"""Does motion feedback improve the fit? A per-pilot test and a cohort verdict.

Per pilot: :func:`hesspipe.identification.motion_test.motion_test` (shared with
diagnose), the likelihood-ratio (F) test of Km on the pilot's describing-function lines;
its module docstring gives the equation and the test. Its **gain** is the share of the
describing-function misfit that the motion path removes.

Across pilots (:func:`cohort_verdict`) the question is the population's — does *the*
pilot use the motion, not *some* pilot — so the verdict rests on the median pilot: an
order-statistic test (Wilkinson 1951). With r = ceil(n/2) and p_(r) the r-th smallest
per-pilot p-value, under "no pilot uses motion" (independent, super-uniform p) P(p_(r) <= x)
<= P(Binomial(n, x) >= r), so ``majority_p = P(Binomial(n, p_(r)) >= r)``, and the verdict is
"yes" when it is below alpha: at least half of the pilots show the effect. Beside it:
Fisher's combination ``-2 Σ log p ~ χ²(2n)``, which tests "at least one pilot" and is
reported, not decisive, and the count of individually significant pilots against
Binomial(n, alpha). History: a binomial count rule said "no" for one of six motion cohorts
of 8 pilots whose weak-motion pilots were each just short of significance (Fisher's p
1e-4; re-run with the median pilot, that benchmark's cohort of roll seed 6, 1 of 8 pilots
significant and binomial p 0.077, says yes at 8.6e-5); Fisher's rule, the verdict before this one, let one
atypical pilot decide: on the independent generator's no-motion pilots whose visual
gain wanders (CV 0.3) it said "yes" for 10 % of cohorts of 8, and for 77 % of cohorts with
one motion pilot among seven without (per-pilot test with the compensatory display;
``benchmarks/bench_cohort_rule.py``, the README gives the figures).

Pilots who flew a condition several times (:func:`pilot_groups` maps run ids to pilots):
each pilot's runs are combined first, by Fisher's rule over their p-values, so that the
count and the cohort test are over pilots, not over runs of the same person.

A pilot whose record has no separated multisine lines (gusts, as in the JSBSim
pipeline's cohort) has no test ("not available", see the motion test), and the
verdict says so instead of guessing from spectra. A record with one forcing function
(a target or a disturbance alone) has one describing function, in which the visual and
vestibular paths act on the same signal: its test rests on the model's shapes of the two
paths alone, and finding nothing there does not rule motion out. So "no" needs at least
half of the pilots' records to have both line sets; otherwise a cohort that is not "yes" is
"undetermined: cannot tell", as diagnose says run by run. (Before, such a cohort was "no":
on the independent generator's precision pilots flying a target alone, yaw angle, single
integrator, six pilots with motion feedback, every pilot's p was 0.5-1 and the verdict
said "no".)
"""

from __future__ import annotations

import math
import re
from typing import Mapping, Sequence

import numpy as np
from scipy import stats

from ..core.errors import HesspipeError

# The per-pilot test lives with identification so that diagnose uses the very same one.
from ..identification.motion_test import (  # noqa: F401
    ALPHA,
    ALTERNATIVES_IN_WORDS,
    PATH_ADVICE,
    PATH_VARIANTS,
    SEPARABLE,
    analysis_window,
    forcing_lines,
    motion_test,
    safe_motion_test,
)


def pilot_groups(run_ids: Sequence[str], pattern: str | None,
                 sources: Mapping[str, str] | None = None,
                 files: Mapping[str, str] | None = None) -> dict[str, str] | None:
    """Pilot id of each run id: the part of the id that `pattern` captures.

    Parameters
    ----------
    run_ids : sequence of str
        Run ids (file stems), e.g. ``["s01_motion_r1", "s01_motion_r2", "s02_motion_r1"]``.
    pattern : str or None
        Regular expression searched in each id; its group ``pilot`` (or else its first
        group, or else the whole match) is the pilot id, e.g. ``r"^(s\\d+)"``. None: every
        run is its own pilot.
    sources : mapping, optional
        Run id → the file it was read from, named in the errors instead of the id.
    files : mapping, optional
        Run id → the id of the file it was read from (:attr:`hesspipe.core.formats.Run.file_id`):
        without a pattern the runs of a file holding several are one pilot's.

    Returns
    -------
    dict or None
        Run id → pilot id (None when `pattern` is None and every file holds one run).

    Raises
    ------
    HesspipeError
        For a pattern that is not a regular expression, or a run id it does not match.
    """
    if pattern is None:
        files = {rid: (files or {}).get(rid, rid) for rid in run_ids}
        return files if any(f != rid for rid, f in files.items()) else None
    try:
        rx = re.compile(pattern)
    except re.error as exc:
        raise HesspipeError(f"pilot_id: {pattern!r} is not a regular expression ({exc})") from None
    out = {}
    for rid in run_ids:
        m = rx.search(rid)
        where = (sources or {}).get(rid, rid)
        if m is None:
            raise HesspipeError(f"{where}: pilot_id pattern {pattern!r} does not match the run id {rid!r}; "
                                f"expected a pattern that finds the pilot in every file name")
        key = m.group("pilot") if "pilot" in rx.groupindex else m.group(1) if rx.groups else m.group(0)
        if not key:
            raise HesspipeError(f"{where}: pilot_id pattern {pattern!r} captures an empty pilot id "
                                f"from the run id {rid!r}")
        out[rid] = key
    return out


def _per_pilot(done: Mapping[str, Mapping], groups: Mapping[str, str]) -> dict[str, dict]:
    # Runs of one pilot are independent records: under "no motion" each p is uniform, so
    # Fisher's combination is the pilot's own test; the cohort then counts pilots, not runs.
    by = {}
    for rid, t in done.items():
        by.setdefault(groups.get(rid, rid), []).append(t)
    out = {}
    for pid, ts in by.items():
        ps = [t["p_value"] for t in ts]
        p = _combined(ps)
        forcing = sorted({t["forcing"] for t in ts})
        out[pid] = {"p_value": p, "gain": float(np.median([t["gain"] for t in ts])),
                    "lr": float(np.median([t["lr"] for t in ts])), "runs": len(ts),
                    "forcing": forcing[0] if len(forcing) == 1 else " / ".join(forcing)}
        for key in ("Km", "Km_per_Ke"):
            v = np.array([t.get(key, math.nan) for t in ts], dtype=float)
            out[pid][key] = float(np.mean(v))
            out[pid][f"{key}_se"] = (float(np.std(v, ddof=1) / math.sqrt(v.size)) if v.size > 1
                                     else ts[0].get(f"{key}_se", math.nan))
        if len(ts) == 1:
            out[pid].update({key: ts[0].get(key) for key in ("Km_interval", "Km_per_Ke_interval",
                                                            "interval_level")})
        else:
            # A reader took the pilot's F and p for a statistic and its p, and Km_se for the
            # run's curvature error.
            out[pid]["combined"] = ("p_value: Fisher's combination of the runs' p; gain and lr: medians "
                                    "over the runs; Km and Km_per_Ke: means over the runs, *_se their "
                                    "standard errors")
    return out


def cohort_verdict(tests: Mapping[str, Mapping], *, alpha: float = ALPHA,
                   groups: Mapping[str, str] | None = None) -> dict:
    """Paired verdict across pilots from their :func:`motion_test` results.

    Parameters
    ----------
    tests : mapping
        Run id → :func:`motion_test` dict (one run per pilot unless `groups`); its
        ``forcing`` says which line sets the record has.
    alpha : float
        Significance level of the per-pilot tests and of the cohort test.
    groups : mapping, optional
        Run id → pilot id (:func:`pilot_groups`) when pilots flew several runs: a pilot's
        runs are combined first (Fisher's combination of their p-values; median gain; Km
        and Km/|Ke| their means, their errors the standard errors over the runs), so the
        count and the cohort test are over pilots.

    Returns
    -------
    dict
        ``answer`` ("yes", "no" or "undetermined": no pilot tested, or not "yes" while fewer
        than half of the pilots' records have both line sets, :data:`SEPARABLE`),
        ``sentence`` (the verdict in words), ``n_separable`` (pilots whose records have both
        line sets), ``majority_p`` (:func:`median_pilot_p`: the cohort test), ``majority_r``,
        ``fisher_p`` (Fisher's combination of the per-pilot p-values: "at least one
        pilot", reported), ``n_tested``, ``n_significant``, ``binomial_p`` (P[X ≥
        n_significant] for X ~ Binomial(n_tested, alpha)), ``median_gain``, ``per_pilot``
        (id → gain, p_value, significant, Km and Km/|Ke| with their profile intervals, or
        with `groups` their means and standard errors over the pilot's runs), ``method``,
        ``path_check`` (:func:`path_verdict`, None when the answer is "yes").
    """
    done = {pid: t for pid, t in tests.items() if t.get("available")}
    method = ("per pilot: likelihood-ratio test of Km on the describing-function lines "
              "(equation error U(1+NM PF) = NM(visual E - vestibular Y), residuals scaled by the "
              f"remnant level of neighbouring unforced bins; {ALTERNATIVES_IN_WORDS}); "
              f"cohort: yes if at least half of the pilots show it, median-pilot order-statistic test "
              f"p < {alpha:g} (Fisher's combination, reported beside it, tests 'at least one')")
    if not done:
        why = ("no pilot's record has multisine forcing lines, so no describing function could be "
               "tested for motion feedback") if tests else "no pilot was identified"
        return {"answer": "undetermined", "n_tested": 0, "n_significant": 0, "method": method,
                "sentence": f"undetermined: {why}", "path_check": None,
                "per_pilot": _per_pilot_out(tests, {}, groups, alpha)}
    n_runs = len(done)
    pilots = _per_pilot(done, groups or {})
    n = len(pilots)
    ps = np.array([t["p_value"] for t in pilots.values()], dtype=float)
    sig = int(np.sum(ps < alpha))
    binom_p = float(stats.binom.sf(sig - 1, n, alpha)) if sig > 0 else 1.0
    fisher_p = float(stats.combine_pvalues(ps, method="fisher").pvalue)
    majority_p, r = median_pilot_p(ps)
    gains = np.array([t["gain"] for t in pilots.values()])
    yes = majority_p < alpha
    skipped = len(tests) - n_runs
    unit = "run(s)" if groups else "pilot(s)"
    tail = f" ({skipped} {unit} without forcing lines not tested)" if skipped else ""
    of_runs = f", {n_runs} runs" if n_runs > n else ""
    first = "each pilot's runs combined first; " if n_runs > n else ""
    claim = "improves" if yes else "does not significantly improve"
    some = (" (evidence that some pilot's fit improves, not the typical pilot's)"
            if not yes and fisher_p < alpha else "")
    # "No" claims that the typical pilot does not use the motion; only records whose two line
    # sets separate the paths can show that (diagnose says "cannot tell" run by run alike).
    one = {pid: t["forcing"] for pid, t in pilots.items() if t["forcing"] != SEPARABLE}
    n_sep = n - len(one)
    answer = "yes" if yes else "no" if n_sep >= r else "undetermined"
    kinds = " / ".join(sorted(set(one.values())))
    opening = {"yes": f"yes: motion feedback {claim}", "no": f"no: motion feedback {claim}",
               "undetermined": f"undetermined: cannot tell whether the pilots use motion: {len(one)} of {n} "
                               f"pilots' records have one forcing function ({kinds}), one describing "
                               "function in which the visual and vestibular paths act on the same "
                               "signal, so they can neither show nor rule out motion feedback (a target "
                               "and a disturbance on lines of their own would); motion feedback "
                               f"{claim}"}[answer]
    shapes = (f" (on the model's shapes of the two paths alone for the {len(one)} pilot(s) with one "
              f"forcing function, {kinds})" if yes and one else "")
    sentence = (f"{opening} the describing-function "
                f"fit for at least half of the {n} pilots{of_runs}{shapes} ({first}median-pilot test p = "
                f"{majority_p:.2g}); individually significant for {sig} of {n} pilots (p < {alpha:g}; "
                f"binomial p = {binom_p:.2g}); Fisher's combined p = {fisher_p:.2g}{some}; "
                f"median share of the misfit removed {100 * float(np.median(gains)):.0f} %{tail}")
    return {"answer": answer, "sentence": sentence, "n_tested": n, "n_separable": n_sep,
            "path_check": None if yes else path_verdict(done, groups or {}, alpha),
            "n_significant": sig, "binomial_p": binom_p, "majority_p": majority_p, "majority_r": r,
            "fisher_p": fisher_p, "median_gain": float(np.median(gains)), "alpha": alpha,
            "method": method + (", a pilot's runs first combined by Fisher's rule (Km/|Ke| and Km: "
                                "mean +/- standard error over the runs)" if groups else ""),
            "per_pilot": _per_pilot_out(tests, pilots, groups, alpha)}


def _combined(ps: Sequence[float]) -> float:
    return ps[0] if len(ps) == 1 else float(stats.combine_pvalues(ps, method="fisher").pvalue)


def path_verdict(tests: Mapping[str, Mapping], groups: Mapping[str, str], alpha: float) -> dict | None:
    """The cohort test again with each of the motion path's likely mistakes
    (:data:`~hesspipe.identification.motion_test.PATH_VARIANTS`) in place of the path given.

    A motion path with the wrong sign, or one differentiation off, makes a motion cohort a
    plain "no" (an independent lab's hexapod roll runs, the path negated: median-pilot p = 1,
    while `diagnose` flagged 17 of 18 runs one by one). Each run's test carries its
    variants' p-values where motion was not named with the path given
    (``motion_test(..., path_check=)``); a run named with it keeps its own p. The pilots'
    runs are combined as for the verdict, and a variant is named where it makes at least half
    of the pilots individually significant, each p times the number of variants below `alpha`
    (Bonferroni). The median-pilot test alone (its p times the variants) flagged the path
    negated on that lab's static cohort with the right path (p = 0.0017; 2 of 6 pilots below
    `alpha`, 1 after the factor): a static pilot's misfit that a vestibular path of either
    sign takes up.

    Parameters
    ----------
    tests : mapping
        Run id → available :func:`motion_test` result.
    groups : mapping
        Run id → pilot id (a run its own pilot where absent).
    alpha : float
        Level of the cohort test.

    Returns
    -------
    dict or None
        ``variants`` (name → ``majority_p``: the median-pilot test's p, ``n_significant``:
        pilots whose combined p times the number of variants is below `alpha`, ``n_pilots``),
        ``named`` (the variants named, in PATH_VARIANTS' order), ``level``;
        None where no run was checked (the plants give no motion path, or motion was named
        on every run).
    """
    if not any(t.get("path_check") for t in tests.values()):
        return None
    out, m = {}, len(PATH_VARIANTS)
    for name in PATH_VARIANTS:
        by: dict[str, list[float]] = {}
        for rid, t in tests.items():
            check = t.get("path_check")
            p = check["p_values"][name] if check else t["p_value"]
            by.setdefault(groups.get(rid, rid), []).append(float(p))
        ps = [_combined(v) for v in by.values()]
        out[name] = {"majority_p": median_pilot_p(ps)[0], "n_significant": int(sum(p * m < alpha for p in ps)),
                     "n_pilots": len(ps)}
    named = [name for name in out if out[name]["n_significant"] >= math.ceil(out[name]["n_pilots"] / 2)]
    return {"variants": out, "named": named, "level": float(alpha)}


def path_verdict_line(check: Mapping | None) -> str:
    """The cohort's ``CHECK motion_path`` line ("" where no variant is named).

    Parameters
    ----------
    check : mapping or None
        :func:`path_verdict`'s result.
    """
    if not check or not check.get("named"):
        return ""
    v, n = check["variants"], len(check["variants"])
    found = " and ".join(f"{name} ({v[name]['n_significant']} of {v[name]['n_pilots']} pilots, median-pilot "
                         f"p = {v[name]['majority_p']:.2g})" for name in check["named"])
    return (f"CHECK motion_path: motion feedback would improve the fit for at least half of the pilots "
            f"with the path {found} (a pilot counted where its p times the {n} variants tried is below "
            f"{check['level']:g}): {PATH_ADVICE}. A cohort whose cab did not move can show this as a misfit its pilots share: "
            f"believe it where the motion cohort flags it and the static cohort does not")


def median_pilot_p(p_values) -> tuple[float, int]:
    """The cohort test that at least half of the pilots show the effect (Wilkinson 1951).

    Parameters
    ----------
    p_values : array_like
        One p-value per pilot (independent; uniform or larger under the null).

    Returns
    -------
    p : float
        ``P(Binomial(n, p_(r)) >= r)``: the probability, with no pilot affected, that r or
        more of n p-values fall at or below the r-th smallest one observed.
    r : int
        ``ceil(n / 2)``, the order statistic tested.
    """
    ps = np.sort(np.asarray(p_values, dtype=float))
    n = ps.size
    if n == 0:
        raise HesspipeError("median_pilot_p: expected at least one p-value, got none")
    r = math.ceil(n / 2)
    return float(stats.binom.sf(r - 1, n, ps[r - 1])), r


def _per_pilot_out(tests, pilots, groups, alpha) -> dict:
    if not groups:
        return {pid: ({"gain": t["gain"], "p_value": t["p_value"], "lr": t["lr"],
                       "Km": t["Km"], "Km_se": t["Km_se"], "Km_interval": t.get("Km_interval"),
                       "Km_per_Ke": t.get("Km_per_Ke"), "Km_per_Ke_interval": t.get("Km_per_Ke_interval"),
                       "interval_level": t.get("interval_level"), "significant": t["significant"],
                       "forcing": t["forcing"]}
                      if t.get("available") else {"available": False, "reason": t.get("reason", "")})
                for pid, t in tests.items()}
    out = {pid: {**t, "significant": t["p_value"] < alpha,
                 "run_ids": [r for r in tests if groups.get(r, r) == pid and tests[r].get("available")]}
           for pid, t in pilots.items()}
    for rid, t in tests.items():
        if not t.get("available"):
            pilot = out.setdefault(groups.get(rid, rid), {"available": False, "reason": t.get("reason", "")})
            pilot.setdefault("untested_runs", []).append(rid)
            pilot.setdefault("untested_reasons", {})[rid] = t.get("reason", "")
    return out


def _estimate(name: str, value, se, ci, level: str) -> str:
    # "NAME v (95 % profile interval lo to hi)", else "NAME v +/- se" (a pilot's runs: the
    # standard error over them); "" without a value (a result written before the ratio).
    if value is None or not math.isfinite(value):
        return ""
    if ci:
        hi = "unbounded" if ci[1] is None or not math.isfinite(ci[1]) else f"{ci[1]:.3g}"
        return f"{name} {value:.3g} ({level} profile interval {ci[0]:.3g} to {hi})"
    if se is not None and math.isfinite(se):
        return f"{name} {value:.3g} +/- {se:.2g}"
    return f"{name} {value:.3g}"


def verdict_lines(verdict: Mapping) -> list[str]:
    """Plain-text lines of a :func:`cohort_verdict`: the sentence, then one line per pilot.

    Parameters
    ----------
    verdict : mapping
        A :func:`cohort_verdict` result (``sentence``, ``per_pilot``, ``method``).
    """
    out = [f"MOTION VERDICT: {verdict['sentence']}"]
    check = path_verdict_line(verdict.get("path_check"))
    if check:
        out.append(f"  {check}")
    for pid, t in verdict.get("per_pilot", {}).items():
        if t.get("available", True) is False:
            out.append(f"  {pid}: not tested ({t.get('reason', 'no forcing lines')})")
            continue
        level = f"{100 * (t.get('interval_level') or 0.95):g} %"
        # Km/|Ke| first: Km itself trades with Ke and the proprioceptive gain along a valley
        # (identification.motion_test), so its interval can span decades where the ratio's
        # does not; Km follows.
        gains = [_estimate("Km/|Ke|", t.get("Km_per_Ke"), t.get("Km_per_Ke_se"), t.get("Km_per_Ke_interval"),
                           level),
                 _estimate("Km", t["Km"], t.get("Km_se"), t.get("Km_interval"), level)]
        gains = [g for g in gains if g]
        km = ", ".join(gains)
        runs = f" ({t['runs']} runs)" if t.get("runs", 1) > 1 else ""
        one = f" (one forcing function, {t['forcing']})" if t.get("forcing", SEPARABLE) != SEPARABLE else ""
        if t.get("runs", 1) > 1:
            stat = (f"median misfit removed {100 * t['gain']:.1f} %, median F = {t['lr']:.3g}, "
                    f"Fisher's p = {t['p_value']:.2g}")
        else:
            stat = f"misfit removed {100 * t['gain']:.1f} %, F = {t['lr']:.3g}, p = {t['p_value']:.2g}"
        # A run left out of its pilot's test is said where the pilot's figures are read (a
        # truncated run was left out without a word; the reason was only in the JSON).
        left = "".join(f"; {rid} not tested ({why})" for rid, why in (t.get("untested_reasons") or {}).items())
        out.append(f"  {pid}{runs}: {stat}{' *' if t['significant'] else ''}{one}, {km}{left}")
    out.append(f"  ({verdict['method']})")
    return out
