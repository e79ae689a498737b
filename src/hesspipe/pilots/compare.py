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
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Callable, Iterable, Mapping, Sequence

import numpy as np

from ..core.config import Fields
from ..core.errors import HesspipeError
from ..core.formats import Plants, Run, _parse_columns, read_run, record_samples
from ..core.io import write_json, write_text
from ..core.seeds import MAX_SEED, check_seed, derive_seed
from ..identification.criteria import CRITERIA, DEFAULT_CRITERION, check_criterion
from .batch import run_batch
from .verdict import safe_motion_test, verdict_lines

CONFIGURATIONS = ("original", "expanded_fixed", "expanded")
#: Parameters shown in the comparison table (Table 5's columns).
TABLE_PARAMETERS = ("Ke", "K1", "K2", "Km")
#: Optimizers of :func:`hesspipe.identification.fit.identify` (each followed by a local polish).
OPTIMIZERS = ("apid", "scipy", "differential_evolution")
#: Where the expanded search starts (see :class:`CompareSettings`).
STARTS = ("warm", "random")
#: Fewest samples a run needs: one Welch segment of the paper's spectra (Eq. 9 pads the rest).
MIN_SAMPLES = 1024  # = hesspipe.identification.spectra.PaperWelch().nperseg; checked in tests


@dataclass(frozen=True)
class CompareSettings:
    """What every pilot's identification uses (picklable, sent to workers).

    Attributes
    ----------
    seed : int
        Base seed; each pilot and configuration gets
        ``derive_seed(seed, pilot_id, configuration)``.
    optimizer : str
        "apid" (the paper's bit-climbing GA, default), "scipy" (bounded Powell
        from Table 1, cheap) or "differential_evolution".
    passes : int
        APID pass budget (paper: 10).
    band : (float, float)
        Fitness band in Hz (paper: 0-5 Hz).
    k : int
        Hess model order for the controlled element (1: rate-like, the roll-rate task).
    km_fixed : float or None
        Km of the ``expanded_fixed`` configuration (None: Table 1's 0.1 times
        :func:`hesspipe.pilot.crossover.gain_scale` of the plants, like every default loop gain).
    start : {"warm", "random"}
        Every search is the optimizer (APID: `restarts` climbs, best kept)
        followed by a local bounded-Powell polish from its result. "warm"
        (default): the first climb of the expanded search starts from the
        expanded_fixed point (the paper's step 3 re-tuning step 2), its other
        restarts at random; then the two models exchange optima (the original
        searches again from the expanded optimum with Km removed, the expanded
        from the original's with Km = 0) until the original stops improving.
        Each model thus gets the best point either search found for it: the
        expanded model, which contains the original at Km = 0, is never worse,
        and the improvement measures what identifying Km adds, not search luck.
        "random": each model searched once from random chromosomes (APID as
        described); results then also carry the luck of each search.
    restarts : int
        APID climbs per identification (the best is kept). 2: with the local
        polish and the exchange of optima, 4 changed neither conclusion of
        benchmarks/bench_compare.py (measured on the first, nearly remnant-free
        cohort: mean improvement 88.3 % with motion feedback, 1.4 vs 1.6 %
        without) and costs a quarter more.
    benchmark : bool
        Also fit the McRuer precision model (the paper's benchmark score);
        off by default: it costs as much as the three configurations together.
    criterion : str
        Fit criterion of every identification (:data:`hesspipe.identification.criteria.CRITERIA`):
        "paper" (Eq. 10; the library's default, the paper's study) or a phase-aware
        one ("df", the command line's and the pipeline's default).
    """

    seed: int = 0
    optimizer: str = "apid"
    passes: int = 10
    band: tuple[float, float] = (0.0, 5.0)
    k: int = 1
    km_fixed: float | None = None
    start: str = "warm"
    restarts: int = 2
    benchmark: bool = False
    criterion: str = "paper"


