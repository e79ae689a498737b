"""ARX identification: least squares, order selection, validation, residual tests.

The model is ARX(na, nb, nk)::

    A(q) y(t) = B(q) u(t - nk) + e(t)
    A(q) = 1 + a1 q^-1 + ... + a_na q^-na
    B(q) = b0 + b1 q^-1 + ... + b_(nb-1) q^-(nb-1)

fitted by linear least squares on the one-step prediction error. Order and
delay are chosen over a grid by an information criterion (AIC, BIC or FPE)
computed on estimation data; every candidate uses the same samples so the
criteria are comparable. The quality of the chosen model is judged on its
*simulated* output (infinite horizon: driven by the input alone, never by
measured outputs), as the fit percent ``100 (1 - ||y - y_sim|| / ||y - mean(y)||)``,
and by residual tests (whiteness, and independence from the input) with
confidence bounds.

Signals are plain numpy arrays of deviations from the operating point (the
caller removes trim values); ``dt`` only labels the discrete transfer function.
Functions raise :class:`~hesspipe.core.errors.HesspipeError` with the caller's
``label`` (e.g. ``"flight/wind.csv: column 'wind_lateral_fps'"``) for data
that cannot support the requested model.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import control as ct
import numpy as np
from scipy import signal

from ..core.errors import HesspipeError

CRITERIA = ("aic", "bic", "fpe")


@dataclass(frozen=True)
class ArxModel:
    """A fitted ARX(na, nb, nk) model.

    Attributes
    ----------
    a : ndarray
        ``[1, a1, ..., a_na]``, coefficients of A(q) in ascending powers of q^-1.
    b : ndarray
        ``[b0, ..., b_(nb-1)]``, coefficients of B(q); b0 multiplies u(t - nk).
    nk : int
        Input delay in samples (>= 0).
    dt : float
        Sample interval in s.
    noise_variance : float
        Mean squared one-step residual on the estimation samples.
    n_samples : int
        Number of equations (samples) used by the least-squares fit.
    """

    a: np.ndarray
    b: np.ndarray
    nk: int
    dt: float
    noise_variance: float
    n_samples: int

    @property
    def na(self) -> int:
        """Order of A(q): number of past outputs."""
        return len(self.a) - 1

    @property
    def nb(self) -> int:
        """Number of B(q) coefficients (input taps)."""
        return len(self.b)

    @property
    def n_params(self) -> int:
        """Number of estimated coefficients, ``na + nb``."""
        return self.na + self.nb

    @property
    def orders(self) -> tuple[int, int, int]:
        """``(na, nb, nk)``."""
        return (self.na, self.nb, self.nk)

    def polynomials(self) -> tuple[np.ndarray, np.ndarray]:
        """Numerator and denominator in descending powers of z, equal length."""
        n = max(self.na, self.nk + self.nb - 1)
        num = np.zeros(n + 1)
        num[self.nk:self.nk + self.nb] = self.b
        den = np.zeros(n + 1)
        den[:self.na + 1] = self.a
        return num, den

    def poles(self) -> np.ndarray:
        """Poles of the model in the z plane (roots of A)."""
        return np.roots(self.a) if self.na else np.array([])

    def is_stable(self, max_growth: float = 0.0) -> bool:
        """All poles grow slower than `max_growth` (1/s): ``ln|z| / dt < max_growth``.

        With the default 0 that is: all poles strictly inside the unit circle.

        Parameters
        ----------
        max_growth : float
            Largest accepted growth rate, 1/s (0: strictly stable; > 0: slowly
            growing poles accepted).
        """
        return self.growth_rate() < max_growth

    def growth_rate(self) -> float:
        """Largest ``ln|z| / dt`` over the poles (1/s); negative for a stable model."""
        p = self.poles()
        if p.size == 0:
            return -math.inf
        with np.errstate(divide="ignore"):
            return float(np.max(np.log(np.abs(p)))) / self.dt

    def tf(self) -> ct.TransferFunction:
        """The model u → y as a discrete python-control transfer function."""
        num, den = self.polynomials()
        return ct.tf(num, den, self.dt)

    def simulate(self, u: np.ndarray) -> np.ndarray:
        """Simulated output from input `u` alone, zero initial state.

        Parameters
        ----------
        u : array
            Input deviations from trim, input units, sampled at :attr:`dt`.

        Returns
        -------
        ndarray
            Output deviations, output units.
        """
        num, den = self.polynomials()
        return signal.lfilter(num, den, np.asarray(u, dtype=float))

    def predict(self, u: np.ndarray, y: np.ndarray) -> np.ndarray:
        """One-step-ahead prediction of `y` (uses measured past outputs).

        Parameters
        ----------
        u, y : array
            Measured input and output deviations (same length), their units.

        Returns
        -------
        ndarray
            Predicted output, output units.
        """
        num, den = self.polynomials()
        u = np.asarray(u, dtype=float)
        y = np.asarray(y, dtype=float)
        # y_hat = B u - (A - 1) y; both filters are causal with zero pre-history.
        return signal.lfilter(num, [1.0], u) - signal.lfilter(np.r_[0.0, den[1:]], [1.0], y)

    def to_dict(self) -> dict:
        """The model as JSON-ready values (orders, coefficients, dt in s, residual variance)."""
        return {"na": self.na, "nb": self.nb, "nk": self.nk, "dt_s": self.dt,
                "a": self.a.tolist(), "b": self.b.tolist(),
                "noise_variance": self.noise_variance, "n_samples": self.n_samples}


def _first_sample(na: int, nb: int, nk: int) -> int:
    """Index of the first sample whose regressors are all inside the record."""
    return max(na, nk + nb - 1, 0)


def _regression(u, y, na, nb, nk, start):
    """Regressor matrix and target for samples ``start .. N-1``."""
    n = len(y)
    rows = np.arange(start, n)
    cols = [-y[rows - i] for i in range(1, na + 1)]
    cols += [u[rows - nk - j] for j in range(nb)]
    return np.column_stack(cols), y[rows]


def _check_signals(u, y, label):
    u = np.asarray(u, dtype=float)
    y = np.asarray(y, dtype=float)
    if u.ndim != 1 or u.shape != y.shape:
        raise HesspipeError(f"{label}: input and output must be 1-D arrays of equal length, "
                            f"got shapes {u.shape} and {y.shape}")
    for name, x in (("input", u), ("output", y)):
        if not np.all(np.isfinite(x)):
            raise HesspipeError(f"{label}: {name} holds NaN or infinite values; expected finite numbers")
    return u, y


def min_samples(na: int, nb: int, nk: int, *, per_parameter: int = 10) -> int:
    """Fewest samples accepted for ARX(na, nb, nk): the lags plus
    `per_parameter` equations per estimated parameter.

    Parameters
    ----------
    na, nb, nk : int
        ARX orders and input delay (samples).
    per_parameter : int
        Equations required per estimated coefficient.
    """
    return _first_sample(na, nb, nk) + per_parameter * (na + nb)


FOCUS = ("prediction", "simulation")


#: Condition number (of the column-scaled regressors) up to which the normal equations are
#: used; above it the shifted Cholesky-QR3 factorisation is, and above _RANK_COND the
#: regressors count as rank deficient.
_NORMAL_EQUATIONS_COND = 1e6
_RANK_COND = 1e12


def _shifted_cholesky_qr3(phi):
    """Thin QR of a tall matrix from Cholesky factors (Fukaya et al. 2020).

    Accurate to working precision for condition numbers up to about 1/eps.
    Order selection solves thousands of small least-squares problems, and
    LAPACK's SVD/QR solvers are 10-100x slower than these matrix products on
    a loaded multi-core machine (thread start-up dominates small problems).
    """
    m, n = phi.shape
    # The Frobenius norm bounds the 2-norm from above: a slightly larger, still safe shift.
    shift = 11 * (m * n + n * (n + 1)) * np.finfo(float).eps * np.sum(phi ** 2)
    # Small n x n inverses and products only: no tall triangular solves (see above).
    r = np.linalg.cholesky(phi.T @ phi + shift * np.eye(n)).T
    q = phi @ np.linalg.inv(r)
    for _ in range(2):
        r2 = np.linalg.cholesky(q.T @ q).T
        q = q @ np.linalg.inv(r2)
        r = r2 @ r
    return q, r


def _least_squares(u, y, na, nb, nk, start, label):
    phi, target = _regression(u, y, na, nb, nk, start)
    # Scale columns so conditioning and rank do not depend on the signals' units.
    scale = np.linalg.norm(phi, axis=0)
    scale[scale == 0] = 1.0
    phi = phi / scale
    gram = phi.T @ phi
    eig = np.linalg.eigvalsh(gram)
    if eig[0] > 0 and eig[-1] / eig[0] < _NORMAL_EQUATIONS_COND ** 2:
        # Normal equations with iterative refinement (corrected semi-normal equations).
        theta = np.linalg.solve(gram, phi.T @ target)
        for _ in range(2):
            theta += np.linalg.solve(gram, phi.T @ (target - phi @ theta))
        return theta / scale
    deficient = HesspipeError(f"{label}: regressors of ARX({na},{nb},{nk}) are rank deficient; "
                              "input not persistently exciting for these orders")
    try:
        q, r = _shifted_cholesky_qr3(phi)
    except np.linalg.LinAlgError:
        raise deficient from None
    if np.linalg.cond(r) > _RANK_COND:
        raise deficient
    return np.linalg.solve(r, q.T @ target) / scale


def _stable_prefilter(a: np.ndarray) -> np.ndarray:
    """A(q) with roots outside the unit circle reflected inside (|z| -> 0.99/|z|)."""
    r = np.roots(a)
    bad = np.abs(r) >= 0.99
    if not bad.any():
        return a
    r[bad] = 0.99 * r[bad] / np.abs(r[bad]) ** 2
    return np.real(np.poly(r))


def arx_fit(u, y, na: int, nb: int, nk: int, *, dt: float = 1.0, start: int | None = None,
            focus: str = "prediction", iterations: int = 10, tol: float = 1e-3,
            label: str = "data") -> ArxModel:
    """Fit ARX(na, nb, nk) by least squares.

    Parameters
    ----------
    u, y : array_like
        Input and output, same length, deviations from the operating point.
    na, nb, nk : int
        Orders of A and B (na >= 0, nb >= 1) and input delay in samples (nk >= 0).
    dt : float
        Sample interval in s (labels the model).
    start : int, optional
        First sample used as an equation (default: the first one with all
        regressors available). Pass a common value to compare candidates on
        identical samples.
    focus : {"prediction", "simulation"}
        ``"prediction"``: ordinary least squares on the one-step equation
        error, which weights the fit by ``|A(e^jw)|^2`` and so neglects low
        frequencies when poles are near z = 1. ``"simulation"``: the same
        least squares on data prefiltered by ``1/A`` of the previous
        iterate (Steiglitz–McBride, MATLAB's ``Focus = 'simulation'``), which
        removes that weighting; the iterate with the smallest simulation
        error on the estimation samples is kept. The model is ARX either way.
    iterations : int
        Most prefiltering iterations for ``focus="simulation"``.
    tol : float
        The iterations stop when the simulation-error variance improves by
        less than this fraction.
    label : str
        Names the data in error messages.

    Returns
    -------
    ArxModel
        ``noise_variance`` is the mean squared one-step residual
        (``"prediction"``) or simulation error (``"simulation"``) on the
        estimation samples.

    Raises
    ------
    HesspipeError
        If the record is too short for the orders, or the regressors are
        rank deficient (input not persistently exciting for these orders).
    """
    u, y = _check_signals(u, y, label)
    if na < 0 or nb < 1 or nk < 0:
        raise HesspipeError(f"{label}: invalid ARX orders na={na}, nb={nb}, nk={nk}; "
                            "expected na >= 0, nb >= 1, nk >= 0")
    if focus not in FOCUS:
        raise HesspipeError(f"focus: expected one of {', '.join(FOCUS)}, got {focus!r}")
    first = _first_sample(na, nb, nk)
    start = first if start is None else max(int(start), first)
    need = max(min_samples(na, nb, nk), start + 10 * (na + nb))
    if len(y) < need:
        raise HesspipeError(f"{label}: record too short for ARX({na},{nb},{nk}): {len(y)} samples, "
                            f"expected at least {need}")
    theta = _least_squares(u, y, na, nb, nk, start, label)

    def model(theta, variance):
        return ArxModel(a=np.r_[1.0, theta[:na]], b=theta[na:].copy(), nk=int(nk), dt=float(dt),
                        noise_variance=float(variance), n_samples=len(y) - start)

    if focus == "prediction":
        phi, target = _regression(u, y, na, nb, nk, start)
        return model(theta, np.mean((target - phi @ theta) ** 2))

    def sim_error(m):
        with np.errstate(all="ignore"):
            e = (y - m.simulate(u))[start:]
            v = float(np.mean(e ** 2))
        return v if np.isfinite(v) else math.inf

    best = model(theta, 0.0)
    best_v = sim_error(best)
    current = best
    for _ in range(iterations if na else 0):
        a = _stable_prefilter(current.a)
        try:
            theta = _least_squares(signal.lfilter([1.0], a, u), signal.lfilter([1.0], a, y),
                                   na, nb, nk, start, label)
        except HesspipeError:
            # Prefiltered regressors collinear: the order is too high for the data
            # (pole-zero cancellation). Keep the best iterate so far.
            break
        current = model(theta, 0.0)
        v = sim_error(current)
        if v < best_v:
            converged = v > best_v * (1 - tol)
            best, best_v = current, v
            if converged:
                break
    return model(np.r_[best.a[1:], best.b], best_v)


def information_criterion(kind: str, variance: float, n: int, d: int) -> float:
    """AIC, BIC or FPE of a model with `d` parameters and residual `variance` on `n` samples.

    ``aic = n ln V + 2 d``, ``bic = n ln V + d ln n``,
    ``fpe = V (1 + d/n) / (1 - d/n)``. Lower is better for all three.

    Parameters
    ----------
    kind : {"aic", "bic", "fpe"}
        The criterion.
    variance : float
        Mean squared one-step residual V, output units^2.
    n : int
        Number of equations (samples).
    d : int
        Number of estimated parameters.
    """
    if kind not in CRITERIA:
        raise HesspipeError(f"criterion: expected one of {', '.join(CRITERIA)}, got {kind!r}")
    v = max(float(variance), np.finfo(float).tiny)
    if kind == "aic":
        return n * math.log(v) + 2 * d
    if kind == "bic":
        return n * math.log(v) + d * math.log(n)
    return v * (1 + d / n) / (1 - d / n) if d < n else math.inf


def excitation_order(u, n_max: int, *, rcond: float = 1e-4) -> int:
    """Order of persistent excitation of `u`, up to `n_max`.

    The order is the number of singular values of the matrix of `n_max`
    lagged copies of `u` above ``rcond`` times the largest. `u` is taken as
    a deviation from the operating point (trim removed, mean not removed: a
    mean is itself one exciting component). Zero input has order 0, one
    sinusoid order 2, white noise order `n_max`. An input of order n can
    identify at most n coefficients of B(q).

    Parameters
    ----------
    u : array
        Input deviations from trim.
    n_max : int
        Largest order looked for (number of lagged copies).
    rcond : float
        Relative singular-value threshold.
    """
    u = np.asarray(u, dtype=float)
    if n_max < 1 or len(u) <= n_max or not np.any(u):
        return 0
    lags = np.column_stack([u[n_max - 1 - i: len(u) - i] for i in range(n_max)])
    sv = np.linalg.svd(lags, compute_uv=False)
    if sv[0] == 0:
        return 0
    return int(np.sum(sv > rcond * sv[0]))


















