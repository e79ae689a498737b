"""The identification's results for a reader: the tables ``hesspipe identify`` and ``hesspipe frf``
print (the command line only prints them), and the model curves a describing function's figure
draws over its points (:func:`hesspipe.viz.frf.frf_figure`)."""

from __future__ import annotations

import math
from typing import Mapping

import numpy as np


def format_identification(result) -> str:
    """A readable summary of an identification, as ``hesspipe identify`` prints it.

    Parameters
    ----------
    result : hesspipe.identification.problem.Identification

    Returns
    -------
    str
        Lines: the run, model and criterion; each parameter and whether it was identified; the
        fitness and the benchmark's; the box's edges; the model's crossover and the
        nonparametric one; the identifiability notes.
    """
    lines = []
    tag = "  [SYNTHETIC DATA]" if result.synthetic else ""
    lines.append(f"run {result.run_id}: model {result.model}, criterion {result.criterion}, "
                 f"optimizer {result.optimizer}, seed {result.seed}{tag}")
    if result.k_rule:
        lines.append(result.k_rule)
    lines.append(f"{'parameter':<10} {'value':>10}  status")
    for name, value in result.parameters.items():
        status = "identified" if name in result.free else (
            "fixed" if name in result.fixed else "default")
        lines.append(f"{name:<10} {value:>10.4g}  {status}")
    what = ("RMS PSD difference" if result.stable else
            "unstable closed loop: the worst score, graded by its growth rate")
    if result.criterion == "paper":
        lines.append(f"fitness            {result.fitness:.6g}   ({what}, "
                     f"{result.band[0]:g}-{result.band[1]:g} Hz; lower is better)")
    else:
        what = result.fitness_units if result.stable else what
        lines.append(f"fitness            {result.fitness:.6g}   (criterion {result.criterion}: "
                     f"{what}; lower is better)")
    bench = result.benchmark_fitness
    lines.append(f"benchmark fitness  {bench:.6g}   (McRuer precision model, same criterion and units)"
                 if math.isfinite(bench) else "benchmark fitness  not computed")
    edges = result.box_edges()
    if edges:
        lines.append("on the box's edge   " + ", ".join(f"{n} = {result.parameters[n]:.4g} ({e['side']} bound "
                                                        f"{e['bound']:.4g})" for n, e in edges.items())
                     + ": the optimum may lie beyond it (Ke and Km grow with 1 + K1 K2 where 1/T1 lies below "
                       "the forcing; plants in other units than the run; a pilot the model cannot follow)")
    # The tracking crossover first, as every table prints it; SPEC's last fall only where it differs.
    last = result.crossover
    c = result.primary_crossover if result.primary_crossover is not None else last
    limits = (f"(assumed limits {c.limits.frequency_rad_s[0]:g}-{c.limits.frequency_rad_s[1]:g} "
              f"rad/s, {c.limits.phase_margin_deg[0]:g}-{c.limits.phase_margin_deg[1]:g} deg)")
    if math.isfinite(c.frequency_rad_s):
        lines.append(f"crossover          {c.frequency_rad_s:.3f} rad/s, phase margin "
                     f"{c.phase_margin_deg:.1f} deg, within limits: {'yes' if c.within_limits else 'no'} "
                     + limits)
        if c.flat_band is not None and c.flat_band.wide:
            lines.append(f"                   the model's {c.flat_band.describe()}")
    else:
        lines.append("crossover          none found (the open loop's gain never crosses 1), within "
                     "limits: no " + limits)
    if c is not last and math.isfinite(last.frequency_rad_s) and last.frequency_rad_s != c.frequency_rad_s:
        lines.append(f"last crossing      {last.frequency_rad_s:.3f} rad/s, phase margin "
                     f"{last.phase_margin_deg:.1f} deg (|L| rises above 1 again above the crossover and "
                     "falls through it last here)")
    frf = result.frf
    if isinstance(frf, str):
        lines.append(f"nonparametric      {frf}")
    elif frf is not None:
        n = frf.crossover
        where = f"({frf.method}; remnant {100 * frf.remnant_share:.0f} % of control power)"
        if math.isfinite(n.frequency_rad_s):
            lines.append(f"nonparametric      crossover {n.frequency_rad_s:.3f} +- {n.frequency_std:.3f} "
                         f"rad/s, phase margin {n.phase_margin_deg:.1f} +- {n.phase_margin_std_deg:.1f} deg "
                         + where + (f"; {n.note}" if n.note else ""))
        else:
            lines.append(f"nonparametric      crossover not found {where}: {n.note or 'no crossing'}")
    lines.append(f"evaluations        {result.evaluations}")
    ident = result.identifiability
    lines.append(f"identifiability    {ident.get('summary', ident.get('method'))}")
    for prod, val in ident.get("identified_products", {}).items():
        lines.append(f"                   {prod} = {val:.4g} (only the product is determined)")
    if not result.stable:
        lines.append("warning: the best parameter set found gives an unstable closed loop")
    return "\n".join(lines)


