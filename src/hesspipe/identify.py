"""Pilot-parameter identification by spectral matching (the paper's APID).

The measured control PSD (:mod:`hesspipe.spectra`) is compared with the PSD
of the control simulated by the pilot model closed around the plants and
driven by the measured disturbance (:class:`hesspipe.hess.Simulator`). The
free parameters are searched by the bit-climbing GA (:mod:`hesspipe.apid`)
or by a scipy optimiser over the same box. Parameter sets whose closed loop
is not stable on the record (growth rate at or above
:func:`hesspipe.hess.growth_limit`, ln 2 / duration: a mode that more than
doubles over the record) get :data:`~hesspipe.hess.UNSTABLE_FITNESS` (1e12)
or more, graded by the growth rate beyond that limit (finite, worse than any
stable fit, which is capped at 1e11) and never raise. Slower growth is not
punished: neither the record nor the pilot can see it.

After the fit, :func:`identifiability` looks at the Jacobian of the
simulated PSD with respect to the free parameters (relative perturbations):
a (near) null direction is a combination the data cannot separate, which
is then confirmed by a profile scan along it. In the adopted Hess structure
K1 and K2 enter only as a product; this is reported, never hidden.
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass, field
from typing import Mapping, Sequence

import numpy as np
from scipy.optimize import differential_evolution

from .apid import ClimbResult, Field, bit_climb
from .crossover import Crossover, CrossoverLimits, loop_crossover
from .errors import HesspipeError
from .hess import (
    LOOP_GAINS,
    STRUCTURAL,
    UNSTABLE_FITNESS,
    PilotModel,
    Simulator,
    gain_scale,
    model_from_name,
    unstable_fitness,
)
from .mcruer import bounded_powell
from .seeds import check_seed

STABLE_CAP = UNSTABLE_FITNESS / 10
from .spectra import PaperWelch, band_mask, psd

OPTIMIZERS = ("apid", "scipy", "differential_evolution")
CORE_FREE = ("Ke", "K1", "K2")

# Relative singular values below NULL_TOL: not identifiable (a structural
# null direction, e.g. K1*K2, sits at 1e-10 or below); below WEAK_TOL: only
# weakly identifiable (a 1 % change along it moves the in-band PSD by less
# than 3e-4 of the strongest direction's change).
NULL_TOL = 1e-4
WEAK_TOL = 3e-2


def default_free(model: PilotModel) -> tuple[str, ...]:
    """The paper's free set: Ke, K1, K2, plus every parameter of the model's effects."""
    extra = [n for n in model.parameter_names() if n not in CORE_FREE and n not in
             ("1/T1", "1/T2", "k", "tau0", "zn", "wn")]
    return CORE_FREE + tuple(extra)


class SpectralObjective:
    """Fitness of parameter sets against one measured run (reusable, fast).

    Parameters
    ----------
    run : hesspipe.formats.Run
    plants : hesspipe.formats.Plants
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
                 band=(0.0, 5.0), psd_method: str = "paper", noise_seed: int = 0):
        self.model = model
        self.base = dict(base)
        self.band = (float(band[0]), float(band[1]))
        self.psd_method = psd_method
        self.fs = run.fs
        self.sim = Simulator(plants, run.disturbance, run.dt, reference=run.reference,
                             noise_seed=noise_seed)
        self.freq_hz, self.measured = psd(run.control, run.fs, method=psd_method)
        self.mask = band_mask(self.freq_hz, self.band)
        if not np.all(np.isfinite(self.measured)):
            raise HesspipeError(f"{run.source or run.id}: the control's power spectrum overflows "
                                f"(control up to {np.max(np.abs(run.control)):.3g}); expected a "
                                "control signal in its physical units")
        self.calls = 0

    def params(self, values: Mapping[str, float]) -> dict:
        p = dict(self.base)
        p.update(values)
        return p

    def loop_psd(self, loop, check_stability: bool = True) -> np.ndarray | None:
        """Simulated control PSD of a loop, or None if it is unstable."""
        if check_stability and not self.sim.stable(loop):
            return None
        control, _ = self.sim.spectra(loop, output=False)
        delta = self.sim.waveform(control)
        if not np.isfinite(delta).all():
            return None
        return psd(delta, self.fs, method=self.psd_method)[1]

    def unstable_fitness(self, loop) -> float:
        """Graded worst fitness: >= UNSTABLE_FITNESS, growing with the loop's growth rate
        beyond the record's limit (:func:`hesspipe.hess.growth_limit`)."""
        return unstable_fitness(self.sim.growth_rate(loop), self.sim.growth_limit)

    def score_loop(self, loop, threshold: float | None = None) -> float:
        """Fitness of a loop; unstable: at least UNSTABLE_FITNESS.

        With a `threshold`, stability is only verified when the spectral
        fitness is below it: a caller that rejects anything at or above the
        threshold (the bit climber) gets the same decisions for less work, and
        sees the unverified value for candidates it rejects anyway.
        """
        self.calls += 1
        if threshold is None:
            rate = self.sim.growth_rate(loop)
            if not rate < self.sim.growth_limit:
                return unstable_fitness(rate, self.sim.growth_limit)
        sim = self.loop_psd(loop, check_stability=False)
        if sim is None:
            return self.unstable_fitness(loop)
        d = sim[self.mask] - self.measured[self.mask]
        value = float(np.sqrt(np.mean(d * d)))   # spectra.fitness with the mask kept
        if not np.isfinite(value):
            return self.unstable_fitness(loop)
        if threshold is not None and value < threshold and not self.sim.stable(loop):
            return self.unstable_fitness(loop)
        # Stable but absurd fits stay below the unstable value, so "unstable"
        # remains the worst fitness there is.
        return min(value, STABLE_CAP)

    def simulated_psd(self, values: Mapping[str, float]) -> np.ndarray | None:
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
        RMS PSD difference over the band at the optimum (lower is better);
        never NaN: an unstable optimum keeps its graded score >= UNSTABLE_FITNESS
        (and ``stable`` is False).
    benchmark_fitness : float
        The same fitness for the McRuer precision model fitted to the data
        (NaN if not computed).
    crossover : Crossover
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
    band: tuple = (0.0, 5.0)
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

    def to_dict(self, spectra: bool = True) -> dict:
        out = {
            "model": self.model, "run_id": self.run_id, "synthetic": self.synthetic,
            "parameters": dict(self.parameters), "free": list(self.free), "fixed": dict(self.fixed),
            "fitness": self.fitness, "benchmark_fitness": self.benchmark_fitness,
            "benchmark_model": "McRuer precision model Kp (TL s+1)/(TI s+1) e^(-tau s) Y_NM",
            "benchmark_parameters": dict(self.benchmark_parameters),
            "crossover": self.crossover.to_dict(), "evaluations": self.evaluations,
            "identifiability": self.identifiability, "optimizer": self.optimizer, "seed": self.seed,
            "restarts": self.restarts, "coding": self.coding,
            "passes": self.passes, "band_hz": list(self.band), "psd_method": self.psd_method,
            "stable": self.stable,
            "fields": {n: {"bits": b, "scale": s, "offset": o} for n, (b, s, o) in self.fields.items()},
            "gain_scale": self.gain_scale,
            "criterion": self.criterion, "fitness_units": self.fitness_units, "k_rule": self.k_rule,
            "nonparametric": _nonparametric(self.frf),
            "primary_crossover": (None if self.primary_crossover is None
                                  else self.primary_crossover.to_dict()),
        }
        if self.climb is not None:
            out["passes_run"] = self.climb.passes
            out["initial"] = dict(self.climb.initial)
        if spectra:
            out["spectra"] = {"freq_hz": self.freq_hz, "measured": self.measured_psd,
                              "simulated": self.simulated_psd}
        return out


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
    :func:`hesspipe.hess.gain_scale` of the plants, so that the search box
    holds the gain a pilot adapted to these plants would use.
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
    # Default gains, boxes and fields follow the plants' gain (see hesspipe.hess.gain_scale).
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


