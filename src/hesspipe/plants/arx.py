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
from scipy import signal, stats

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


@dataclass(frozen=True)
class Candidate:
    """One grid point of an order selection.

    Attributes
    ----------
    na, nb, nk : int
        Orders and input delay (samples).
    criterion : float
        Value of the information criterion (lower is better).
    noise_variance : float
        Mean squared one-step residual, output units^2.
    stable : bool
        Whether the fit may be chosen (stable, or stable on the record).
    """

    na: int
    nb: int
    nk: int
    criterion: float
    noise_variance: float
    stable: bool = True

    def to_dict(self) -> dict:
        """The candidate as JSON-ready values."""
        return {"na": self.na, "nb": self.nb, "nk": self.nk, "criterion": self.criterion,
                "noise_variance": self.noise_variance, "stable": self.stable}


@dataclass(frozen=True)
class OrderSelection:
    """Result of :func:`select_order`: the best model and the whole grid.

    Attributes
    ----------
    model : ArxModel
        The chosen model, fitted.
    criterion : str
        ``"aic"``, ``"bic"`` or ``"fpe"``.
    candidates : tuple of Candidate
        Every grid point.
    excitation_order : int
        Order of persistent excitation of the input.
    n_samples : int
        Equations every candidate was fitted on.
    """

    model: ArxModel
    criterion: str
    candidates: tuple[Candidate, ...]
    excitation_order: int
    n_samples: int

    @property
    def best(self) -> Candidate:
        """The chosen candidate (same orders as :attr:`model`)."""
        m = self.model
        return next(c for c in self.candidates if (c.na, c.nb, c.nk) == m.orders)

    def ranked(self, n: int = 10) -> list[Candidate]:
        """The `n` best candidates, best first.

        Parameters
        ----------
        n : int
            How many.
        """
        return sorted(self.candidates, key=lambda c: c.criterion)[:n]


def check_data(u, y, *, na_max: int = 6, nb_max: int = 6, nk_max: int = 3, min_excitation: int = 4,
               rcond: float = 1e-4, label: str = "data") -> int:
    """Check that `u`, `y` can support an order selection; return the excitation order.

    Parameters
    ----------
    u, y : array
        Input and output deviations from trim (same length).
    na_max, nb_max, nk_max : int
        Largest orders and input delay (samples) of the grid.
    min_excitation : int
        Least excitation order accepted.
    rcond : float
        Relative singular-value threshold of :func:`excitation_order`.
    label : str
        What the data is called in messages (e.g. the file).

    Raises
    ------
    HesspipeError
        Non-finite values; ``"... input not persistently exciting ..."`` if
        the excitation order of `u` is below `min_excitation`; ``"... record
        too short ..."`` if the record cannot support the largest candidate.
    """
    u, y = _check_signals(u, y, label)
    order = excitation_order(u, max(nb_max, min_excitation), rcond=rcond)
    if order < min_excitation:
        raise HesspipeError(f"{label}: input not persistently exciting (excitation order {order}, "
                            f"expected at least {min_excitation}); use a broadband excitation "
                            "(multisine, PRBS or turbulence)")
    nb_top = min(nb_max, order)
    need = _first_sample(na_max, nb_top, nk_max) + 10 * (na_max + nb_top)
    if len(y) < need:
        raise HesspipeError(f"{label}: record too short for ARX orders up to ({na_max},{nb_top},{nk_max}): "
                            f"{len(y)} samples, expected at least {need}")
    return order


