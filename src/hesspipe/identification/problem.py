"""The identification problem: free and fixed parameters, bit fields, the paper's objective
(Eq. 10 over the simulated control PSD) and the result every criterion returns.

:mod:`hesspipe.identification.fit` (the paper's APID) and
:mod:`hesspipe.identification.criteria` (the phase-aware criteria) both build on it.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Mapping

import numpy as np

from ..core.errors import HesspipeError
from ..core.paper import FITNESS_BAND_HZ
from ..pilot.crossover import Crossover, crossover_fields, gain_scale
from ..pilot.hess import LOOP_GAINS, STRUCTURAL, PilotModel, model_from_name
from ..pilot.simulation import UNSTABLE_FITNESS, Simulator, unstable_fitness
from .apid import ClimbResult, Field
from .spectra import band_mask, psd, rms_difference, spectral_view

STABLE_CAP = UNSTABLE_FITNESS / 10
CORE_FREE = ("Ke", "K1", "K2")


def default_free(model: PilotModel) -> tuple[str, ...]:
    """The paper's free set: Ke, K1, K2, plus every parameter of the model's effects.

    Parameters
    ----------
    model : PilotModel
    """
    extra = [n for n in model.parameter_names() if n not in CORE_FREE and n not in
             ("1/T1", "1/T2", "k", "tau0", "zn", "wn")]
    return CORE_FREE + tuple(extra)


class SpectralObjective:
    """Fitness of parameter sets against one measured run (reusable, fast).

    Parameters
    ----------
    run : hesspipe.core.formats.Run
    plants : hesspipe.core.formats.Plants
    model : PilotModel
    base : dict
        Complete parameter values; free ones are overwritten per call.
    band : (lo, hi)
        Fitness band, Hz.
    psd_method : {"paper", "scipy"}
    noise_seed : int
        Remnant noise seed (common random numbers across evaluations).
    """

    def __init__(self, run, plants, model: PilotModel, base: Mapping[str, float], *,
                 band=FITNESS_BAND_HZ, psd_method: str = "paper", noise_seed: int = 0):
        run = spectral_view(run)   # the same segments' span at every logging rate
        self.run = run
        self.model = model
        self.base = dict(base)
        self.band = (float(band[0]), float(band[1]))
        self.psd_method = psd_method
        self.fs = run.fs
        self.sim = Simulator(plants, run.disturbance, run.dt, reference=run.reference_forcing,
                             noise_seed=noise_seed)
        self.freq_hz, self.measured = psd(run.control, run.fs, method=psd_method)
        self.mask = band_mask(self.freq_hz, self.band)
        if not np.all(np.isfinite(self.measured)):
            raise HesspipeError(f"{run.source or run.id}: the control's power spectrum overflows "
                                f"(control up to {np.max(np.abs(run.control)):.3g}); expected a "
                                "control signal in its physical units")
        self.calls = 0

    def params(self, values: Mapping[str, float]) -> dict:
        """Complete parameters: :attr:`base` with `values` over it.

        Parameters
        ----------
        values : mapping
            Free parameter values, name → value.
        """
        p = dict(self.base)
        p.update(values)
        return p

    def loop_psd(self, loop, check_stability: bool = True) -> np.ndarray | None:
        """Simulated control PSD of a loop, or None if it is unstable.

        Parameters
        ----------
        loop : Loop
            The pilot's loop.
        check_stability : bool
            Check stability on the record first (False: the caller has).

        Returns
        -------
        ndarray or None
            On :attr:`freq_hz`, control units^2/Hz.
        """
        if check_stability and not self.sim.stable(loop):
            return None
        control, _ = self.sim.spectra(loop, output=False)
        delta = self.sim.waveform(control)
        if not np.isfinite(delta).all():
            return None
        return psd(delta, self.fs, method=self.psd_method)[1]

    def psd_fitness(self, simulated_psd) -> float:
        """Eq. 10 fitness of a simulated control PSD against the measured one.

        Parameters
        ----------
        simulated_psd : array
            Control PSD on :attr:`freq_hz` (all bins), control units^2/Hz, as
            :meth:`loop_psd` returns it.

        Returns
        -------
        float
            RMS difference over the band's bins, control^2/Hz
            (:func:`hesspipe.identification.spectra.rms_difference`).
        """
        return rms_difference(np.asarray(simulated_psd)[self.mask], self.measured[self.mask])

    def unstable_fitness(self, loop) -> float:
        """Graded worst fitness: >= UNSTABLE_FITNESS, growing with the loop's growth rate
        beyond the record's limit (:func:`hesspipe.pilot.simulation.growth_limit`).

        Parameters
        ----------
        loop : Loop
            The pilot's loop.
        """
        return unstable_fitness(self.sim.growth_rate(loop), self.sim.growth_limit)

    def score_loop(self, loop, threshold: float | None = None) -> float:
        """Fitness of a loop; unstable: at least UNSTABLE_FITNESS.

        With a `threshold`, stability is only verified when the spectral
        fitness is below it: a caller that rejects anything at or above the
        threshold (the bit climber) gets the same decisions for less work, and
        sees the unverified value for candidates it rejects anyway.

        Parameters
        ----------
        loop : Loop
            The pilot's loop.
        threshold : float, optional
            Fitness the caller rejects at or above, control^2/Hz.

        Returns
        -------
        float
            Eq. 10 fitness, control^2/Hz, capped at ``UNSTABLE_FITNESS / 10`` for a
            stable loop.
        """
        self.calls += 1
        if threshold is None:
            rate = self.sim.growth_rate(loop)
            if not rate < self.sim.growth_limit:
                return unstable_fitness(rate, self.sim.growth_limit)
        sim = self.loop_psd(loop, check_stability=False)
        if sim is None:
            return self.unstable_fitness(loop)
        value = self.psd_fitness(sim)
        if not np.isfinite(value):
            return self.unstable_fitness(loop)
        if threshold is not None and value < threshold and not self.sim.stable(loop):
            return self.unstable_fitness(loop)
        # Stable but absurd fits stay below the unstable value, so "unstable"
        # remains the worst fitness there is.
        return min(value, STABLE_CAP)

    def simulated_psd(self, values: Mapping[str, float]) -> np.ndarray | None:
        """Simulated control PSD (control units^2/Hz) for free parameter `values`; None if unstable.

        Parameters
        ----------
        values : mapping
            Free parameter values, name → value.
        """
        return self.loop_psd(self.model.loop(self.params(values)))

    accepts_threshold = True

    def __call__(self, values: Mapping[str, float], threshold: float | None = None) -> float:
        return self.score_loop(self.model.loop(self.params(values)), threshold)


@dataclass(frozen=True)
class Identification:
    """Result of :func:`identify`.

    Attributes
    ----------
    model : str
        Model name ("original", "expanded", ...).
    parameters : dict
        All parameter values (identified and fixed), name → value.
    free, fixed : tuple / dict
        Identified names; fixed name → value (user-fixed only).
    fitness : float
        The criterion's misfit at the optimum, lower is better, in ``fitness_units``
        (``paper``: RMS PSD difference over the band, Eq. 10; ``df``: the describing
        function's weighted misfit; ``output``: the output-error misfit); never NaN: an
        unstable optimum keeps its graded score >= UNSTABLE_FITNESS (and ``stable`` is False).
    benchmark_fitness : float
        The same fitness for the McRuer precision model fitted to the data
        (NaN if not computed).
    crossover : Crossover
        Where ``|L|`` falls through 1 for the last time (SPEC.md's definition: the gain crossover in the
        control-theory sense; with a lightly damped neuromuscular peak it can lie far above
        the tracking crossover). The tracking crossover a human-factors reader compares with
        the crossover model is ``primary_crossover``.
    primary_crossover : Crossover or None
        The tracking crossover: the first fall of ``|L|`` through 1 above the record's
        lowest resolvable frequency (:func:`hesspipe.pilot.crossover.tracking_crossover`);
        what the reports and tables print.
    stable : bool
        Whether the identified closed loop is stable on the record.
    evaluations : int
        Fitness evaluations of the search.
    identifiability : dict
        See :func:`identifiability`.
    measured_psd, simulated_psd, freq_hz : ndarray
        Spectra over all bins (``simulated_psd`` NaN if the optimum is unstable).
    """

    model: str
    parameters: dict
    free: tuple
    fixed: dict
    fitness: float
    benchmark_fitness: float
    crossover: Crossover
    evaluations: int
    identifiability: dict
    measured_psd: np.ndarray
    simulated_psd: np.ndarray
    freq_hz: np.ndarray
    optimizer: str = "apid"
    restarts: int = 1
    coding: str = "gray"
    seed: int = 0
    passes: int = 10
    band: tuple = FITNESS_BAND_HZ
    psd_method: str = "paper"
    run_id: str = ""
    synthetic: bool = False
    stable: bool = True
    benchmark_parameters: dict = field(default_factory=dict)
    fields: dict = field(default_factory=dict)
    climb: ClimbResult | None = field(default=None, repr=False)
    gain_scale: float = 1.0
    criterion: str = "paper"
    fitness_units: str = "RMS PSD difference (Eq. 10)"
    k_rule: str = ""
    frf: object = field(default=None, repr=False)
    primary_crossover: Crossover | None = None

    def box_edges(self) -> dict:
        """Free parameters found on the edge of their search box, name → ``{"side", "bound"}``.

        The box is the APID bit field's span (``fields``) or, for the least-squares
        criteria, the model's bounds (scaled to the plants' gain as the search was). On
        its edge the optimum may lie outside: plants in other units than the runs, or a
        pilot the model cannot follow. A lower bound of 0 is left out: there the
        parameter is absent (Km = 0: no motion feedback; 1/T1 = 0: no proprioceptive lead).
        Within :data:`BOX_EDGE` of the box's width counts as on it.
        """
        if self.fields:
            box = {f.name: (f.lo, f.hi) for f in (Field(n, *spec) for n, spec in self.fields.items())}
        else:
            box = model_from_name(self.model).bounds(self.gain_scale)
        out = {}
        for name in self.free:
            if name not in box or name not in self.parameters:
                continue
            lo, hi = box[name]
            v, tol = float(self.parameters[name]), BOX_EDGE * (hi - lo)
            if not (np.isfinite(v) and np.isfinite(tol)):
                continue
            if v >= hi - tol:
                out[name] = {"side": "upper", "bound": float(hi)}
            elif lo != 0.0 and v <= lo + tol:
                out[name] = {"side": "lower", "bound": float(lo)}
        return out

    def to_dict(self, spectra: bool = True) -> dict:
        """The identification as JSON-ready values.

        Parameters
        ----------
        spectra : bool
            Include the measured and simulated PSDs (control units^2/Hz).
        """
        out = {
            "model": self.model, "run_id": self.run_id, "synthetic": self.synthetic,
            "parameters": dict(self.parameters), "free": list(self.free), "fixed": dict(self.fixed),
            "fitness": self.fitness, "benchmark_fitness": self.benchmark_fitness,
            "benchmark_model": "McRuer precision model Kp (TL s+1)/(TI s+1) e^(-tau s) Y_NM",
            "benchmark_parameters": dict(self.benchmark_parameters),
            **crossover_fields(self.primary_crossover, self.crossover), "evaluations": self.evaluations,
            "identifiability": self.identifiability, "optimizer": self.optimizer, "seed": self.seed,
            "restarts": self.restarts, "coding": self.coding,
            "passes": self.passes, "band_hz": list(self.band), "psd_method": self.psd_method,
            "stable": self.stable,
            "fields": {n: {"bits": b, "scale": s, "offset": o} for n, (b, s, o) in self.fields.items()},
            "gain_scale": self.gain_scale,
            "criterion": self.criterion, "fitness_units": self.fitness_units, "k_rule": self.k_rule,
            "nonparametric": _nonparametric(self.frf), "at_box_edge": self.box_edges(),
        }
        if self.climb is not None:
            out["passes_run"] = self.climb.passes
            out["initial"] = dict(self.climb.initial)
        if spectra:
            out["spectra"] = {"freq_hz": self.freq_hz, "measured": self.measured_psd,
                              "simulated": self.simulated_psd}
        return out


BOX_EDGE = 0.005
"""Share of a search box's width within which a fitted parameter counts as on its edge
(:meth:`Identification.box_edges`)."""


def _nonparametric(frf) -> dict | None:
    if frf is None:
        return None
    if isinstance(frf, str):  # why it could not be estimated
        return {"note": frf}
    return {"method": frf.method, "crossover": frf.crossover.to_dict(),
            "remnant_share_of_control_power": frf.remnant_share,
            "lines": int(frf.feedback.freq_rad_s.size)}


def _as_field(name, spec) -> Field:
    if isinstance(spec, Field):
        return Field(name, spec.bits, spec.scale, spec.offset)
    bits, scale, offset = spec
    return Field(name, int(bits), float(scale), float(offset))


def default_fields(model, plants, k: int = 1) -> dict[str, tuple[int, float, float]]:
    """APID bit fields of `model` around `plants`, name → (bits, scale, offset).

    Table 1's fields with the loop gains' (Ke, Km, Ko) spans scaled by
    :func:`hesspipe.pilot.crossover.gain_scale` of the plants, so that the search box
    holds the gain a pilot adapted to these plants would use.

    Parameters
    ----------
    model : PilotModel or str
    plants : hesspipe.core.formats.Plants
    k : {1, 2}
        Table 1 column.
    """
    return model_from_name(model).fields(gain_scale(plants, k))


def _resolve(model, free, fixed, k, fields, plants):
    names = model.parameter_names()
    fixed = dict(fixed or {})
    for n, v in fixed.items():
        if n not in names:
            raise HesspipeError(f"fixed: unknown parameter {n!r} for model {model.name}; expected one "
                                f"of {', '.join(names)}")
        try:
            fixed[n] = float(v)
        except (TypeError, ValueError):
            raise HesspipeError(f"fixed: {n}: expected a number, got {v!r}") from None
    if "k" in fixed:
        k = int(round(fixed["k"]))
    if free is None:
        free = tuple(n for n in default_free(model) if n not in fixed)
    else:
        free = tuple(free)
        both = [n for n in free if n in fixed]
        if both:
            raise HesspipeError(f"free: {both[0]!r} is also fixed; expected each parameter either "
                                "free (identified) or fixed, not both")
    for n in free:
        if n not in names:
            raise HesspipeError(f"free: unknown parameter {n!r} for model {model.name}; expected "
                                f"some of {', '.join(n2 for n2 in names if n2 not in STRUCTURAL)}")
        if n in STRUCTURAL:
            raise HesspipeError(f"free: {n!r} selects the model structure and cannot be "
                                f"identified; hold it in fixed instead ({n}=2)")
    if len(set(free)) != len(free):
        raise HesspipeError(f"free: a parameter is listed twice in {','.join(free)}")
    # Default gains, boxes and fields follow the plants' gain (see hesspipe.pilot.crossover.gain_scale).
    gain = gain_scale(plants, k)
    base = model.complete(fixed, k, strict=True, gain=gain)
    bounds = model.bounds(gain)
    for n, v in fixed.items():
        lo, hi = bounds.get(n, (-np.inf, np.inf))
        if not lo <= v <= hi:
            scaled = " (Table 1's box times the plants' gain scale)" if n in LOOP_GAINS else ""
            raise HesspipeError(f"fixed: {n} = {v:g} is outside the parameter's range "
                                f"{lo:.4g}..{hi:.4g}{scaled}; expected a value in it")
    defaults = model.fields(gain)
    fields = dict(fields or {})
    for n in fields:
        if n not in free:
            raise HesspipeError(f"bit field for {n!r}, which is not a free parameter "
                                f"({', '.join(free)})")
    out = []
    for n in free:
        f = _as_field(n, fields.get(n, defaults[n]))
        f.check_within(*bounds[n])
        out.append(f)
    return base, free, fixed, out, gain
