"""Output refits behind :mod:`hesspipe.diagnose.aircraft`: the columns' spectra and the
plants' responses on one FFT grid, the nuisance columns every refit shares (the slow
modes' initial state and a slow drift), and the evidence test that compares two refits.

Private implementation module; :mod:`hesspipe.diagnose.aircraft` re-exports what the
tests and the README name (``DRIFT_HZ``, ``evidence_p``).
"""

from __future__ import annotations

import math

import numpy as np
import scipy.optimize
import scipy.signal
import scipy.stats

from ..pilot.blocks import from_tf
from ..pilot.simulation import Contour
from ..plants.validation import fit_percent

#: Upper end (Hz) of the band in which the output residuals are compared (the pilot's
#: band, as the control spectra; above it the residuals are interpolation and rounding).
EVIDENCE_BAND_HZ = 5.0
#: Upper frequency of the slow drift fitted with every refit, Hz (:meth:`_Paths.drift`; 0:
#: none): its polynomial has degree ``2 T DRIFT_HZ`` on a record of T s (8 on 70 s, the
#: degree chosen on the benchmark's 70 s records), so it spans the same band at any length.
DRIFT_HZ = 4.0 / 70.0
#: Integrators of the control path from which on the slow drift is fitted.
DRIFT_INTEGRATORS = 2


