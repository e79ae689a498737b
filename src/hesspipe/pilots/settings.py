"""Settings of the pilots stage, validated on construction.

:class:`CompareSettings` is what every pilot's identification uses (sent to the
workers); :class:`PilotsConfig` is the ``[pilots]`` table: the cohort, the runs'
format and the batch, plus the identification settings by the same names
(:meth:`PilotsConfig.settings` maps them; one set of checks serves both).
"""

from __future__ import annotations

import re
from dataclasses import dataclass

from ..core._time import MAX_INTERVAL_S, MIN_INTERVAL_S
from ..core.choices import CRITERIA, DEFAULT_CRITERION, DEFAULT_DISPLAY, DISPLAYS, OPTIMIZERS
from ..core.config import Fields, Settings
from ..core.errors import HesspipeError
from ..core.formats import parse_columns, record_samples
from ..core.paper import FITNESS_BAND_HZ, WELCH_SEGMENT
from ..core.seeds import MAX_SEED
from ..flight.target import FORCINGS as _FORCINGS
from ..pilot.effects import EFFECTS

#: The model configurations every pilot is identified with (Table 5's rows).
CONFIGURATIONS = ("original", "expanded_fixed", "expanded")
#: Where the expanded search starts (see :class:`CompareSettings`).
STARTS = ("warm", "random")
#: Fewest samples a run needs: one Welch segment of the paper's spectra (Eq. 9 pads the rest).
MIN_SAMPLES = WELCH_SEGMENT  # one segment of the paper's Welch estimate
#: How the pipeline's synthetic cohort is simulated (``[pilots] simulator``).
SIMULATORS = ("jsbsim", "fft")
#: How a cohort's pilots are drawn (``[pilots] cohort``, :func:`hesspipe.pilots.cohort.cohort_spec`):
#: the crossover-model cohort (the pipeline's default) or the Table 1 draw of earlier versions
#: (kept so that their studies repeat).
COHORT_DRAWS = ("crossover_model", "table1")
#: Identification settings that :class:`PilotsConfig` and :class:`CompareSettings` share by name.
_SHARED = ("optimizer", "passes", "km_fixed", "start", "restarts", "benchmark", "criterion", "display")


def _seed(f: Fields, key: str) -> int:
    return f.integer(key, min=0, max=MAX_SEED)  # the pipeline's own seed rule and message


def _identification(f: Fields, band: str) -> dict:
    """The checks of the identification settings both classes hold (`band`: its field name)."""
    lo_hi = f.numbers(band, length=2)
    if not 0 <= lo_hi[0] < lo_hi[1]:
        raise f.error(band, "[low, high] Hz with 0 <= low < high", list(lo_hi))
    return {band: lo_hi, "optimizer": f.string("optimizer", choices=OPTIMIZERS),
            "passes": f.integer("passes", min=1), "km_fixed": f.number("km_fixed", None, min=0.0),
            "start": f.string("start", choices=STARTS), "restarts": f.integer("restarts", min=1),
            "benchmark": f.boolean("benchmark"), "criterion": f.string("criterion", choices=CRITERIA),
            "display": f.string("display", choices=DISPLAYS)}


