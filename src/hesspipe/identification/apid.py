"""APID's optimiser: the bit-climbing genetic algorithm (Davis 1991).

One chromosome holds every identified parameter as a bit field, decoded as
``value = offset + integer / scale`` (the paper: 10-11 bits, scale 100). The
chromosome starts at random. A pass flips every bit once, in a fresh random
order, keeping a flip if it improves (lowers) the fitness and undoing it
otherwise. Passes repeat until the pass budget is spent or a pass brings
no improvement. A seed makes a run repeat exactly; every evaluation is kept
in the history.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Mapping, Sequence

import numpy as np

from ..core.errors import HesspipeError

MAX_BITS = 30


@dataclass(frozen=True)
class Field:
    """One parameter's bit field.

    Attributes
    ----------
    name : str
    bits : int
        1..30.
    scale : float
        Decoded value = offset + integer / scale.
    offset : float
    """

    name: str
    bits: int
    scale: float = 100.0
    offset: float = 0.0

    def __post_init__(self):
        if not (isinstance(self.bits, (int, np.integer)) and 1 <= self.bits <= MAX_BITS):
            raise HesspipeError(f"bit field {self.name!r}: expected 1 to {MAX_BITS} bits, "
                                f"got {self.bits!r}")
        if not (np.isfinite(self.scale) and self.scale > 0 and np.isfinite(self.offset)):
            raise HesspipeError(f"bit field {self.name!r}: expected a positive finite scale and "
                                f"a finite offset, got scale={self.scale!r}, offset={self.offset!r}")

    @property
    def lo(self) -> float:
        """Smallest value the field decodes (integer 0), parameter units."""
        return float(self.offset)

    @property
    def hi(self) -> float:
        """Largest value the field decodes (all bits set), parameter units."""
        return float(self.offset + (2 ** self.bits - 1) / self.scale)

    @property
    def resolution(self) -> float:
        """Step between neighbouring values, parameter units (``1 / scale``)."""
        return 1.0 / float(self.scale)

    def decode(self, integer: int) -> float:
        """Parameter value of the field's integer.

        Parameters
        ----------
        integer : int
            In ``0 .. 2**bits - 1`` (binary, not Gray).

        Returns
        -------
        float
            ``offset + integer / scale``, parameter units.
        """
        return float(self.offset + int(integer) / self.scale)

    def encode(self, value: float) -> int:
        """Nearest representable integer (clipped to the field).

        Parameters
        ----------
        value : float
            Parameter value, its units.
        """
        return int(np.clip(round((value - self.offset) * self.scale), 0, 2 ** self.bits - 1))

    def check_within(self, lo: float, hi: float) -> None:
        """Raise unless every value the field can decode lies in [lo, hi].

        Parameters
        ----------
        lo, hi : float
            The parameter's bounds, its units.
        """
        tol = 1e-9 * max(1.0, abs(lo), abs(hi))
        if self.lo < lo - tol or self.hi > hi + tol:
            raise HesspipeError(
                f"bit field {self.name!r} ({self.bits} bits, scale {self.scale:g}, offset "
                f"{self.offset:g}) spans {self.lo:g}..{self.hi:g}; expected a field within the "
                f"parameter's bounds {lo:g}..{hi:g}")


def gray_to_int(g: int) -> int:
    """Integer whose reflected Gray code is `g`.

    Parameters
    ----------
    g : int
        A reflected Gray code (>= 0).
    """
    n = g
    shift = 1
    while g >> shift:
        n ^= g >> shift
        shift += 1
    return n


def int_to_gray(n: int) -> int:
    """Reflected Gray code of `n`.

    Parameters
    ----------
    n : int
        Non-negative integer.
    """
    return n ^ (n >> 1)


@dataclass(frozen=True)
class Evaluation:
    """One fitness evaluation of the climb.

    Attributes
    ----------
    index : int
        Evaluation number, from 0.
    pass_ : int
        Pass over the chromosome's bits, from 0.
    bit : int
        The flipped bit (-1: the initial chromosome).
    fitness : float
        Fitness of the candidate (the objective's units; lower is better).
    accepted : bool
        Whether the flip was kept.
    """

    index: int
    pass_: int
    bit: int          # flipped bit (-1: the initial chromosome)
    fitness: float
    accepted: bool


@dataclass(frozen=True)
class ClimbResult:
    """Outcome of :func:`bit_climb`.

    Attributes
    ----------
    values : dict
        Best parameter values, name → decoded value.
    fitness : float
        Their fitness.
    evaluations : int
        Objective calls.
    history : tuple of Evaluation
        Every evaluation in order.
    passes : int
        Passes run.
    initial : dict
        The random initial values.
    """

    values: dict
    fitness: float
    evaluations: int
    history: tuple
    passes: int
    initial: dict

    def best_so_far(self) -> np.ndarray:
        """Best fitness after each evaluation (for convergence plots)."""
        return np.minimum.accumulate(np.array([h.fitness for h in self.history]))


def bit_climb(objective: Callable[[dict], float], fields: Sequence[Field], *, passes: int = 10,
              seed: int = 0, initial: Mapping[str, float] | None = None,
              coding: str = "binary") -> ClimbResult:
    """Minimise `objective` over the bit fields by bit climbing.

    Parameters
    ----------
    objective : callable
        ``objective(values: dict) -> float``; lower is better. Must return a
        finite number (callers map failures to a worst value). If it has a
        true ``accepts_threshold`` attribute it is called as
        ``objective(values, threshold=best)`` for trial flips and only needs to
        be exact below the threshold (a flip at or above it is rejected anyway).
    fields : sequence of Field
    passes : int
        Pass budget (paper: 10).
    seed : int
        Seeds the initial chromosome and every pass's bit order.
    initial : mapping, optional
        Start here instead of a random chromosome (encoded to the nearest bits).
    coding : {"binary", "gray"}
        How a field's bits give its integer: plain binary (the paper) or
        reflected Gray code, where neighbouring values differ by one bit (no
        "Hamming cliffs", Davis's representational bias).
    """
    if coding not in ("binary", "gray"):
        raise HesspipeError(f"bit climbing: coding must be 'binary' or 'gray', got {coding!r}")
    to_int = gray_to_int if coding == "gray" else int
    from_int = int_to_gray if coding == "gray" else int
    fields = list(fields)
    if not fields:
        raise HesspipeError("bit climbing: expected at least one parameter to identify")
    names = [f.name for f in fields]
    if len(set(names)) != len(names):
        raise HesspipeError(f"bit climbing: parameter listed twice in {', '.join(names)}")
    if int(passes) < 1:
        raise HesspipeError(f"passes: expected at least 1, got {passes!r}")
    rng = np.random.default_rng(seed)
    if initial is None:
        genes = [int(rng.integers(0, 2 ** f.bits)) for f in fields]
    else:
        genes = [from_int(f.encode(initial[f.name])) if f.name in initial
                 else int(rng.integers(0, 2 ** f.bits)) for f in fields]
    # Global bit index -> (field, bit within field).
    owner = [(i, b) for i, f in enumerate(fields) for b in range(f.bits)]

    def decode(g):
        return {f.name: f.decode(to_int(x)) for f, x in zip(fields, g)}

    history: list[Evaluation] = []

    lazy = getattr(objective, "accepts_threshold", False)

    def evaluate(g, pass_, bit, threshold=None):
        value = float(objective(decode(g), threshold=threshold) if lazy and threshold is not None
                      else objective(decode(g)))
        if not np.isfinite(value):
            raise HesspipeError("bit climbing: the objective returned a non-finite fitness")
        history.append(Evaluation(len(history), pass_, bit, value, False))
        return value

    best = evaluate(genes, 0, -1)
    history[-1] = Evaluation(0, 0, -1, best, True)
    initial_values = decode(genes)
    done = 0
    for p in range(1, int(passes) + 1):
        done = p
        improved = False
        for bit in rng.permutation(len(owner)):
            i, b = owner[bit]
            trial = list(genes)
            trial[i] ^= 1 << b
            value = evaluate(trial, p, int(bit), best)
            if value < best:
                best, genes, improved = value, trial, True
                h = history[-1]
                history[-1] = Evaluation(h.index, h.pass_, h.bit, h.fitness, True)
        if not improved:
            break
    return ClimbResult(decode(genes), best, len(history), tuple(history), done, initial_values)
