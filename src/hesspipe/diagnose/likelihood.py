"""The diagnosis's likelihood: log-spectral residuals of a model's expected control
spectrum (:mod:`hesspipe.diagnose.expected`) against the measured one, their variances and
the likelihood-ratio statistics; the fits are in :mod:`hesspipe.diagnose.fitting`.

The criterion
-------------
Fits and scores use the same residual: ``r_k = ln P_model(f_k) - ln P_measured(f_k)``
over the paper-Welch bins of the band (DC excluded). ``P_model`` is the PSD of the
model's deterministic response to the measured disturbance plus the *expected* PSD of
its remnant through the closed loop (exact, not a random draw, so fits do not depend on
a noise realization). "Expected" means the expectation of the paper-Welch estimate: the
remnant's density folded through the Hamming window's kernel (:func:`welch_kernel`),
not the density at the bin's centre — a closed loop around a plant with a small static
gain passes slow noise almost unopposed, a spike at DC far narrower than a bin, and its
point value once made every remnant model's Eq. 10 gap (which includes DC) explode.

Log residuals are used because the linear Eq. 10 fitness is dominated by the few bins
around the PSD peak and is blind to the low-power bands where a remnant, an extra delay
or a Dutch-roll pair show. Welch bins are not independent (the Hamming window correlates
neighbours), so the residuals count as ``n_eff = n_bins / ENBW`` observations (ENBW:
equivalent noise bandwidth of the window, 1.36 bins).

The residuals are Gaussian with bin variances ``s2 + a_k`` (``weighting =
"random-share"``, :meth:`_Problem.random_variance`): ``a_k = psi'(nu/2)(1 - rho_k^2)``
is the chance scatter of a Welch log-estimate whose share ``1 - rho_k`` of power is
random (the model's remnant; its deterministic part is driven by the measured
disturbance, the data's own realization, and does not scatter against them), and
``s2`` is a common model-error variance, estimated by maximum likelihood for each
parameter set. The log of a chance estimate is biased low (``psi(nu/2) - ln(nu/2)``,
scaled like ``a_k``); the model's log PSD carries the same bias. Treating every bin alike (``weighting = "uniform"``, ``a = 0``) lets the
Welch scatter of the remnant-dominated bins drown a pilot effect that shows, free of
chance, in the bins the pilot's response dominates: with a remnant of a fifth of the
control power, motion feedback was then never named. The likelihood-ratio statistic
between the current model and the model with one more effect is
``Lambda = (NLL_0 - NLL_1) / ENBW`` (``NLL``: -2 log-likelihood over the bins; with
``a = 0`` it is ``n_eff ln((V0 + res) / (V1 + res))``, ``res`` below), chi-square with ``dof`` = number of added
parameters under the null. Robustness to chance and to over-fitting:

* The best of ``m`` candidates of a round is named only if ``p < alpha / m``
  (Bonferroni: the best of m tries is a multiple comparison) and
  ``delta_BIC = Lambda - dof ln(n_eff) > 0``, which pays for every added parameter.
  delta_BIC is the reported score.
* Each squared residual counts as ``e^2 + (resolution_db / 4.34)^2`` (0.1 dB RMS by
  default): a model that matches the data to better than that leaves only optimizer
  round-off, and a ratio of two round-off residuals must not count as evidence.
* The augmented fit starts from the effect switched off, so it is never worse than the
  model it extends (nested models, ``Lambda >= 0``), and from a grid over the effect's
  parameters jointly with the pilot gains, so a real effect is not missed for a bad
  local optimum.

* Both PSDs are floored at ``dynamic_range_db`` (40 dB) below the band's measured peak
  before the logs: a Hamming window's leakage (-43 dB sidelobes) bounds what a Welch
  estimate resolves, and deeper bins would otherwise dominate the log residual.

Two measures
------------
The reported gap is the paper's Eq. 10 fitness (linear PSD difference, RMS over the
band's bins, DC included); it is dominated by the bins around the PSD peak. The
selection criterion is log-spectral (above). The two can disagree: an effect can fix the
shape of the spectrum in the low-power bands while moving power away from the peak. A
candidate is therefore named only if, besides being significant on the log scale, its
Eq. 10 gap is no larger than that of the model it extends (``Step.gap_ok``): the named
effect must explain the data better on both the shape and the power level, so an
accepted effect never worsens the reported gap, and ``gap_after <= gap_before`` holds by
construction. The guard costs no fit; a single objective mixing both was not used
because the Welch scatter of linear PSDs is proportional to their level (Eq. 10 has no
calibrated likelihood), so the significance test could not be kept. Both measures are
reported for every candidate (``gap``, ``log_rms_db``). (The disagreement that made
this guard necessary on the JSBSim 737 data was mostly the DC point value of the
remnant's PSD, fixed above; the guard makes the property hold whatever its cause.)

A likelihood-ratio test was preferred over cross-validation across record segments
because a 70 s record holds only three to four 1024-sample Welch segments: halving it
leaves spectra too coarse to fit. Recording noise on the control column is, to a PSD,
broadband control noise, i.e. a remnant with Tn = 0: once it rises above the dynamic
range floor (about 1 % of the control's RMS for the validation runs) the workflow names
``remnant``, which is the physical reading a control PSD allows.

Known limit: a PSD cannot tell the pilot's response to the disturbance from noise of
the same spectrum, so a "low-gain pilot plus strong remnant" can mimic a mis-fitted
baseline; the joint grid over effect parameters and pilot gains is what lets the right
effect win in the benchmark, not a guarantee.
"""