def select_order(u, y, *, na_max: int = 6, nb_max: int = 6, nk_min: int = 1, nk_max: int = 3,
                 criterion: str = "bic", dt: float = 1.0, min_excitation: int = 4,
                 rcond: float = 1e-4, stable_only: bool = True, focus: str = "prediction",
                 iterations: int = 10, max_growth: float = 0.0, label: str = "data") -> OrderSelection:
    """Choose ARX orders and delay by an information criterion, and fit.

    The grid is ``na in 1..na_max``, ``nb in 1..nb_max`` (capped at the input's
    excitation order), ``nk in nk_min..nk_max``. All candidates are fitted on
    the same samples (those after the longest lag of the grid). With
    `stable_only`, candidates with a pole on or outside the unit circle are
    listed but cannot be chosen: the plants are stable aircraft, and an
    equation-error fit can place a slow pole just outside the circle, which
    the one-step criterion cannot see but the simulated output does.
    `max_growth` (1/s, default 0) relaxes "stable" to "stable on the record":
    poles growing slower than it are accepted (a record of duration T
    cannot tell a pole at ``ln|z|/dt = +1e-4`` from one at ``-1e-4``; see
    :func:`hesspipe.pilot.simulation.growth_limit`). Refusing them can leave only
    candidates that fit badly (the MD11's slightly divergent spiral mode).

    Parameters
    ----------
    u, y : array
        Input and output deviations from trim, same length, sampled at `dt`.
    na_max, nb_max : int
        Largest orders of A(q) and B(q).
    nk_min, nk_max : int
        Range of the input delay, samples.
    criterion : {"aic", "bic", "fpe"}
        Information criterion (lower is better).
    dt : float
        Sample interval, s.
    min_excitation : int
        Least excitation order of `u` accepted.
    rcond : float
        Relative singular-value threshold of :func:`excitation_order`.
    stable_only : bool
        Only stable candidates (see above) may be chosen.
    focus : {"prediction", "simulation"}
        Fit criterion of each candidate (see :func:`fit_arx`).
    iterations : int
        Most prefiltering iterations for ``focus="simulation"``.
    max_growth : float
        Largest pole growth rate counted as stable, 1/s.
    label : str
        What the data is called in messages.

    Raises
    ------
    HesspipeError
        ``"... not persistently exciting ..."`` if the input's excitation
        order is below `min_excitation`; ``"... record too short ..."`` if
        the record cannot support the largest candidate.
    """
    if criterion not in CRITERIA:
        raise HesspipeError(f"criterion: expected one of {', '.join(CRITERIA)}, got {criterion!r}")
    order = check_data(u, y, na_max=na_max, nb_max=nb_max, nk_max=nk_max,
                       min_excitation=min_excitation, rcond=rcond, label=label)
    u, y = np.asarray(u, dtype=float), np.asarray(y, dtype=float)
    nb_top = min(nb_max, order)
    start = _first_sample(na_max, nb_top, nk_max)
    n = len(y) - start
    cands = []
    for nk in range(nk_min, nk_max + 1):
        for na in range(1, na_max + 1):
            for nb in range(1, nb_top + 1):
                try:
                    m = arx_fit(u, y, na, nb, nk, dt=dt, start=start, focus=focus,
                                iterations=iterations, label=label)
                except HesspipeError:
                    continue  # rank deficient at this order: not a candidate
                cands.append(Candidate(na, nb, nk, information_criterion(
                    criterion, m.noise_variance, n, na + nb), m.noise_variance,
                    m.is_stable(max_growth)))
    if not cands:
        raise HesspipeError(f"{label}: regressors rank deficient at every order; input not "
                            "persistently exciting")
    pool = [c for c in cands if c.stable] if stable_only else cands
    if not pool:
        raise HesspipeError(f"{label}: every ARX candidate up to ({na_max},{nb_top},{nk_max}) is unstable; "
                            "expected a stable plant (check the record, or set stable_only = false)")
    best = min(pool, key=lambda c: c.criterion)
    model = arx_fit(u, y, best.na, best.nb, best.nk, dt=dt, start=start, focus=focus,
                    iterations=iterations, label=label)
    return OrderSelection(model=model, criterion=criterion, candidates=tuple(cands),
                          excitation_order=order, n_samples=n)


