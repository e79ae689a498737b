"""Two conditions flown by the same persons: does their behaviour change between them?

The field's direct answer to "does the pilot need motion?" compares what the same persons do
with and without the cue, not only how well a model with a vestibular path fits each run
(:func:`~hesspipe.pilots.verdict.cohort_verdict`, ``hesspipe pilots``). Motion experiments
report, per person and condition, the crossover frequency and phase margin of the loop the
disturbance sees, the tracking performance and the control effort, and test the differences
across persons with a repeated-measures analysis; with two conditions that is a paired t
test (Zaal et al. 2009, roll tracking; Pool et al. 2010, yaw; in both the disturbance loop's
crossover and phase margin rose with motion).

Per person and condition, from the person's runs alone (no pilot model is fitted):

* the describing function H = U/E at the disturbance's lines, the runs averaged line by line
  (:func:`~hesspipe.identification.frf_average.average_frf`; broadband runs: each run by
  Welch, the metrics averaged), and the crossover and phase margin of L = H Yc
  (:mod:`~hesspipe.identification.frf_crossover`). With a compensatory display, H at those
  lines is the visual and the vestibular response together (e = -y there), the classical
  "disturbance open loop";
* the variances of the displayed error e = r - y and of the control u over the analysed
  window (the runs' mean), and the remnant's share of the control power;
* with target and disturbance on their own lines, the output channel apart from the error
  channel (:mod:`~hesspipe.identification.frf_channels`, no model): the median |Hpy|/|Hpe|
  between 1 and 5 rad/s, the person's response to the output itself (with a compensatory
  display and a moving cab, the vestibular path) relative to the visual one. The remnant
  alone raises it above zero, so it is compared between conditions, not against zero.

Across the persons who flew both conditions, each metric's difference (variances as log
ratios) gets a two-sided paired t test. The primary metrics (crossover, phase margin, error
variance) are Holm-adjusted together (family-wise error at :data:`ALPHA`) and make the verdict,
which names those that differ or says that none was found; the control variance and the
remnant share are reported beside them, unadjusted.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Mapping, Sequence

import numpy as np
from scipy import stats

from ..core.errors import HesspipeError
from ..core.formats import as_plants, as_runs
from ..core.provenance import SYNTHETIC_BANNER
from ..core.seeds import derive_seed
from ..identification.frf import estimate_frf
from ..identification.frf_average import average_frf, check_repeats
from ..identification.lines import SEPARABLE, forcing_sets, windowed
from ..plants.consistency import check_consistent
from .verdict import pilot_groups

ALPHA = 0.05
"""Family-wise error rate of the paired tests over all metrics (Holm)."""
MIN_PERSONS = 3
"""Fewest persons with both conditions for a paired test (two leave one degree of freedom)."""


@dataclass(frozen=True)
class Metric:
    """A per-person measure the conditions are compared on.

    Attributes
    ----------
    key : str
        Its key in the records.
    label : str
        Its name in words.
    unit : str
        Its unit ("" for a fraction).
    log : bool
        Compared as a ratio (a variance): the test is on the logarithms, the effect a ratio.
    primary : bool
        In the verdict (Holm-adjusted with the other primary metrics); a secondary metric's
        test is reported beside them, unadjusted.
    unless : str
        Key of a flag that, true for a person in either condition, leaves the person out of
        this metric's test ("" for none).
    """

    key: str
    label: str
    unit: str
    log: bool = False
    primary: bool = True
    unless: str = ""


METRICS = (
    Metric("crossover_rad_s", "disturbance-loop crossover", "rad/s", unless="crossover_ill_defined"),
    Metric("phase_margin_deg", "phase margin", "deg", unless="crossover_ill_defined"),
    Metric("error_variance", "error variance", "output unit^2 as read (an angle logged in deg: rad^2)", log=True),
    Metric("control_variance", "control variance", "control unit^2 as read (deg: rad^2)", log=True, primary=False),
    Metric("remnant_share", "remnant share of control power", "", primary=False),
    Metric("output_channel", "output channel |Hpy|/|Hpe|", "", log=True, primary=False),
)
"""The loop the disturbance sees and the tracking performance are the primary measures of motion
experiments; control effort, remnant and the output channel are reported beside them. A person
whose crossover is ill-defined in either condition (|L| near 1 over a wide band, where noise
places the crossing: :attr:`~hesspipe.identification.frf_crossover.FrfCrossover.ill_defined`)
is left out of the crossover's and the phase margin's tests."""


@dataclass(frozen=True)
class ConditionComparison:
    """Result of :func:`compare_conditions`.

    Attributes
    ----------
    labels : (str, str)
        The two conditions' names; differences are the second's minus the first's.
    persons : dict
        Person id → ``{label: metrics}`` for every person with runs in a condition; the
        metrics are those of :data:`METRICS` plus ``runs`` (ids), ``crossover_std`` (rad/s),
        ``phase_margin_std_deg``, ``crossover_ill_defined`` and the forcing's variances.
    tests : dict
        Metric key → ``{"n", "higher", "effect", "t", "p_value", "p_holm"}`` (``effect``: the
        mean difference, or for a log metric the geometric-mean ratio; ``p_holm`` None for a
        secondary metric, and for the variances with ``confounded`` where the forcing differs
        between the conditions); None where fewer than :data:`MIN_PERSONS` persons have the metric
        in both conditions.
    verdict : str
        In words (:func:`conditions_verdict`).
    synthetic : bool
        Some run is labelled synthetic.
    notes : tuple of str
        Persons in one condition only, metrics not found.
    """

    labels: tuple
    persons: dict
    tests: dict
    verdict: str
    synthetic: bool
    notes: tuple = ()

    def to_dict(self) -> dict:
        """JSON-ready, with the definitions of the metrics and the test."""
        return {"synthetic": self.synthetic, "labels": list(self.labels), "verdict": self.verdict,
                "alpha": ALPHA, "test": "two-sided paired t test per metric across persons, Holm-"
                "adjusted over the primary metrics; variances compared as log ratios",
                "metrics": {m.key: {"label": m.label, "unit": m.unit, "log": m.log, "primary": m.primary}
                            for m in METRICS},
                "tests": self.tests, "persons": self.persons, "notes": list(self.notes)}


def person_metrics(runs: Sequence, plants, *, seed: int = 0) -> dict:
    """The metrics of one person in one condition (module doc).

    Parameters
    ----------
    runs : sequence of hesspipe.core.formats.Run
        The person's runs of the condition: repeats of one forcing.
    plants : hesspipe.core.formats.Plants
        Yc for the crossover of L = H Yc.
    seed : int
        Seed of the crossover's uncertainty draws.

    Returns
    -------
    dict
        ``runs`` (ids), ``averaged`` (how the runs were combined: "line by line", "one run", or
        "run by run: " and why), ``crossover_rad_s`` and ``crossover_std`` (rad/s; NaN when |L| does not
        fall through 1 between the lines), ``phase_margin_deg`` and ``phase_margin_std_deg``
        (deg), ``crossover_ill_defined`` (|L| near 1 over a wide band: :attr:`~hesspipe.
        identification.frf_crossover.FrfCrossover.ill_defined`), ``error_variance`` (output unit², e = reference - output), ``control_variance``
        (control unit²), ``remnant_share`` (0-1), ``output_channel`` (the median |Hpy|/|Hpe| at
        1-5 rad/s, :attr:`~hesspipe.identification.frf_channels.Channels.ratio_median`; NaN
        without both line sets), ``reference_variance`` and ``disturbance_variance`` (the
        forcing's, in their columns' units²).

    Raises
    ------
    HesspipeError
        A record given twice; a run whose column signs or units are at odds with the plants
        (:func:`hesspipe.plants.consistency.check_consistent`); what a run's describing
        function raises.
    """
    runs = list(runs)
    if not runs:
        raise HesspipeError("person_metrics: expected at least one run, got none")
    check_repeats([], runs)   # a record given twice is an error, not a repeat
    for run in runs:
        # The crossover and phase margin are of L = H Yc: a column in another unit than the
        # plants' scales L and moves both, where pilots refused the same files.
        check_consistent(run, plants)
    frf, averaged = None, "line by line" if len(runs) > 1 else "one run"
    try:
        frf = average_frf(runs, plants, seed=seed)
    except HesspipeError as exc:
        # Broadband forcing (no lines) or runs of different forcings (lengths, line sets) are
        # not averaged line by line; each run's own estimate still is, and an error of one
        # run recurs there.
        averaged = f"run by run: {exc}"
    if frf is not None:
        c = frf.crossover
        wc, wc_sd, pm, pm_sd, rem, ch = (c.frequency_rad_s, c.frequency_std, c.phase_margin_deg,
                                         c.phase_margin_std_deg, frf.remnant_share, _channel(frf))
        flat = c.ill_defined
    else:
        each = [estimate_frf(r, plants, seed=seed) for r in runs]
        per = np.array([(f.crossover.frequency_rad_s, f.crossover.frequency_std, f.crossover.phase_margin_deg,
                         f.crossover.phase_margin_std_deg, f.remnant_share, _channel(f)) for f in each])
        flat = any(f.crossover.ill_defined for f in each)
        wc, wc_sd, pm, pm_sd, rem, ch = per.mean(axis=0)
        # Independent runs: the mean's variance is the sum of theirs over N squared.
        wc_sd, pm_sd = (float(np.sqrt(np.sum(per[:, i] ** 2))) / len(runs) for i in (1, 3))
    cut = [windowed(r) for r in runs]

    def variance(column: str) -> float:
        return float(np.mean([np.var(np.asarray(getattr(r, column))) for r in cut]))
    return {"runs": [r.id for r in runs], "averaged": averaged,
            "crossover_rad_s": float(wc), "crossover_std": float(wc_sd),
            "phase_margin_deg": float(pm), "phase_margin_std_deg": float(pm_sd),
            "crossover_ill_defined": bool(flat),
            "error_variance": variance("error"), "control_variance": variance("control"),
            "remnant_share": float(rem), "output_channel": float(ch),
            "reference_variance": variance("reference"), "disturbance_variance": variance("disturbance")}


def _channel(frf) -> float:
    ch = frf.channels
    return math.nan if ch is None else ch.ratio_median


def paired_tests(persons: Mapping[str, Mapping[str, Mapping]], labels: tuple, *,
                 confounded: frozenset = frozenset()) -> dict:
    """Each metric's paired t test across the persons with both conditions, the primary ones
    Holm-adjusted together.

    Parameters
    ----------
    persons : mapping
        Person → condition label → :func:`person_metrics` (a metric missing or not finite
        there, or the metric's ``unless`` flag true in either condition, leaves the person out
        of that metric's test).
    labels : (str, str)
        The conditions; a difference is the second's minus the first's.
    confounded : frozenset of str
        Metrics whose difference the design explains (:func:`forcing_ratios`): tested and
        marked ``confounded``, but left out of the primary family and so of the verdict.

    Returns
    -------
    dict
        Metric key → ``{"n", "higher", "effect", "t", "p_value", "p_holm"}`` or None (module
        doc and :class:`ConditionComparison`).
    """
    a, b = labels
    tests: dict = {}
    for m in METRICS:
        pairs = [(float(c[a].get(m.key, math.nan)), float(c[b].get(m.key, math.nan)))
                 for c in persons.values() if a in c and b in c
                 and not (m.unless and (c[a].get(m.unless) or c[b].get(m.unless)))]
        pairs = [(x, y) for x, y in pairs if math.isfinite(x) and math.isfinite(y) and (not m.log or min(x, y) > 0)]
        if len(pairs) < MIN_PERSONS:
            tests[m.key] = None
            continue
        x, y = np.array(pairs).T
        d = np.log(y) - np.log(x) if m.log else y - x
        if np.ptp(d) <= 1e-12 * max(1.0, float(np.max(np.abs(d)))):
            # No spread (to rounding): the t statistic is undefined (and scipy warns).
            t, p = (0.0, 1.0) if abs(float(np.mean(d))) <= 1e-12 else (math.copysign(math.inf, float(np.mean(d))), 0.0)
        else:
            t, p = (float(v) for v in stats.ttest_1samp(d, 0.0))
        tests[m.key] = {"n": len(pairs), "higher": int(np.sum(d > 0)),
                        "effect": float(np.exp(np.mean(d))) if m.log else float(np.mean(d)),
                        "t": t, "p_value": p, "p_holm": None,
                        **({"confounded": True} if m.key in confounded else {})}
    primary = {m.key for m in METRICS if m.primary and m.key not in confounded}
    done = sorted((k for k, v in tests.items() if v is not None and k in primary), key=lambda k: tests[k]["p_value"])
    running = 0.0
    for i, key in enumerate(done):   # Holm's step-down, kept monotone
        running = max(running, min(1.0, (len(done) - i) * tests[key]["p_value"]))
        tests[key]["p_holm"] = running
    return tests


#: The forcing's power may differ between the conditions by this factor (median over the
#: persons) before the error and control variances, which scale with it, leave the verdict.
FORCING_TOLERANCE = 1.25


def forcing_ratios(persons: Mapping[str, Mapping[str, Mapping]], labels: tuple) -> dict:
    """The forcing's power in the second condition over the first's, median over the persons
    who flew both, per forcing column (``reference``, ``disturbance``; a column without power
    in either condition left out).

    Parameters
    ----------
    persons : mapping
        Person → condition label → :func:`person_metrics`.
    labels : (str, str)
        The conditions.

    Returns
    -------
    dict
        Column → ratio of variances.
    """
    a, b = labels
    out = {}
    for column in ("reference", "disturbance"):
        key = f"{column}_variance"
        r = [c[b][key] / c[a][key] for c in persons.values() if a in c and b in c
             and c[a].get(key, 0.0) > 0 and c[b].get(key, 0.0) > 0]
        if r:
            out[column] = float(np.median(r))
    return out


def conditions_verdict(tests: Mapping[str, Mapping | None], labels: tuple, n_both: int, *,
                       ill_defined: int = 0) -> str:
    """The comparison in words.

    Parameters
    ----------
    tests : mapping
        :func:`paired_tests`' result.
    labels : (str, str)
        The conditions.
    n_both : int
        Persons with runs in both conditions.
    ill_defined : int
        Of them, those whose crossover is ill-defined in a condition: where that leaves the
        crossover untested, the verdict says so (a "no difference" read alone would cover it).

    Returns
    -------
    str
        "undetermined: ...", "the conditions differ: ..." or "no difference found: ...".
    """
    verdict = _verdict(tests, labels, n_both)
    if ill_defined and tests.get("crossover_rad_s") is None and n_both >= MIN_PERSONS:
        verdict += (f"; the crossover and phase margin are not compared: ill-defined for {ill_defined} of "
                    f"{n_both} persons (the notes name them)")
    return verdict


def _verdict(tests: Mapping[str, Mapping | None], labels: tuple, n_both: int) -> str:
    a, b = labels
    done = {m.key: tests[m.key] for m in METRICS if m.primary and tests.get(m.key) is not None
            and tests[m.key]["p_holm"] is not None}
    if not done:
        return (f"undetermined: {n_both} person(s) flew both {a} and {b} with the metrics found; "
                f"a paired test needs at least {MIN_PERSONS}")
    found = [m for m in METRICS if m.key in done and done[m.key]["p_holm"] < ALPHA]
    if not found:
        best = min(done.values(), key=lambda v: v["p_holm"])
        return (f"no difference found between {a} and {b} in the primary metrics ({best['n']} persons; smallest "
                f"Holm-adjusted p = {best['p_holm']:.2g}, needs < {ALPHA:g})")
    return f"the conditions differ: {b} against {a}: " + "; ".join(_effect(m, done[m.key]) for m in found)


def _effect(m: Metric, t: Mapping) -> str:
    more = "higher" if (t["effect"] > 1 if m.log else t["effect"] > 0) else "lower"
    return (f"{m.label} {more} ({_size(m, t['effect'])} on average; higher for {t['higher']} of {t['n']} persons, "
            f"p = {t['p_value']:.2g}, Holm {t['p_holm']:.2g})")


def check_labels(labels) -> tuple[str, str]:
    """The two conditions' names, checked.

    Parameters
    ----------
    labels : sequence of str
        E.g. ``("static", "motion")``.

    Returns
    -------
    tuple of str

    Raises
    ------
    HesspipeError
        Unless two different non-empty names.
    """
    labels = tuple(str(x) for x in labels)
    if len(labels) != 2 or labels[0] == labels[1] or not all(labels):
        raise HesspipeError(f"labels: expected two different non-empty names, got {labels!r}")
    return labels


def compare_conditions(runs_a: Sequence, runs_b: Sequence, plants, *, labels: tuple = ("A", "B"),
                       pilot_id: str | None = None, seed: int = 0) -> ConditionComparison:
    """Compare two conditions flown by the same persons (module doc).

    Parameters
    ----------
    runs_a, runs_b : sequence of hesspipe.core.formats.Run
        Each condition's runs.
    plants : hesspipe.core.formats.Plants
        The controlled element of both conditions (Yc for the crossover).
    labels : (str, str)
        The conditions' names (e.g. ``("static", "motion")``); differences are the second's
        minus the first's.
    pilot_id : str, optional
        Regular expression that finds the person in each run id
        (:func:`~hesspipe.pilots.verdict.pilot_groups`); None: the run id is the person, so a
        person's run has the same file name in both conditions.
    seed : int
        Base seed of the crossovers' uncertainty draws (one stream per person and condition).

    Returns
    -------
    ConditionComparison

    Raises
    ------
    HesspipeError
        Equal labels, a condition without runs, a record in both conditions (or twice in one), a
        pattern that does not match a run id, no person in both conditions, or what
        :func:`person_metrics` raises (naming the run).
    """
    labels = check_labels(labels)
    plants = as_plants(plants)
    persons: dict[str, dict] = {}
    synthetic, grouped = False, []
    runs_a, runs_b = as_runs(list(runs_a)), as_runs(list(runs_b))
    # One folder given for both conditions (or a file copied into the other) would compare
    # records with themselves and report "no difference" for nothing.
    check_repeats([], [*runs_a, *runs_b])
    for label, runs in zip(labels, (runs_a, runs_b)):
        if not runs:
            raise HesspipeError(f"condition {label!r}: no runs; expected at least one")
        synthetic |= any(getattr(r, "synthetic", False) for r in runs)
        groups = pilot_groups([r.id for r in runs], pilot_id, {r.id: r.source for r in runs if r.source},
                              {r.id: getattr(r, "file_id", r.id) for r in runs}) or {r.id: r.id for r in runs}
        by: dict[str, list] = {}
        for r in runs:
            by.setdefault(groups[r.id], []).append(r)
        grouped.append(by)
    both = set(grouped[0]) & set(grouped[1])
    if not both:
        how = ("a run's file name" if pilot_id is None else f"as the pilot_id pattern {pilot_id!r} finds them")
        raise HesspipeError(
            f"no person flew both {labels[0]!r} and {labels[1]!r}: the persons ({how}) are "
            f"{_some(grouped[0])} and {_some(grouped[1])}; expected the same persons in both "
            + ("(set pilot_id to a pattern that finds the person in each file name, e.g. '^(s[0-9]+)_')"
               if pilot_id is None else "(a pattern that finds the person, not the condition)"))
    for label, by in zip(labels, grouped):
        for person, own in sorted(by.items()):
            persons.setdefault(person, {})[label] = person_metrics(
                own, plants, seed=derive_seed(seed, "conditions", label, person))
    notes = [f"{p}: flew only {next(iter(c))}; left out of the paired tests"
             for p, c in sorted(persons.items()) if len(c) < 2]
    for p, c in sorted(persons.items()):
        notes += [f"{p} ({label}): no crossover found (|L| does not fall through 1 between the lines)"
                  for label, v in c.items() if not math.isfinite(v["crossover_rad_s"])]
        notes += [f"{p} ({label}): {len(v['runs'])} runs averaged {v['averaged']}"
                  for label, v in c.items() if v["averaged"] != "line by line" and len(v["runs"]) > 1]
    flat = [f"{p} ({', '.join(label for label in labels if c[label]['crossover_ill_defined'])})"
            for p, c in sorted(persons.items()) if len(c) == 2 and any(v["crossover_ill_defined"] for v in c.values())]
    if flat:
        notes.append("crossover ill-defined (~ in the table: |L| stays near 1 over a wide band and the crossing's "
                     f"spread is more than a quarter of it, so noise places it) for {', '.join(flat)}: left out of "
                     "the crossover's and the phase margin's tests")
    # The crossover is the disturbance loop's, measured at its lines; runs without them (a
    # target alone) give the loop the target sees, which a vestibular path changes otherwise.
    if not any(forcing_sets(r) in (SEPARABLE, "disturbance only") for r in [*runs_a, *runs_b]):
        notes.append("no run has disturbance lines: the crossover and phase margin of this comparison are the target "
                     "loop's (measured at the target's lines), not the disturbance loop's")
    # A lab that lowers the forcing in the motion condition (the cab's travel) changes the
    # error and control variances by as much: a review's same persons at half the forcing
    # read "the conditions differ: error variance lower (x0.255)".
    ratios = forcing_ratios(persons, labels)
    confounded, differs = frozenset(), ""
    if any(not 1 / FORCING_TOLERANCE <= v <= FORCING_TOLERANCE for v in ratios.values()):
        confounded = frozenset({"error_variance", "control_variance"})
        differs = ", ".join(f"{c} power x{v:.3g}" for c, v in ratios.items())
        notes.append(f"the forcing differs between the conditions ({labels[1]} against {labels[0]}: {differs}, "
                     "median over the persons): the error and control variances scale with it, so they are "
                     "left out of the verdict")
    tests = paired_tests(persons, labels, confounded=confounded)
    verdict = conditions_verdict(tests, labels, len(both), ill_defined=len(flat))
    if differs:
        # Said in the headline: where the forcing's level is the factor studied, the verdict
        # alone would read as "no difference" in the variances.
        verdict += f"; the error and control variances are not compared: the forcing differs ({differs})"
    return ConditionComparison(labels=labels, persons=persons, tests=tests, verdict=verdict,
                               synthetic=synthetic, notes=tuple(notes))


def format_conditions(result: ConditionComparison) -> str:
    """The comparison as the command line prints it.

    Parameters
    ----------
    result : ConditionComparison
        From :func:`compare_conditions`.

    Returns
    -------
    str
        The verdict first, then each metric's test and a line per person (crossover in rad/s,
        phase margin in deg, the error variance's ratio, the remnant's share), then the notes.
    """
    a, b = result.labels
    out = ([SYNTHETIC_BANNER] if result.synthetic else []) \
        + [f"CONDITIONS VERDICT: {result.verdict}", f"paired tests ({b} against {a}, two-sided paired t "
           f"across persons; the primary metrics Holm-adjusted together, alpha {ALPHA:g}):"]
    for m in METRICS:
        t = result.tests.get(m.key)
        held = ("not in the verdict: the forcing differs" if t is not None and t.get("confounded") else
                "secondary, unadjusted" if t is None or t["p_holm"] is None else f"Holm {t['p_holm']:.2g}")
        out.append(f"  {m.label:32s} " + (f"fewer than {MIN_PERSONS} persons with it in both" if t is None else
                   f"{'ratio' if m.log else 'mean difference'} {_size(m, t['effect'])}, higher for "
                   f"{t['higher']} of {t['n']}, p = {t['p_value']:.2g} ({held})"))
    out.append(f"{'person':10s} {'wc ' + a:>12s} {'wc ' + b:>12s} {'PM ' + a:>10s} {'PM ' + b:>10s} "
               f"{'var(e) ratio':>13s} {'remnant':>15s}")
    for p, c in sorted(result.persons.items()):
        x, y = c.get(a), c.get(b)
        ratio = (f"{y['error_variance'] / x['error_variance']:.3g}" if x and y and x["error_variance"] > 0
                 else "-")
        rem = f"{_pct(x)} -> {_pct(y)}"
        out.append(f"{p:10s} {_num(x, 'crossover_rad_s'):>12s} {_num(y, 'crossover_rad_s'):>12s} "
                   f"{_num(x, 'phase_margin_deg', '.1f'):>10s} {_num(y, 'phase_margin_deg', '.1f'):>10s} "
                   f"{ratio:>13s} {rem:>15s}")
    out += [f"note: {n}" for n in result.notes]
    return "\n".join(out)


def _some(by: Mapping) -> str:
    names = sorted(by)
    return ", ".join(names[:3]) + (f" ... ({len(names)})" if len(names) > 3 else "")


def _size(m: Metric, effect: float) -> str:
    if m.log:
        return f"x{effect:.3g}"
    return f"{effect:+.3g} {m.unit}" if m.unit else f"{100 * effect:+.3g} points"


def _num(c, key, spec=".3g") -> str:
    if c is None or not math.isfinite(c[key]):
        return "-"
    flat = key in ("crossover_rad_s", "phase_margin_deg") and c.get("crossover_ill_defined")
    return ("~" if flat else "") + format(c[key], spec)


def _pct(c) -> str:
    return "-" if c is None else f"{100 * c['remnant_share']:.0f} %"