@dataclass(frozen=True)
class PilotComparison:
    """The three configurations identified on one pilot's run.

    Attributes
    ----------
    id, source : str
        Pilot id (file stem) and file.
    synthetic : bool
        True if the run's file says it was generated by a model.
    original, expanded_fixed, expanded : dict
        Each the identification's ``to_dict()`` (model, parameters, fixed,
        fitness, benchmark_fitness, crossover, evaluations, identifiability).
    improvement : float
        ``1 - expanded.fitness / original.fitness`` (NaN if undefined).
    freq_hz, measured_psd : ndarray
        Frequency bins (Hz) and the measured control PSD.
    simulated_psd : dict
        Configuration name → simulated control PSD on `freq_hz`.
    """

    id: str
    source: str
    synthetic: bool
    original: dict
    expanded_fixed: dict
    expanded: dict
    improvement: float
    freq_hz: np.ndarray = field(repr=False, default_factory=lambda: np.zeros(0))
    measured_psd: np.ndarray = field(repr=False, default_factory=lambda: np.zeros(0))
    simulated_psd: dict = field(repr=False, default_factory=dict)
    frf: object = field(repr=False, default=None)
    motion_test: dict = field(default_factory=dict)   # hesspipe.pilots.verdict.motion_test

    def configuration(self, name: str) -> dict:
        """The result of configuration `name` (one of :data:`CONFIGURATIONS`)."""
        if name not in CONFIGURATIONS:
            raise HesspipeError(f"unknown configuration {name!r}; expected one of {', '.join(CONFIGURATIONS)}")
        return getattr(self, name)

    def to_dict(self, *, psd: bool = True) -> dict:
        out = {"id": self.id, "source": self.source, "synthetic": self.synthetic}
        for name in CONFIGURATIONS:
            out[name] = self.configuration(name)
        out["improvement"] = self.improvement
        out["motion_test"] = self.motion_test
        if psd:
            out["psd"] = {"freq_hz": self.freq_hz, "measured": self.measured_psd,
                          **{k: v for k, v in self.simulated_psd.items()}}
        return out


@dataclass(frozen=True)
class PilotFailure:
    """A run that could not be read or identified."""

    id: str
    source: str
    error: str

    def to_dict(self) -> dict:
        return {"id": self.id, "source": self.source, "error": self.error}


@dataclass(frozen=True)
class Comparison:
    """Result of :func:`compare_pilots`.

    Attributes
    ----------
    pilots : tuple of PilotComparison
        In the order of the input files (sorted by name for a folder).
    failures : tuple of PilotFailure
        Files that were skipped, with their errors.
    settings : CompareSettings
    plants : dict
        The plants' coefficients (for the record).
    """

    pilots: tuple[PilotComparison, ...]
    failures: tuple[PilotFailure, ...] = ()
    settings: CompareSettings = CompareSettings()
    plants: dict = field(default_factory=dict)

    @property
    def ok(self) -> bool:
        """True if every file was processed."""
        return not self.failures

    @property
    def synthetic(self) -> bool:
        """True if any pilot's run is synthetic."""
        return any(p.synthetic for p in self.pilots)

    @property
    def improvements(self) -> np.ndarray:
        return np.array([p.improvement for p in self.pilots], dtype=float)

    def improvement_stats(self) -> dict:
        """Mean, sample standard deviation, min and max of the improvement (NaNs excluded)."""
        x = self.improvements
        x = x[np.isfinite(x)]
        if x.size == 0:
            return {"mean": math.nan, "std": math.nan, "min": math.nan, "max": math.nan, "n": 0}
        return {"mean": float(x.mean()), "std": float(x.std(ddof=1)) if x.size > 1 else math.nan,
                "min": float(x.min()), "max": float(x.max()), "n": int(x.size)}

    @property
    def mean_improvement(self) -> float:
        return self.improvement_stats()["mean"]

    def verdict(self) -> dict:
        """Does motion feedback improve the fit? :func:`hesspipe.pilots.verdict.cohort_verdict`."""
        from .verdict import cohort_verdict

        return cohort_verdict({p.id: p.motion_test for p in self.pilots})

    def to_dict(self, *, psd: bool = True) -> dict:
        stats = self.improvement_stats()
        n_synth = sum(p.synthetic for p in self.pilots)
        return {
            "motion_verdict": self.verdict(),
            "synthetic": self.synthetic,
            "synthetic_pilots": n_synth,
            "measured_pilots": len(self.pilots) - n_synth,
            "note": ("SYNTHETIC DATA: runs generated by a model, not measured" if self.synthetic
                     else "measured runs"),
            "configurations": {
                "original": "original Hess model; Ke, K1, K2 identified",
                "expanded_fixed": "expanded model with the original's parameters and Km fixed "
                                  f"at {_fmt(self.km_fixed_value(), 'g')} (not re-identified)",
                "expanded": "expanded model; Ke, K1, K2 and Km identified" + (
                    ", search started from expanded_fixed" if self.settings.start == "warm"
                    else ", search started from a random chromosome"),
            },
            "improvement_definition": "1 - expanded.fitness / original.fitness",
            "mean_improvement": stats["mean"],
            "std_improvement": stats["std"],
            "min_improvement": stats["min"],
            "max_improvement": stats["max"],
            "n_pilots": len(self.pilots),
            "settings": {"seed": self.settings.seed, "optimizer": self.settings.optimizer,
                         "passes": self.settings.passes, "band_hz": list(self.settings.band),
                         "k": self.settings.k, "km_fixed": self.km_fixed_value(),
                         "start": self.settings.start, "restarts": self.settings.restarts,
                         "benchmark": self.settings.benchmark, "criterion": self.settings.criterion},
            "plants": self.plants,
            "pilots": [p.to_dict(psd=psd) for p in self.pilots],
            "failures": [f.to_dict() for f in self.failures],
        }

    def km_fixed_value(self) -> float | None:
        """Km of the expanded_fixed configuration (None if no pilot was processed).

        The default (``settings.km_fixed`` None) is Table 1's scaled to the plants, as used.
        """
        if self.settings.km_fixed is not None:
            return self.settings.km_fixed
        for p in self.pilots:
            return float(p.expanded_fixed["parameters"]["Km"])
        return None

    def table(self) -> str:
        """The comparison as a plain-text table (Table 5 per pilot), mean and spread."""
        return format_table(self)