def format_frf(frf) -> str:
    """A readable table of a describing function, as ``hesspipe frf`` prints it.

    Parameters
    ----------
    frf : hesspipe.identification.frf.Frf

    Returns
    -------
    str
        Lines: each line's |H| (dB) and phase (deg) with their standard deviations; the
        error and output channels where the record has them; the remnant share; the
        nonparametric crossover (rad/s) and phase margin (deg); the estimate's notes.
    """
    tag = "  [SYNTHETIC DATA]" if frf.synthetic else ""
    r = frf.feedback
    lines = [f"run {frf.run_id}: describing function H = U/E, {frf.method} "
             f"({r.freq_rad_s.size} {'lines' if frf.method == 'multisine' else 'Welch bins'}, "
             f"{frf.window[1] * frf.dt:.4g} s analysed){tag}",
             f"{'w rad/s':>9} {'|H| dB':>8} {'+-dB':>6} {'phase deg':>10} {'+-deg':>6}"]
    d = r.to_dict()
    for i in range(r.freq_rad_s.size):
        lines.append(f"{d['frequency_rad_s'][i]:9.3f} {d['magnitude_db'][i]:8.2f} "
                     f"{d['magnitude_db_std'][i]:6.2f} {d['phase_deg'][i]:10.1f} {d['phase_deg_std'][i]:6.1f}")
    if frf.reference is not None:
        lines.append(f"reference lines: {frf.reference.freq_rad_s.size} (their own response, in the JSON)")
    ch = frf.channels
    if ch is not None:
        lines += ["channels at the reference lines, U = Hpe E - Hpy Y (Hpy: the response to the "
                  "output itself; the vestibular path with a compensatory display and motion, minus a "
                  "feedforward on a pursuit display, zero without either):",
                  f"{'w rad/s':>9} {'|Hpe| dB':>9} {'phase deg':>10} {'|Hpy| dB':>9} {'phase deg':>10} "
                  f"{'+-dB':>6} {'|Hpy/Hpe|':>9}"]
        rel = ch.sigma_Hpy / np.abs(ch.Hpy)
        for w, pe, py, r in zip(ch.freq_rad_s, ch.Hpe, ch.Hpy, rel):
            lines.append(f"{w:9.3f} {20 * np.log10(abs(pe)):9.2f} {np.degrees(np.angle(pe)):10.1f} "
                         f"{20 * np.log10(abs(py)):9.2f} {np.degrees(np.angle(py)):10.1f} "
                         f"{20 / np.log(10) * r:6.2f} {abs(py) / abs(pe):9.3f}")
        lines.append(f"median |Hpy|/|Hpe| at {ch.lines_in_band} line(s) between 1 and 5 rad/s: "
                     f"{ch.ratio_median:.3g} (remnant raises it; compare conditions, not zero)")
    lines.append(f"remnant share of control power  {frf.remnant_share:.3f}   (every bin to the Nyquist "
                 f"frequency; diagnose counts its band only)")
    c = frf.crossover
    if math.isfinite(c.frequency_rad_s):
        lines.append(f"crossover (nonparametric)      {c.frequency_rad_s:.3f} +- {c.frequency_std:.3f} "
                     f"rad/s, phase margin {c.phase_margin_deg:.1f} +- {c.phase_margin_std_deg:.1f} deg "
                     f"({c.estimate} estimate; the other in the JSON)")
        if c.note:
            lines.append(f"  {c.note}")
    else:
        lines.append(f"crossover (nonparametric)      not found: {c.note}")
    for n in frf.notes:
        lines.append(f"note: {n}")
    return "\n".join(lines)


def model_curves(model: str, parameters: Mapping[str, float], criterion: str = "paper",
                 benchmark_parameters: Mapping[str, float] | None = None) -> dict:
    """The describing functions :func:`hesspipe.viz.frf.frf_figure` draws over the points: an
    identified model's and its McRuer precision benchmark's.

    Parameters
    ----------
    model : str
        The model's name (``original``, ``expanded``, ...).
    parameters : mapping
        Its complete parameters (units as the pilot model's).
    criterion : str
        The criterion it was identified by (for the label).
    benchmark_parameters : mapping, optional
        The precision benchmark's parameters; none: no benchmark curve.

    Returns
    -------
    dict
        Label -> callable ``H(s)``, the describing function U/E at ``s = j w``.
    """
    from ..pilot.hess import model_from_name
    from ..pilot.mcruer import precision_loop
    from .criteria import model_df

    loop = model_from_name(model).loop(parameters)
    out = {f"{model} model ({criterion})": lambda s: model_df(loop, s)}
    if benchmark_parameters:
        bench = precision_loop(benchmark_parameters)
        out["McRuer precision benchmark"] = lambda s: model_df(bench, s)
    return out
