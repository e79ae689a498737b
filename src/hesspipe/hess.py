"""The Hess structural pilot model, original and expanded, closed around the plants.

Original model (SPEC.md "Stage three", series form)::

    u_e   = Ke exp(-tau0 s) e                         visual / central processing
    delta = Y_NM (u_e - u_p - u_v)                    u_v = 0 without motion feedback
    Y_NM  = wn^2 / (s^2 + 2 zn wn s + wn^2)
    u_p   = Y_PF delta,  Y_PF = [K1 s / (s + 1/T1)] [K2 / (s + 1/T2)^(k-1)]

with the plants ``y = Yc delta + Yd w`` and ``e = r - y`` (r = 0: null the roll
rate). The expanded model adds the effect ``motion_feedback``
(:mod:`hesspipe.effects`): ``u_v = Km Y_SCC Y_MP Y_WO y``. Other effects
augment the loop the same way.

Simulation is done in the frequency domain on a zero-padded FFT grid: every
block, the delays included, is evaluated exactly at ``s = j w``; the input
samples are taken as band-limited (no hold). Padding the record to several
times its length makes the circular convolution a linear one, so the result
is the zero-initial-state response. Stability is decided separately from
the roots of the closed loop's characteristic polynomial (delays as Padé
approximants of an order chosen for the delay), because an FFT simulation of
an unstable loop returns finite nonsense.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass, replace
from typing import Mapping

import math

import numpy as np
import scipy.fft as sfft

from .blocks import (Block, Loop, ONE, Term, from_tf, max_delay, max_real_root, pade_order_for,
                     stable_poly)
from .effects import EFFECTS, get_effect
from .errors import HesspipeError
from .motion import motion_block, with_motion_path

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

UNSTABLE_FITNESS = 1.0e12
"""Least fitness given to a parameter set whose closed loop is unstable: finite (optimisers
and JSON cope) and worse than any stable fit (those are capped at a tenth of it).
Identification grades it, ``UNSTABLE_FITNESS * (1 + min(growth rate, 1000))``, so that
an optimiser standing on the unstable side still sees the way back."""


def table1(k: int = 1) -> dict[str, float]:
    """Table 1 defaults of the paper for a rate-like (k=1) or acceleration-like (k=2) plant.

    Includes Km = 0.1 of the motion path.
    """
    if k not in (1, 2):
        raise HesspipeError(f"k: expected 1 (plant ~ K/s) or 2 (plant ~ K/s^2), got {k!r}")
    out = {name: spec[0] for name, spec in _CORE.items()}
    out["k"] = float(k)
    out["Km"] = EFFECTS["motion_feedback"].parameters["Km"][0]
    return out


@dataclass(frozen=True)
class PilotModel:
    """A Hess structural model plus zero or more effects.

    Parameters
    ----------
    effects : tuple of str
        Effect ids of :data:`hesspipe.effects.EFFECTS`, applied in order.
    """

    effects: tuple[str, ...] = ()

    def __post_init__(self):
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
        """
        out = {n: v for n, v in table1(k).items() if n in PARAMETERS}
        for e in self.effects:
            out.update({n: spec[0] for n, spec in EFFECTS[e].parameters.items()})
        return _scaled(out, gain, lambda v, g: v * g)

    def bounds(self, gain: float = 1.0) -> dict[str, tuple[float, float]]:
        """Search box of every parameter, name → (lo, hi); :data:`LOOP_GAINS` times `gain`."""
        out = {n: (spec[1], spec[2]) for n, spec in _CORE.items()}
        for e in self.effects:
            out.update({n: (spec[1], spec[2]) for n, spec in EFFECTS[e].parameters.items()})
        return _scaled(out, gain, lambda b, g: (b[0] * g, b[1] * g))

    def fields(self, gain: float = 1.0) -> dict[str, tuple[int, float, float]]:
        """Default APID bit field of every parameter, name → (bits, scale, offset).

        The fields of :data:`LOOP_GAINS` span their box times `gain` (scale / gain,
        offset x gain), with the same number of bits.
        """
        out = {n: (spec[3], spec[4], spec[5]) for n, spec in _CORE.items()}
        for e in self.effects:
            out.update(EFFECTS[e].fields)
        return _scaled(out, gain, lambda f, g: (f[0], f[1] / g, f[2] * g))

    def units(self) -> dict[str, str]:
        out = {n: spec[6] for n, spec in _CORE.items()}
        for e in self.effects:
            out.update(EFFECTS[e].units)
        return out

    def with_effect(self, effect_id: str) -> "PilotModel":
        """This model with `effect_id` appended."""
        return PilotModel(self.effects + (effect_id,))

    def complete(self, params: Mapping[str, float] | None = None, k: int | None = None, *,
                 strict: bool = False, gain: float = 1.0) -> dict[str, float]:
        """All parameters: `params` over the defaults.

        `k` (if given, else ``params["k"]``, else 1) picks the Table 1 column;
        `gain` scales the default :data:`LOOP_GAINS` (see :meth:`defaults`).
        Names no model knows are an error; parameters of effects this model
        does not have (Km of :func:`table1` for the original model) are
        dropped, or are an error if `strict`.
        """
        params = dict(params or {})
        names = self.parameter_names()
        known = set(PARAMETERS).union(*(e.parameters for e in EFFECTS.values()))
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

    def loop(self, params: Mapping[str, float]) -> Loop:
        """The loop's blocks for complete parameters (see :meth:`complete`)."""
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