_BENCHMARK_CACHE: dict = {}


def _benchmark_key(run, plants, band, psd_method) -> str:
    h = hashlib.sha1()
    for arr in (run.control, run.disturbance, run.reference, run.time[:2]):
        h.update(np.ascontiguousarray(arr, dtype=float).tobytes())
    for sys in (plants.control_to_output, plants.disturbance_to_output):
        h.update(repr((np.asarray(sys.num[0][0]).tolist(), np.asarray(sys.den[0][0]).tolist())).encode())
    h.update(repr((band, psd_method)).encode())
    return h.hexdigest()


def benchmark(run, plants, *, band=(0.0, 5.0), psd_method: str = "paper"):
    """McRuer precision-model fit to `run` (cached per run, plants, band, method)."""
    from .mcruer import fit_precision

    key = _benchmark_key(run, plants, band, psd_method)
    if key not in _BENCHMARK_CACHE:
        obj = SpectralObjective(run, plants, PilotModel(), PilotModel().complete(),
                                band=band, psd_method=psd_method)
        if len(_BENCHMARK_CACHE) > 64:
            _BENCHMARK_CACHE.clear()
        _BENCHMARK_CACHE[key] = fit_precision(obj.score_loop)
    return _BENCHMARK_CACHE[key]


def _scipy_search(objective, fields, x0, *, optimizer, seed, passes):
    lo = np.array([f.lo for f in fields])
    span = np.array([f.hi - f.lo for f in fields])

    def values_of(u):
        return {fl.name: float(lo[i] + span[i] * np.clip(u[i], 0, 1)) for i, fl in enumerate(fields)}

    def f(u):
        return objective(values_of(u))

    u0 = np.clip((np.array([x0[fl.name] for fl in fields]) - lo) / span, 0, 1)
    if optimizer == "differential_evolution":
        r = differential_evolution(f, [(0.0, 1.0)] * len(fields), seed=seed, maxiter=10 * passes,
                                   popsize=8, tol=1e-6, polish=False, x0=u0)
        return values_of(r.x), float(r.fun)
    u, fun = bounded_powell(f, u0, [(0.0, 1.0)] * len(fields), xtol=1e-4, ftol=1e-6,
                            maxfev=200 * len(fields) * passes)
    return values_of(u), fun


