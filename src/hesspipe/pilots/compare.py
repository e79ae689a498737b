"""Compare pilots: each run identified with three model configurations.

For every pilot (one measured run) the paper's Table 5 is rebuilt:

``original``
    the original Hess structural model, Ke, K1, K2 identified by APID;
``expanded_fixed``
    the expanded model (motion feedback added) with the *original's*
    identified parameters and Km fixed at Table 1's value (0.1) — not
    re-identified, as in the paper's "Exp." row;
``expanded``
    the expanded model with Ke, K1, K2 and Km identified together; by default
    its search starts from ``expanded_fixed`` and the two models' searches
    exchange optima (see :class:`CompareSettings`), so the expanded model,
    which contains the original at Km = 0, never ends worse than it.

``improvement = 1 - expanded.fitness / original.fitness`` (fitness is the
RMS difference of control PSDs, lower is better; the paper reports about
0.5 on average). Pilots are processed as a batch by :mod:`hesspipe.pilots.batch`;
every pilot's seeds are derived from the base seed and its id, so results do
not depend on the order or the number of workers. A file that cannot be
read or identified is reported with its error and does not stop the batch.
"""

from __future__ import annotations

import functools
import math
from dataclasses import replace
from pathlib import Path
from typing import Callable, Mapping, Sequence

import numpy as np

from ..core._listing import list_runs  # noqa: F401  (re-exported: the pilots API)
from ..core.errors import HesspipeError
from ..core.formats import (
    Plants,
    Run,
    as_plants,
    as_runs,
    check_sample_rate,
    parse_columns,
    plants_coefficients,
    read_file_runs,
)
from ..core.paper import FITNESS_BAND_HZ
from ..core.seeds import derive_seed
from ..flight.target import named_forcing
from ..identification.criteria import choose_k
from ..identification.fit import benchmark as mcruer_benchmark
from ..identification.fit import identify
from ..identification.frf_average import check_repeats
from ..identification.problem import SpectralObjective
from ..pilot.crossover import crossover_fields, gain_scale, loop_crossover, tracking_crossover
from ..pilot.hess import PilotModel, model_from_name
from ..pilot.motion import motion_path_note
from ..plants.consistency import check_consistent
from .batch import run_batch
from .cohort import cohort_spec, synth_cohort

# The stage's settings live in .settings and its text in .report; their names are imported
# here too, where users and older code look for them.
from .report import TABLE_PARAMETERS, _fmt, format_table, write_comparison  # noqa: F401
from .results import Comparison, PilotComparison, PilotFailure
from .settings import (  # noqa: F401
    CONFIGURATIONS,
    MIN_SAMPLES,
    OPTIMIZERS,
    SIMULATORS,
    STARTS,
    CompareSettings,
    PilotsConfig,
)
from .verdict import ALPHA, pilot_groups, safe_motion_test

# -- one pilot ------------------------------------------------------------------------------

def _km_fixed(settings: CompareSettings, plants) -> float:
    if settings.km_fixed is not None:
        return float(settings.km_fixed)

    # Table 1's Km, in the same plant-gain units as the identification's defaults.
    return float(PilotModel(("motion_feedback",)).defaults(settings.k, gain_scale(plants, settings.k))["Km"])


