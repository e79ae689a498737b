"""Pilot-parameter identification by spectral matching (the paper's APID).

The measured control PSD (:mod:`hesspipe.identification.spectra`) is compared with the PSD
of the control simulated by the pilot model closed around the plants and
driven by the measured disturbance (:class:`hesspipe.pilot.simulation.Simulator`). The
free parameters are searched by the bit-climbing GA (:mod:`hesspipe.identification.apid`)
or by a scipy optimiser over the same box. Parameter sets whose closed loop
is not stable on the record (growth rate at or above
:func:`hesspipe.pilot.simulation.growth_limit`, ln 2 / duration: a mode that more than
doubles over the record) get :data:`~hesspipe.pilot.simulation.UNSTABLE_FITNESS` (1e12)
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

import dataclasses
import hashlib
from typing import Mapping, Sequence

import numpy as np
from scipy.optimize import differential_evolution

from ..core.choices import OPTIMIZERS  # one list, in a light module: the command line reads it too
from ..core.errors import HesspipeError
from ..core.formats import as_plants, as_runs, siso_coefficients
from ..core.paper import FITNESS_BAND_HZ, WELCH_SEGMENT
from ..core.seeds import check_seed
from ..pilot.crossover import CrossoverLimits, loop_crossover, tracking_crossover
from ..pilot.hess import PilotModel, model_from_name
from ..pilot.mcruer import bounded_powell, fit_precision
from ..pilot.simulation import unstable_fitness
from ..plants.consistency import check_consistent
from .apid import Field, bit_climb
from .criteria import check_criterion, choose_k, identify_phase_aware
from .frf import estimate_frf
from .frf_average import average_frf
from .problem import (
    Identification,
    SpectralObjective,
    _resolve,
)

# Relative singular values below NULL_TOL: not identifiable (a structural
# null direction, e.g. K1*K2, sits at 1e-10 or below); below WEAK_TOL: only
# weakly identifiable (a 1 % change along it moves the in-band PSD by less
# than 3e-4 of the strongest direction's change).
NULL_TOL = 1e-4
WEAK_TOL = 3e-2


_BENCHMARK_CACHE: dict = {}


def _benchmark_key(run, plants, band, psd_method) -> str:
    h = hashlib.sha1()
    for arr in (run.control, run.disturbance, run.reference, run.time[:2]):
        h.update(np.ascontiguousarray(arr, dtype=float).tobytes())
    for sys in (plants.control_to_output, plants.disturbance_to_output):
        h.update(repr(tuple(c.tolist() for c in siso_coefficients(sys))).encode())
    h.update(repr((band, psd_method)).encode())
    return h.hexdigest()


def benchmark(run, plants, *, band=FITNESS_BAND_HZ, psd_method: str = "paper"):
    """McRuer precision-model fit to `run` (cached per run, plants, band, method).

    Parameters
    ----------
    run : hesspipe.core.formats.Run
        The measured run.
    plants : hesspipe.core.formats.Plants
    band : (float, float)
        Fitness band, Hz.
    psd_method : {"paper", "scipy"}
        PSD estimate.

    Returns
    -------
    PrecisionFit
        Parameters and Eq. 10 fitness (control^2/Hz) of the benchmark.
    """

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

    Parameters
    ----------
    run : hesspipe.core.formats.Run
        The measured run.

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
             optimizer: str = "apid", band=FITNESS_BAND_HZ, k: int | None = None,
             fields: Mapping[str, Field | tuple] | None = None, psd_method: str = "paper",
             with_benchmark: bool = True, with_identifiability: bool = True,
             limits: CrossoverLimits = CrossoverLimits(),
             initial: Mapping[str, float] | None = None, restarts: int = 4,
             coding: str = "gray", criterion: str = "paper", frf=None,
             check_plants: bool = True) -> Identification:
    """Identify pilot parameters from a measured run by matching control PSDs.

    Parameters
    ----------
    run : hesspipe.core.formats.Run or sequence of Run
        Measured (or synthetic) run: disturbance, output, control. Several runs of one
        pilot in one condition (repeats of one multisine forcing) are fitted through their
        averaged describing function (:func:`~hesspipe.identification.frf_average.average_frf`;
        criterion "df" only); the reported spectra and the run id are the first run's.
    plants : hesspipe.core.formats.Plants
    model : PilotModel or str
        "original", "expanded", "original+remnant", ...
    free : sequence of str, optional
        Parameters to identify (default: Ke, K1, K2 and the effects' parameters,
        less any fixed). Empty: no search, the fixed/default values are evaluated.
    fixed : mapping, optional
        Parameters held at given values (others not free: Table 1 defaults, the
        loop gains Ke, Km, Ko scaled by :func:`hesspipe.pilot.crossover.gain_scale` of `plants`).
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
        None: Hess's rule on the plant (:func:`hesspipe.identification.criteria.choose_k`).
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
        phase-aware criteria of :mod:`hesspipe.identification.criteria` (describing-function
        error at the excited lines / control output error), multi-start
        least squares (`restarts` starts); tau0, wn, zn free by default.
    frf : hesspipe.identification.frf.Frf, optional
        The run's nonparametric describing function (estimated if None).
    check_plants : bool
        Refuse a run whose columns' sign or units the plants show to be wrong
        (:func:`hesspipe.plants.consistency.check_consistent`); callers that checked already
        pass False.

    Raises
    ------
    HesspipeError
        Unknown parameter, bad field, record shorter than one segment, unstable Yd, a
        column's sign or units at odds with the plants.
        Never for unstable parameter sets.
    """

    model = model_from_name(model)
    criterion = check_criterion(criterion)
    runs = as_runs(run)
    plants = as_plants(plants)
    if not runs:
        raise HesspipeError("run: expected at least one run, got none")
    if criterion != "df" and len(runs) > 1:
        raise HesspipeError(f"criterion: {len(runs)} runs are fitted through their averaged "
                            f"describing function, which only criterion 'df' uses; got {criterion!r}")
    for one in runs:
        check_control(one)
        if check_plants:
            check_consistent(one, plants)
    if len(runs) > 1 and frf is None:
        frf = average_frf(runs, plants, seed=check_seed(seed))
    run = runs[0]
    if fixed and "k" in fixed:
        k_rule = f"k = {int(round(float(fixed['k'])))} (given)"
    elif k is None:
        k, k_rule = choose_k(plants)
    elif isinstance(k, bool) or k not in (1, 2):
        raise HesspipeError(f"k: expected Table 1's column 1 (a K/s-like plant) or 2 (K/s^2-like), got {k!r}")
    else:
        k_rule = f"k = {k} (given)"
    seed = check_seed(seed)
    if isinstance(restarts, bool) or not isinstance(restarts, (int, np.integer)) or restarts < 1:
        raise HesspipeError(f"restarts: expected an integer >= 1, got {restarts!r}")
    if criterion != "paper":
        # The band and PSD method still define the control PSDs reported beside the fit.
        result = identify_phase_aware(run, plants, model, criterion=criterion, free=free, fixed=fixed,
                                      seed=seed, k=k, k_rule=k_rule, limits=limits,
                                      with_benchmark=with_benchmark, frf=frf, starts=restarts,
                                      initial=initial, fields=fields, band=band, psd_method=psd_method)
        if len(runs) > 1:
            result = dataclasses.replace(result, run_id=frf.run_id or result.run_id)
        return result
    if optimizer not in OPTIMIZERS:
        raise HesspipeError(f"optimizer: expected one of {', '.join(OPTIMIZERS)}, got {optimizer!r}")
    where = run.source or run.id
    nper = WELCH_SEGMENT
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
        primary_crossover=tracking_crossover(loop, obj.sim.yc_block, len(run.time) * run.dt, limits), frf=frf if frf is not None else _try_frf(run, plants, seed))


def _try_frf(run, plants, seed):
    """The run's nonparametric describing function, or why there is none (a string)."""

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

    Parameters
    ----------
    objective : SpectralObjective
        The fit's objective.
    values : mapping
        The fitted free parameters, name → value.
    fields : sequence of Field
        Their bit fields (spans scale parameters at zero).
    rel_step : float
        Relative finite-difference step.
    tol : float
        Relative singular value below which a direction is unidentifiable.

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
