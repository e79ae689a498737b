"""The diagnosis's likelihood: the expected control spectrum of a model, log-spectral
residuals, their variances, fits and the likelihood-ratio statistics.

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
from dataclasses import dataclass
from typing import Any, Mapping, Sequence

import numpy as np
import scipy.optimize
import scipy.signal
import scipy.special
import scipy.stats

from ..core.errors import HesspipeError
from ..core.formats import Plants, Run
from ..core.seeds import derive_seed
from ..identification.spectra import PaperWelch
from ..pilot.blocks import ZERO, from_tf
from ..pilot.effects import get_effect
from ..pilot.simulation import Simulator
from .settings import DiagnoseConfig
from .spectra import (
    _DB,
    Band,
    _eq10,
    _log_residual,
    _psd,
    _window_gain,
    band_disagreement,
    welch_kernel,
    welch_statistics,
)

_UNSTABLE_RESIDUAL = 25.0  # ln-units per bin for an unstable parameter set (e^25 mismatch)
#: Welch bins of the density beyond the highest reported frequency folded into the
#: expected remnant PSD (Hamming sidelobes 32 bins out are below -60 dB).
_KERNEL_MARGIN = 32
#: Slowest remnant (s) for which the widened Kn box (:meth:`_Problem.bounds`) still lets
#: the remnant carry twice the measured control's RMS.
_REMNANT_TN_REF = 2.0
#: Frequency (Hz) below which the expected remnant PSD samples the density on the
#: simulator's fine grid (:meth:`_Problem.remnant_psd`).
_FINE_HZ = 1.0




# -- fitting --------------------------------------------------------------------------------

@dataclass(frozen=True)
class _Fit:
    model: Any
    parameters: dict
    free: tuple[str, ...]
    psd: np.ndarray          # model control PSD: deterministic part + expected remnant
    residual: np.ndarray     # ln model PSD - ln measured PSD over the band's bins
    evaluations: int
    stable: bool
    nll: float = math.inf    # -2 log-likelihood (+ constant) over the band's bins

    @property
    def variance(self) -> float:
        return float(np.mean(self.residual ** 2))


class _Problem:
    """Measured spectra and the fitting machinery shared by every fit of one diagnosis.

    The model's control PSD is the paper-Welch PSD of its deterministic response to the
    measured disturbance (and reference), plus the expected PSD of its remnant through
    the closed loop (zero without remnant), computed exactly rather than from a random
    draw so that fits and scores do not depend on a noise realization.
    """

    def __init__(self, run: Run, plants: Plants, cfg: DiagnoseConfig, seed: int):

        self.run, self.plants, self.cfg = run, plants, cfg
        self.freq, self.measured = _psd(run.control, run.fs)
        lo, hi = cfg.band_hz
        self.mask = (self.freq > 0) & (self.freq >= lo) & (self.freq <= hi)
        if int(self.mask.sum()) < 3:
            raise HesspipeError(f"{run.source or run.id}: fewer than 3 Welch bins in the band "
                                f"{lo:g}-{hi:g} Hz; expected a longer record or a wider band")
        est = PaperWelch()
        self.nu, self.var_floor, self.enbw = welch_statistics(len(run))
        self.n_eff = float(self.mask.sum()) / self.enbw
        self.log_bias = float(scipy.special.digamma(self.nu / 2.0) - math.log(self.nu / 2.0))
        self.resolution = (cfg.resolution_db / _DB) ** 2
        # A Hamming window's leakage (highest sidelobe -43 dB) bounds what a Welch
        # estimate can resolve below its peak; deeper bins are compared at that level.
        self.psd_floor = float(np.max(self.measured[self.mask])) * 10.0 ** (-cfg.dynamic_range_db / 10.0)
        self.window_gain = _window_gain(len(run))
        # The remnant is evaluated in expectation, so the simulator's noise is never used;
        # its seed is derived all the same for reproducibility.
        self.sim = Simulator(plants, run.disturbance, run.dt, reference=run.reference,
                             noise_seed=derive_seed(seed, "diagnose"))
        f = self.freq.copy()
        f[0] = f[1] * 1e-6
        self.s = 2j * np.pi * f
        self.yc = from_tf(plants.control_to_output).response(self.s)
        # Expected remnant PSD (see :meth:`remnant_psd`): the density up to `_KERNEL_MARGIN`
        # bins past the highest reported frequency, folded through the window kernel. It
        # is sampled every 1/16 Welch bin below `_FINE_HZ`, where the narrow features are
        # (lightly damped aircraft pairs, slow remnant that the loop barely opposes), every
        # quarter bin above (closed-loop features there are broad), and geometrically
        # from 1e-6 Hz up to the first fine point: a plant with a near-zero static gain
        # leaves a spike at DC narrower than any affordable uniform grid.
        top = max(float(cfg.band_hz[1]), float(cfg.band_edges_hz[-1]))
        self.n_kernel = int(np.searchsorted(self.freq, top, side="right"))
        bin_hz = run.fs / est.nperseg
        end = min(top + _KERNEL_MARGIN * bin_hz, run.fs / 2)
        fine = np.arange(bin_hz / 16, min(_FINE_HZ, end), bin_hz / 16)
        grid = np.concatenate([[0.0], np.geomspace(1e-6, fine[0], 41)[:-1], fine,
                               np.arange(fine[-1] + bin_hz / 4, end + bin_hz / 8, bin_hz / 4)])
        self.kernel = welch_kernel(len(run), run.fs, self.freq[:self.n_kernel], grid)
        g = grid.copy()
        g[0] = 1e-9   # finite value just above DC (integrating plants)
        # One evaluation per block serves both: the fine grid, then the bins above it.
        self.n_fine = g.size
        self.s_all = np.concatenate([2j * np.pi * g, self.s[self.n_kernel:]])
        self.yc_all = from_tf(plants.control_to_output).response(self.s_all)

    # model pieces -----------------------------------------------------------------------
    def loop(self, model, params):
        # Through the plants' motion path, as the Simulator sees it (remnant_density too).
        return self.sim.prepare(model.loop(model.complete(params)))

    def stochastic(self, model, params) -> bool:
        """Whether the model's loop has a remnant."""
        return not self.loop(model, params).noise.is_zero

    def control(self, model, params, loop=None) -> np.ndarray | None:
        """Deterministic control (remnant off) driven by the measured disturbance; None if
        the loop is unstable (a remnant filter has no poles in the right half plane)."""

        loop = self.loop(model, params) if loop is None else loop
        u = self.sim.control(loop.replace(noise=ZERO))
        return None if u is None or not np.all(np.isfinite(u)) else u

    def remnant_density(self, loop, s: np.ndarray, yc: np.ndarray) -> np.ndarray:
        """Two-sided PSD (control units^2/Hz) of the remnant's share of the control at `s`.

        The unit-variance white sequence of :class:`hesspipe.pilot.simulation.Simulator` has a
        two-sided density ``dt``; the closed loop passes it to the control through
        ``noise / (1 + NM PF + NM (visual + vestibular) Yc plant)`` (the loop of
        :class:`hesspipe.pilot.blocks.Loop`); `yc` is Yc's response at `s`.
        """
        nm = loop.neuromuscular.response(s)
        den = 1.0 + nm * loop.proprioceptive.response(s) + nm * (
            loop.visual.response(s) + loop.vestibular.response(s)) * yc * loop.plant.response(s)
        return np.abs(loop.noise.response(s) / den) ** 2 * self.run.dt

    def remnant_psd(self, loop) -> np.ndarray:
        """Expected paper-Welch PSD of the remnant's share of the control.

        Up to the highest reported frequency the density is folded through the window
        kernel (:func:`welch_kernel`), which is what the estimator's expectation is; above
        it (outside every fit, score and report) the density at the bin times the
        window's gain (:func:`_window_gain`) stands in.
        """
        if loop.noise.is_zero:
            return np.zeros_like(self.freq)
        dens = self.remnant_density(loop, self.s_all, self.yc_all)
        return np.concatenate([self.kernel @ dens[:self.n_fine], dens[self.n_fine:] * self.window_gain])

    def residual(self, model, params, s2: float | None = None) -> tuple[np.ndarray, np.ndarray, float] | None:
        """(likelihood residual vector, model PSD on the full grid, s2), None for an
        unstable loop. The vector's sum of squares is -2 log-likelihood
        (:meth:`likelihood_vector`, with the model-error variance `s2` given or profiled)."""
        loop = self.loop(model, params)
        u = self.control(model, params, loop)
        if u is None:
            return None
        _, det = _psd(u, self.run.fs)
        rem = self.remnant_psd(loop)
        p = det + rem
        vec, s2 = self.likelihood_vector(p, rem, s2)
        return vec, p, s2

    def log_residual(self, psd: np.ndarray) -> np.ndarray:
        """``ln P_model - ln P_measured`` over the band's bins (floored, see module doc)."""
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

    # identification --------------------------------------------------------------------
    def bounds(self, model) -> dict[str, tuple[float, float]]:
        """Search boxes: the model's, with the remnant gain's widened to the data's level.

        Kn is in control units, so a fixed box cannot suit every control column (a
        normalised aileron command of 0.03 RMS and a stick of 1 RMS). The upper bound is
        raised, if needed, to what lets the remnant alone, open loop and as slow as
        ``Tn = _REMNANT_TN_REF``, carry twice the measured control's RMS
        (``Kn sqrt(dt / (2 Tn))`` is the RMS of sampled white noise through
        ``Kn / (Tn s + 1)``): the closed loop only lowers it, so any remnant share of the
        control up to the whole of it stays inside the box.
        """
        out = dict(model.bounds())
        if "Kn" in out:
            lo, hi = out["Kn"]
            need = 2.0 * float(np.std(self.run.control)) * math.sqrt(2.0 * _REMNANT_TN_REF / self.run.dt)
            out["Kn"] = (lo, max(hi, need))
        return out

    def free_parameters(self, model) -> tuple[str, ...]:
        names = model.parameter_names()
        missing = [p for p in self.cfg.free if p not in names]
        if missing:
            raise HesspipeError(f"diagnose: free parameter '{missing[0]}' is not a parameter of model "
                                f"{model.name} (its parameters: {', '.join(names)})")
        return tuple(self.cfg.free) + tuple(
            p for e in model.effects for p in _effect(e).parameters if p not in self.cfg.free)

    def fit(self, model, start: Mapping[str, float], grid: Sequence[str] = ()) -> _Fit:
        """Least-squares fit of the free parameters of `model` on the log-spectral residual.

        Starts: `start`, the effect switched off (:data:`_NULL`) and a grid over the
        `grid` parameters; then bounded least squares from the best start. A point is
        kept only if it lowers the sum of squares, so an augmented model is never worse
        than the model it extends.
        """
        names = model.parameter_names()
        bounds = self.bounds(model)
        params = {**model.defaults(k=self.cfg.k), **{k: v for k, v in start.items() if k in names}}
        free = self.free_parameters(model)
        scale = _UnitScale([bounds[p] for p in free], [p not in self.cfg.free for p in free])
        bad = np.full(2 * int(self.mask.sum()), _UNSTABLE_RESIDUAL)
        count = [0]

        def residual(values: Mapping[str, float], s2: float | None = None) -> np.ndarray:
            count[0] += 1
            out = self.residual(model, {**params, **values}, s2)
            return bad if out is None else out[0]

        def model_error_variance(values) -> float:
            """The profiled s2 at `values`: the fixed weights of a least-squares run."""
            out = self.residual(model, {**params, **values})
            return self.resolution if out is None else out[2]

        best_vals = {p: float(np.clip(params[p], bounds[p][0], bounds[p][1])) for p in free}
        best_r = residual(best_vals)

        def consider(vals):
            nonlocal best_vals, best_r
            r = residual(vals)
            if float(r @ r) < float(best_r @ best_r):
                best_vals, best_r = dict(vals), r

        consider({**best_vals, **{p: v for p, v in _NULL.items() if p in free and p not in self.cfg.free}})
        starts = [best_vals]
        if grid:
            # Least squares alone stalls on the periodic stretches of a delay, the
            # narrow valley of a resonance or the several valleys of Ke and K1. The
            # `grid` parameters are gridded over their box jointly with the core gains
            # (at their start values and at quarter points of their box: an added effect
            # often moves the gains far, e.g. a delay against a gain stuck at its
            # bound); least squares over all free parameters then runs from the best few.
            base_u = scale.to_unit([best_vals[p] for p in free])
            n_new = max(len([p for p in grid if p not in self.cfg.free]), 1)
            levels = self.cfg.grid if n_new == 1 else max(3, self.cfg.grid // n_new)
            axes = []
            for i, p in enumerate(free):
                if p in grid:
                    axes.append((np.arange(levels) + 0.5) / levels)
                elif p in self.cfg.free:
                    axes.append(np.unique([base_u[i], *self.cfg.gain_levels]))
                else:
                    axes.append(np.array([base_u[i]]))
            ranked = []
            for point in np.stack(np.meshgrid(*axes, indexing="ij"), -1).reshape(-1, len(free)):
                vals = dict(zip(free, scale.from_unit(point)))
                r = residual(vals)
                ranked.append((float(r @ r), vals))
                if float(r @ r) < float(best_r @ best_r):
                    best_vals, best_r = vals, r
            ranked.sort(key=lambda sv: sv[0])
            starts = [best_vals] + [v for _, v in ranked[:self.cfg.starts] if v is not best_vals]
        for start_vals in (starts if free else []):
            u0 = scale.to_unit([start_vals[p] for p in free])
            s2 = model_error_variance(start_vals)
            sol = scipy.optimize.least_squares(lambda u: residual(dict(zip(free, scale.from_unit(u))), s2),
                                               u0, bounds=(0.0, 1.0), diff_step=1e-2,
                                               max_nfev=self.cfg.max_evaluations, method="trf")
            consider(dict(zip(free, scale.from_unit(sol.x))))
        final = {**params, **best_vals}
        out = self.residual(model, final)
        p = None if out is None else out[1]
        if p is None:
            nan = np.full_like(self.measured, np.nan)
            return _Fit(model, final, free, nan, bad[:bad.size // 2], count[0] + 1, False, math.inf)
        return _Fit(model, final, free, p, self.log_residual(p), count[0] + 1, True, float(best_r @ best_r))

    # scoring and reporting ---------------------------------------------------------------
    def variance(self, fit: _Fit) -> float:
        """Residual variance, floored at the resolution (see the module docstring)."""
        return max(fit.variance, self.resolution)

    def log_rms_db(self, psd: np.ndarray) -> float:
        r = _log_residual(self.measured[self.mask], psd[self.mask], self.psd_floor)
        return _DB * math.sqrt(float(np.mean(r ** 2)))

    def bands(self, psd: np.ndarray, scatter: float) -> tuple[Band, ...]:
        return band_disagreement(self.freq, self.measured, psd, self.cfg.band_edges_hz,
                                 var_floor=scatter, enbw_bins=self.enbw, alpha=self.cfg.alpha,
                                 floor=self.psd_floor)

    def gap(self, psd: np.ndarray) -> float:
        return _eq10(self.measured, psd, self.freq, self.cfg.band_hz)


#: Parameter values that switch an effect off (the augmented model then equals the
#: model it extends). Effects not listed start from their defaults only.
_NULL = {"Km": 0.0, "Ko": 0.0, "tau_x": 0.0, "Kn": 0.0, "r_dr": 1.0}


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


def _effect(effect_id: str):

    return get_effect(effect_id)


class _UnitScale:
    """Map parameter boxes to the unit cube for the optimizer.

    Parameters flagged `log` (effect parameters with a box starting at or above zero)
    are mapped logarithmically over three decades below the upper bound (or from the
    lower bound if higher): a delay, a remnant gain or a damping ratio matters in
    ratios, and 0.01 must be as reachable as 1. Values below that range sit at the
    cube's edge. The others (the pilot gains) are mapped linearly.
    """

    def __init__(self, boxes, log):
        lo = np.array([b[0] for b in boxes], dtype=float)
        hi = np.array([b[1] for b in boxes], dtype=float)
        self.log = np.asarray(log, dtype=bool) & (lo >= 0) & (hi > 0)
        lo_log = np.log(np.maximum(np.maximum(lo, hi * 1e-3), 1e-300))
        self.lo = np.where(self.log, lo_log, lo)
        self.hi = np.where(self.log, np.log(np.maximum(hi, 1e-300)), hi)
        self.span = np.where(self.hi > self.lo, self.hi - self.lo, 1.0)

    def to_unit(self, x) -> np.ndarray:
        x = np.asarray(x, dtype=float)
        y = np.where(self.log, np.log(np.maximum(x, 1e-300)), x)
        return np.clip((y - self.lo) / self.span, 0.0, 1.0)

    def from_unit(self, u) -> list[float]:
        y = self.lo + np.clip(np.asarray(u, dtype=float), 0.0, 1.0) * self.span
        return [float(v) for v in np.where(self.log, np.exp(y), y)]
