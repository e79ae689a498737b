"""Small linear-systems toolkit of the independent generator.

Written for :mod:`hesspipe.humanlike` alone so the generator shares no code
with the identification it is meant to test: transfer functions as
coefficient lists (descending powers of s), their frequency responses, a
controllable-canonical state-space realisation and the exact zero-order-hold
discretisation used by the fine-step simulator.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg
import scipy.signal

from ..core.errors import HesspipeError


def tf(num, den, what: str = "transfer function") -> tuple[np.ndarray, np.ndarray]:
    """Return ``(num, den)`` as float arrays with leading zeros stripped.

    Parameters
    ----------
    num, den : sequence of float
        Descending powers of s.
    what : str
        What the messages call it.

    Raises
    ------
    HesspipeError
        If a list is empty or non-finite, the denominator is zero, or the
        transfer function is improper (numerator degree above denominator's).
    """
    try:
        n = np.atleast_1d(np.asarray(num, dtype=float))
        d = np.atleast_1d(np.asarray(den, dtype=float))
    except (TypeError, ValueError):
        raise HesspipeError(f"{what}: expected lists of numbers for 'num' and 'den'") from None
    if n.ndim != 1 or d.ndim != 1 or not n.size or not d.size \
            or not (np.all(np.isfinite(n)) and np.all(np.isfinite(d))):
        raise HesspipeError(f"{what}: expected non-empty lists of finite numbers for 'num' and 'den'")
    n = np.trim_zeros(n, "f")
    d = np.trim_zeros(d, "f")
    if not d.size:
        raise HesspipeError(f"{what}: 'den' is all zeros")
    if not n.size:
        n = np.zeros(1)
    if n.size > d.size:
        raise HesspipeError(f"{what}: improper (numerator degree {n.size - 1} > denominator "
                            f"degree {d.size - 1}); expected a proper transfer function")
    return n, d


def freqresp(num, den, w) -> np.ndarray:
    """Frequency response ``num(jw)/den(jw)`` (complex) at `w` (rad/s).

    Parameters
    ----------
    num, den : array
        Descending powers of s.
    w : array
        Angular frequencies, rad/s.
    """
    s = 1j * np.asarray(w, dtype=float)
    return np.polyval(num, s) / np.polyval(den, s)


def series(*tfs) -> tuple[np.ndarray, np.ndarray]:
    """Product of transfer functions given as ``(num, den)`` pairs.

    Parameters
    ----------
    *tfs : (num, den)
        Transfer functions, descending powers of s.
    """
    num, den = np.ones(1), np.ones(1)
    for n, d in tfs:
        num, den = polymul(num, n), polymul(den, d)
    return num, den


def polymul(a, b) -> np.ndarray:
    """``numpy.polymul`` of coefficient arrays, the same values at a twentieth of the cost
    (numpy builds two ``poly1d`` objects per call; a precision pilot's draw makes ~900,000
    calls).

    Parameters
    ----------
    a, b : array
        Polynomials, descending powers of s (leading zeros dropped, as numpy does).
    """
    return np.convolve(_lead(a), _lead(b))


def _lead(a) -> np.ndarray:
    a = np.atleast_1d(np.asarray(a))
    if a.size and a[0] != 0:   # the common case
        return a
    nz = np.flatnonzero(a)
    return a[nz[0]:] if nz.size else np.zeros(1, dtype=a.dtype)


@dataclass(frozen=True)
class StateSpace:
    """Continuous state space ``x' = A x + B u``, ``y = C x + D u`` (single output).

    ``B`` is (n, m) for m inputs, ``C`` is (n,), ``D`` is (m,).

    Attributes
    ----------
    A : ndarray
        (n, n), 1/s.
    B : ndarray
        (n, m).
    C : ndarray
        (n,).
    D : ndarray
        (m,), feedthrough.
    """

    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    D: np.ndarray

    @property
    def order(self) -> int:
        """Number of states n."""
        return self.A.shape[0]

    def freqresp(self, w, inp: int = 0) -> np.ndarray:
        """Frequency response from input `inp` to the output at `w` (rad/s).

        Parameters
        ----------
        w : array
            Angular frequencies, rad/s.
        inp : int
            Input index.
        """
        w = np.atleast_1d(np.asarray(w, dtype=float))
        n = self.order
        if not n:
            return np.full(w.shape, self.D[inp], dtype=complex)
        # One stacked solve for all frequencies: the pilots' draws evaluate the plant ~10^3
        # times with a few points each, and a solve per frequency took 60 % of a precision
        # pilot's draw with motion (the same LAPACK solve per matrix: equal to the bit).
        m = 1j * w.reshape(-1, 1, 1) * np.eye(n) - self.A
        x = np.linalg.solve(m, np.broadcast_to(self.B[:, inp], (w.size, n))[..., None])[..., 0]
        return (x @ self.C).reshape(w.shape) + self.D[inp]


def ss_from_tf(num, den) -> StateSpace:
    """Controllable-canonical realisation of a proper SISO transfer function.

    Parameters
    ----------
    num, den : sequence of float
        Descending powers of s (proper).
    """
    num, den = tf(num, den)
    a0 = den[0]
    den = den / a0
    num = np.concatenate([np.zeros(den.size - num.size), num / a0])
    n = den.size - 1
    d = num[0]
    # Strictly proper remainder: num - d*den, coefficients of s^(n-1) .. s^0.
    rem = (num - d * den)[1:]
    A = np.zeros((n, n))
    if n:
        A[0, :] = -den[1:]
        A[1:, :-1] = np.eye(n - 1)
    B = np.zeros((n, 1))
    if n:
        B[0, 0] = 1.0
    return StateSpace(A, B, rem.copy(), np.array([d]))


def stack_inputs(*systems: StateSpace) -> StateSpace:
    """Sum of SISO systems, each driven by its own input (block-diagonal).

    The result has one input per system and one output: the sum of theirs.

    Parameters
    ----------
    *systems : StateSpace
        Single-input systems.
    """
    n = sum(s.order for s in systems)
    A = np.zeros((n, n))
    B = np.zeros((n, len(systems)))
    C = np.zeros(n)
    D = np.zeros(len(systems))
    i = 0
    for j, s in enumerate(systems):
        k = s.order
        A[i:i + k, i:i + k] = s.A
        B[i:i + k, j] = s.B[:, 0]
        C[i:i + k] = s.C
        D[j] = s.D[0]
        i += k
    return StateSpace(A, B, C, D)


@dataclass(frozen=True)
class Discrete:
    """Exact zero-order-hold discretisation of a :class:`StateSpace` at step `h` (s).

    Attributes
    ----------
    Ad, Bd : ndarray
        Discrete state and input matrices for one step.
    C, D : ndarray
        Output and feedthrough (as the continuous system's).
    """

    Ad: np.ndarray
    Bd: np.ndarray
    C: np.ndarray
    D: np.ndarray


def zoh(sys: StateSpace, h: float) -> Discrete:
    """Discretise `sys` with a zero-order hold on its inputs (exact for piecewise-constant u).

    Uses the matrix exponential of the augmented matrix ``[[A, B], [0, 0]] h``.

    Parameters
    ----------
    sys : StateSpace
    h : float
        Step, s.
    """
    n, m = sys.B.shape
    M = np.zeros((n + m, n + m))
    M[:n, :n] = sys.A
    M[:n, n:] = sys.B
    E = scipy.linalg.expm(M * h)
    return Discrete(E[:n, :n], E[:n, n:], sys.C.copy(), sys.D.copy())


def discretise(sys: StateSpace, h: float) -> Discrete:
    """ZOH for strictly proper blocks, bilinear (Tustin) for blocks with feedthrough.

    A held input seen by a block with feedthrough (a near-differentiator such as
    the motion path s/(0.01 s + 1)) mixes the current input with a state that
    lags half a step, which distorts its output by several per cent at h = 1/1200 s;
    the bilinear map keeps both parts consistent while staying causal.

    Parameters
    ----------
    sys : StateSpace
    h : float
        Step, s.
    """
    if not np.any(sys.D):
        return zoh(sys, h)
    n, m = sys.B.shape
    Ad, Bd, Cd, Dd, _ = scipy.signal.cont2discrete(
        (sys.A, sys.B, sys.C.reshape(1, n), sys.D.reshape(1, m)), h, method="bilinear")
    return Discrete(Ad, Bd, np.asarray(Cd).reshape(n), np.asarray(Dd).reshape(m))


def is_stable(den, *, allow_integrators: int = 0) -> bool:
    """True if the roots of `den` have negative real parts.

    Up to `allow_integrators` roots exactly at the origin (trailing zero
    coefficients) are allowed: a plant's integrators.

    Parameters
    ----------
    den : array
        Denominator, descending powers of s.
    allow_integrators : int
        How many roots at s = 0 are allowed.
    """
    den = np.trim_zeros(np.asarray(den, dtype=float), "f")
    k = 0
    while k < allow_integrators and den.size > 1 and den[-1] == 0.0:
        den = den[:-1]
        k += 1
    if den.size <= 1:
        return True
    return bool(np.all(np.roots(den).real < 0))


def tf_dict(t) -> dict:
    """A transfer function as the plants file writes it.

    Parameters
    ----------
    t : (num, den)
        Polynomial coefficients, highest power of s first.

    Returns
    -------
    dict
        ``{"num": [...], "den": [...]}`` of floats.
    """
    return {"num": [float(x) for x in t[0]], "den": [float(x) for x in t[1]]}
