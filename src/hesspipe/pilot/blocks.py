"""Linear blocks with exact transport delays, and the pilot-loop layout.

A :class:`Block` is a sum of terms ``gain * num(s)/den(s) * exp(-delay s)``.
It is evaluated exactly on a frequency grid (the delay as ``exp(-j w tau)``,
never a rational approximation) for simulation and crossover metrics; only
the stability test turns delays into Padé approximants, because it needs
the roots of a polynomial.

:class:`Loop` is the block diagram of SPEC.md "Stage three" that every pilot
model fills in::

    e = r - y                         (displayed error)
    delta = NM (visual e - PF delta - vestibular y) + noise n
    y = plant Yc delta + Yd w

Effects (:mod:`hesspipe.pilot.effects`) change a loop by replacing or multiplying
its blocks, so the core never needs to know about them.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field, fields
from typing import Iterable

import numpy as np

from ..core.errors import HesspipeError
from ..core.formats import siso_coefficients


def _poly(coeffs) -> tuple[float, ...]:
    """Coefficients (descending powers of s) as a tuple with leading zeros removed."""
    out = tuple(np.atleast_1d(np.asarray(coeffs, dtype=float)).tolist())
    i = 0
    while i < len(out) - 1 and out[i] == 0.0:
        i += 1
    return out[i:] if out else (0.0,)


def _pmul(a, b) -> np.ndarray:
    return np.convolve(a, b)


def _padd(a, b) -> np.ndarray:
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    if a.size < b.size:
        a, b = b, a
    out = a.copy()
    out[a.size - b.size:] += b
    return out


@dataclass(frozen=True)
class Term:
    """``gain * num(s) / den(s) * exp(-delay s)``; polynomials in descending powers of s.

    The gain is kept apart from the polynomials so that a block whose gains
    change between evaluations (an identification) reuses its cached shape.

    Attributes
    ----------
    num, den : tuple of float
        Polynomials in s, descending powers (``den`` not all zero).
    delay : float
        Transport delay, s (>= 0).
    gain : float
        Multiplier (any sign).
    """

    num: tuple[float, ...]
    den: tuple[float, ...]
    delay: float = 0.0
    gain: float = 1.0


@dataclass(frozen=True)
class Block:
    """A sum of :class:`Term` s: a rational transfer function with delays.

    Build with :func:`tf`, :func:`gain`, :func:`delay`, then ``*`` (series)
    and ``+`` (parallel). ``Block()`` is the zero block.

    Attributes
    ----------
    terms : tuple of Term
        The parallel terms (their responses add).
    """

    terms: tuple[Term, ...] = ()

    @property
    def is_zero(self) -> bool:
        """True if every term has zero gain or a zero numerator (the block passes nothing)."""
        return all(t.gain == 0 or not any(t.num) for t in self.terms)

    def __mul__(self, other: "Block | float") -> "Block":
        if not isinstance(other, Block):
            other = gain(other)
        out = []
        for a in self.terms:
            for b in other.terms:
                # A unit polynomial on either side is the other's: no product computed (a
                # gain times a block, the common case, multiplies nothing).
                num = b.num if a.num == (1.0,) else a.num if b.num == (1.0,) else _poly(_pmul(a.num, b.num))
                den = b.den if a.den == (1.0,) else a.den if b.den == (1.0,) else _poly(_pmul(a.den, b.den))
                out.append(Term(num, den, a.delay + b.delay, a.gain * b.gain))
        return Block(tuple(out))

    __rmul__ = __mul__

    def __add__(self, other: "Block") -> "Block":
        return Block(self.terms + other.terms)

    def response(self, s: np.ndarray, cache: dict | None = None) -> np.ndarray:
        """Complex response at the points `s` (e.g. ``1j * omega``), delays exact.

        `cache` (a dict owned by the caller, tied to this `s`) memoises each
        term's shape (polynomials and delay, without the gain), so blocks
        whose gains alone change between calls cost one multiplication.

        Parameters
        ----------
        s : array of complex
            Laplace variable, 1/s.
        cache : dict, optional
            The caller's shape cache, valid for this `s` only.

        Returns
        -------
        ndarray of complex
            Same shape as `s`; output units per input unit.
        """
        if len(self.terms) == 1:
            t = self.terms[0]
            val = _shape(t, s, cache)
            return val if t.gain == 1.0 else t.gain * val
        total = np.zeros(np.shape(s), dtype=complex)
        for t in self.terms:
            total += t.gain * _shape(t, s, cache)
        return total

    def rational(self, pade_order: int = 8) -> tuple[np.ndarray, np.ndarray]:
        """``(num, den)`` polynomials with each delay replaced by its Padé approximant.

        Terms are put over the product of their denominators without
        cancellation, so every pole of every term stays visible (what a
        stability test wants).

        Parameters
        ----------
        pade_order : int
            Order n of the [n/n] Padé approximant of each delay.
        """
        if not self.terms:
            return np.zeros(1), np.ones(1)
        if len(self.terms) == 1:
            t = self.terms[0]
            num, den = _term_rational(t.num, t.den, t.delay, pade_order)
            return (num if t.gain == 1.0 else t.gain * num), den
        parts = []
        for t in self.terms:
            num, den = _term_rational(t.num, t.den, t.delay, pade_order)
            parts.append((t.gain * num, den))
        num, den = parts[0]
        for n2, d2 in parts[1:]:
            num = _padd(_pmul(num, d2), _pmul(n2, den))
            den = _pmul(den, d2)
        return num, den


@functools.lru_cache(maxsize=1024)
def _term_rational(num, den, tau, order):
    num, den = np.asarray(num), np.asarray(den)
    if tau:
        pn, pd = pade(tau, order)
        num, den = _pmul(num, pn), _pmul(den, pd)
    return num, den


def _shape(t: Term, s, cache) -> np.ndarray:
    key = (t.num, t.den, t.delay)
    val = None if cache is None else cache.get(key)
    if val is None:
        # A unit polynomial is not evaluated: dividing by 1 + 0j, or 1 + 0j by the other,
        # gives the same numbers (and a fit's fresh shapes are mostly a mode over 1).
        if t.den == (1.0,):
            val = np.polyval(t.num, s) if t.num != (1.0,) else np.ones(np.shape(s), dtype=complex)
        else:
            val = (1.0 if t.num == (1.0,) else np.polyval(t.num, s)) / np.polyval(t.den, s)
        if t.delay:
            val = val * np.exp(-s * t.delay)
        if cache is not None:
            cache[key] = val
    return val


def tf(num, den, delay: float = 0.0) -> Block:
    """Block ``num(s)/den(s) * exp(-delay s)`` (coefficients in descending powers of s).

    Parameters
    ----------
    num, den : sequence of float
        Polynomials in s, descending powers.
    delay : float
        Transport delay, s (>= 0).
    """
    den_p = _poly(den)
    if not any(den_p):
        raise HesspipeError("transfer function with a zero denominator")
    return Block((Term(_poly(num), den_p, float(delay)),))


def gain(k: float) -> Block:
    """Constant block.

    Parameters
    ----------
    k : float
        The gain (any sign), output units per input unit.
    """
    return Block((Term((1.0,), (1.0,), 0.0, float(k)),))


def delay(tau: float) -> Block:
    """Pure transport delay ``exp(-tau s)``.

    Parameters
    ----------
    tau : float
        Delay, s (>= 0).
    """
    return Block((Term((1.0,), (1.0,), float(tau)),))


ZERO = Block()
ONE = gain(1.0)


@functools.lru_cache(maxsize=256)
def pade(tau: float, order: int) -> tuple[np.ndarray, np.ndarray]:
    """Diagonal Padé approximant of ``exp(-tau s)`` as ``(num, den)`` polynomials."

    Parameters
    ----------
    tau : float
        Delay, s (0 gives ``(1, 1)``).
    order : int
        n of the [n/n] approximant.
    """
    if tau == 0:
        return np.ones(1), np.ones(1)
    n = int(order)
    # Coefficients of the [n/n] approximant in ascending powers of (tau s).
    c = [math.factorial(2 * n - k) * math.factorial(n)
         / (math.factorial(2 * n) * math.factorial(k) * math.factorial(n - k)) for k in range(n + 1)]
    den = np.array([c[k] * tau ** k for k in range(n + 1)])[::-1]
    num = np.array([c[k] * (-tau) ** k for k in range(n + 1)])[::-1]
    return num, den


def from_tf(sys) -> Block:
    """Block from a SISO python-control TransferFunction (continuous time).

    Parameters
    ----------
    sys : control.TransferFunction
        SISO, continuous.
    """
    num, den = siso_coefficients(sys)
    return tf(num, den)


@dataclass(frozen=True)
class Loop:
    """The pilot-vehicle loop of SPEC.md, block by block.

    Attributes
    ----------
    visual : Block
        Displayed error e → command u_e (central processing: ``Ke exp(-tau0 s)``).
    vestibular : Block
        Plant output y (roll rate) → perceived motion signal u_v, subtracted
        from the command (zero without motion feedback).
    neuromuscular : Block
        ``Y_NM``: command → control delta.
    proprioceptive : Block
        ``Y_PF``: control delta → u_p, subtracted from the command.
    plant : Block
        Factor multiplying the control plant Yc (an aircraft effect).
    noise : Block
        Shapes a unit-variance white sequence into remnant added to delta
        (zero block: no remnant).
    sensation : Block
        The pilot's part of :attr:`vestibular`: cab angular velocity (rad/s) →
        u_v. ``vestibular`` is this times the simulator's motion path
        (default: the paper's platform × washout); :mod:`hesspipe.pilot.motion`
        rebuilds it for a plants file's ``motion_path``.
    """

    visual: Block
    vestibular: Block
    neuromuscular: Block
    proprioceptive: Block
    plant: Block = field(default=ONE)
    noise: Block = field(default=ZERO)
    sensation: Block = field(default=ZERO)

    def replace(self, **changes) -> "Loop":
        """The same loop with some blocks replaced.

        Parameters
        ----------
        **changes : Block
            New blocks by attribute name (``noise=ZERO`` ...).
        """
        unknown = changes.keys() - _LOOP_FIELDS
        if unknown:
            raise TypeError(f"Loop has no block {', '.join(sorted(unknown))}")
        # The frozen instance's fields copied without dataclasses.replace's __init__, which
        # was a tenth of a describing-function fit's model evaluation (two per call).
        new = object.__new__(Loop)
        new.__dict__.update(self.__dict__, **changes)
        return new

    def pilot_open_loop(self, s, yc, cache=None) -> np.ndarray:
        """Open loop broken at the displayed error, ``L = Y_pilot Yc``, at `s`.

        ``L = NM visual Yc' / (1 + NM PF + NM vestibular Yc')`` with
        ``Yc' = Yc plant`` (the inner loops closed, see :meth:`return_difference`).

        Parameters
        ----------
        s : array of complex
            Laplace variable, 1/s (``1j * omega`` with omega in rad/s).
        yc : array of complex
            The control plant's response at `s` (without :attr:`plant`),
            output units per control unit.
        cache : dict, optional
            Shape cache tied to `s` (see :meth:`Block.response`).

        Returns
        -------
        ndarray of complex
            L at `s`, dimensionless; the loop is negative feedback (``1 + L``).
        """
        nm = self.neuromuscular.response(s, cache)
        v = self.visual.response(s, cache)
        ycp = yc * self.plant.response(s, cache)
        return nm * v * ycp / self._return_difference(s, ycp, cache, nm, visual=False)

    def return_difference(self, s, yc, cache=None, *, visual: bool = True) -> np.ndarray:
        """The loop's denominator ``1 + NM PF + NM (visual + vestibular) Yc plant`` at `s`.

        The one frequency-response form of the closed loop's denominator: the
        control is ``delta = (NM visual R - NM (visual + vestibular) Yd W + N n) / D``.
        :meth:`characteristic` is its numerator polynomial and
        :meth:`return_difference_products` its products (for cached evaluation).

        Parameters
        ----------
        s : array of complex
            Laplace variable, 1/s (``1j * omega`` with omega in rad/s).
        yc : array of complex or None
            The control plant's response at `s` (without :attr:`plant`),
            output units per control unit. None: the loop opened at the plant,
            the pilot's own ``1 + NM PF`` (``NM / (1 + NM PF)`` is the pilot's
            command-to-control response).
        cache : dict, optional
            Shape cache tied to `s` (see :meth:`Block.response`).
        visual : bool
            False: leave the visual path out, ``1 + NM PF + NM vestibular Yc plant``
            (the denominator of :meth:`pilot_open_loop`, the loop broken at the
            displayed error).

        Returns
        -------
        ndarray of complex
            D at `s`, dimensionless; its zeros are the closed loop's modes.
        """
        nm = self.neuromuscular.response(s, cache)
        if yc is None:
            return 1.0 + nm * self.proprioceptive.response(s, cache)
        ycp = yc * self.plant.response(s, cache)
        return self._return_difference(s, ycp, cache, nm, visual)

    def _return_difference(self, s, ycp, cache, nm, visual: bool) -> np.ndarray:
        pf = self.proprioceptive.response(s, cache)
        m = self.vestibular.response(s, cache)
        if visual:
            m = self.visual.response(s, cache) + m
        return 1.0 + nm * pf + nm * m * ycp

    def return_difference_products(self, yc: "Block") -> list[tuple["Block", ...]]:
        """The products that :meth:`return_difference` sums to 1, as blocks.

        ``NM visual Yc'``, ``NM vestibular Yc'`` (left out when the vestibular
        block is zero) and ``NM PF`` (left out when PF is zero), in that order;
        :class:`hesspipe.pilot.simulation.Simulator` evaluates them with shapes
        cached across gain changes.

        Parameters
        ----------
        yc : Block
            The control plant including :attr:`plant` (``Yc' = Yc plant``).

        Returns
        -------
        list of tuple of Block
            Each tuple's blocks multiply; the denominator is ``1 + sum``.
        """
        nm, pf = self.neuromuscular, self.proprioceptive
        paths = [self.visual] if self.vestibular.is_zero else [self.visual, self.vestibular]
        return [(nm, p, yc) for p in paths] + ([] if pf.is_zero else [(nm, pf)])

    def characteristic(self, yc: Block, pade_order: int = 8) -> np.ndarray:
        """Characteristic polynomial of the closed loop (delays as Padé approximants).

        With NM = a/b, PF = c/d, visual + vestibular = p/q and Yc plant = g/h,
        the loop's modes are the roots of ``b d q h + a c q h + a p d g``
        (the numerator of ``1 + NM PF + NM (visual + vestibular) Yc``).

        Parameters
        ----------
        yc : Block
            The control plant Yc (without :attr:`plant`, which is applied here).
        pade_order : int
            Order of the Padé approximants of the delays.

        Returns
        -------
        ndarray
            Polynomial coefficients, descending powers of s; all roots in the left
            half plane for a stable loop.
        """
        yc = yc if self.plant.terms == ONE.terms else yc * self.plant
        path = self.visual if self.vestibular.is_zero else self.visual + self.vestibular
        blocks = (self.neuromuscular, self.proprioceptive, yc)
        if all(len(b.terms) == 1 for b in blocks) and path.terms:
            # Polynomials are linear in the blocks' gains: cache the shapes,
            # combine with the gains (an identification changes gains only).
            nm, pf, g = (b.terms[0] for b in blocks)
            s0, s1, s2 = _char_shapes(_key(nm), _key(pf), tuple(_key(t) for t in path.terms),
                                      _key(g), pade_order)
            out = s0 + (nm.gain * pf.gain) * s1
            for t, shape in zip(path.terms, s2):
                out = out + (nm.gain * t.gain * g.gain) * shape
            return out
        a, b = self.neuromuscular.rational(pade_order)
        c, d = self.proprioceptive.rational(pade_order)
        p, q = path.rational(pade_order)
        g, h = yc.rational(pade_order)
        qh = _pmul(q, h)
        return _padd(_padd(_pmul(_pmul(b, d), qh), _pmul(_pmul(a, c), qh)),
                     _pmul(_pmul(a, p), _pmul(d, g)))


_LOOP_FIELDS = frozenset(f.name for f in fields(Loop))


def _key(t: Term):
    return (t.num, t.den, t.delay)


@functools.lru_cache(maxsize=512)
def _char_shapes(nm, pf, path, yc, order):
    """Gain-free parts of ``b d q h + a c q h + a p d g`` (see Loop.characteristic).

    Returns ``(S0, S1, [S2_i])`` padded to one length, so that the
    characteristic polynomial is ``S0 + g_nm g_pf S1 + sum_i g_nm g_i g_yc S2_i``.
    """
    a, b = _term_rational(*nm, order)
    c, d = _term_rational(*pf, order)
    g, h = _term_rational(*yc, order)
    rats = [_term_rational(*t, order) for t in path]
    q = np.ones(1)
    for _, qi in rats:
        q = _pmul(q, qi)
    ps = []
    for i, (pi, _) in enumerate(rats):
        other = np.ones(1)
        for j, (_, qj) in enumerate(rats):
            if j != i:
                other = _pmul(other, qj)
        ps.append(_pmul(pi, other))
    qh = _pmul(q, h)
    parts = [_pmul(_pmul(b, d), qh), _pmul(_pmul(a, c), qh)] + [_pmul(_pmul(a, p), _pmul(d, g)) for p in ps]
    n = max(len(x) for x in parts)
    parts = [np.concatenate([np.zeros(n - len(x)), x]) for x in parts]
    for x in parts:
        x.flags.writeable = False
    return parts[0], parts[1], tuple(parts[2:])


def max_real_root(poly: np.ndarray) -> float:
    """Largest real part of the roots of `poly` (-inf for a constant, +inf if invalid).

    Parameters
    ----------
    poly : array
        Coefficients, descending powers of s (leading zeros allowed).

    Returns
    -------
    float
        Growth rate of the fastest-growing mode, 1/s (> 0: unstable).
    """
    poly = np.asarray(poly, dtype=float)
    nz = np.flatnonzero(poly)
    if nz.size == 0 or not np.isfinite(poly).all():
        return float("inf")
    poly = poly[nz[0]:]
    n = poly.size - 1
    if n < 1:
        return float("-inf")
    # Eigenvalues of the companion matrix (what numpy.roots does, minus its checks).
    comp = np.zeros((n, n))
    comp[0, :] = -poly[1:] / poly[0]
    comp[np.arange(1, n), np.arange(n - 1)] = 1.0
    return float(np.linalg.eigvals(comp).real.max())


def stable_poly(poly: np.ndarray, margin: float = 0.0) -> bool:
    """True if every root of `poly` has real part < -margin.

    Parameters
    ----------
    poly : array
        Coefficients, descending powers of s.
    margin : float
        Required decay rate, 1/s (0: plain stability).
    """
    return max_real_root(poly) < -margin


def pade_order_for(total_delay: float) -> int:
    """Padé order accurate well past the neuromuscular band for this delay.

    The [n/n] approximant's phase is good to ``w tau`` of about ``n``; loops
    cross over below about 20 rad/s and roll off past the neuromuscular
    mode, so ``w tau < 30 tau`` must be covered.

    Parameters
    ----------
    total_delay : float
        The loop's largest delay, s.

    Returns
    -------
    int
        Between 4 and 16.
    """
    return int(min(16, max(4, math.ceil(30.0 * total_delay) + 2)))


def max_delay(blocks: Iterable[Block]) -> float:
    """Largest transport delay of the blocks' terms, s (0 if there is none).

    Parameters
    ----------
    blocks : iterable of Block
    """
    return max((t.delay for b in blocks for t in b.terms), default=0.0)
