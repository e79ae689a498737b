"""The generator's knobs: the effects it can hide, the literature's ranges and the options of
:func:`~hesspipe.humanlike.trial.draw_trial`, and their checks (private: :mod:`.trial`
re-exports the constants)."""

from __future__ import annotations

import numpy as np

from ..core.errors import HesspipeError

EFFECTS = ("motion_feedback", "extra_delay", "remnant", "dutch_roll", "actuator_lag", "rate_limit")

# Literature ranges (SPEC "Describing functions"; McRuer crossover model), deliberately
# not centred on hesspipe's Table 1 cohort. Each may be overridden by a value or (lo, hi).
RANGES = dict(tau=(0.15, 0.35), wn=(7.0, 15.0), zn=(0.1, 0.5), wc=(1.5, 4.0), pm=(20.0, 60.0),
              inv_T1=(0.1, 1.0), inv_T2=(0.2, 2.0), K1=(1.0, 5.0),
              remnant_share=(0.10, 0.40), remnant_tn=(0.1, 0.3), w_corner=(1.5, 2.0),
              km_ratio=(0.2, 1.0), extra_delay=(0.04, 0.10), actuator_tau=(0.05, 0.15),
              rate_limit_factor=(1.0, 2.0), d_ratio=(0.5, 1.0))
EFFECT_REMNANT = (0.40, 0.60)
OPTIONS = dict(fs=60.0, T_m=45.0, run_in=None, fade=5.0, fine_ratio=20, n_lines=10,
               output="rate", disturbance=None, gain=1.0, d_rms=None, r_rms=None,
               remnant_at="control", tau_m=0.0, motion_path=None, name=None, style=None,
               pilot_params=None, gain_drift=0.0, drift_tc=10.0, line_bins=None, feedforward=0.0,
               ff_delay=None, threshold=0.0, logged_run_in=0.0, logged_run_out=0.0)


def _check_line_bins(bins, n_log: int):
    """The `line_bins` option as two int arrays, or None; one-line errors otherwise."""
    if bins is None:
        return None
    try:
        pair = tuple(bins)
        k_d, k_t = (np.asarray(b, dtype=float) for b in pair)
    except (TypeError, ValueError):
        raise HesspipeError("line_bins: expected a pair of line-number lists (disturbance, target), "
                            f"got {bins!r}") from None
    for name, k, given in (("disturbance", k_d, pair[0]), ("target", k_t, pair[1])):
        if k.ndim != 1 or k.size < 2 or np.any(k != np.round(k)) or np.any(np.diff(k) <= 0) \
                or k[0] < 1 or k[-1] >= n_log // 2:
            raise HesspipeError(f"line_bins: the {name} lines must be at least two increasing whole "
                                f"numbers from 1 to {n_log // 2 - 1}, got {given!r}")
    if np.intersect1d(k_d, k_t).size:
        raise HesspipeError(f"line_bins: the sets share line(s) {np.intersect1d(k_d, k_t).astype(int).tolist()}; "
                            "expected disjoint disturbance and target lines")
    return k_d.astype(int), k_t.astype(int)


def _range(overrides: dict, key: str, default) -> tuple:
    v = overrides.pop(key, None)
    if v is None:
        return tuple(default)
    if np.isscalar(v):
        return (float(v), float(v))
    try:
        lo, hi = (float(x) for x in v)
    except (TypeError, ValueError):
        raise HesspipeError(f"{key}: expected a number or (low, high), got {v!r}") from None
    if not lo <= hi:
        raise HesspipeError(f"{key}: expected low <= high, got ({lo}, {hi})")
    return (lo, hi)


def _checked_options(effects: tuple, task: str, pilot: str, overrides: dict) -> tuple:
    # draw_trial's ranges and options with the overrides applied and checked (its Raises),
    # the forcing's line numbers, and the gain drift's CV and correlation time.
    ov = dict(overrides)
    ranges = {k: _range(ov, k, v) for k, v in RANGES.items()}
    opts = {k: ov.pop(k, v) for k, v in OPTIONS.items()}
    if ov:
        raise HesspipeError(f"draw_trial: unknown option(s) {', '.join(sorted(ov))}; expected "
                            f"{', '.join(list(RANGES) + list(OPTIONS))}")
    if opts["run_in"] is None:
        opts["run_in"] = 60.0 if {"motion_feedback", "dutch_roll"} & set(effects) else 15.0
    bad = [e for e in effects if e not in EFFECTS]
    if bad:
        raise HesspipeError(f"effects: unknown {', '.join(bad)}; expected {', '.join(EFFECTS)}")
    if task not in ("disturbance", "tracking", "both"):
        raise HesspipeError(f"task: expected 'disturbance', 'tracking' or 'both', got {task!r}")
    if pilot not in ("precision", "hess"):
        raise HesspipeError(f"pilot: expected 'precision' or 'hess', got {pilot!r}")
    drift, drift_tc = float(opts["gain_drift"]), float(opts["drift_tc"])
    if not 0.0 <= drift <= 0.5:
        raise HesspipeError(f"gain_drift: expected a coefficient of variation in [0, 0.5], got {drift!r}")
    if not drift_tc > 0.0:
        raise HesspipeError(f"drift_tc: expected a correlation time > 0 s, got {drift_tc!r}")
    n_log = opts["fs"] * opts["T_m"]
    if abs(n_log - round(n_log)) > 1e-9 or n_log < 4:
        raise HesspipeError(f"T_m: fs*T_m must be a whole number of samples, got {n_log:g}")
    line_bins = _check_line_bins(opts["line_bins"], int(round(n_log)))
    if "remnant" in effects and "remnant_share" not in overrides:
        ranges["remnant_share"] = EFFECT_REMNANT
    return ranges, opts, line_bins, drift, drift_tc