def check_control(run) -> None:
    """Refuse a run whose control never moves: it holds no control power to match.

    Raises
    ------
    HesspipeError
        Naming the run's file and the control column.
    """
    control = np.asarray(run.control, dtype=float)
    if control.size and float(np.ptp(control)) == 0.0:
        raise HesspipeError(f"{run.source or run.id}: column 'control' is {control[0]:g} throughout: "
                            "no control power, nothing to identify; expected the pilot's control signal")


def identify(run, plants, model="original", *, free: Sequence[str] | None = None,
             fixed: Mapping[str, float] | None = None, seed: int = 0, passes: int = 10,
             optimizer: str = "apid", band=(0.0, 5.0), k: int | None = None,
             fields: Mapping[str, Field | tuple] | None = None, psd_method: str = "paper",
             with_benchmark: bool = True, with_identifiability: bool = True,
             limits: CrossoverLimits = CrossoverLimits(),
             initial: Mapping[str, float] | None = None, restarts: int = 4,
             coding: str = "gray", criterion: str = "paper", frf=None) -> Identification:
    """Identify pilot parameters from a measured run by matching control PSDs.

    Parameters
    ----------
    run : hesspipe.formats.Run
        Measured (or synthetic) run: disturbance, output, control.
    plants : hesspipe.formats.Plants
    model : PilotModel or str
        "original", "expanded", "original+remnant", ...
    free : sequence of str, optional
        Parameters to identify (default: Ke, K1, K2 and the effects' parameters,
        less any fixed). Empty: no search, the fixed/default values are evaluated.
    fixed : mapping, optional
        Parameters held at given values (others not free: Table 1 defaults, the
        loop gains Ke, Km, Ko scaled by :func:`hesspipe.hess.gain_scale` of `plants`).
    seed : int
        APID's random chromosome and bit orders; differential evolution's seed;
        the remnant noise seed.
    passes : int
        APID pass budget (scipy optimisers scale their budgets with it).
    optimizer : {"apid", "scipy", "differential_evolution"}
        "scipy" is bounded Powell from the default values (deterministic, cheap).
    band : (lo, hi)
        Fitness band, Hz.
    k : int, optional
        Table 1 column (1: plant ~ K/s, 2: ~ K/s^2) unless ``fixed["k"]``;
        None: Hess's rule on the plant (:func:`hesspipe.criteria.choose_k`).
    fields : mapping, optional
        APID bit fields name → Field or (bits, scale, offset); must lie in the
        parameter's bounds. Default :func:`default_fields` (Table 1's, the loop
        gains' spans scaled to the plants).
    with_benchmark, with_identifiability : bool
        Compute the McRuer benchmark score / the identifiability analysis.
    restarts : int
        APID: independent climbs from random chromosomes (seeds spawned from
        `seed` by numpy's SeedSequence); the best is kept. 1: the paper's single climb.
    coding : {"gray", "binary"}
        APID: bits → integer by Gray code (default; no Hamming cliffs, so a
        climb stalls far less) or plain binary (the paper).
    criterion : {"paper", "df", "output"}
        "paper": Eq. 10 (control PSD), searched as above. "df" / "output":
        phase-aware criteria of :mod:`hesspipe.criteria` (describing-function
        error at the excited lines / control output error), multi-start
        least squares (`restarts` starts); tau0, wn, zn free by default.
    frf : hesspipe.frf.Frf, optional
        The run's nonparametric describing function (estimated if None).

    Raises
    ------
    HesspipeError
        Unknown parameter, bad field, record shorter than one segment, unstable Yd.
        Never for unstable parameter sets.
    """
    from .criteria import check_criterion, choose_k, identify_phase_aware

    model = model_from_name(model)
    criterion = check_criterion(criterion)
    if fixed and "k" in fixed:
        k_rule = f"k = {int(round(float(fixed['k'])))} (given)"
    elif k is None:
        k, k_rule = choose_k(plants)
    else:
        k_rule = f"k = {k} (given)"
    seed = check_seed(seed)
    check_control(run)
    if criterion != "paper":
        # The band and PSD method still define the control PSDs reported beside the fit.
        return identify_phase_aware(run, plants, model, criterion=criterion, free=free, fixed=fixed,
                                    seed=seed, k=k, k_rule=k_rule, limits=limits,
                                    with_benchmark=with_benchmark, frf=frf, starts=restarts,
                                    initial=initial, fields=fields, band=band, psd_method=psd_method)
    if optimizer not in OPTIMIZERS:
        raise HesspipeError(f"optimizer: expected one of {', '.join(OPTIMIZERS)}, got {optimizer!r}")
    where = run.source or run.id
    nper = PaperWelch().nperseg
    if len(run) < nper:
        raise HesspipeError(f"{where}: {len(run)} samples is shorter than one spectral segment "
                            f"({nper} samples); expected a longer record")
    base, free, fixed, flds, gain = _resolve(model, free, fixed, k, fields, plants)
    obj = SpectralObjective(run, plants, model, base, band=band, psd_method=psd_method,
                            noise_seed=seed)
    climb = None
    if not free:
        # Nothing to search: evaluate the given parameters (e.g. Table 5's
        # "expanded with Km fixed" row, which reuses the original's values).
        values, best, optimizer = {}, obj({}), "none"
    elif optimizer == "apid":
        if int(restarts) < 1:
            raise HesspipeError(f"restarts: expected at least 1, got {restarts!r}")
        # Independent streams per climb: restarts of seed 0 and seed 1 share nothing.
        seeds = [int(c.generate_state(1)[0]) for c in np.random.SeedSequence(seed).spawn(int(restarts))]
        for i, climb_seed in enumerate(seeds):
            c = bit_climb(obj, flds, passes=passes, seed=climb_seed,
                          initial=initial if i == 0 else None, coding=coding)
            if climb is None or c.fitness < climb.fitness:
                climb = c
        values, best = climb.values, climb.fitness
    else:
        x0 = dict(base)
        x0.update(initial or {})
        values, best = _scipy_search(obj, flds, x0, optimizer=optimizer, seed=seed, passes=passes)
    evaluations = obj.calls
    params = obj.params(values)
    loop = obj.sim.prepare(model.loop(params))
    sim_psd = obj.loop_psd(loop)
    stable = sim_psd is not None
    cross = loop_crossover(loop, obj.sim.yc_block, limits)
    ident = (identifiability(obj, values, flds) if with_identifiability and stable and flds
             else {"method": "not computed" if stable else "optimum unstable"})
    bench_fit, bench_par = float("nan"), {}
    if with_benchmark:
        b = benchmark(run, plants, band=band, psd_method=psd_method)
        bench_fit, bench_par = b.fitness, b.parameters
    return Identification(
        model=model.name, parameters=params, free=free, fixed=fixed,
        fitness=best if np.isfinite(best) else unstable_fitness(float("nan")), benchmark_fitness=bench_fit,
        crossover=cross, evaluations=evaluations, identifiability=ident,
        measured_psd=obj.measured, simulated_psd=sim_psd if stable else np.full_like(obj.measured, np.nan),
        freq_hz=obj.freq_hz, optimizer=optimizer, seed=seed, passes=passes,
        band=obj.band, psd_method=psd_method, run_id=run.id, restarts=int(restarts), coding=coding, synthetic=run.synthetic, stable=stable,
        benchmark_parameters=bench_par, fields={f.name: (f.bits, f.scale, f.offset) for f in flds},
        climb=climb, gain_scale=gain, k_rule=k_rule,
        primary_crossover=loop_crossover(loop, obj.sim.yc_block, limits, first=True), frf=frf if frf is not None else _try_frf(run, plants, seed))