@functools.lru_cache(maxsize=4)
def reference_crossover(k: int = 1) -> float:
    """Crossover (rad/s) of Table 1's original model around ``Yc = 1/s^k``.

    2.886 rad/s for k = 1, the value Table 1 is calibrated for (SPEC.md).
    """
    import control as ct

    from .crossover import crossover

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


def core_loop(p: Mapping[str, float]) -> Loop:
    """Blocks of the original Hess structural model for parameters `p`."""
    wn, zn = float(p["wn"]), float(p["zn"])
    w2 = wn * wn
    nm = Block((Term((1.0,), (1.0, 2.0 * zn * wn, w2), 0.0, w2),))
    a1 = float(p["1/T1"])
    # With 1/T1 = 0 the lead K1 s/(s + 0) is the constant K1; writing it as
    # such keeps a cancelled pole at s = 0 out of the stability test.
    num, den = ((1.0, 0.0), (1.0, a1)) if a1 != 0 else ((1.0,), (1.0,))
    if int(p["k"]) == 2:
        den = tuple(np.convolve(den, (1.0, float(p["1/T2"]))).tolist())
    pf = Block((Term(num, den, 0.0, float(p["K1"]) * float(p["K2"])),))
    visual = Block((Term((1.0,), (1.0,), float(p["tau0"]), float(p["Ke"])),))
    return Loop(visual=visual, vestibular=Block(), neuromuscular=nm, proprioceptive=pf)