def evaluate(run: Run, plants: Plants, model, params: Mapping[str, float], *,
             band: tuple[float, float] = FITNESS_BAND_HZ, k: int = 1, benchmark: bool = False,
             criterion: str = "paper", frf=None) -> dict:
    """Fitness and crossover of fixed parameters on a run, nothing identified.

    Returns a dict with the keys of ``Identification.to_dict(spectra=False)``
    that apply (``free`` empty, ``evaluations`` 1) plus ``simulated_psd``.

    Parameters
    ----------
    run, plants : Run, Plants
        The run; Yc and Yd.
    model, params : PilotModel or str, mapping of str to float
        The model (or its name) and its parameters (completed strictly for order `k`).
    band : (float, float)
        Frequency band of the fitness, Hz.
    k : int
        Hess model order.
    benchmark : bool
        Also fit the McRuer benchmark (its fitness otherwise NaN).
    criterion, frf
        As in :func:`hesspipe.identification.fit.identify` ("paper", "df" or "output").
    """

    model = model_from_name(model)
    complete = model.complete(params, k, strict=True)
    if criterion != "paper":
        # Looked up at call time: tests intercept identification.fit.identify here.
        from ..identification.fit import identify

        res = identify(run, plants, model, free=(), fixed=complete, k=k, band=band,
                       with_benchmark=benchmark, with_identifiability=False, criterion=criterion,
                       frf=frf, check_plants=False)
        out = res.to_dict(spectra=False)
        out.update(free=[], evaluations=1,
                   identifiability={"method": "not computed: nothing identified"},
                   simulated_psd=res.simulated_psd)
        return out
    obj = SpectralObjective(run, plants, model, complete, band=band)
    loop = obj.sim.prepare(model.loop(complete))
    sim_psd = obj.loop_psd(loop)
    fit = obj.psd_fitness(sim_psd) if sim_psd is not None else obj.unstable_fitness(loop)  # never NaN
    bench_fit, bench_par = math.nan, {}
    if benchmark:
        bench = mcruer_benchmark(run, plants, band=band)
        bench_fit, bench_par = bench.fitness, dict(bench.parameters)
    return {"model": model.name, "run_id": run.id, "synthetic": run.synthetic,
            "parameters": complete, "free": [], "fixed": complete, "fitness": fit,
            "benchmark_fitness": bench_fit, "benchmark_parameters": bench_par,
            **crossover_fields(tracking_crossover(loop, obj.sim.yc_block, len(run.time) * run.dt),
                               loop_crossover(loop, obj.sim.yc_block)), "evaluations": 1,
            "identifiability": {"method": "not computed: nothing identified"},
            "band_hz": list(obj.band), "stable": sim_psd is not None,
            "simulated_psd": sim_psd if sim_psd is not None else np.full_like(obj.measured, np.nan)}


#: Round trips of :func:`_exchange` (each: one climb per model); pathological pilots whose
#: climbs run out of passes would otherwise ping-pong for long.
KM_INTERVAL = 0.95
"""Confidence level of each pilot's profile-likelihood interval of Km in the motion verdict
(:func:`hesspipe.identification.motion_test.motion_test`'s ``interval``)."""
EXCHANGE_ROUNDS = 3


def _exchange(run, plants, original, expanded, seed, common):
    """Give each model the best point the other's search found, by warm-started searches.

    The expanded model contains the original (Km = 0). An expanded optimum
    that beats the original with Km ~ 0 only shows that the original's search
    stopped early; a local search of the original from that point (Km
    removed) gives the original that fit too. Conversely the expanded search
    searches from the original's optimum with Km = 0 (and :func:`compare_run`
    falls back to exactly that point, see :func:`_reduced`, if it still ends
    worse: the climb's bit fields cannot represent a polished optimum exactly).
    Repeated until the original stops improving (at most
    :data:`EXCHANGE_ROUNDS` times): the improvement then measures what Km
    adds, not search luck. Returns the two results and the evaluations spent.
    """
    spent = {"original": 0, "expanded": 0}

    def local(model, key, initial):
        # One climb from `initial` (a climb never ends worse than its start; Powell alone can,
        # when a line search runs into an unstable corner) and its polish.
        result, n = _search(run, plants, model, seed(key), {**common, "restarts": 1}, initial)
        spent[model] += n
        return result

    for r in range(EXCHANGE_ROUNDS):
        if expanded.fitness > original.fitness:
            forth = local("expanded", f"expanded-{r}", {**original.parameters, "Km": 0.0})
            if forth.fitness < expanded.fitness:
                expanded = forth
        back = local("original", f"original-{r}",
                     {n: v for n, v in expanded.parameters.items() if n != "Km"})
        if not back.fitness < original.fitness:
            break
        original = back
    return original, expanded, spent