from __future__ import annotations

import math

import numpy as np
import scipy.special

from ..core.errors import HesspipeError
from ..core.formats import Run
from .settings import DiagnoseConfig
from .spectra import _DB, Band, _eq10, _log_residual, _psd, band_disagreement, welch_statistics


class Likelihood:
    """The measured control spectrum and the likelihood of a model's expected one against it.

    See the module docstring for the criterion: log-spectral residuals over the band's
    Welch bins, bin variances from the model's random share and a profiled model error.

    Parameters
    ----------
    run : hesspipe.core.formats.Run
        The measured run (its control column).
    cfg : DiagnoseConfig
        Band (Hz), band edges, weighting, resolution and dynamic range (dB), alpha.
    """

    def __init__(self, run: Run, cfg: DiagnoseConfig):
        self.run, self.cfg = run, cfg
        self.freq, self.measured = _psd(run.control, run.fs)
        lo, hi = cfg.band_hz
        self.mask = (self.freq > 0) & (self.freq >= lo) & (self.freq <= hi)
        if int(self.mask.sum()) < 3:
            raise HesspipeError(f"{run.source or run.id}: fewer than 3 Welch bins in the band "
                                f"{lo:g}-{hi:g} Hz; expected a longer record or a wider band")
        self.nu, self.var_floor, self.enbw = welch_statistics(len(run))
        self.n_eff = float(self.mask.sum()) / self.enbw
        self.log_bias = float(scipy.special.digamma(self.nu / 2.0) - math.log(self.nu / 2.0))
        self.resolution = (cfg.resolution_db / _DB) ** 2
        # A Hamming window's leakage (highest sidelobe -43 dB) bounds what a Welch
        # estimate can resolve below its peak; deeper bins are compared at that level.
        self.psd_floor = float(np.max(self.measured[self.mask])) * 10.0 ** (-cfg.dynamic_range_db / 10.0)

    def log_residual(self, psd: np.ndarray) -> np.ndarray:
        """``ln P_model - ln P_measured`` over the band's bins (floored, see module doc).

        Parameters
        ----------
        psd : ndarray
            A model's control PSD on all Welch bins, control units^2/Hz.
        """
        return _log_residual(self.measured[self.mask], psd[self.mask], self.psd_floor)

    def random_variance(self, psd: np.ndarray, remnant: np.ndarray) -> np.ndarray:
        """Chance variance of each bin's log residual given the model's random share.

        The deterministic part of the model is driven by the measured disturbance: it is
        the same realization as the data's, and its Welch estimate has no scatter against
        them. Only the remnant's share is random. With ``rho = deterministic / total``
        power of a bin, the estimate ``|D + R|^2`` has relative variance
        ``(2 / nu)(1 - rho^2)`` (the ``|R|^2`` term and the cross term), so the log
        residual scatters by ``psi'(nu / 2)(1 - rho^2)``: the Welch scatter where the
        remnant dominates, nothing where it is absent. ``weighting = "uniform"`` gives
        zero (every bin alike, the model-error variance alone).

        Parameters
        ----------
        psd : ndarray
            A model's control PSD on all Welch bins, control units^2/Hz.
        remnant : ndarray
            Its remnant's share, control units^2/Hz.
        """
        if self.cfg.weighting == "uniform":
            return np.zeros(int(self.mask.sum()))
        tot = psd[self.mask] + self.psd_floor
        rho = np.clip((psd[self.mask] - remnant[self.mask] + self.psd_floor) / tot, 0.0, 1.0)
        return self.var_floor * (1.0 - rho ** 2)

    def likelihood_vector(self, psd: np.ndarray, remnant: np.ndarray,
                          s2: float | None = None) -> tuple[np.ndarray, float]:
        """Residual vector of the Gaussian likelihood of the log residuals ``e``.

        Bin variances ``s2 + a_k``: ``a_k`` the chance variance of
        :meth:`random_variance`, ``s2`` a common model-error variance estimated by
        maximum likelihood for this parameter set (profiled). Each squared residual
        counts as ``e_k^2 + resolution`` (``resolution_db``: mismatches below it are
        round-off, not evidence; a smooth version of a floor). Returned:
        ``[sqrt(e_k^2 + resolution) / sigma_k, sqrt(ln(sigma_k^2 / resolution))]`` whose sum
        of squares is ``sum (e^2 + resolution) / sigma^2 + sum ln sigma^2`` + constant, i.e.
        -2 log-likelihood. With ``a = 0`` it is ``n (1 + ln((mean e^2 + resolution) /
        resolution))``: the homoscedastic likelihood-ratio test of ``uniform`` weighting.

        A given `s2` is used instead of the profiled one, and ``e_k`` keeps its sign: that
        is the weighted least-squares form in which Gauss-Newton steps work (a profiled
        variance normalises the first half of the vector to a constant sum). Every
        comparison between parameter sets uses the profiled form.
        Returns the vector and the ``s2`` used.

        Parameters
        ----------
        psd : ndarray
            A model's control PSD on all Welch bins, control units^2/Hz.
        remnant : ndarray
            Its remnant's share, control units^2/Hz.
        s2 : float, optional
            Model-error variance to use (None: profiled).
        """
        a = self.random_variance(psd, remnant)
        # The log of a Welch estimate is biased low by psi(nu/2) - ln(nu/2) where the bin
        # is all chance, scaled like the variance for a mixed bin (delta method).
        e = self.log_residual(psd) + self.log_bias * (a / self.var_floor)
        e2 = e * e + self.resolution
        given = s2 is not None
        s2 = s2 if given else _profile_variance(e2, a, self.resolution)
        var = s2 + a
        # Least-squares mode keeps the residual's sign (a smooth Gauss-Newton model).
        first = e / np.sqrt(var) if given else np.sqrt(e2 / var)
        return np.concatenate([first, np.sqrt(np.log(var / self.resolution))]), s2

    def variance(self, fit) -> float:
        """Residual variance, floored at the resolution (see the module docstring).

        Parameters
        ----------
        fit : hesspipe.diagnose.fitting._Fit
            A fit (its residual variance, ln-units^2).
        """
        return max(fit.variance, self.resolution)

    def log_rms_db(self, psd: np.ndarray) -> float:
        """RMS of the log-spectral residual over the band, dB.

        Parameters
        ----------
        psd : ndarray
            A model's control PSD on all Welch bins, control units^2/Hz.
        """
        r = _log_residual(self.measured[self.mask], psd[self.mask], self.psd_floor)
        return _DB * math.sqrt(float(np.mean(r ** 2)))

    def bands(self, psd: np.ndarray, scatter: float) -> tuple[Band, ...]:
        """Band-wise disagreement of a model's PSD with the measured one (see :func:`band_disagreement`).

        Parameters
        ----------
        psd : ndarray
            A model's control PSD on all Welch bins, control units^2/Hz.
        scatter : float
            Variance of a bin's log residual taken as chance, ln-units^2.
        """
        return band_disagreement(self.freq, self.measured, psd, self.cfg.band_edges_hz,
                                 var_floor=scatter, enbw_bins=self.enbw, alpha=self.cfg.alpha,
                                 floor=self.psd_floor)

    def gap(self, psd: np.ndarray) -> float:
        """The paper's Eq. 10 fitness of a model's PSD against the measured one, control^2/Hz.

        Parameters
        ----------
        psd : ndarray
            A model's control PSD on all Welch bins, control units^2/Hz.
        """
        return _eq10(self.measured, psd, self.freq, self.cfg.band_hz)


def _profile_variance(e2: np.ndarray, a: np.ndarray, floor: float, iterations: int = 30) -> float:
    """Maximum-likelihood common variance ``s2 >= floor`` of residuals with squares `e2`
    whose bins have extra known variances `a` (``e_k ~ N(0, s2 + a_k)``): fixed-point
    iteration of the score equation ``sum (e^2 - s2 - a) / (s2 + a)^2 = 0``; exact
    (``mean e^2``) when every ``a`` is zero."""
    if not np.any(a > 0):
        return max(float(np.mean(e2)), floor)
    s2 = max(float(np.mean(e2 - a)), floor)
    for _ in range(iterations):
        w = 1.0 / (s2 + a) ** 2
        new = max(float(np.sum(w * (e2 - a)) / np.sum(w)), floor)
        if abs(new - s2) <= 1e-9 * s2:
            break
        s2 = new
    return s2