def model_from_name(name: str | PilotModel) -> PilotModel:
    """"original", "expanded", or "+"-joined effect ids ("expanded+remnant").

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


@dataclass(frozen=True)
class Simulation:
    """Closed-loop time histories at the input's sample times.

    Attributes
    ----------
    time : ndarray
        s, from 0.
    control : ndarray
        Pilot control delta (input of Yc).
    output : ndarray
        Controlled output y (roll rate, rad/s).
    error : ndarray
        Displayed error e = r - y.
    stable : bool
        False if the closed loop is unstable; the arrays are then NaN.
    """

    time: np.ndarray
    control: np.ndarray
    output: np.ndarray
    error: np.ndarray
    stable: bool = True


def plant_pad_factor(plants, duration_s: float, *, decays: float = 5.0, cap: int = 16) -> int:
    """FFT padding (multiples of the record) that lets the slowest loop dynamics decay.

    The slowest pole or zero of Yc and Yd (zeros too: a high-gain loop puts a
    closed-loop mode next to a slow zero) or the pilot's proprioceptive washout
    (1/T1 = 0.01 rad/s in Table 1) sets the longest tail; the grid is made long
    enough for `decays` of its time constants, at least 4 and at most `cap`
    records. Identification uses it: an evaluation on a grid whose tail wraps
    onto the record mis-states the lowest PSD bins and biases the gains.
    """
    rates = []
    for sys in (plants.control_to_output, plants.disturbance_to_output):
        for poly in (np.squeeze(sys.num[0][0]), np.squeeze(sys.den[0][0])):
            poly = np.trim_zeros(np.atleast_1d(poly).astype(float), "f")
            if poly.size > 1:
                roots = np.abs(np.roots(poly))
                rates += [r for r in roots if r > 1e-9]
    # The pilot's own slowest dynamics (Table 1's proprioceptive washout 1/T1) too.
    rates.append(table1(1)["1/T1"])
    tail = decays / min(rates)
    return int(min(cap, max(4, np.ceil(1 + tail / duration_s))))


class Simulator:
    """Closed-loop simulation prepared for one record: call it with many loops.

    Everything that does not depend on the pilot (frequency grid, plant
    responses, input spectra, remnant noise) is computed once, and block
    shapes are cached, so one call costs a few vector operations and an
    inverse FFT.

    Parameters
    ----------
    plants : hesspipe.formats.Plants
        Yc (control → output) and Yd (disturbance → output).
    disturbance : array
        w at the sample times.
    dt : float
        Sample interval, s.
    reference : array, optional
        r (default 0).
    noise_seed : int
        Seed of the unit-variance white sequence that remnant shapes.
    pad_factor : int, optional
        The record is zero-padded to this many times its length; the
        response beyond it wraps around onto the record's start. Default:
        :func:`plant_pad_factor` — at least 4, more when the plants hold
        modes or zeros slow enough that a closed loop tail would outlast
        the padding (a pilot's high gain pulls a closed-loop mode onto a
        slow plant zero).
    """

    def __init__(self, plants, disturbance, dt: float, *, reference=None, noise_seed: int = 0,
                 pad_factor: int | None = None):
        w = np.asarray(disturbance, dtype=float)
        if w.ndim != 1 or w.size < 2:
            raise HesspipeError("disturbance: expected a 1-D signal of at least 2 samples")
        if not (dt > 0 and np.isfinite(dt)):
            raise HesspipeError(f"dt: expected a positive sample interval, got {dt!r}")
        self.n = w.size
        self.dt = float(dt)
        if pad_factor is None:
            pad_factor = plant_pad_factor(plants, self.n * self.dt)
        self.nfft = sfft.next_fast_len(max(int(pad_factor), 2) * self.n, real=True)
        omega = 2.0 * np.pi * np.fft.rfftfreq(self.nfft, self.dt)
        # The DC point is evaluated just above zero so that integrating plants
        # (1/s) give their finite closed-loop limit instead of inf/inf.
        omega[0] = omega[1] * 1e-6
        self.s = 1j * omega
        self._cache: dict = {}
        self._seen: set = set()
        self.yc_block = from_tf(plants.control_to_output)
        self.yd_block = from_tf(plants.disturbance_to_output)
        yd_den = np.asarray(self.yd_block.terms[0].den)
        if not stable_poly(yd_den, margin=-1e-12):
            raise HesspipeError("plants: disturbance_to_output has unstable poles "
                                f"{np.round(np.roots(yd_den), 4).tolist()}; expected a stable Yd")
        self.yc = self.yc_block.response(self.s)
        self.ydw = self.yd_block.response(self.s) * sfft.rfft(w, self.nfft)
        r = None if reference is None else np.asarray(reference, dtype=float)
        if r is not None and r.shape != w.shape:
            raise HesspipeError("reference: expected the same length as the disturbance")
        self.r = r if r is not None and np.any(r) else None
        self.rf = None if self.r is None else sfft.rfft(self.r, self.nfft)
        self.noise_seed = int(noise_seed)
        self._noise = None
        self.cab = motion_block(plants)   # None: the paper's platform x washout

    def prepare(self, loop: Loop) -> Loop:
        """`loop` with its vestibular feedback through the plants' ``motion_path``."""
        return with_motion_path(loop, self.cab)

    def _trim_cache(self):
        if len(self._cache) > 96:  # each entry is one complex spectrum (~100 kB)
            self._cache.clear()
        if len(self._seen) > 4096:
            self._seen.clear()

    @property
    def noise(self) -> np.ndarray:
        """Spectrum of the seeded unit-variance white sequence used by remnant."""
        if self._noise is None:
            white = np.random.default_rng(self.noise_seed).standard_normal(self.n)
            self._noise = sfft.rfft(white, self.nfft)
        return self._noise

    def growth_rate(self, loop: Loop) -> float:
        """Largest real part (1/s) of the closed loop's modes; < 0 means stable.

        The remnant shaping filter's poles count too (it feeds the loop).
        """
        loop = self.prepare(loop)
        order = pade_order_for(max_delay((loop.visual, loop.vestibular, loop.neuromuscular,
                                          loop.proprioceptive, loop.plant)))
        rate = max_real_root(loop.characteristic(self.yc_block, order))
        for t in loop.noise.terms:
            if t.gain != 0:
                rate = max(rate, max_real_root(t.den))
        return rate

    def stable(self, loop: Loop) -> bool:
        """True if the closed loop is asymptotically stable."""
        return self.growth_rate(loop) < 0.0

    def spectra(self, loop: Loop, output: bool = True) -> tuple[np.ndarray, np.ndarray | None]:
        """FFT-grid spectra (control, output) of the closed loop; no stability check.

        ``delta = (NM vis R - NM (vis + ves) Yd W + N n) / (1 + NM PF + NM (vis + ves) Yc')``
        """
        self._trim_cache()
        loop = self.prepare(loop)
        yc = self.yc_block if loop.plant.terms == ONE.terms else self.yc_block * loop.plant
        nm, pf, vis, ves = loop.neuromuscular, loop.proprioceptive, loop.visual, loop.vestibular
        paths = [vis] if ves.is_zero else [vis, ves]
        local: dict = {}
        den = self._sum([(nm, p, yc) for p in paths] + ([] if pf.is_zero else [(nm, pf)]), local)
        den += 1.0
        num = self._sum([(nm, p, "ydw") for p in paths], local)
        np.negative(num, out=num)
        if self.rf is not None:
            num += self._sum([(nm, vis, "rf")], local)
        if not loop.noise.is_zero:
            num += self._sum([(loop.noise, "noise")], local)
        num /= den
        if not output:
            return num, None
        return num, yc.response(self.s, self._cache) * num + self._fixed("ydw")

    def _fixed(self, name: str) -> np.ndarray:
        return {"ydw": self.ydw, "rf": self.rf}.get(name) if name != "noise" else self.noise

    def _sum(self, products, local: dict) -> np.ndarray:
        """Sum of products of blocks / fixed spectra, with each product's shape cached.

        Gains are scalars outside the cached shapes, so when only gains change
        (Ke, K1, K2, Km ...) a product costs one scalar multiplication.
        """
        total = None
        for factors in products:
            blocks = [f for f in factors if not isinstance(f, str)]
            if all(len(b.terms) == 1 for b in blocks):
                gain = 1.0
                for b in blocks:
                    gain *= b.terms[0].gain
                key = ("prod",) + tuple(f if isinstance(f, str) else
                                        (f.terms[0].num, f.terms[0].den, f.terms[0].delay)
                                        for f in factors)
                shape = self._cache.get(key)
                if shape is None:
                    # Cache a shape only once it is asked for twice: shapes that
                    # change at every call (a fit of time constants) would just
                    # churn the cache.
                    keep = key in self._seen
                    self._seen.add(key)
                    cache = self._cache if keep else local  # local: this call only
                    shape = None
                    for f in factors:
                        part = (self._fixed(f) if isinstance(f, str) else
                                Block((replace(f.terms[0], gain=1.0),)).response(self.s, cache))
                        shape = part if shape is None else shape * part
                    if keep:
                        self._cache[key] = shape
                term = gain * shape
            else:
                term = np.ones(self.s.shape, dtype=complex)
                for f in factors:
                    term = term * (self._fixed(f) if isinstance(f, str) else f.response(self.s, self._cache))
            if total is None:
                total = term
            else:
                total += term
        return total

    def control(self, loop: Loop) -> np.ndarray | None:
        """Simulated control delta, or None if the loop is unstable."""
        if not self.stable(loop):
            return None
        control, _ = self.spectra(loop, output=False)
        return sfft.irfft(control, self.nfft)[: self.n]

    def run(self, loop: Loop) -> Simulation:
        t = self.dt * np.arange(self.n)
        if not self.stable(loop):
            nan = np.full(self.n, np.nan)
            return Simulation(t, nan, nan.copy(), nan.copy(), stable=False)
        cf, yf = self.spectra(loop)
        delta = sfft.irfft(cf, self.nfft)[: self.n]
        y = sfft.irfft(yf, self.nfft)[: self.n]
        r = self.r if self.r is not None else np.zeros(self.n)
        return Simulation(t, delta, y, r - y, stable=True)