# -- one pilot ------------------------------------------------------------------------------

def _km_fixed(settings: CompareSettings, plants) -> float:
    if settings.km_fixed is not None:
        return float(settings.km_fixed)
    from ..pilot.crossover import gain_scale
    from ..pilot.hess import PilotModel

    # Table 1's Km, in the same plant-gain units as the identification's defaults.
    return float(PilotModel(("motion_feedback",)).defaults(settings.k, gain_scale(plants, settings.k))["Km"])


def evaluate(run: Run, plants: Plants, model, params: Mapping[str, float], *,
             band: tuple[float, float] = (0.0, 5.0), k: int = 1, benchmark: bool = False,
             criterion: str = "paper", frf=None) -> dict:
    """Fitness and crossover of fixed parameters on a run, nothing identified.

    Returns a dict with the keys of ``Identification.to_dict(spectra=False)``
    that apply (``free`` empty, ``evaluations`` 1) plus ``simulated_psd``.
    """
    from ..identification.fit import benchmark as mcruer_benchmark
    from ..identification.problem import SpectralObjective
    from ..pilot.crossover import loop_crossover
    from ..pilot.hess import model_from_name

    model = model_from_name(model)
    complete = model.complete(params, k, strict=True)
    if criterion != "paper":
        from ..identification.fit import identify

        res = identify(run, plants, model, free=(), fixed=complete, k=k, band=band,
                       with_benchmark=benchmark, with_identifiability=False, criterion=criterion,
                       frf=frf)
        out = res.to_dict(spectra=False)
        out.update(free=[], evaluations=1,
                   identifiability={"method": "not computed: nothing identified"},
                   simulated_psd=res.simulated_psd)
        return out
    obj = SpectralObjective(run, plants, model, complete, band=band)
    loop = obj.sim.prepare(model.loop(complete))
    sim_psd = obj.loop_psd(loop)
    fit = (float(np.sqrt(np.mean((obj.measured[obj.mask] - sim_psd[obj.mask]) ** 2)))
           if sim_psd is not None else obj.unstable_fitness(loop))  # finite, never NaN
    bench_fit, bench_par = math.nan, {}
    if benchmark:
        bench = mcruer_benchmark(run, plants, band=band)
        bench_fit, bench_par = bench.fitness, dict(bench.parameters)
    return {"model": model.name, "run_id": run.id, "synthetic": run.synthetic,
            "parameters": complete, "free": [], "fixed": complete, "fitness": fit,
            "benchmark_fitness": bench_fit, "benchmark_parameters": bench_par,
            "crossover": loop_crossover(loop, obj.sim.yc_block).to_dict(), "evaluations": 1,
            "identifiability": {"method": "not computed: nothing identified"},
            "band_hz": list(obj.band), "stable": sim_psd is not None,
            "simulated_psd": sim_psd if sim_psd is not None else np.full_like(obj.measured, np.nan)}