def _reduced(original: dict) -> dict:
    """The original's result as an expanded-model result with Km = 0 (the same loop)."""
    return {**original, "model": "expanded", "parameters": {**original["parameters"], "Km": 0.0},
            "free": list(original.get("free", [])) + ["Km"], "identifiability": {
                "method": "not computed: the original's optimum with Km = 0"},
            "note": "no expanded search beat the original; Km = 0 reduces the expanded model "
                    "to the original, so this is its best known point"}


def _polish(run, plants, model, initial, seed, common):
    """Bounded Powell from `initial` over the same free parameters and box."""

    return identify(run, plants, model, seed=seed, initial=initial,
                    **{**common, "optimizer": "scipy", "restarts": 1})


def _search(run, plants, model, seed, common, initial=None):
    """APID (or the chosen optimizer), then a local polish from its result; the better is kept.

    Binary-coded bit climbing stalls in narrow valleys (lightly damped loops
    give sharp spectral peaks): a continuous local search from its result
    finishes the job. Returns the result and the evaluations spent.
    """

    first = identify(run, plants, model, seed=seed, initial=initial, **common)
    if common["optimizer"] == "scipy" or common.get("criterion", "paper") != "paper":
        # Phase-aware criteria are fitted by multi-start least squares: already local.
        return first, first.evaluations
    polished = _polish(run, plants, model, first.parameters, seed, common)
    # NaN (an unstable end point) never compares smaller: the climb's result is kept then.
    best = polished if polished.fitness < first.fitness else first
    return best, first.evaluations + polished.evaluations


def _with_k(settings: CompareSettings, plants: Plants) -> CompareSettings:
    """`settings` with ``k`` chosen by Hess's rule on the control plant when it is None."""
    if settings.k is not None:
        return settings

    return replace(settings, k=choose_k(plants)[0])


def pilot_motion_test(run: Run, plants: Plants, start: Mapping[str, float], settings: CompareSettings) -> dict:
    """A pilot's motion test as the cohort verdict reads it
    (:func:`hesspipe.identification.motion_test.safe_motion_test`, the 95 % intervals of Km
    and Km/|Ke|); where motion is not named, the motion path's likely mistakes are tried
    too (``path_check``), so the cohort verdict can say a wrong path
    (:func:`hesspipe.pilots.verdict.path_verdict`).

    Parameters
    ----------
    run : Run
        The pilot's run.
    plants : Plants
        Yc, Yd and the optional motion path.
    start : mapping
        Starting pilot parameters (the original model's fit).
    settings : CompareSettings
        ``k`` (resolved, 1 or 2), ``band`` (Hz) and ``display``.

    Returns
    -------
    dict
        The test's result.
    """
    return safe_motion_test(run, plants, start, k=settings.k, band_hz=tuple(settings.band),
                            interval=KM_INTERVAL, display=settings.display, path_check=ALPHA)