def simulate(model, params: Mapping[str, float] | None, plants, disturbance, dt: float, *,
             reference=None, seed: int | None = None, k: int | None = None) -> Simulation:
    """Simulate the closed loop of `model` with `params` around `plants`.

    Parameters
    ----------
    model : PilotModel or str
        "original", "expanded", ... (see :func:`model_from_name`).
    params : mapping
        Parameter values; missing ones take the model's defaults (Table 1).
    plants : hesspipe.formats.Plants
    disturbance : array
        Disturbance w (input of Yd) sampled at `dt`, from t = 0.
    dt : float
        Sample interval, s.
    reference : array, optional
        Reference r (default 0).
    seed : int, optional
        Seed of the remnant noise (default 0); ignored without remnant.

    Returns
    -------
    Simulation
        ``stable=False`` (NaN arrays) for an unstable loop; never raises for it.
    """
    model = model_from_name(model)
    p = model.complete(params, k)
    loop = model.loop(p)
    sim = Simulator(plants, disturbance, dt, reference=reference,
                    noise_seed=0 if seed is None else int(seed))
    pad = causal_pad_factor(sim, loop)
    if pad > sim.nfft / sim.n:
        sim = Simulator(plants, disturbance, dt, reference=reference,
                        noise_seed=0 if seed is None else int(seed), pad_factor=pad)
    return sim.run(loop)