#: Round trips of :func:`_exchange` (each: one climb per model); pathological pilots whose
#: climbs run out of passes would otherwise ping-pong for long.
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
    from ..identification.fit import identify

    return identify(run, plants, model, seed=seed, initial=initial,
                    **{**common, "optimizer": "scipy", "restarts": 1})


def _search(run, plants, model, seed, common, initial=None):
    """APID (or the chosen optimizer), then a local polish from its result; the better is kept.

    Binary-coded bit climbing stalls in narrow valleys (lightly damped loops
    give sharp spectral peaks): a continuous local search from its result
    finishes the job. Returns the result and the evaluations spent.
    """
    from ..identification.fit import identify

    first = identify(run, plants, model, seed=seed, initial=initial, **common)
    if common["optimizer"] == "scipy" or common.get("criterion", "paper") != "paper":
        # Phase-aware criteria are fitted by multi-start least squares: already local.
        return first, first.evaluations
    polished = _polish(run, plants, model, first.parameters, seed, common)
    # NaN (an unstable end point) never compares smaller: the climb's result is kept then.
    best = polished if polished.fitness < first.fitness else first
    return best, first.evaluations + polished.evaluations


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
    common = dict(optimizer=settings.optimizer, passes=settings.passes, band=tuple(settings.band),
                  k=settings.k, restarts=settings.restarts, with_benchmark=settings.benchmark)
    frf = None
    if settings.criterion != "paper":
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
        motion_test=safe_motion_test(run, plants, original.parameters, k=settings.k,
                                     band_hz=tuple(settings.band)),
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

def list_runs(paths_or_dir: str | Path | Iterable[str | Path]) -> list[Path]:
    """The run files of a folder (``*.csv``, sorted) or of an explicit list.

    ``*.truth.json`` and other non-CSV files beside the runs are ignored.
    """
    if isinstance(paths_or_dir, (str, Path)):
        path = Path(paths_or_dir)
        if path.is_dir():
            files = sorted(p for p in path.iterdir() if p.is_file() and p.suffix.lower() == ".csv")
            if not files:
                raise HesspipeError(f"{path}: no run files (*.csv) in this folder")
            return files
        if not path.exists():
            raise HesspipeError(f"{path}: not found; expected a folder of run CSV files or a CSV file")
        return [path]
    files = [Path(p) for p in paths_or_dir]
    if not files:
        raise HesspipeError("compare-pilots: no run files given")
    return files


def read_runs(paths: Sequence[Path], *, columns=None, resample: bool = False,
              min_samples: int = MIN_SAMPLES) -> tuple[list[Run], list[PilotFailure]]:
    """Read every file; a bad file becomes a :class:`PilotFailure`, not an exception."""
    runs, failures = [], []
    seen: dict[str, Path] = {}
    for path in paths:
        try:
            run = read_run(path, columns=columns, resample=resample, min_samples=min_samples)
        except HesspipeError as exc:
            failures.append(PilotFailure(Path(path).stem, str(path), str(exc)))
            continue
        if run.id in seen:
            failures.append(PilotFailure(run.id, str(path), f"{path}: pilot id {run.id!r} repeats "
                                         f"{seen[run.id]}; expected one file per pilot"))
            continue
        seen[run.id] = Path(path)
        runs.append(run)
    return runs, failures


