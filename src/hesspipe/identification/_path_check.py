"""The motion path's check (:func:`~hesspipe.identification.motion_test.motion_test`'s
``path_check``): where motion is not named with the plants' ``motion_path``, the test's Km
alternative refitted with the path's likely mistakes in its place.
"""

from __future__ import annotations

import numpy as np

from ..core._tf import siso_coefficients
from ..pilot.blocks import tf
from ..pilot.hess import PilotModel
from ._line_fit import _fit, _nested_f

PATH_VARIANTS = {"negated": (-1.0, 0), "differentiated": (1.0, 1), "integrated": (1.0, -1)}
"""The motion path's likely mistakes that :func:`~.motion_test.motion_test`'s ``path_check`` tries, name:
(sign, powers of s multiplied in): its sign (the cab's rotation against the logged output's)
and one differentiation off (an angle output given the path of a rate, or the reverse). On the
lab stand-in's single-integrator yaw runs (s/(0.01 s + 1), motion named on 6 of 6) the path
negated named motion on 2 of 6, without its differentiator on 1 of 6, without a word."""

PATH_ADVICE = ("check motion_path's sign and whether it differentiates the output (SPEC: output -> cab "
               "angular velocity)")
"""What a user does where a variant names motion (diagnose's run line, pilots' cohort line)."""


def _variant_cabs(plants) -> dict:
    # The motion path's PATH_VARIANTS as blocks (none where the plants give no path: the
    # paper's platform x washout, whose angle-output mistake motion_path_note names).
    mp = getattr(plants, "motion_path", None)
    if mp is None:
        return {}
    num, den = siso_coefficients(mp)
    out = {}
    for name, (sign, power) in PATH_VARIANTS.items():
        n_ = sign * (np.append(num, np.zeros(power)) if power > 0 else num)
        d_ = np.append(den, np.zeros(-power)) if power < 0 else den
        out[name] = tf(n_, d_)
    return out


def _path_check(plants, km_problem, core, km0, rss_o, p_o, base, n_res, data, w, level: float,
                keep: int) -> dict | None:
    # motion_test's path_check: the Km alternative (its search problem: base, free, lo, hi)
    # refitted with each of the path's likely mistakes (PATH_VARIANTS) in place of the path
    # given; None without a path to vary.
    cabs = _variant_cabs(plants)
    if not cabs:
        return None
    expanded = PilotModel(("motion_feedback",))
    base_e, free_e, lo_e, hi_e = km_problem
    starts = [[c[n_] for n_ in core] + [km] for c in (p_o, base)
              for km in (1e-6, km0, 10 * km0, 0.5 * abs(c["Ke"]))]
    dof = n_res - len(free_e) - 1   # as the test's: the equaliser held at the original's value counts
    p, gain = {}, {}
    for name, cab in cabs.items():
        rss_v, _, _ = _fit(expanded, base_e, free_e, lo_e, hi_e, starts, cab, *data[1:], w, keep=keep)
        p[name] = _nested_f(rss_o, min(rss_v, rss_o), 1, dof)[1]
        gain[name] = float(1.0 - min(rss_v, rss_o) / rss_o) if rss_o > 0 else 0.0
    # Bonferroni over the variants: on records without motion feedback a variant is then
    # found with probability at most `level`, as motion itself is.
    named = [name for name in p if p[name] * len(p) < level]
    return {"p_values": p, "gains": gain, "named": named, "better": min(named, key=p.get) if named else None,
            "level": float(level)}
