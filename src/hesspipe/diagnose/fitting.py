"""Fitting a pilot model for the diagnosis: search boxes, starts, grid and bounded least
squares on the log-spectral likelihood (:mod:`hesspipe.diagnose.likelihood`) of the
model's expected spectrum (:mod:`hesspipe.diagnose.expected`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Mapping, Sequence

import numpy as np
import scipy.optimize

from ..core.errors import HesspipeError
from ..core.formats import Plants, Run
from ..identification.spectra import spectral_view
from ..pilot.crossover import gain_scale
from ..pilot.effects import get_effect
from .expected import ExpectedSpectrum
from .likelihood import Likelihood
from .settings import DiagnoseConfig

_UNSTABLE_RESIDUAL = 25.0  # ln-units per bin for an unstable parameter set (e^25 mismatch)
#: Slowest remnant (s) for which the widened Kn box (:meth:`_Problem.bounds`) still lets
#: the remnant carry twice the measured control's RMS.
_REMNANT_TN_REF = 2.0


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


class Problem:
    """Everything one diagnosis's fits share: the model's expected spectrum and its likelihood.

    Parameters
    ----------
    run : hesspipe.core.formats.Run
        The measured run.
    plants : hesspipe.core.formats.Plants
        The plants the models are closed around.
    cfg : DiagnoseConfig
        The diagnosis's settings.
    seed : int
        Base seed.

    Attributes
    ----------
    spectrum : ExpectedSpectrum
        A model's expected control PSD on the run's Welch bins.
    likelihood : Likelihood
        The measured PSD and the likelihood of a model's against it.
    gain : float
        :func:`hesspipe.pilot.crossover.gain_scale` of the plants for ``cfg.k``: the loop
        gains' defaults and boxes follow the plants' gain, as identification's do (a plant
        in degrees, 57 times one in radians, takes a pilot gain 57 times smaller).
    """

    def __init__(self, run: Run, plants: Plants, cfg: DiagnoseConfig, seed: int):
        run = spectral_view(run)   # the same segments' span at every logging rate
        self.run, self.plants, self.cfg = run, plants, cfg
        self.gain = gain_scale(plants, cfg.k)
        self.likelihood = Likelihood(run, cfg)
        self.spectrum = ExpectedSpectrum(run, plants, cfg, seed, self.likelihood.freq)

    def residual(self, model, params, s2: float | None = None) -> tuple[np.ndarray, np.ndarray, float] | None:
        """(likelihood residual vector, model PSD on the full grid, s2), None for an
        unstable loop. The vector's sum of squares is -2 log-likelihood
        (:meth:`Likelihood.likelihood_vector`, with the model-error variance `s2` given or
        profiled).

        Parameters
        ----------
        model : hesspipe.pilot.hess.PilotModel
            The model.
        params : mapping
            Its parameters.
        s2 : float, optional
            Model-error variance to use instead of the profiled one.
        """
        out = self.spectrum.model_psd(model, params)
        if out is None:
            return None
        p, rem = out
        vec, s2 = self.likelihood.likelihood_vector(p, rem, s2)
        return vec, p, s2

    def bounds(self, model) -> dict[str, tuple[float, float]]:
        """Search boxes: the model's, with the remnant gain's widened to the data's level.

        Kn is in control units, so a fixed box cannot suit every control column (a
        normalised aileron command of 0.03 RMS and a stick of 1 RMS). The upper bound is
        raised, if needed, to what lets the remnant alone, open loop and as slow as
        ``Tn = _REMNANT_TN_REF``, carry twice the measured control's RMS
        (``Kn sqrt(dt / (2 Tn))`` is the RMS of sampled white noise through
        ``Kn / (Tn s + 1)``): the closed loop only lowers it, so any remnant share of the
        control up to the whole of it stays inside the box.

        Parameters
        ----------
        model : hesspipe.pilot.hess.PilotModel
            The model whose boxes are taken.
        """
        out = dict(model.bounds(self.gain))
        if "Kn" in out:
            lo, hi = out["Kn"]
            need = 2.0 * float(np.std(self.run.control)) * math.sqrt(2.0 * _REMNANT_TN_REF / self.run.dt)
            out["Kn"] = (lo, max(hi, need))
        return out

    def free_parameters(self, model) -> tuple[str, ...]:
        """The configured free parameters plus every parameter of the model's effects.

        Parameters
        ----------
        model : hesspipe.pilot.hess.PilotModel
            The model; a configured free parameter it lacks is an error.
        """
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

        Parameters
        ----------
        model : hesspipe.pilot.hess.PilotModel
            The model to fit.
        start : mapping
            Starting values (the fit of the model it extends).
        grid : sequence of str
            Parameters gridded over their box before least squares (an added effect's).
        """
        names = model.parameter_names()
        bounds = self.bounds(model)
        params = {**model.defaults(k=self.cfg.k, gain=self.gain), **{k: v for k, v in start.items() if k in names}}
        free = self.free_parameters(model)
        scale = _UnitScale([bounds[p] for p in free], [p not in self.cfg.free for p in free])
        bad = np.full(2 * int(self.likelihood.mask.sum()), _UNSTABLE_RESIDUAL)
        count = [0]

        def residual(values: Mapping[str, float], s2: float | None = None) -> np.ndarray:
            count[0] += 1
            out = self.residual(model, {**params, **values}, s2)
            return bad if out is None else out[0]

        def model_error_variance(values) -> float:
            """The profiled s2 at `values`: the fixed weights of a least-squares run."""
            out = self.residual(model, {**params, **values})
            return self.likelihood.resolution if out is None else out[2]

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
            nan = np.full_like(self.likelihood.measured, np.nan)
            return _Fit(model, final, free, nan, bad[:bad.size // 2], count[0] + 1, False, math.inf)
        return _Fit(model, final, free, p, self.likelihood.log_residual(p), count[0] + 1, True, float(best_r @ best_r))

    # scoring and reporting ---------------------------------------------------------------


#: Parameter values that switch an effect off (the augmented model then equals the
#: model it extends). Effects not listed start from their defaults only.
_NULL = {"Km": 0.0, "Ko": 0.0, "tau_x": 0.0, "Kn": 0.0, "r_dr": 1.0}


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