def compare_run(run: Run, plants: Plants, settings: CompareSettings = CompareSettings()) -> PilotComparison:
    """Identify the three configurations on one run.

    Parameters
    ----------
    run : Run
        One pilot's record.
    plants : Plants
        Yc (control → roll rate) and Yd (wind → roll rate).
    settings : CompareSettings

    Returns
    -------
    PilotComparison
    """
    settings = _with_k(settings, plants)
    check_consistent(run, plants)   # once here; the searches below skip it
    common = dict(optimizer=settings.optimizer, passes=settings.passes, band=tuple(settings.band),
                  k=settings.k, restarts=settings.restarts, with_benchmark=settings.benchmark,
                  check_plants=False)
    frf = None
    if settings.criterion != "paper":
        # Looked up at call time, like identify above.
        from ..identification.frf import estimate_frf

        # One nonparametric estimate serves every configuration's fit.
        frf = estimate_frf(run, plants, seed=settings.seed)
        common.update(criterion=settings.criterion, frf=frf)
    seed = functools.partial(derive_seed, settings.seed, run.id)
    km = _km_fixed(settings, plants)
    spent = {}
    original, spent["original"] = _search(run, plants, "original", seed("original"), common)
    warm = settings.start == "warm"
    # Step 3 re-tunes from step 2 ("warm"): the first of APID's climbs starts at expanded_fixed
    # (the original's optimum, Km fixed), the others at random, as many as the original had.
    initial = {**original.parameters, "Km": km} if warm else None
    expanded, spent["expanded"] = _search(run, plants, "expanded", seed("expanded"), common, initial)
    if warm:
        original, expanded, more = _exchange(run, plants, original, expanded, seed, common)
        spent = {m: spent[m] + more[m] for m in spent}
    # The paper's "Exp." row: the original's parameters with the motion path added at a fixed
    # gain, evaluated rather than re-fitted.
    fixed = evaluate(run, plants, "expanded", {**original.parameters, "Km": km},
                     band=settings.band, k=settings.k, benchmark=settings.benchmark,
                     criterion=settings.criterion, frf=frf)
    mask = np.asarray(original.freq_hz) <= settings.band[1]
    fixed_psd = fixed.pop("simulated_psd")
    # "evaluations"/"optimizer" are the kept search's; "evaluations_total" everything spent.
    search = (f"{settings.optimizer} ({settings.restarts} restarts) + local Powell polish"
              + (", optima exchanged between the models" if warm else ""))
    original_d = {**original.to_dict(spectra=False), "evaluations_total": spent["original"],
                  "search": search}
    expanded_psd = expanded.simulated_psd
    if warm and not expanded.fitness <= original.fitness:
        expanded_d, expanded_psd = _reduced(original_d), original.simulated_psd
    else:
        expanded_d = expanded.to_dict(spectra=False)
    expanded_d.update(evaluations_total=spent["expanded"], search=search)
    o_fit, e_fit = original_d["fitness"], expanded_d["fitness"]
    # Undefined (NaN) when either optimum is unstable: their scores are penalties, not fits.
    improvement = (1.0 - e_fit / o_fit if original_d.get("stable", True) and expanded_d.get("stable", True)
                   and o_fit and math.isfinite(o_fit) and o_fit > 0 else math.nan)
    return PilotComparison(
        id=run.id, source=run.source, synthetic=run.synthetic,
        original=original_d, expanded_fixed=fixed, expanded=expanded_d, improvement=float(improvement),
        motion_test=pilot_motion_test(run, plants, original.parameters, settings),
        freq_hz=np.asarray(original.freq_hz)[mask], measured_psd=np.asarray(original.measured_psd)[mask],
        simulated_psd={"original": np.asarray(original.simulated_psd)[mask],
                       "expanded_fixed": np.asarray(fixed_psd)[mask],
                       "expanded": np.asarray(expanded_psd)[mask]},
        frf=frf if frf is not None else (original.frf if not isinstance(original.frf, str) else None))


def _guarded(job, run: Run):
    """Run `job(run)`; turn any exception into a PilotFailure so the batch goes on."""
    where = run.source or run.id
    try:
        return job(run)
    except HesspipeError as exc:
        msg = str(exc)
    except Exception as exc:  # noqa: BLE001 - one pilot's crash must not lose the others
        msg = f"{type(exc).__name__}: {exc}"
    return PilotFailure(run.id, run.source, msg if msg.startswith(where) else f"{where}: {msg}")


# -- many pilots ------------------------------------------------------------------------------

