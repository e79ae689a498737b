"""Crossover frequency and phase margin of the pilot-vehicle loop.

The loop is broken at the displayed error (SPEC.md "Crossover metrics"):
``L(s) = Y_pilot(s) Yc(s)`` where ``Y_pilot`` is the whole pilot from e to
delta with its inner loops (proprioceptive and, for the expanded model, the
motion path through the plant) closed::

    L = NM visual Yc / (1 + NM PF + NM vestibular Yc)

Crossover: the highest frequency where ``|L(j w)|`` falls through 1; phase
margin ``180 deg + angle L(j wc)``, wrapped to (-180, 180]. The limits are
this project's assumption (default 1-5 rad/s and 20-60 deg), and the
output says so.
"""

from __future__ import annotations

import functools
from dataclasses import asdict, dataclass
from typing import Mapping

import numpy as np
from scipy.optimize import brentq

from ..core.errors import HesspipeError
from .blocks import Block, from_tf
from .hess import PilotModel, model_from_name, table1
from .motion import motion_block, with_motion_path

LIMITS_NOTE = ("crossover-model limits are an assumption of hesspipe (configurable), "
               "not values from the paper")


@dataclass(frozen=True)
class CrossoverLimits:
    """Acceptable crossover frequency (rad/s) and phase margin (deg)."""

    frequency_rad_s: tuple[float, float] = (1.0, 5.0)
    phase_margin_deg: tuple[float, float] = (20.0, 60.0)


@dataclass(frozen=True)
class Crossover:
    """Crossover metrics of one pilot-vehicle loop.

    Attributes
    ----------
    frequency_rad_s : float
        Crossover frequency wc (NaN if |L| never crosses 1 in 1e-3..1e3 rad/s).
    phase_margin_deg : float
        180 + angle L(j wc), deg (NaN without a crossover).
    within_limits : bool
        Both inside :class:`CrossoverLimits`.
    limits : CrossoverLimits
    """

    frequency_rad_s: float
    phase_margin_deg: float
    within_limits: bool
    limits: CrossoverLimits = CrossoverLimits()

    def to_dict(self) -> dict:
        return {"frequency_rad_s": self.frequency_rad_s, "phase_margin_deg": self.phase_margin_deg,
                "within_limits": self.within_limits,
                "limits": {k: list(v) for k, v in asdict(self.limits).items()},
                "limits_note": LIMITS_NOTE}


def _plant_block(plants) -> Block:
    if isinstance(plants, Block):
        return plants
    yc = getattr(plants, "control_to_output", plants)
    return from_tf(yc)


def loop_crossover(loop, yc: Block, limits: CrossoverLimits = CrossoverLimits(), *,
                   first: bool = False) -> Crossover:
    """Crossover of an already built :class:`~hesspipe.pilot.blocks.Loop` with control plant `yc`.

    `first`: the lowest frequency where |L| falls through 1 (the primary crossover)
    instead of the highest (SPEC's definition, which a neuromuscular or
    proprioceptive peak touching 1 far above the forcing's band moves there).
    """
    def gain_db(w):
        s = 1j * np.atleast_1d(np.asarray(w, dtype=float))
        with np.errstate(divide="ignore"):  # a zero gain (Ke = 0) is log 0 = -inf: no crossover
            return np.log(np.abs(loop.pilot_open_loop(s, yc.response(s))))

    w = np.logspace(-3, 3, 3001)
    g = gain_db(w)
    down = np.nonzero((g[:-1] > 0) & (g[1:] <= 0))[0]
    if down.size == 0:
        return Crossover(float("nan"), float("nan"), False, limits)
    i = down[0] if first else down[-1]
    wc = brentq(lambda x: float(gain_db(x)[0]), w[i], w[i + 1], xtol=1e-10, rtol=1e-12)
    s = np.array([1j * wc])
    phase = np.degrees(np.angle(loop.pilot_open_loop(s, yc.response(s))[0]))
    pm = (180.0 + phase + 180.0) % 360.0 - 180.0
    pm = 180.0 if pm == -180.0 else pm
    within = (limits.frequency_rad_s[0] <= wc <= limits.frequency_rad_s[1]
              and limits.phase_margin_deg[0] <= pm <= limits.phase_margin_deg[1])
    return Crossover(float(wc), float(pm), bool(within), limits)


def crossover(model, params: Mapping[str, float] | None, plants, *,
              limits: CrossoverLimits = CrossoverLimits(), k: int | None = None) -> Crossover:
    """Crossover frequency and phase margin of `model` with `params` around `plants`.

    Parameters
    ----------
    model : PilotModel or str
    params : mapping
        Parameter values (missing: Table 1 defaults).
    plants : Plants or control.TransferFunction
        The control plant Yc (or Plants holding it).
    limits : CrossoverLimits
    """
    model = model_from_name(model)
    p = model.complete(params, k)
    return loop_crossover(with_motion_path(model.loop(p), motion_block(plants)),
                          _plant_block(plants), limits)


@functools.lru_cache(maxsize=4)
def reference_crossover(k: int = 1) -> float:
    """Crossover (rad/s) of Table 1's original model around ``Yc = 1/s^k``.

    2.886 rad/s for k = 1, the value Table 1 is calibrated for (SPEC.md).
    """
    import control as ct

    return float(crossover(PilotModel(), table1(k), ct.tf([1.0], [1.0] + [0.0] * k)).frequency_rad_s)


def gain_scale(plants, k: int = 1) -> float:
    """Factor by which a pilot's loop gains (:data:`LOOP_GAINS`) differ from Table 1's on `plants`.

    Table 1 is calibrated for ``Yc = 1/s^k``, where it crosses over at
    ``wr`` = :func:`reference_crossover` (2.9 rad/s for k = 1). A pilot
    adapts his gain to the controlled element (McRuer's crossover model), so
    the factor is the one that puts the crossover of Table 1's original model
    around `plants` at the same ``wr``: ``g = 1 / |L(j wr)|`` with ``L`` the
    open loop of Table 1's pilot and the plants' Yc. Exactly 1 for ``1/s^k``;
    about 0.44 for the paper's analytic roll plant ``2.436/(s + 1.05)`` and
    2.7 for the JSBSim 737's ARX plant (normalised aileron command).

    Parameters
    ----------
    plants : Plants or control.TransferFunction
        The plants (only Yc, control → output, is used).
    k : int
        Table 1 column (1: rate-like, 2: acceleration-like controlled element).

    Returns
    -------
    float
        Positive factor multiplying Ke, Km, Ko defaults, boxes and bit fields.
    """
    wr = reference_crossover(k)
    yc = from_tf(getattr(plants, "control_to_output", plants))
    s = np.array([1j * wr])
    mag = float(np.abs(PilotModel().loop(table1(k)).pilot_open_loop(s, yc.response(s))[0]))
    if not (mag > 0 and np.isfinite(mag)):
        raise HesspipeError(f"plants: control_to_output has gain {mag:g} at the reference crossover "
                            f"{wr:.3g} rad/s; expected a finite non-zero gain")
    return 1.0 / mag
