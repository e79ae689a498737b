"""Validation of a fitted plant: fit percent and the residual tests (whiteness, independence from
the input) on held-out data."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy import signal, stats


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