def read_runs(paths: Sequence[Path], *, columns=None, resample: bool = False,
              min_samples: int = MIN_SAMPLES, sample_rate: float | None = None
              ) -> tuple[list[Run], list[PilotFailure]]:
    """Read every file; a bad file becomes a :class:`PilotFailure`, not an exception.

    Returns ``(runs, failures)`` in file order; a repeated pilot id is a failure too.

    Parameters
    ----------
    paths : sequence of Path
        The run files.
    columns, resample, min_samples, sample_rate
        Passed to :func:`hesspipe.core.formats.read_file_runs` (a file may hold several runs).
    """
    runs, failures = [], []
    seen: dict[str, str] = {}
    for path in paths:
        try:
            found = read_file_runs(path, columns=columns, resample=resample, min_samples=min_samples,
                                   sample_rate=sample_rate)
        except HesspipeError as exc:
            failures.append(PilotFailure(Path(path).stem, str(path), str(exc), unread=True))
            continue
        for run in found:
            if run.id in seen:
                failures.append(PilotFailure(run.id, run.source, f"{run.source}: run id {run.id!r} repeats "
                                             f"{seen[run.id]}; expected each file name (the run's id) once"))
                continue
            seen[run.id] = run.source
            runs.append(run)
    return runs, failures


def compare_pilots(paths_or_dir, plants: Plants, settings: CompareSettings | None = None, *,
                   workers: int | None = None, scheduler: str | None = None, columns=None,
                   resample: bool = False, progress: bool | None = None, job=None,
                   pilot_id: str | None = None, sample_rate: float | None = None,
                   on_read: Callable[[dict, tuple], None] | None = None, **fields) -> Comparison:
    """Identify original, expanded-fixed-Km and expanded models on each pilot's run.

    Parameters
    ----------
    paths_or_dir : path, iterable of paths, Run or list of Run
        A folder of run files (the file stem is the pilot id), the files, or runs already
        read or built in memory (each run's id is the pilot id).
    plants : Plants
        Yc (control → roll rate) and Yd (lateral wind ft/s → roll rate rad/s).
    workers : int, optional
        Local processes (default all cores; 1: in this process).
    scheduler : str, optional
        Dask distributed scheduler address; the work is submitted there instead.
    settings : CompareSettings, optional
        What every identification uses (default ``CompareSettings()``).
    **fields
        Fields of :class:`CompareSettings` replacing those of `settings`, e.g.
        ``compare_pilots(folder, plants, seed=3, restarts=1)``.
    columns, resample, sample_rate
        Passed to :func:`hesspipe.core.formats.read_file_runs`.
    progress : bool, optional
        Progress bar (default: only on a terminal).
    job : callable, optional
        ``job(run) -> PilotComparison`` replacing the identification (tests,
        custom studies); must be picklable for workers > 1.
    pilot_id : str, optional
        Regular expression that finds the pilot in each file stem when pilots flew
        several runs (:func:`hesspipe.pilots.verdict.pilot_groups`, e.g. ``r"^(s\\d+)_"``):
        each run is still identified on its own, and the motion verdict combines a pilot's
        runs before counting pilots (in a file holding several runs, ``s01#2``, it is
        searched in the whole id). Default: each file is a pilot, its runs one pilot's.
    on_read : callable, optional
        ``on_read(reading, unread)``, called once the files are read and before any
        identification: ``reading`` maps each run's source to its reading notes, ``unread``
        holds the :class:`PilotFailure` of each file that could not be read (a command
        line says them at once, not minutes later with the table).

    Returns
    -------
    Comparison
        Bad files are listed in ``failures`` rather than raised; callers decide
        what a failure means (the CLI exits non-zero).

    Raises
    ------
    HesspipeError
        No run files at all, bad settings, or an unreachable scheduler.
    """
    plants = as_plants(plants)
    settings = _with_k(replace(settings or CompareSettings(), **fields), plants)  # validated here
    if job is None and settings.km_fixed is None:
        settings = replace(settings, km_fixed=_km_fixed(settings, plants))
    if isinstance(paths_or_dir, Run) or (isinstance(paths_or_dir, (list, tuple)) and paths_or_dir
                                         and all(isinstance(r, Run) for r in paths_or_dir)):
        runs, failures, paths = as_runs(paths_or_dir), [], []
    else:
        parse_columns(columns)  # a bad column mapping is the user's one mistake, not every file's
        paths = list_runs(paths_or_dir)
        pilot_groups([p.stem for p in paths], pilot_id, {p.stem: str(p) for p in paths})  # before any work
        check_sample_rate(sample_rate)   # the user's one mistake, not every file's
        runs, failures = read_runs(paths, columns=columns, resample=resample, sample_rate=sample_rate)
    groups = pilot_groups([r.id for r in runs], pilot_id, {r.id: r.source for r in runs},
                          {r.id: r.file_id for r in runs})
    check_repeats([], runs)   # a record copied into the folder would count its evidence twice
    if on_read is not None:
        on_read({r.source: r.notes for r in runs if r.notes}, tuple(failures))
    if job is None:
        job = functools.partial(compare_run, plants=plants, settings=settings)
    results = run_batch(functools.partial(_guarded, job), runs, workers=workers, scheduler=scheduler,
                        desc="pilots", unit="pilot", progress=progress)
    pilots = tuple(r for r in results if isinstance(r, PilotComparison))
    failures += [r for r in results if isinstance(r, PilotFailure)]
    # In file order; a run of a file holding several is 'PATH#k'.
    failures.sort(key=lambda f: next((i for i, p in enumerate(paths)
                                      if f.source == str(p) or f.source.startswith(f"{p}#")), len(paths)))

    return Comparison(pilots=pilots, failures=tuple(failures), settings=settings, groups=groups,
                      reading={r.source: r.notes for r in runs if r.notes}, plants=plants_record(plants))


