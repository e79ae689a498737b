"""The Hess structural pilot model, original and expanded, closed around the plants.

Original model (SPEC.md "Stage three", series form)::

    u_e   = Ke exp(-tau0 s) e                         visual / central processing
    delta = Y_NM (u_e - u_p - u_v)                    u_v = 0 without motion feedback
    Y_NM  = wn^2 / (s^2 + 2 zn wn s + wn^2)
    u_p   = Y_PF delta,  Y_PF = [K1 s / (s + 1/T1)] [K2 / (s + 1/T2)^(k-1)]

with the plants ``y = Yc delta + Yd w`` and ``e = r - y`` (r = 0: null the roll
rate). The expanded model adds the effect ``motion_feedback``
(:mod:`hesspipe.pilot.effects`): ``u_v = Km Y_SCC Y_MP Y_WO y``. Other effects
augment the loop the same way.

The closed loop is simulated by :mod:`hesspipe.pilot.simulation`; the crossover and the
plants' gain scale are in :mod:`hesspipe.pilot.crossover`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Mapping

import numpy as np

from ..core.config import Fields
from ..core.errors import HesspipeError
from .blocks import Block, Loop, Term
from .effects import EFFECTS, get_effect

PARAMETERS: tuple[str, ...] = ("Ke", "K1", "K2", "1/T1", "1/T2", "k", "tau0", "zn", "wn")
"""Core parameter names, as in the paper's Table 1 (Km belongs to ``motion_feedback``)."""

# name: (Table 1 value, search box lo, hi, APID bits, scale, offset, unit)
# Boxes: the paper's APID ranges for K1/K2 (10 bits at scale 100); Ke 11 bits
# at scale 50 (0..40.94, twice the paper's 0..20.47, which put Table 1's
# Ke = 20 at its edge: pilots around Table 1 need room on both sides); the
# others are bounded to physically sensible values. Ke's box and field are
# further scaled by the plants' gain (gain_scale).
_CORE = {
    "Ke": (20.0, 0.0, 40.94, 11, 50.0, 0.0, "1"),
    "K1": (3.0, 0.0, 10.23, 10, 100.0, 0.0, "1"),
    "K2": (2.0, 0.0, 10.23, 10, 100.0, 0.0, "1"),
    "1/T1": (0.01, 0.0, 1.023, 10, 1000.0, 0.0, "rad/s"),
    "1/T2": (0.1, 0.0, 10.23, 10, 100.0, 0.0, "rad/s"),
    "k": (1.0, 1.0, 2.0, 1, 1.0, 1.0, "1"),
    "tau0": (0.1, 0.0, 1.023, 10, 1000.0, 0.0, "s"),
    "zn": (0.707, 0.0, 2.047, 11, 1000.0, 0.0, "1"),
    "wn": (10.0, 0.0, 40.94, 11, 50.0, 0.0, "rad/s"),
}
STRUCTURAL = ("k",)
"""Parameters that select the structure and are never identified."""

LOOP_GAINS = ("Ke", "Km", "Ko")
"""Gains on the plant's output on its way into the pilot (visual error, vestibular and otolith
sensations). Table 1 sets them for ``Yc = 1/s^k``; a pilot adapts them to the controlled
element (crossover model), so their defaults, search boxes and bit fields are scaled by
:func:`gain_scale` of the plants. K1, K2 (proprioceptive) act on the pilot's own control
and are not scaled."""

def table1(k: int = 1) -> dict[str, float]:
    """Table 1 defaults of the paper for a rate-like (k=1) or acceleration-like (k=2) plant.

    Includes Km = 0.1 of the motion path.

    Parameters
    ----------
    k : {1, 2}
        1 for a plant like K/s near crossover, 2 for K/s^2.

    Returns
    -------
    dict
        Ke, K1, K2 (gains), 1/T1, 1/T2 (rad/s), tau0 (s), zn, wn (rad/s), k, Km.
    """
    if k not in (1, 2):
        raise HesspipeError(f"k: expected 1 (plant ~ K/s) or 2 (plant ~ K/s^2), got {k!r}")
    out = {name: spec[0] for name, spec in _CORE.items()}
    out["k"] = float(k)
    out["Km"] = EFFECTS["motion_feedback"].parameters["Km"][0]
    return out


