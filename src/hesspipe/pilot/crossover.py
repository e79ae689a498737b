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

SPEC.md defines the crossover by ``|L(j wc)| = 1`` and does not say which
crossing counts when there are several. On fitted plants there are: the
JSBSim 737's aileron channel has a right-half-plane zero near +0.006 rad/s
and a slow pole near 0.07 rad/s, so a pilot's |L| crosses 1 around 0.002
rad/s too, and a neuromuscular peak can touch 1 again far above the band the
data show. The crossover of the pilot's tracking loop, the one the crossover
model is about, is the *primary* crossover in the record's band
(:func:`tracking_crossover`): the first fall through 1 above the lowest
frequency a record of the given length resolves, ``2 pi / duration``
(0.09 rad/s for 70 s; a crossing slower than one cycle per record is neither
seen by the data nor placed by plants fitted to it).
"""

from __future__ import annotations

import functools
import math
from dataclasses import asdict, dataclass
from typing import Mapping

import control as ct
import numpy as np
from scipy.optimize import brentq

from ..core.errors import HesspipeError
from .blocks import Block, from_tf
from .hess import PilotModel, model_from_name, table1
from .motion import motion_block, with_motion_path

LIMITS_NOTE = ("crossover-model limits are an assumption of hesspipe (configurable), "
               "not values from the paper")
FLAT_FACTOR = 1.25
"""|L| within this factor of 1 (either way) counts as "at crossover" for :func:`flat_band`."""
FLAT_SPAN = 2.5
"""A :func:`flat_band` spanning more than this factor in frequency is wide: across it |L| falls
by less than about 10 dB per decade, half the crossover model's -20 dB/decade (whose band spans
FLAT_FACTOR**2 = 1.56), so where |L| passes 1 there is set by a few per cent of gain, and the
phase margin changes along the band."""


@dataclass(frozen=True)
class CrossoverLimits:
    """Acceptable crossover frequency (rad/s) and phase margin (deg).

    Attributes
    ----------
    frequency_rad_s : (float, float)
        Lowest and highest acceptable crossover frequency, rad/s.
    phase_margin_deg : (float, float)
        Lowest and highest acceptable phase margin, deg.
    """

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
    flat_band : FlatBand or None
        Where |L| stays near 1 around the crossover (:func:`flat_band`; a wide one makes the
        crossover sensitive to the parameters); None without a crossover.
    """

    frequency_rad_s: float
    phase_margin_deg: float
    within_limits: bool
    limits: CrossoverLimits = CrossoverLimits()
    flat_band: "FlatBand | None" = None

    def to_dict(self) -> dict:
        """JSON-ready: frequency (rad/s), margin (deg), the verdict and the limits it used."""
        return {"frequency_rad_s": self.frequency_rad_s, "phase_margin_deg": self.phase_margin_deg,
                "within_limits": self.within_limits,
                "limits": {k: list(v) for k, v in asdict(self.limits).items()},
                "limits_note": LIMITS_NOTE,
                "flat_band": None if self.flat_band is None else self.flat_band.to_dict()}


@dataclass(frozen=True)
class FlatBand:
    """The band around a crossover where |L| stays within :data:`FLAT_FACTOR` of 1.

    Attributes
    ----------
    low_rad_s, high_rad_s : float
        Its edges, rad/s (the searched span's edge where |L| is still near 1 there).
    phase_margin_range_deg : (float, float)
        The lowest and highest ``180 + angle L`` along it, deg.
    """

    low_rad_s: float
    high_rad_s: float
    phase_margin_range_deg: tuple[float, float]

    @property
    def wide(self) -> bool:
        """The band spans more than :data:`FLAT_SPAN` in frequency."""
        return self.high_rad_s > FLAT_SPAN * self.low_rad_s

    def describe(self) -> str:
        """The band in words."""
        lo, hi = self.phase_margin_range_deg
        return (f"|L| stays within a factor {FLAT_FACTOR:g} of 1 from {self.low_rad_s:.2g} to "
                f"{self.high_rad_s:.2g} rad/s (less than half the crossover model's -20 dB/decade), so "
                f"where it passes 1 is set by a few per cent of gain; 180 + angle L is {lo:.0f} to "
                f"{hi:.0f} deg along the band")

    def to_dict(self) -> dict:
        """JSON-ready fields (rad/s, deg) with the rule in words."""
        return {"low_rad_s": self.low_rad_s, "high_rad_s": self.high_rad_s,
                "phase_margin_range_deg": list(self.phase_margin_range_deg), "wide": self.wide,
                "rule": (f"the band around the crossover where |L| stays within a factor {FLAT_FACTOR:g} "
                         f"of 1; wide when it spans more than a factor {FLAT_SPAN:g}")}


FLAT_MARK_MEANING = (f"the model's |L| stays within a factor {FLAT_FACTOR:g} of 1 over more than a factor "
                     f"{FLAT_SPAN:g} around the crossover, so a few per cent of gain move the crossover "
                     "along that band and the phase margin with it")