def fit_percent(y, y_sim) -> float:
    """``100 (1 - ||y - y_sim|| / ||y - mean(y)||)``; 100 is perfect, may be negative.

    Parameters
    ----------
    y : array
        Measured output.
    y_sim : array
        Simulated output, same units and length.
    """
    y = np.asarray(y, dtype=float)
    y_sim = np.asarray(y_sim, dtype=float)
    denom = np.linalg.norm(y - y.mean())
    if denom == 0:
        return -math.inf
    return float(100.0 * (1.0 - np.linalg.norm(y - y_sim) / denom))


def _xcorr(a, b, max_lag):
    """Normalised cross-correlation r_ab(k) = sum a(t+k) b(t) / (N s_a s_b), k = -M..M."""
    a = a - a.mean()
    b = b - b.mean()
    n = len(a)
    scale = n * a.std() * b.std()
    full = signal.correlate(a, b, mode="full", method="fft") / (scale if scale > 0 else 1.0)
    mid = n - 1
    return full[mid - max_lag: mid + max_lag + 1]


@dataclass(frozen=True)
class ResidualTests:
    """Whiteness of residuals and their independence from the input.

    Bounds are the two-sided `confidence` limits of a normalised correlation
    under the null hypothesis: ``z / sqrt(N)`` for the autocorrelation, and
    ``z sqrt(sum_k r_e(k) r_u(k)) / sqrt(N)`` for the cross-correlation
    (Bartlett's formula, valid for a coloured input). Pass/fail uses
    portmanteau tests at significance ``1 - confidence``: Ljung-Box on the
    autocorrelation (lags 1..M, chi² with M dof) and ``N sum r_eu² / (sum r_e r_u)``
    on the cross-correlation (lags 0..M, chi² with M+1 dof).

    Attributes
    ----------
    lags : ndarray
        Autocorrelation lags 0..M, samples.
    autocorrelation : ndarray
        Normalised autocorrelation of the residuals at `lags` (1 at lag 0).
    autocorrelation_bound : float
        Its confidence bound (dimensionless).
    cross_lags : ndarray
        Cross-correlation lags, samples (k >= 0: residual at t + k, input at t).
    cross_correlation : ndarray
        Normalised residual/input cross-correlation at `cross_lags`.
    cross_correlation_bound : float
        Its confidence bound.
    whiteness_statistic, whiteness_p : float
        Ljung-Box statistic and p-value.
    independence_statistic, independence_p : float
        Cross-correlation statistic and p-value.
    confidence : float
        Confidence level of the bounds, e.g. 0.99.
    n_samples : int
        Residual samples used.
    """

    lags: np.ndarray
    autocorrelation: np.ndarray
    autocorrelation_bound: float
    cross_lags: np.ndarray
    cross_correlation: np.ndarray
    cross_correlation_bound: float
    whiteness_statistic: float
    whiteness_p: float
    independence_statistic: float
    independence_p: float
    confidence: float
    n_samples: int

    @property
    def white(self) -> bool:
        """True if the whiteness test passes at significance ``1 - confidence``."""
        return self.whiteness_p >= 1 - self.confidence

    @property
    def independent(self) -> bool:
        """True if the independence test passes at significance ``1 - confidence``."""
        return self.independence_p >= 1 - self.confidence

    def to_dict(self) -> dict:
        """The tests as JSON-ready values (pass flags, statistics, p-values, bounds)."""
        auto_out = int(np.sum(np.abs(self.autocorrelation[1:]) > self.autocorrelation_bound))
        cross_out = int(np.sum(np.abs(self.cross_correlation) > self.cross_correlation_bound))
        return {
            "confidence": self.confidence, "n_samples": self.n_samples,
            "max_lag": int(self.lags[-1]),
            "whiteness": {"pass": self.white, "test": "Ljung-Box, lags 1..M",
                          "statistic": self.whiteness_statistic, "p_value": self.whiteness_p,
                          "bound": self.autocorrelation_bound,
                          "max_abs": float(np.max(np.abs(self.autocorrelation[1:]))),
                          "lags_outside_bound": auto_out},
            "independence": {"pass": self.independent,
                             "test": "residual/input cross-correlation, lags 0..M, chi-square",
                             "statistic": self.independence_statistic,
                             "p_value": self.independence_p,
                             "bound": self.cross_correlation_bound,
                             "max_abs": float(np.max(np.abs(self.cross_correlation))),
                             "lags_outside_bound": cross_out},
        }