def _try_frf(run, plants, seed):
    """The run's nonparametric describing function, or why there is none (a string)."""
    from .frf import estimate_frf

    try:
        return estimate_frf(run, plants, seed=seed)
    except HesspipeError as exc:
        return f"no nonparametric estimate: {exc}"


def identifiability(objective: SpectralObjective, values: Mapping[str, float],
                    fields: Sequence[Field], *, rel_step: float = 1e-3,
                    tol: float = NULL_TOL) -> dict:
    """Which free parameters the spectral fit can separate, at `values`.

    The columns of the Jacobian of the in-band simulated PSD with respect to
    each free parameter, scaled by the parameter's size (relative
    sensitivities; the field span for a parameter at zero), are decomposed
    by SVD. A right singular vector whose singular value is below `tol`
    times the largest is a direction the data cannot see; it is confirmed by
    a profile scan (fitness at +-10 % along it) and described, e.g. "K1*K2
    only" for a (+1, -1) direction in log coordinates.

    Returns
    -------
    dict
        ``method, rank, n_free, relative_singular_values, unidentifiable
        (list of {parameters, kind, direction, relative_singular_value,
        meaning, profile_fitness_change}), weak (directions with relative
        singular value below WEAK_TOL), identifiable (names not in a null
        direction), identified_products, summary``.
    """
    names = [f.name for f in fields]
    mask = objective.mask
    x = np.array([values[n] for n in names], dtype=float)
    scale = np.array([abs(v) if abs(v) > 1e-6 * (f.hi - f.lo) else (f.hi - f.lo)
                      for v, f in zip(x, fields)])

    def band_psd(xv):
        out = objective.simulated_psd(dict(zip(names, xv)))
        return None if out is None else out[mask]

    p0 = band_psd(x)
    cols = []
    for i in range(len(names)):
        h = rel_step * scale[i]
        xp, xm = x.copy(), x.copy()
        xp[i] += h
        xm[i] -= h
        pp, pm = band_psd(xp), band_psd(xm)
        if pp is not None and pm is not None:
            cols.append((pp - pm) / (2 * rel_step))
        elif pp is not None:
            cols.append((pp - p0) / rel_step)
        elif pm is not None:
            cols.append((p0 - pm) / rel_step)
        else:
            cols.append(np.zeros_like(p0))
    jac = np.column_stack(cols)
    _, sv, vt = np.linalg.svd(jac, full_matrices=False)
    top = sv[0] if sv.size and sv[0] > 0 else 1.0
    rel = sv / top
    f0 = objective(values)
    unident = []
    involved: set[str] = set()
    for j, r in enumerate(rel):
        if r >= tol:
            continue
        v = vt[j] / np.max(np.abs(vt[j]))
        big = [i for i in range(len(names)) if abs(v[i]) > 0.1]
        # Profile: move 10 % along the direction (relative coordinates).
        changes = []
        for sgn in (1.0, -1.0):
            xv = x * np.exp(sgn * 0.1 * v) if np.all(x[big] > 0) else x + sgn * 0.1 * v * scale
            changes.append(objective(dict(zip(names, xv))) - f0)
        kind, meaning = _meaning([names[i] for i in big], v[big])
        unident.append({"parameters": [names[i] for i in big], "kind": kind,
                        "direction": {names[i]: float(v[i]) for i in big},
                        "relative_singular_value": float(r), "meaning": meaning,
                        "profile_fitness_change": float(max(abs(c) for c in changes)),
                        "profile_relative_change": float(max(abs(c) for c in changes) / max(f0, 1e-300))})
        involved.update(names[i] for i in big)
    weak = []
    for j, r in enumerate(rel):
        if tol <= r < WEAK_TOL:
            v = vt[j] / np.max(np.abs(vt[j]))
            big = [i for i in range(len(names)) if abs(v[i]) > 0.1]
            weak.append({"parameters": [names[i] for i in big],
                         "direction": {names[i]: float(v[i]) for i in big},
                         "relative_singular_value": float(r),
                         "meaning": "only weakly separated: " + ", ".join(
                             f"{v[i]:+.2f} ln {names[i]}" for i in big) + " is poorly determined"})
    rank = int(np.sum(rel >= tol))
    ident = [n for n in names if n not in involved]
    summary = (f"all {len(names)} free parameters identifiable (rank {rank})" if not unident else
               f"rank {rank} of {len(names)}: " + "; ".join(u["meaning"] for u in unident))
    if weak:
        summary += f"; {len(weak)} weakly identified direction(s)"
    products = {}
    for u in unident:
        if u["kind"] == "product":
            a, b = u["parameters"]
            products[f"{a}*{b}"] = float(values[a] * values[b])
    return {"method": "SVD of the relative-sensitivity Jacobian of the in-band PSD, with a "
                      "profile scan along each null direction",
            "rank": rank, "n_free": len(names), "tolerance": tol,
            "relative_singular_values": rel.tolist(), "unidentifiable": unident,
            "weak_tolerance": WEAK_TOL, "weak": weak,
            "identifiable": ident, "identified_products": products, "summary": summary}


def _meaning(names, coeffs) -> tuple[str, str]:
    """Classify a null direction given in relative (log) coordinates."""
    if len(names) == 1:
        return "insensitive", f"{names[0]} has no effect on the control spectrum"
    if len(names) == 2 and abs(abs(coeffs[0]) - abs(coeffs[1])) < 0.05:
        a, b = names
        if coeffs[0] * coeffs[1] < 0:
            return "product", f"{a} and {b} enter only as the product {a}*{b}"
        return "ratio", f"{a} and {b} enter only as the ratio {a}/{b}"
    return "combination", "only a combination of " + ", ".join(names) + " is determined"