def causal_pad_factor(sim: Simulator, loop, *, decays: float = 7.0, max_samples: int = 1 << 21) -> int:
    """Zero-padding factor that makes one FFT simulation of `loop` causal to ``e^-decays``.

    The FFT grid wraps the response around after ``nfft`` samples. A closed loop
    whose slowest mode outlasts that — a pilot's gain pulls a closed-loop mode
    next to a slow plant zero, with a time constant of many records — would
    fold its tail back onto the record's start. A single simulation, synthetic
    data above all, must be the causal response a time-domain simulator gives,
    so it pads until that mode has decayed `decays` times (at most
    `max_samples`). Unstable loops keep the simulator's padding.
    """
    rate = sim.growth_rate(loop)
    if not rate < 0.0:
        return 4
    samples = sim.n + decays / (-rate * sim.dt)
    return int(max(4, math.ceil(min(samples, max_samples) / sim.n)))


def synthetic_run(model, params: Mapping[str, float] | None, plants, disturbance, dt: float, *,
                  seed: int = 0, run_id: str = "synthetic", reference=None, k: int | None = None):
    """A :class:`hesspipe.formats.Run` generated by `model`, labelled synthetic.

    Raises
    ------
    HesspipeError
        If the closed loop is unstable (there is nothing to record).
    """
    from .formats import Run

    model = model_from_name(model)
    p = model.complete(params, k)
    sim = simulate(model, p, plants, disturbance, dt, reference=reference, seed=seed)
    if not sim.stable:
        raise HesspipeError(f"synthetic run {run_id}: the closed loop of model {model.name} is "
                            "unstable with these parameters")
    text = ", ".join(f"{n}={p[n]:g}" for n in model.parameter_names())
    comments = ("synthetic data: generated by the hesspipe pilot model, not measured",
                f"model: {model.name}", f"parameters: {text}", f"seed: {seed}")
    ref = np.zeros(len(sim.time)) if reference is None else np.asarray(reference, dtype=float)
    return Run(time=sim.time, disturbance=np.asarray(disturbance, dtype=float), output=sim.output,
               control=sim.control, reference=ref, id=run_id, synthetic=True, comments=comments)