"""What the tables' :func:`flat_mark` means, in the captions' words."""


def flat_mark(cross: Mapping) -> str:
    """The tables' mark of a crossover in a wide flat band.

    Parameters
    ----------
    cross : mapping
        A crossover as :meth:`Crossover.to_dict` writes it (a comparison's JSON).

    Returns
    -------
    str
        "~" where it crosses and its ``flat_band`` is wide, else "".
    """
    f = cross.get("frequency_rad_s")
    crossed = isinstance(f, (int, float)) and math.isfinite(f)
    return "~" if crossed and (cross.get("flat_band") or {}).get("wide") else ""


def phase_margin_deg(phase_deg):
    """The phase margin of a loop whose phase at the crossover is `phase_deg` (deg): 180 + the
    phase, wrapped into (-180, 180] deg; array or float as given.

    Parameters
    ----------
    phase_deg : float or array
        The loop's phase at its crossover, deg (negative: lagging).

    Returns
    -------
    float or numpy.ndarray
        Degrees; positive where the loop lags by less than 180 deg.
    """
    pm = (180.0 + np.asarray(phase_deg, dtype=float) + 180.0) % 360.0 - 180.0
    pm = np.where(pm == -180.0, 180.0, pm)
    return float(pm) if pm.ndim == 0 else pm


def flat_band(w, L, wc: float) -> FlatBand | None:
    """The band around `wc` where |L| stays within :data:`FLAT_FACTOR` of 1.

    Parameters
    ----------
    w : array
        Ascending frequencies, rad/s (a fine grid, or measured lines).
    L : array of complex
        The loop at `w`.
    wc : float
        The crossover, rad/s.

    Returns
    -------
    FlatBand or None
        None when `wc` is not finite or no point of `w` is near 1 around it.
    """
    w, L = np.asarray(w, dtype=float), np.asarray(L)
    if not np.isfinite(wc) or w.size == 0:
        return None
    with np.errstate(divide="ignore"):   # a zero gain is far from 1, not a warning
        near = np.abs(np.log(np.abs(L))) <= np.log(FLAT_FACTOR)
    # the points near 1 connected to the crossover (which lies between two of them, or beside one)
    i = int(np.clip(np.searchsorted(w, wc), 0, w.size - 1))
    start = next((j for j in (i, i - 1) if 0 <= j < w.size and near[j]), None)
    if start is None:
        return None
    lo = hi = start
    while lo > 0 and near[lo - 1]:
        lo -= 1
    while hi < w.size - 1 and near[hi + 1]:
        hi += 1
    pm = np.atleast_1d(phase_margin_deg(np.degrees(np.angle(L[lo:hi + 1]))))
    return FlatBand(float(min(w[lo], wc)), float(max(w[hi], wc)), (float(np.min(pm)), float(np.max(pm))))


TRACKING_DEFINITION = ("tracking crossover: the first fall of |L| through 1 above the lowest frequency the "
                       "record resolves, 2 pi / duration (what the tables print)")
LAST_FALL_DEFINITION = ("the last fall of |L| through 1 in 0.001-1000 rad/s (SPEC.md's |L| = 1 at its highest "
                        "crossing; a neuromuscular peak touching 1 can put it far above the tracking crossover)")


def crossover_fields(tracking: Crossover | None, last_fall: Crossover) -> dict:
    """The two crossovers as a result's JSON fields, each with its definition.

    ``crossover`` is the tracking crossover (the one tables print and the crossover model
    is about; `last_fall` where no record length gave one), ``crossover_last_fall`` SPEC's
    highest crossing.

    Parameters
    ----------
    tracking : Crossover or None
        :func:`tracking_crossover`'s.
    last_fall : Crossover
        :func:`loop_crossover`'s (``first=False``).

    Returns
    -------
    dict
        ``{"crossover": {...}, "crossover_last_fall": {...}}``.
    """
    shown = tracking if tracking is not None else last_fall
    return {"crossover": {**shown.to_dict(),
                          "definition": TRACKING_DEFINITION if tracking is not None else LAST_FALL_DEFINITION},
            "crossover_last_fall": {**last_fall.to_dict(), "definition": LAST_FALL_DEFINITION}}


def _plant_block(plants) -> Block:
    if isinstance(plants, Block):
        return plants
    yc = getattr(plants, "control_to_output", plants)
    return from_tf(yc)