def plants_record(plants: Plants) -> dict:
    """The plants' coefficients for a result's record: both paths, the cab's motion path
    where the file gives one, and the note of :func:`hesspipe.pilot.motion.motion_path_note`
    where it applies (the motion test's vestibular path rests on it).

    Parameters
    ----------
    plants : hesspipe.core.formats.Plants
        The plants the runs were identified with.

    Returns
    -------
    dict
        ``control_to_output``, ``disturbance_to_output`` and, where given,
        ``motion_path`` as ``{"num", "den"}`` (descending powers of s); ``motion_path_note``
        where it applies.
    """
    out = plants_coefficients(plants)
    note = motion_path_note(plants)
    if note:
        out["motion_path_note"] = note
    return out


def run_study(config: PilotsConfig, plants: Plants, out_dir: str | Path, *, seed: int = 0,
              progress: bool | None = None, draw: Callable | None = None) -> Comparison:
    """The pipeline's pilots stage: cohort (or data folder) → comparison files in `out_dir`.

    Without ``config.data`` a synthetic frequency-domain cohort of ``config.n`` pilots
    is written to ``out_dir/cohort`` (with ``simulator = "jsbsim"`` the pipeline's
    pilots stage has flown the cohort in JSBSim before and passes its folder as
    ``data``: :func:`hesspipe.pilots.flown.fly_pipeline_cohort`); then every run is compared and ``comparison.json``,
    ``comparison.md`` and ``figures/<pilot>.png`` are written. Failed pilots
    are listed in the outputs; the caller decides whether ``not result.ok``
    fails the stage. `draw` is :func:`write_comparison`'s, used when ``config.figures``.

    Parameters
    ----------
    config, plants : PilotsConfig, Plants
        The ``[pilots]`` settings; Yc and Yd.
    out_dir : str or Path
        Output folder.
    seed : int
        Base seed, used when ``config`` sets none.
    progress, draw
        Progress bar (default: only on a terminal); figure writer (see above).
    """

    out_dir = Path(out_dir)
    settings = config.settings(seed)
    seed = settings.seed
    if config.data:
        source = Path(config.data)
    else:
        source = out_dir / "cohort"
        synth_cohort(plants, config.n, seed, config.effects, source,
                     spec=cohort_spec(config.cohort, duration_s=config.duration_s, dt_s=config.dt_s,
                                      target=named_forcing(config.forcing)))
    result = compare_pilots(source, plants, settings, workers=config.workers or None,
                            scheduler=config.scheduler or None, columns=config.columns or None,
                            resample=config.resample, progress=progress, pilot_id=config.pilot_id or None,
                            sample_rate=config.sample_rate)
    write_comparison(result, out_dir, draw=draw if config.figures else None)
    return result