def compare_pilots(paths_or_dir, plants: Plants, *, workers: int | None = None,
                   scheduler: str | None = None, seed: int = 0, optimizer: str = "apid",
                   passes: int = 10, band: tuple[float, float] = (0.0, 5.0), k: int | None = None,
                   km_fixed: float | None = None, start: str = "warm", restarts: int = 2,
                   benchmark: bool = False, columns=None,
                   resample: bool = False, progress: bool | None = None, job=None,
                   criterion: str = "paper") -> Comparison:
    """Identify original, expanded-fixed-Km and expanded models on each pilot's run.

    Parameters
    ----------
    paths_or_dir : path or iterable of paths
        A folder of run CSVs (the file stem is the pilot id) or the files.
    plants : Plants
        Yc (control → roll rate) and Yd (lateral wind ft/s → roll rate rad/s).
    workers : int, optional
        Local processes (default all cores; 1: in this process).
    scheduler : str, optional
        Dask distributed scheduler address; the work is submitted there instead.
    seed : int
        Base seed (pilot seeds derive from it and the pilot id).
    optimizer, passes, band, k, km_fixed, start, restarts, benchmark, criterion
        See :class:`CompareSettings`.
    columns, resample
        Passed to :func:`hesspipe.core.formats.read_run`.
    progress : bool, optional
        Progress bar (default: only on a terminal).
    job : callable, optional
        ``job(run) -> PilotComparison`` replacing the identification (tests,
        custom studies); must be picklable for workers > 1.

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
    if start not in STARTS:
        raise HesspipeError(f"start: expected one of {', '.join(STARTS)}, got {start!r}")
    if k is None:
        from ..identification.criteria import choose_k

        k = choose_k(plants)[0]  # Hess's rule on the control plant
    settings = CompareSettings(seed=check_seed(seed), optimizer=optimizer, passes=int(passes),
                               band=(float(band[0]), float(band[1])), k=int(k),
                               km_fixed=None if km_fixed is None else float(km_fixed), start=start,
                               restarts=int(restarts), benchmark=bool(benchmark),
                               criterion=check_criterion(criterion))
    if job is None and settings.km_fixed is None:
        settings = replace(settings, km_fixed=_km_fixed(settings, plants))
    _parse_columns(columns)  # a bad --columns is the user's one mistake, not every file's
    paths = list_runs(paths_or_dir)
    runs, failures = read_runs(paths, columns=columns, resample=resample)
    if job is None:
        job = functools.partial(compare_run, plants=plants, settings=settings)
    results = run_batch(functools.partial(_guarded, job), runs, workers=workers, scheduler=scheduler,
                        desc="pilots", unit="pilot", progress=progress)
    pilots = tuple(r for r in results if isinstance(r, PilotComparison))
    failures += [r for r in results if isinstance(r, PilotFailure)]
    order = {str(p): i for i, p in enumerate(paths)}
    failures.sort(key=lambda f: order.get(f.source, len(order)))
    from ..core.formats import tf_coefficients

    return Comparison(pilots=pilots, failures=tuple(failures), settings=settings,
                      plants={"control_to_output": tf_coefficients(plants.control_to_output),
                              "disturbance_to_output": tf_coefficients(plants.disturbance_to_output)})


# -- reporting --------------------------------------------------------------------------------

def _fmt(x, spec=".3g") -> str:
    if x is None or (isinstance(x, float) and not math.isfinite(x)):
        return "-"
    return format(x, spec)


def format_table(comparison: Comparison) -> str:
    """Plain-text comparison: one row per pilot and configuration, then mean and spread."""
    head = ("pilot", "configuration", *TABLE_PARAMETERS, "fitness", "improvement", "wc rad/s", "PM deg")
    rows = []
    for p in comparison.pilots:
        for name in CONFIGURATIONS:
            conf = p.configuration(name)
            params = conf.get("parameters", {})
            cross = conf.get("crossover") or {}
            rows.append((p.id + (" *" if p.synthetic else "") if name == "original" else "", name,
                         *(_fmt(params.get(k)) if k in params else "x" for k in TABLE_PARAMETERS),
                         _fmt(conf.get("fitness"), ".4g"),
                         f"{100 * p.improvement:.1f} %" if name == "expanded" and math.isfinite(p.improvement)
                         else "",
                         _fmt(cross.get("frequency_rad_s")), _fmt(cross.get("phase_margin_deg"))))
    widths = [max(len(str(r[i])) for r in [head, *rows]) for i in range(len(head))]
    line = lambda r: "  ".join(str(c).ljust(w) if i < 2 else str(c).rjust(w)  # noqa: E731
                               for i, (c, w) in enumerate(zip(r, widths)))
    out = []
    if comparison.synthetic:
        out.append("SYNTHETIC DATA (* = run generated by a model, not measured)")
    out += verdict_lines(comparison.verdict()) + [""]
    out += [line(head), line(["-" * w for w in widths]), *(line(r) for r in rows)]
    s = comparison.improvement_stats()
    if s["n"]:
        spread = f", sd {100 * s['std']:.1f} %" if math.isfinite(s["std"]) else ""
        out.append(f"improvement (1 - expanded/original fitness) over {s['n']} pilot(s): mean "
                   f"{100 * s['mean']:.1f} %{spread}, range {100 * s['min']:.1f} .. {100 * s['max']:.1f} %")
    notes: dict[str, int] = {}
    for p in comparison.pilots:
        for name in ("original", "expanded"):
            for u in (p.configuration(name).get("identifiability") or {}).get("unidentifiable", []):
                notes[u["meaning"]] = notes.get(u["meaning"], 0) + 1
    for meaning, count in notes.items():
        out.append(f"identifiability: {meaning} ({count} of {2 * len(comparison.pilots)} "
                   "identifications); only that combination is determined")
    out.append(f"expanded_fixed: original's parameters with Km = {_fmt(comparison.km_fixed_value(), 'g')}, "
               "not re-identified; x = not in the model")
    for f in comparison.failures:
        out.append(f"FAILED {f.id}: {f.error}")
    return "\n".join(out)


def write_comparison(comparison: Comparison, out_dir: str | Path, *, draw: Callable | None = None,
                     json_name: str = "comparison.json", table_name: str = "comparison.md") -> list[Path]:
    """Write ``comparison.json``, ``comparison.md`` and the figures of `draw` into `out_dir`.

    ``draw(folder, comparison)`` writes figures into `folder` and returns their
    names relative to it (:func:`hesspipe.viz.compare.draw_comparison`:
    ``figures/<pilot>.png`` and ``figures/<pilot>_df.png``); None: no figures.
    Each file is written atomically; callers that need all-or-nothing wrap
    this in :func:`hesspipe.core.io.staged_output`.
    """
    out_dir = Path(out_dir)
    record = comparison.to_dict()
    # Runs made inside out_dir (the pipeline's cohort) are named relative to it: the folder
    # may be a staging folder that is renamed once the stage succeeds.
    for entry in record["pilots"] + record["failures"]:
        src = Path(entry["source"])
        if src.is_absolute() and src.is_relative_to(out_dir.resolve()):
            entry["source"] = str(src.relative_to(out_dir.resolve()))
    written = [write_json(out_dir / json_name, record),
               write_text(out_dir / table_name, "```\n" + comparison.table() + "\n```\n")]
    if draw is not None:
        written += [out_dir / name for name in draw(out_dir, comparison)]
    return written


# -- pipeline configuration --------------------------------------------------------------------

#: How the pipeline's synthetic cohort is simulated (``[pilots] simulator``).
SIMULATORS = ("jsbsim", "fft")


@dataclass(frozen=True)
class PilotsConfig:
    """The ``[pilots]`` table of the pipeline configuration.

    Attributes
    ----------
    data : str
        Folder of measured runs; empty: a synthetic cohort is generated.
    n : int
        Synthetic cohort size.
    seed : int or None
        Cohort and identification seed (None: the pipeline seed).
    effects : tuple of str
        Effects in every synthetic pilot (remnant noise is always added).
    duration_s, dt_s : float
        Synthetic record length and sample interval.
    workers : int
        Local processes (0: all cores).
    scheduler : str
        Dask scheduler address ("" : local processes).
    optimizer : str
        "apid", "scipy" or "differential_evolution".
    passes : int
        APID pass budget.
    band_hz : (float, float)
        Fitness band.
    km_fixed : float or None
        Km of the expanded_fixed configuration (None: Table 1 times the plants' gain scale).
    start : str
        "warm" or "random" (see :class:`CompareSettings`).
    restarts : int
        APID climbs per identification.
    benchmark : bool
        Also compute the McRuer benchmark score per pilot.
    figures : bool
        Write a PSD figure per pilot (and a describing-function figure).
    columns : str
        Column names of the data's files, "ROLE=NAME,..." ("": the format's names).
    resample : bool
        Interpolate non-uniform time columns onto a uniform grid instead of refusing them.
    simulator : str
        How the synthetic cohort is made: "jsbsim" (the pilots fly the JSBSim
        aircraft in closed loop, :func:`hesspipe.pilots.flown.fly_cohort`) or "fft"
        (the linear frequency-domain model around the fitted plants).
    criterion : str
        Fit criterion (see :class:`CompareSettings`); default
        :data:`hesspipe.identification.criteria.DEFAULT_CRITERION`, as the identify command.
    """

    data: str = ""
    n: int = 6
    seed: int | None = None
    effects: tuple[str, ...] = ("motion_feedback",)
    duration_s: float = 70.0
    dt_s: float = 0.02
    workers: int = 0
    scheduler: str = ""
    optimizer: str = "apid"
    passes: int = 10
    band_hz: tuple[float, float] = (0.0, 5.0)
    km_fixed: float | None = None
    start: str = "warm"
    restarts: int = 2
    benchmark: bool = False
    figures: bool = True
    columns: str = ""
    resample: bool = False
    simulator: str = "jsbsim"
    criterion: str = DEFAULT_CRITERION

    @classmethod
    def from_table(cls, table: Mapping | None, source: str, prefix: str = "pilots") -> "PilotsConfig":
        f = Fields(table, source, prefix)
        d = cls()
        effects = f.strings("effects", d.effects)
        _check_effects(effects, f"{source}: field '{prefix}.effects'")
        seed = f.integer("seed", None, min=0, max=MAX_SEED)
        band = f.numbers("band_hz", list(d.band_hz), length=2)
        if not 0 <= band[0] < band[1]:
            raise f.error("band_hz", "[low, high] Hz with 0 <= low < high", list(band))
        km = f.number("km_fixed", None, min=0.0)
        cfg = cls(data=f.string("data", d.data), n=f.integer("n", d.n, min=1),
                  seed=seed, effects=tuple(effects),
                  duration_s=f.number("duration_s", d.duration_s, min=0.0, strict_min=True),
                  dt_s=f.number("dt_s", d.dt_s, min=0.0, max=0.1, strict_min=True),
                  workers=f.integer("workers", d.workers, min=0),
                  scheduler=f.string("scheduler", d.scheduler),
                  optimizer=f.string("optimizer", d.optimizer, choices=OPTIMIZERS),
                  passes=f.integer("passes", d.passes, min=1),
                  band_hz=band, km_fixed=km, start=f.string("start", d.start, choices=STARTS),
                  restarts=f.integer("restarts", d.restarts, min=1),
                  benchmark=f.boolean("benchmark", d.benchmark),
                  figures=f.boolean("figures", d.figures),
                  columns=f.string("columns", d.columns), resample=f.boolean("resample", d.resample),
                  simulator=f.string("simulator", d.simulator, choices=SIMULATORS),
                  criterion=f.string("criterion", d.criterion, choices=CRITERIA))
        f.reject_unknown()
        try:
            _parse_columns(cfg.columns)
            record_samples(cfg.duration_s, cfg.dt_s, min_samples=MIN_SAMPLES)
        except HesspipeError as exc:
            field = "columns" if str(exc).startswith("columns") else "duration_s"
            raise HesspipeError(f"{source}: field '{prefix}.{field}': {exc}") from None
        return cfg


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
    """
    from .cohort import CohortSpec, synth_cohort

    out_dir = Path(out_dir)
    seed = config.seed if config.seed is not None else int(seed)
    if config.data:
        source = Path(config.data)
    else:
        source = out_dir / "cohort"
        synth_cohort(plants, config.n, seed, config.effects, source,
                     spec=CohortSpec(duration_s=config.duration_s, dt_s=config.dt_s))
    result = compare_pilots(source, plants, workers=config.workers or None,
                            scheduler=config.scheduler or None, seed=seed, optimizer=config.optimizer,
                            passes=config.passes, band=config.band_hz, km_fixed=config.km_fixed,
                            start=config.start, restarts=config.restarts, benchmark=config.benchmark,
                            columns=config.columns or None, resample=config.resample, progress=progress,
                            criterion=config.criterion)
    write_comparison(result, out_dir, draw=draw if config.figures else None)
    return result


def _check_effects(effects: tuple[str, ...], where: str) -> None:
    """Raise unless every effect id is known (the registry lives in hesspipe.pilot.effects)."""
    try:
        from ..pilot.effects import EFFECTS
    except ImportError:  # registry not available: accept, synth_cohort checks again
        return
    for e in effects:
        if e not in EFFECTS:
            raise HesspipeError(f"{where}: unknown effect {e!r}; expected one of {', '.join(EFFECTS)}")