def loop_crossover(loop, yc: Block, limits: CrossoverLimits = CrossoverLimits(), *,
                   first: bool = False, w_min: float = 1e-3) -> Crossover:
    """Crossover of an already built :class:`~hesspipe.pilot.blocks.Loop` with control plant `yc`.

    `first`: the lowest frequency where |L| falls through 1 (the primary crossover)
    instead of the highest (SPEC's definition, which a neuromuscular or
    proprioceptive peak touching 1 far above the forcing's band moves there).
    `w_min` (rad/s): crossings below it are ignored (see :func:`tracking_crossover`).

    Parameters
    ----------
    loop : hesspipe.pilot.blocks.Loop
        The pilot's loop, motion path included.
    yc : hesspipe.pilot.blocks.Block
        Control plant, control -> output.
    limits : CrossoverLimits
        Acceptable ranges (the verdict ``within_limits``).
    first : bool
        The lowest falling crossing above `w_min` instead of the highest.
    w_min : float
        Lowest frequency searched, rad/s.

    Returns
    -------
    Crossover
        NaN frequency and margin when |L| never falls through 1.
    """
    def open_loop(w):
        s = 1j * np.atleast_1d(np.asarray(w, dtype=float))
        return loop.pilot_open_loop(s, yc.response(s))

    def gain_db(w):
        with np.errstate(divide="ignore"):  # a zero gain (Ke = 0) is log 0 = -inf: no crossover
            return np.log(np.abs(open_loop(w)))

    if not (math.isfinite(w_min) and 1e-3 <= w_min < 1e3):
        raise HesspipeError(f"w_min: expected a frequency in [0.001, 1000) rad/s, got {w_min!r}")
    w = np.logspace(-3, 3, 3001)
    w = np.concatenate(([w_min], w[w > w_min]))
    L = open_loop(w)
    with np.errstate(divide="ignore"):
        g = np.log(np.abs(L))
    down = np.nonzero((g[:-1] > 0) & (g[1:] <= 0))[0]
    if down.size == 0:
        return Crossover(float("nan"), float("nan"), False, limits)
    i = down[0] if first else down[-1]
    wc = brentq(lambda x: float(gain_db(x)[0]), w[i], w[i + 1], xtol=1e-10, rtol=1e-12)
    pm = phase_margin_deg(np.degrees(np.angle(open_loop(wc)[0])))
    within = (limits.frequency_rad_s[0] <= wc <= limits.frequency_rad_s[1]
              and limits.phase_margin_deg[0] <= pm <= limits.phase_margin_deg[1])
    return Crossover(float(wc), float(pm), bool(within), limits, flat_band(w, L, wc))


def record_band_floor(duration_s: float) -> float:
    """Lowest frequency a record of `duration_s` resolves, ``2 pi / duration`` (rad/s).

    Parameters
    ----------
    duration_s : float
        Record length, s (> 0). The result is clipped to 1e-3..1 rad/s.
    """
    if not (math.isfinite(duration_s) and duration_s > 0):
        raise HesspipeError(f"duration_s: expected a record length > 0 s, got {duration_s!r}")
    return min(max(2.0 * math.pi / duration_s, 1e-3), 1.0)


def tracking_crossover(loop, yc: Block, duration_s: float,
                       limits: CrossoverLimits = CrossoverLimits()) -> Crossover:
    """The crossover of the pilot's tracking loop on a record of `duration_s` seconds.

    The first frequency above ``2 pi / duration_s`` (:func:`record_band_floor`)
    where ``|L|`` falls through 1 (see the module docstring for why this one).

    Parameters
    ----------
    loop : hesspipe.pilot.blocks.Loop
        The pilot's loop, motion path included.
    yc : hesspipe.pilot.blocks.Block
        Control plant, control -> output.
    duration_s : float
        Record length, s.
    limits : CrossoverLimits
        Acceptable ranges.
    """
    return loop_crossover(loop, yc, limits, first=True, w_min=record_band_floor(duration_s))


def crossover(model, params: Mapping[str, float] | None, plants, *,
              limits: CrossoverLimits = CrossoverLimits(), k: int | None = None,
              duration_s: float | None = None) -> Crossover:
    """Crossover frequency and phase margin of `model` with `params` around `plants`.

    Parameters
    ----------
    model : PilotModel or str
    params : mapping
        Parameter values (missing: Table 1 defaults).
    plants : Plants or control.TransferFunction
        The control plant Yc (or Plants holding it).
    limits : CrossoverLimits
    duration_s : float, optional
        Record length (s): given, the tracking loop's crossover in the record's
        band (:func:`tracking_crossover`); else SPEC's highest crossing.
    """
    model = model_from_name(model)
    p = model.complete(params, k)
    loop = with_motion_path(model.loop(p), motion_block(plants))
    if duration_s is not None:
        return tracking_crossover(loop, _plant_block(plants), duration_s, limits)
    return loop_crossover(loop, _plant_block(plants), limits)


@functools.lru_cache(maxsize=4)
def reference_crossover(k: int = 1) -> float:
    """Crossover (rad/s) of Table 1's original model around ``Yc = 1/s^k``.

    2.886 rad/s for k = 1, the value Table 1 is calibrated for (SPEC.md).

    Parameters
    ----------
    k : int
        Table 1 column and plant order (1 or 2).
    """

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