def _known_parameters() -> set[str]:
    """Every parameter some model has: the core's and every registered effect's."""
    return set(PARAMETERS).union(*(e.parameters for e in EFFECTS.values()))


@dataclass(frozen=True)
class PilotModel:
    """A Hess structural model plus zero or more effects.

    Parameters
    ----------
    effects : tuple of str
        Effect ids of :data:`hesspipe.pilot.effects.EFFECTS`, applied in order.
    """

    effects: tuple[str, ...] = ()

    def __post_init__(self):
        if isinstance(self.effects, str):
            raise HesspipeError(f"effects: expected a tuple of effect ids, got the string {self.effects!r} "
                                "(model_from_name builds a model from its name, e.g. 'expanded')")
        effects = tuple(self.effects)
        for e in effects:
            get_effect(e)
        if len(set(effects)) != len(effects):
            raise HesspipeError(f"effects listed twice in {'+'.join(effects)}")
        object.__setattr__(self, "effects", effects)

    @property
    def name(self) -> str:
        """"original", "expanded" (motion feedback only) or "original+effect+..."."""
        if not self.effects:
            return "original"
        if self.effects[0] == "motion_feedback":
            return "+".join(("expanded",) + self.effects[1:])
        return "+".join(("original",) + self.effects)

    def parameter_names(self) -> tuple[str, ...]:
        """Core names then each effect's parameters."""
        names = list(PARAMETERS)
        for e in self.effects:
            names.extend(EFFECTS[e].parameters)
        return tuple(names)

    def defaults(self, k: int = 1, gain: float = 1.0) -> dict[str, float]:
        """Table 1 values (for `k`) and each effect's default.

        `gain` (:func:`gain_scale` of the plants) multiplies the :data:`LOOP_GAINS`.

        Parameters
        ----------
        k : {1, 2}
            Table 1 column (plant ~ K/s or K/s^2).
        gain : float
            Scale of the loop gains (> 0; 1: Table 1 as printed).
        """
        out = {n: v for n, v in table1(k).items() if n in PARAMETERS}
        for e in self.effects:
            out.update({n: spec[0] for n, spec in EFFECTS[e].parameters.items()})
        return _scaled(out, gain, lambda v, g: v * g)

    def bounds(self, gain: float = 1.0) -> dict[str, tuple[float, float]]:
        """Search box of every parameter, name → (lo, hi); :data:`LOOP_GAINS` times `gain`.""

        Parameters
        ----------
        gain : float
            Scale of the loop gains' boxes (> 0).
        """
        out = {n: (spec[1], spec[2]) for n, spec in _CORE.items()}
        for e in self.effects:
            out.update({n: (spec[1], spec[2]) for n, spec in EFFECTS[e].parameters.items()})
        return _scaled(out, gain, lambda b, g: (b[0] * g, b[1] * g))

    def fields(self, gain: float = 1.0) -> dict[str, tuple[int, float, float]]:
        """Default APID bit field of every parameter, name → (bits, scale, offset).

        The fields of :data:`LOOP_GAINS` span their box times `gain` (scale / gain,
        offset x gain), with the same number of bits.

        Parameters
        ----------
        gain : float
            Scale of the loop gains (> 0).
        """
        out = {n: (spec[3], spec[4], spec[5]) for n, spec in _CORE.items()}
        for e in self.effects:
            out.update(EFFECTS[e].fields)
        return _scaled(out, gain, lambda f, g: (f[0], f[1] / g, f[2] * g))

    def units(self) -> dict[str, str]:
        """Units of every parameter of this model, name → unit string (e.g. ``"s"``)."""
        out = {n: spec[6] for n, spec in _CORE.items()}
        for e in self.effects:
            out.update(EFFECTS[e].units)
        return out

    def with_effect(self, effect_id: str) -> "PilotModel":
        """This model with `effect_id` appended.

        Parameters
        ----------
        effect_id : str
            An id of :data:`hesspipe.pilot.effects.EFFECTS`.
        """
        return PilotModel(self.effects + (effect_id,))

    def complete(self, params: Mapping[str, float] | None = None, k: int | None = None, *,
                 strict: bool = False, gain: float = 1.0) -> dict[str, float]:
        """All parameters: `params` over the defaults.

        `k` (if given, else ``params["k"]``, else 1) picks the Table 1 column;
        `gain` scales the default :data:`LOOP_GAINS` (see :meth:`defaults`).
        Names no model knows are an error; parameters of effects this model
        does not have (Km of :func:`table1` for the original model) are
        dropped, or are an error if `strict`.

        Parameters
        ----------
        params : mapping, optional
            Parameter values by name (units as :meth:`units`).
        k : {1, 2}, optional
            Table 1 column.
        strict : bool
            Refuse parameters of effects this model does not have.
        gain : float
            Scale of the default loop gains (> 0).

        Returns
        -------
        dict
            Every parameter of the model, floats.
        """
        params = dict(params or {})
        names = self.parameter_names()
        known = _known_parameters()
        unknown = [n for n in params if n not in (names if strict else known)]
        if unknown:
            raise HesspipeError(f"unknown parameter {unknown[0]!r} for model {self.name}; "
                                f"expected one of {', '.join(names)}")
        params = {n: v for n, v in params.items() if n in names}
        kk = int(round(params.get("k", k if k is not None else 1)))
        out = self.defaults(kk, gain)
        out.update({n: float(v) for n, v in params.items()})
        out["k"] = float(kk)
        bad = [n for n, v in out.items() if not np.isfinite(v)]
        if bad:
            raise HesspipeError(f"parameter {bad[0]!r}: expected a finite number, got {out[bad[0]]!r}")
        if out["k"] not in (1.0, 2.0):
            raise HesspipeError(f"parameter 'k': expected 1 or 2, got {params.get('k')!r}")
        return out

    def check_values(self, params: Mapping, source: str) -> dict[str, float]:
        """Given parameter values (a file's) checked for this model, before any flight.

        Each name must be a parameter some model has (as in :meth:`complete`, those of
        effects this model lacks are dropped) and each value a number at or above the low
        end of the parameter's search box (:meth:`bounds`, whose loop gains start at 0 on any
        gain scale), ``wn`` above it. The boxes' high ends are the search's reach, not a
        pilot's: a drawn pilot's truth may lie beyond them (``Kn`` per simulation step).

        Parameters
        ----------
        params : mapping
            Name → value.
        source : str
            Where they came from (a file), named in messages.

        Returns
        -------
        dict
            This model's parameters among them, as floats.

        Raises
        ------
        HesspipeError
            ``SOURCE: field 'NAME': ...`` naming the first bad one and what was expected.
        """
        f = Fields(params, source)
        names = self.parameter_names()
        known = _known_parameters()
        lows = {n: lo for n, (lo, _) in self.bounds().items()}
        out = {}
        for name in f.table:
            if name not in known:
                raise f.fail(name, f"unknown parameter for model {self.name}; expected one of "
                                   f"{', '.join(names)}")
            # wn = 0 is in the box, but its neuromuscular lag then passes nothing: no pilot.
            value = f.number(name, min=lows.get(name), strict_min=name == "wn")
            if name in names:
                out[name] = value
        return out

    def loop(self, params: Mapping[str, float]) -> Loop:
        """The loop's blocks for complete parameters (see :meth:`complete`).

        Parameters
        ----------
        params : mapping
            Complete parameters (:meth:`complete`).
        """
        loop = core_loop(params)
        for e in self.effects:
            loop = EFFECTS[e].apply(loop, params)
        return loop