class _Paths:
    """Column spectra and plant responses on one zero-padded FFT grid.

    The grid is the shifted contour of :class:`hesspipe.pilot.simulation.Contour` (the
    convention of the plant check): on ``s = j w`` an integrating plant is infinite at
    DC and its response wraps around the padded record, which made the nominal refit of
    a K/s^2 plant miss by 1e9 % and let any candidate "close" that gap."""

    def __init__(self, run, plants, edge_s: float = 1.0):

        self.n = len(run)
        self.dt = run.dt
        self.contour = Contour.for_record(self.n, run.dt)
        self.nfft = self.contour.nfft
        self.s = self.contour.s
        self.yc = from_tf(plants.control_to_output).response(self.s)
        self.yd = from_tf(plants.disturbance_to_output).response(self.s)
        self.cols = {k: np.asarray(getattr(run, k), dtype=float) for k in ("control", "disturbance", "output")}
        self.spec = {k: self.fft(v) for k, v in self.cols.items()}
        k = min(int(round(edge_s / run.dt)), self.n // 10)
        self.sl = slice(k, self.n - k)
        # Integrators of the control path (poles that barely decay over the record): the
        # drift from the logged control's folded content grows with each one.
        t_rec = self.n * run.dt
        self.integrators = sum(abs(complex(q)) < 0.1 / t_rec
                               for q in np.atleast_1d(plants.control_to_output.poles()))
        self.drift_degree = max(2, int(round(2.0 * t_rec * DRIFT_HZ))) if DRIFT_HZ > 0 else -1

    def fft(self, x: np.ndarray) -> np.ndarray:
        return self.contour.spectrum(x)

    def basis(self, poles) -> np.ndarray:
        """Free responses (columns over the fitted samples) of the slow `poles`: the record
        starts mid-flight, not at rest, and a lightly damped mode's initial condition
        lasts far past the left-out edge. A pole repeated m times gives t^k e^(qt),
        k < m (a double integrator's initial rate is a ramp)."""
        t = self.dt * np.arange(self.n)[self.sl]
        tn = t / max(t[-1], 1e-300)  # powers of t on [0, 1]: well-scaled columns
        cols, seen = [], []
        for q in poles:
            if q.real < -0.5 or q.real > 1e-6 or q.imag < -1e-9:
                continue  # fast (gone within the edge), unstable, or the conjugate's twin
            m = sum(abs(q - r) < 1e-6 * max(1.0, abs(q)) for r in seen)
            seen.append(q)
            e = np.exp(q.real * t) * tn ** m
            cols.append(e * np.cos(q.imag * t))
            if abs(q.imag) > 1e-9:
                cols.append(e * np.sin(q.imag * t))
        return np.stack(cols, axis=1) if cols else np.zeros((t.size, 0))

    def free(self, poles) -> np.ndarray:
        """The nuisance columns of every refit: :meth:`basis` of `poles` and :meth:`drift`."""
        b = self.basis(poles)
        return np.concatenate([b, self.drift(b.shape[0])], axis=1)

    def drift(self, m: int) -> np.ndarray:
        """Slow drift columns (Legendre polynomials of degree 0..``drift_degree`` over the
        `m` fitted samples; see :data:`DRIFT_HZ`), a nuisance shared by the nominal refit and every candidate.

        A logger samples the control, it does not average it: the control's content above
        the logging Nyquist folds down, and a plant with integrators turns the folded part
        into a slow drift of the simulated output (a double integrator fed the logged
        control of the independent generator is off by 12-38 % of the output's standard
        deviation, 94-98 % of that residual's power below 0.1 Hz, though the control's part
        above the Nyquist is 0.3-0.5 % of its power; fed the same control low-passed at
        the Nyquist before sampling it fits at 99.9 %: benchmarks/bench_drift_cause.py).
        Without these columns the evidence test took the drift for a slow pair or a rate
        limit. Fitted only behind at least ``DRIFT_INTEGRATORS``
        integrators of the control path: elsewhere the folded part stays as small as it is
        in the control, and the polynomial would absorb the slow part of a real aircraft
        effect (degree 8 on every plant lost 9 of 48 Dutch-roll and 8 of 48 actuator-lag
        names on development seeds 100-105)."""
        if self.drift_degree < 0 or self.integrators < DRIFT_INTEGRATORS:
            return np.zeros((m, 0))
        x = np.linspace(-1.0, 1.0, m)
        return np.polynomial.legendre.legvander(x, self.drift_degree)

    def residual(self, a: np.ndarray, b: np.ndarray, poles) -> np.ndarray:
        """Output error of ``a + g b`` plus free responses of `poles`, with the disturbance
        path's gain ``g`` and the initial conditions fitted by linear least squares."""
        y = self.cols["output"][self.sl] - a[self.sl]
        b = b[:, None] if b.ndim == 1 else b
        A = np.concatenate([b[self.sl], self.free(poles)], axis=1)
        return y - A @ _linear_fit(A, y)

    def fit_of(self, r: np.ndarray) -> float:
        y = self.cols["output"][self.sl]
        return float(100.0 * (1.0 - np.linalg.norm(r) / max(np.linalg.norm(y - y.mean()), 1e-300)))

    def time(self, spectrum: np.ndarray) -> np.ndarray:
        return self.contour.waveform(spectrum)

    def fit(self, y: np.ndarray, y_sim: np.ndarray) -> float:
        return fit_percent(y[self.sl], y_sim[self.sl])


def evidence_p(r_small: np.ndarray, r_big: np.ndarray, dof: int, dt: float,
               band_hz: float = EVIDENCE_BAND_HZ) -> float:
    """p-value of the hypothesis that the model leaving `r_big` fits the output no better
    than the one leaving `r_small` (fewer parameters) beyond chance.

    An F test of the two residual powers over the periodogram bins up to `band_hz`, with
    as many independent values as the smaller model's residual spreads over (twice its
    periodogram's participation ratio; 2 N for white noise over N bins). Output residuals
    are coloured: counted as 2 N values, a slow drift in a handful of low bins (on a K/s^2
    baseline: aliased remnant integrated twice) is broadband evidence. There a Dutch-roll
    pair that absorbed the drift, and tripled the residual at 0.15-1 Hz, halved the raw
    residual power and was named. The price: a residual that is one lightly damped mode
    (a Dutch roll the plants lack) also spreads over few bins, so a short record gives
    little evidence (SYNTHETIC generator roll plants: Dutch roll named on 9 of 20 records
    of 45 s at 50 Hz, 19 of 20 of 70 s at 60 Hz; the thirtieth revision's scratch runs).

    Parameters
    ----------
    r_small, r_big : ndarray
        Output residuals (output units) of the smaller and the larger model, same samples.
    dof : int
        Parameters the larger model adds.
    dt : float
        Sample step, s.
    band_hz : float
        Highest frequency compared, Hz.

    Returns
    -------
    float
        The F test's p-value (1.0 if the larger model fits no better).
    """
    m = r_big.size
    taper = scipy.signal.windows.tukey(m, 0.1)
    f = np.fft.rfftfreq(m, dt)
    keep = (f > 0) & (f <= band_hz)
    p_small = np.abs(np.fft.rfft(r_small * taper))[keep] ** 2
    p_big = np.abs(np.fft.rfft(r_big * taper))[keep] ** 2
    ss_small, ss_big = float(p_small.sum()), float(p_big.sum())
    # Independent values the smaller model's residual spreads over: twice the bins'
    # participation ratio (a periodogram bin of noise is chi-square with 2 dof, whose
    # participation over N bins is N / 2: 4 PR is 2 N for white noise).
    n_eff = min(4.0 * ss_small ** 2 / max(float(np.sum(p_small ** 2)), 1e-300), 2.0 * keep.sum())
    if ss_big >= ss_small or n_eff <= dof + 1:
        return 1.0
    stat = ((ss_small - ss_big) / dof) / (ss_big / (n_eff - dof))
    return float(scipy.stats.f.sf(stat, dof, n_eff - dof))


def _linear_fit(A: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Least-squares coefficients of ``A x = y`` through the normal equations of the
    column-normalised `A` (a few columns, thousands of rows: 60 times cheaper than an SVD
    of `A`, which the Gauss-Newton refits call hundreds of times); the small Gram matrix is
    solved by SVD, so dependent columns do no harm."""
    norm = np.sqrt(np.sum(A * A, axis=0))
    norm[norm == 0] = 1.0
    An = A / norm
    x = np.linalg.lstsq(An.T @ An, An.T @ y, rcond=1e-12)[0]
    return x / norm


def _rate_limited(u: np.ndarray, rate: float, dt: float) -> np.ndarray:
    """`u` through a surface that moves at most `rate` units per s (starting at u[0])."""
    out = np.empty_like(u)
    x, step = float(u[0]), rate * dt
    for i, v in enumerate(u):
        x += min(max(v - x, -step), step)
        out[i] = x
    return out


def _slow_pole(plants) -> float | None:
    """Magnitude (rad/s) of the slowest stable real pole of Yc (the roll mode), if any."""
    poles = np.asarray(plants.control_to_output.poles() if hasattr(plants.control_to_output, "poles")
                       else [], dtype=complex)
    real = [-p.real for p in poles if abs(p.imag) < 1e-9 and p.real < -1e-6]
    return min(real) if real else None


def _lsq(residual, x0s, lo, hi, max_nfev: int = 60):
    """Best bounded least-squares solution over starts `x0s`: (x, sum of squares)."""
    best = (None, math.inf)
    for x0 in x0s:
        sol = scipy.optimize.least_squares(residual, x0, bounds=(lo, hi), max_nfev=max_nfev,
                                           x_scale="jac", method="trf")
        cost = 2.0 * float(sol.cost)
        if cost < best[1]:
            best = (sol.x, cost)
    return best


def _poles(*systems) -> list[complex]:
    out: list[complex] = []
    for sys in systems:
        out += [complex(q) for q in np.atleast_1d(sys.poles())]
    return out