@dataclass(frozen=True)
class CompareSettings(Settings):
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
    k : int or None
        Hess model order for the controlled element (1: rate-like, the roll-rate task;
        2: attitude-like); None: Hess's rule on the control plant
        (:func:`hesspipe.identification.criteria.choose_k`), resolved per study.
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
    display : str
        What the pilots saw (:data:`hesspipe.core.choices.DISPLAYS`): "compensatory" (the
        error alone), "pursuit" (target and output apart: the motion test fits the
        feedforward humans then add, :func:`hesspipe.identification.motion_test.motion_test`)
        or "either" (not known: motion only where the test finds it for both, where the
        record shows the feedforward; else as for "compensatory").
    """

    seed: int = 0
    optimizer: str = "apid"
    passes: int = 10
    band: tuple[float, float] = FITNESS_BAND_HZ
    k: int | None = None
    km_fixed: float | None = None
    start: str = "warm"
    restarts: int = 2
    benchmark: bool = False
    criterion: str = "paper"
    display: str = DEFAULT_DISPLAY

    def _checked(self, f: Fields) -> dict:
        return dict(seed=_seed(f, "seed"), k=f.integer("k", None, min=1, max=2),
                    **_identification(f, "band"))


#: How the pipeline's synthetic cohort is simulated (``[pilots] simulator``).
SIMULATORS = ("jsbsim", "fft")
#: The synthetic cohort's forcing (``[pilots] forcing``): the paper's turning side wind with the
#: broadband gusts (no forcing lines), or :data:`hesspipe.flight.target.TWO_INPUT` (wind and
#: roll-rate target multisines on interleaved lines, a run-in flown before a JSBSim record).
FORCINGS = tuple(_FORCINGS)


@dataclass(frozen=True)
class PilotsConfig(Settings):
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
        Interpolate non-uniform time columns onto a uniform grid, and missed samples (empty
        or NaN cells), instead of refusing them.
    sample_rate : float or None
        Hz, for data files without a time column (:func:`hesspipe.core.formats.read_run`);
        None (default): every file has times.
    simulator : str
        How the synthetic cohort is made: "jsbsim" (the pilots fly the JSBSim
        aircraft in closed loop, :func:`hesspipe.pilots.flown.fly_cohort`) or "fft"
        (the linear frequency-domain model around the fitted plants).
    criterion : str
        Fit criterion (see :class:`CompareSettings`); default
        :data:`hesspipe.identification.criteria.DEFAULT_CRITERION`, as the identify command.
    display : str
        What the pilots saw, "compensatory", "pursuit" or "either" (see :class:`CompareSettings`).
    cohort : str
        How the synthetic pilots are drawn (:data:`COHORT_DRAWS`): "crossover_model"
        (default; within the crossover-model limits, :mod:`hesspipe.pilots.cohort`) or "table1".
    forcing : str
        The synthetic cohort's forcing (:data:`FORCINGS`): "two_input" (default,
        :data:`hesspipe.flight.target.TWO_INPUT`: wind and roll-rate target multisines on
        interleaved lines, from which the motion verdict can answer; a JSBSim flight is
        ``duration_s`` plus its 15 s run-in, the record the last ``duration_s``; the
        frequency-domain model's record is the loop's periodic steady state) or "paper" (the
        paper's turning side wind with gusts: one forcing function, no lines, the verdict
        "undetermined").
    plants : str
        A plants JSON for the runs in ``data`` (another task or simulator than the
        aircraft flown here: a yaw experiment's controlled element and ``motion_path``);
        "" (default): the plants stage's. Only with ``data``; diagnose uses it too.
    pilot_id : str
        A regular expression that finds the pilot in each file name of ``data`` (its group
        ``pilot``, else its first group) when pilots flew several runs; "" (default):
        every file is a pilot (:func:`hesspipe.pilots.verdict.pilot_groups`).
    """

    TABLE = "pilots"

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
    band_hz: tuple[float, float] = FITNESS_BAND_HZ
    km_fixed: float | None = None
    start: str = "warm"
    restarts: int = 2
    benchmark: bool = False
    figures: bool = True
    columns: str = ""
    resample: bool = False
    sample_rate: float | None = None
    simulator: str = "jsbsim"
    criterion: str = DEFAULT_CRITERION
    display: str = DEFAULT_DISPLAY
    cohort: str = "crossover_model"
    forcing: str = "two_input"
    plants: str = ""
    pilot_id: str = ""

    def _checked(self, f: Fields) -> dict:
        effects = f.strings("effects")
        unknown = [e for e in effects if e not in EFFECTS]
        if unknown:
            raise f.fail("effects", f"unknown effect {unknown[0]!r}; expected one of {', '.join(EFFECTS)}")
        out = dict(data=f.string("data"), n=f.integer("n", min=1),
                   seed=None if f.table["seed"] is None else _seed(f, "seed"), effects=effects,
                   duration_s=f.number("duration_s", min=0.0, strict_min=True),
                   dt_s=f.number("dt_s", min=0.0, max=0.1, strict_min=True),
                   workers=f.integer("workers", min=0), scheduler=f.string("scheduler"),
                   figures=f.boolean("figures"), columns=f.string("columns"),
                   resample=f.boolean("resample"),
                   sample_rate=None if f.table["sample_rate"] is None else f.number(
                       "sample_rate", min=1.0 / MAX_INTERVAL_S, max=1.0 / MIN_INTERVAL_S),
                   simulator=f.string("simulator", choices=SIMULATORS),
                   cohort=f.string("cohort", choices=COHORT_DRAWS),
                   forcing=f.string("forcing", choices=FORCINGS), plants=f.string("plants"),
                   pilot_id=f.string("pilot_id"), **_identification(f, "band_hz"))
        if out["plants"] and not out["data"]:
            raise f.fail("plants", "a plants file is for the runs of a data folder (the synthetic cohort "
                                   "flies the plants stage's aircraft); set data too, or leave plants empty")
        if out["pilot_id"]:
            try:
                re.compile(out["pilot_id"])
            except re.error as exc:
                raise f.fail("pilot_id", f"expected a regular expression, got {out['pilot_id']!r} ({exc})") from None
        try:
            parse_columns(out["columns"])
        except HesspipeError as exc:
            raise f.fail("columns", str(exc)) from None
        try:
            record_samples(out["duration_s"], out["dt_s"], min_samples=MIN_SAMPLES)
        except HesspipeError as exc:
            raise f.fail("duration_s", str(exc)) from None
        return out


    def settings(self, seed: int = 0) -> CompareSettings:
        """The identification settings of this table; its ``seed``, else `seed` (the pipeline's).

        Parameters
        ----------
        seed : int
            Base seed used when the table sets none (``seed`` is None).

        Returns
        -------
        CompareSettings
            With ``band`` = :attr:`band_hz` (Hz) and the shared settings
            (optimizer, passes, km_fixed, start, restarts, benchmark,
            criterion, display) copied by name.
        """
        return CompareSettings(seed=self.seed if self.seed is not None else seed, band=self.band_hz,
                               **{name: getattr(self, name) for name in _SHARED})