def _scaled(table: dict, gain: float, how) -> dict:
    if not (gain > 0 and np.isfinite(gain)):
        raise HesspipeError(f"gain scale: expected a positive finite number, got {gain!r}")
    if gain == 1.0:
        return table
    return {n: how(v, gain) if n in LOOP_GAINS else v for n, v in table.items()}


def core_loop(p: Mapping[str, float]) -> Loop:
    """Blocks of the original Hess structural model for parameters `p`.

    Parameters
    ----------
    p : mapping
        Ke, K1, K2, 1/T1 and 1/T2 (rad/s), tau0 (s), zn, wn (rad/s), k.

    Returns
    -------
    Loop
        Visual ``Ke exp(-tau0 s)``, neuromuscular second order, proprioceptive
        ``K1 K2 s/(s + 1/T1)`` (times ``1/(s + 1/T2)`` for k = 2), no vestibular path.
    """
    wn, zn = float(p["wn"]), float(p["zn"])
    w2 = wn * wn
    nm = Block((Term((1.0,), (1.0, 2.0 * zn * wn, w2), 0.0, w2),))
    a1 = float(p["1/T1"])
    # With 1/T1 = 0 the lead K1 s/(s + 0) is the constant K1; writing it as
    # such keeps a cancelled pole at s = 0 out of the stability test.
    num, den = ((1.0, 0.0), (1.0, a1)) if a1 != 0 else ((1.0,), (1.0,))
    if int(p["k"]) == 2:
        # Times (s + 1/T2), written out (np.convolve was a sixth of a fit's model evaluation).
        a2 = float(p["1/T2"])
        den = (1.0, a1 + a2, a1 * a2) if a1 != 0 else (1.0, a2)
    pf = Block((Term(num, den, 0.0, float(p["K1"]) * float(p["K2"])),))
    visual = Block((Term((1.0,), (1.0,), float(p["tau0"]), float(p["Ke"])),))
    return Loop(visual=visual, vestibular=Block(), neuromuscular=nm, proprioceptive=pf)