def independence_test(e: np.ndarray, u: np.ndarray, max_lag: int = 25, *,
                      ar_order: int = 10) -> tuple[float, float]:
    """Residual/input cross-correlation test for a coloured input (prewhitened).

    The input is whitened by a least-squares AR(`ar_order`) filter; for a white residual
    independent of the input, ``S = N sum_k r(k)^2`` over the normalised cross-
    correlations of the residual at t + k with the whitened input at t, k = 0..max_lag,
    is then chi-square with max_lag + 1 degrees of freedom. (Without prewhitening the
    lags of a smooth input such as a pilot's control are strongly correlated and the
    same sum rejects far too often.)

    Parameters
    ----------
    e : array
        Residuals.
    u : array
        Input, same length.
    max_lag : int
        Largest lag M, samples.
    ar_order : int
        Order of the prewhitening AR filter.

    Returns
    -------
    statistic, p_value : float
    """
    e = np.asarray(e, dtype=float) - np.mean(e)
    u = np.asarray(u, dtype=float) - np.mean(u)
    n = len(e)
    p = int(min(ar_order, n // 20))
    if p > 0:
        lagged = np.column_stack([u[p - i - 1:n - i - 1] for i in range(p)])
        a = np.linalg.lstsq(lagged, u[p:], rcond=None)[0]
        u = u[p:] - lagged @ a
        e = e[p:]
        n = len(e)
    m = int(min(max_lag, n // 4))
    se, su = float(np.std(e)), float(np.std(u))
    if se == 0 or su == 0:
        return 0.0, 1.0
    r = np.array([float(e[k:] @ u[:n - k]) for k in range(m + 1)]) / (n * se * su)
    stat = n * float(r @ r)
    return stat, float(stats.chi2.sf(stat, m + 1))


def residual_tests(e, u, *, max_lag: int = 25, confidence: float = 0.99) -> ResidualTests:
    """Autocorrelation of residuals `e` and their cross-correlation with input `u`.

    Cross-correlation lags k >= 0 mean the residual at t + k against the
    input at t (a model that misses input dynamics shows up there).

    Parameters
    ----------
    e : array
        Residuals (output units).
    u : array
        Input, same length.
    max_lag : int
        Largest lag M, samples.
    confidence : float
        Confidence level of bounds and tests, in (0, 1).
    """
    e = np.asarray(e, dtype=float)
    u = np.asarray(u, dtype=float)
    n = len(e)
    max_lag = int(min(max_lag, n // 4))
    z = stats.norm.ppf(0.5 + confidence / 2)
    r_e = _xcorr(e, e, max_lag)
    r_u = _xcorr(u, u, max_lag)
    r_eu = _xcorr(e, u, max_lag)
    auto = r_e[max_lag:]
    lags = np.arange(max_lag + 1)
    k = lags[1:]
    q_lb = float(n * (n + 2) * np.sum(auto[1:] ** 2 / (n - k)))
    p_lb = float(stats.chi2.sf(q_lb, max_lag))
    bartlett = max(float(np.sum(r_e * r_u)), 1e-12)
    # The statistic is computed on the prewhitened input: the lags of a smooth
    # input are correlated, and the plain sum rejects white residuals.
    s_x, p_x = independence_test(e, u, max_lag)
    return ResidualTests(lags=lags, autocorrelation=auto, autocorrelation_bound=float(z / math.sqrt(n)),
                         cross_lags=np.arange(-max_lag, max_lag + 1), cross_correlation=r_eu,
                         cross_correlation_bound=float(z * math.sqrt(bartlett / n)),
                         whiteness_statistic=q_lb, whiteness_p=p_lb, independence_statistic=s_x,
                         independence_p=p_x, confidence=confidence, n_samples=n)
