"""The same pilot on another run (SYNTHETIC): a paired design's second trial.

A within-subject experiment flies each pilot in a baseline condition and in the condition
under study (a simulator with more latency, motion on or off). The pilot is the same, but
not identical from run to run: human operators' identified parameters scatter between
repeated runs of one task (delays by about 0.01 s, gains by 5-15 %), and each run has its
own remnant. :func:`retest` draws such a second run of a drawn trial's pilot; the
aircraft (plant, actuator, Dutch roll) and the logger stay those of the first trial.
"""

from __future__ import annotations

import numpy as np

from ..core.errors import HesspipeError
from ..core.seeds import derive_seed
from .trial import EFFECTS, TrialSpec, draw_trial

PILOT_SIDE = ("motion_feedback", "extra_delay", "remnant")
"""Effects of the pilot (or of the simulator's cueing) that a retest may switch on or off;
the others belong to the aircraft and stay as drawn."""

RETEST = dict(tau_sd=(0.005, 0.015), gain_cv=(0.05, 0.15), wn_cv=(0.02, 0.08))
"""Run-to-run scatter of one pilot: the visual delay's standard deviation (s), the gains'
(Ke, K1) and the neuromuscular frequency's coefficients of variation, each drawn per
retest from these ranges."""

_OPTIONS = ("fs", "T_m", "fade", "fine_ratio", "n_lines", "output", "tau_m", "gain_drift", "drift_tc",
            "line_bins", "feedforward", "ff_delay", "threshold")


def retest(spec: TrialSpec, seed: int, *, effects=None, name: str | None = None) -> TrialSpec:
    """A second run of `spec`'s pilot: another draw of the run-to-run scatter, the remnant
    and the forcing's phases; the aircraft, task and logger of `spec`.

    Parameters
    ----------
    spec : TrialSpec
        The first trial (hess or precision pilot).
    seed : int
        Seed of the second run (the scatter, forcing and remnant are drawn from it).
    effects : iterable of str, optional
        Pilot-side effects of the second run (any of :data:`PILOT_SIDE`); default: those of
        `spec`. Aircraft-side effects are always `spec`'s.
    name : str, optional
        Trial id (default ``spec.name + "-retest"``).

    Returns
    -------
    TrialSpec
        The second trial; its pilot's ``tau_v`` (s) is the first's plus the scatter, and
        ``extra_delay`` (s) is the first trial's when both have the effect (a repeat of the
        condition: the simulator's latency), else drawn afresh when the effect is on.

    Raises
    ------
    HesspipeError
        For an unknown or aircraft-side effect in `effects`.
    """
    pilot_side = tuple(e for e in spec.effects if e in PILOT_SIDE) if effects is None else tuple(effects)
    bad = [e for e in pilot_side if e not in PILOT_SIDE]
    if bad:
        raise HesspipeError(f"retest: effects: expected pilot-side effects ({', '.join(PILOT_SIDE)}), "
                            f"got {', '.join(bad)}")
    if "motion_feedback" in pilot_side and not spec.pilot.get("Km"):
        raise HesspipeError("retest: effect 'motion_feedback': the first trial's pilot has no Km")
    aircraft = tuple(e for e in spec.effects if e in EFFECTS and e not in PILOT_SIDE)
    rng = np.random.default_rng(derive_seed(seed, "retest-scatter"))
    tau_sd, gain_cv, wn_cv = (float(rng.uniform(*RETEST[k])) for k in ("tau_sd", "gain_cv", "wn_cv"))
    p = {k: v for k, v in spec.pilot.items() if k not in ("tau", "extra_delay", "km_ratio")}
    # The pilot's own delay stays a human's (the generator's range, widened by the scatter).
    p["tau_v"] = float(np.clip(p["tau_v"] + rng.normal(0.0, tau_sd), 0.1, 0.45))
    for key in ("Ke", "Kp", "K1", "Km"):
        if p.get(key):
            p[key] = float(p[key] * np.exp(rng.normal(0.0, gain_cv)))
    if p.get("wn"):
        p["wn"] = float(p["wn"] * np.exp(rng.normal(0.0, wn_cv)))
    if "motion_feedback" not in pilot_side:
        p["Km"] = 0.0
    over = {k: spec.options[k] for k in _OPTIONS if k in spec.options}
    for key in ("logged_run_in", "logged_run_out"):
        if spec.options.get(key):
            over[key] = spec.options[key]
    if spec.options.get("logged_run_in"):
        # The logger starts as long before the measurement as on the first run, so the
        # run-in it logs is the first run's too.
        over["run_in"] = spec.options["run_in"]
    if "actuator_lag" in aircraft:
        over["actuator_tau"] = spec.actuator["tau"]
    if "rate_limit" in aircraft:
        over["rate_limit_factor"] = spec.actuator["rate_limit_factor"]
    if spec.motion_tf is not None:   # the same cab, whether or not the retest's pilot uses it
        over["motion_path"] = spec.motion_tf
    if "extra_delay" in pilot_side and spec.pilot.get("extra_delay"):
        # A repeat of the condition: the simulator's latency is the same on every run.
        over["extra_delay"] = (spec.pilot["extra_delay"],) * 2
    return draw_trial(spec.plant, seed, task=spec.task, pilot=p["structure"],
                      effects=aircraft + pilot_side, pilot_params=p, style=spec.style,
                      name=name or f"{spec.name}-retest", **over)