def km_per_ke(p: Mapping[str, float]) -> float:
    """Km/|Ke|: the vestibular path's gain relative to the visual one (output units per
    rad/s of cab motion; dimensionless on a rate task, s on an angle task).

    Where the proprioceptive corner 1/T1 lies below the frequencies that matter, the
    inner loop ``NM/(1 + NM K1 K2)`` is one gain ``1/(1 + K1 K2)`` times a neuromuscular
    mode, so Ke and Km scale together along a valley of (K1, wn, zn) that data hardly
    bound; their ratio is the same all along it, and is what compares pilots.

    Parameters
    ----------
    p : mapping
        Pilot parameters with Ke and, for a model with motion feedback, Km.

    Returns
    -------
    float
        NaN without Km or with Ke = 0.
    """
    km, ke = p.get("Km"), p.get("Ke")
    return float(km) / abs(float(ke)) if km is not None and ke else float("nan")


def model_from_name(name: str | PilotModel) -> PilotModel:
    """"original", "expanded", or "+"-joined effect ids ("expanded+remnant").

    Parameters
    ----------
    name : str or PilotModel
        A model name (a PilotModel is returned as it is).

    Raises
    ------
    HesspipeError
        Unknown name or effect.
    """
    if isinstance(name, PilotModel):
        return name
    parts = [p.strip() for p in str(name).split("+") if p.strip()]
    if not parts or parts[0] not in ("original", "expanded"):
        raise HesspipeError(f"unknown model {name!r}; expected 'original' or 'expanded' "
                            f"(optionally followed by +EFFECT, effects: {', '.join(EFFECTS)})")
    effects = (("motion_feedback",) if parts[0] == "expanded" else ()) + tuple(parts[1:])
    return PilotModel(effects)
