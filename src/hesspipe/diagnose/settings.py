"""Settings of the ``diagnose`` stage: one frozen dataclass, validated on construction."""

from __future__ import annotations

from dataclasses import dataclass

from ..core.choices import DEFAULT_DISPLAY, DISPLAYS
from ..core.config import Fields, Settings
from ..core.paper import FITNESS_BAND_HZ
from ..identification.motion_test import ALPHA as MOTION_ALPHA
from ..identification.motion_test import MIN_VISUAL_DELAY

#: Significance level of a candidate's improvement (Bonferroni over the candidates), the
#: default of ``DiagnoseConfig.alpha``.
ALPHA = 0.01
#: Plant-check fit (percent) below which the plants are taken to miss part of the aircraft,
#: the default of ``DiagnoseConfig.plant_fit_ok``.
PLANT_FIT_OK = 90.0

#: Default band edges (Hz) for the band-wise disagreement.
BAND_EDGES_HZ = (0.0, 0.25, 0.5, 1.0, 2.0, 3.5, 5.0)

#: Core pilot parameters freed in every fit. K1 and K2 appear only as a product
#: (SPEC.md), so K2 stays at its Table 1 value and K1 carries the product.
CORE_FREE = ("Ke", "K1")





# -- configuration --------------------------------------------------------------------------

@dataclass(frozen=True)
class DiagnoseConfig(Settings):
    """Settings of :func:`diagnose` (the ``[diagnose]`` table of a pipeline file).

    Attributes
    ----------
    candidates : tuple of str or None
        Effect ids to try; None tries every registered effect not already in the model.
    band_hz : (float, float)
        Frequency band of the fits, scores and Eq. 10 gap, Hz.
    band_edges_hz : tuple of float
        Edges of the bands reported by the locate step, Hz (increasing).
    alpha : float
        Family-wise significance level of one round (Bonferroni over its candidates).
    max_effects : int
        Most effects named in one diagnosis.
    free : tuple of str
        Core parameters freed in every fit (effect parameters are always free).
    grid : int
        Grid levels of a new effect's parameter (``grid // n``, at least 3, each for an
        effect with n parameters; ``grid`` per core gain for the baseline fit).
    gain_levels : tuple of float
        Levels (fractions of their box) at which the core gains join a candidate's grid,
        besides their current values.
    starts : int
        Best grid points from which least squares is run (besides the start value).
    max_evaluations : int
        Least-squares function-evaluation budget of one fit.
    max_lag : int
        Lags of the residual tests.
    plant_fit_ok : float
        Plant-check fit percent (initial state refitted) at or above which the plants match;
        below it, aircraft-side candidates and file errors are tried
        (:mod:`hesspipe.diagnose.aircraft`).
    resolution_db : float
        Floor of the RMS log-spectral residual, dB: smaller mismatches are not evidence.
    dynamic_range_db : float
        PSD levels further below the band's measured peak are compared at that level
        (the Hamming window's leakage, -43 dB sidelobes, limits what a Welch estimate
        resolves); it also sets how weak a broadband noise floor may be and still be
        named a remnant.
    weighting : {"random-share", "uniform"}
        Variance model of the log-spectral residual: "random-share" (default) gives each
        bin the Welch scatter of the model's random (remnant) share of it on top of a
        common model-error variance; "uniform" the common variance alone.
    k : int
        Controlled-element order of the Hess model (1 rate, 2 attitude).
    motion_alpha : float
        Significance level of the describing-function test of motion feedback
        (:mod:`hesspipe.diagnose.motion`).
    display : {"compensatory", "pursuit", "either"}
        What the pilot saw: the error alone, target and output apart (the motion test
        then fits the feedforward humans add on the target;
        :func:`hesspipe.identification.motion_test.motion_test`), or not known (motion only
        where the test finds it for both, where the record shows the feedforward; else as
        for compensatory).
    """

    TABLE = "diagnose"

    candidates: tuple[str, ...] | None = None
    band_hz: tuple[float, float] = FITNESS_BAND_HZ
    band_edges_hz: tuple[float, ...] = BAND_EDGES_HZ
    alpha: float = ALPHA
    max_effects: int = 3
    free: tuple[str, ...] = CORE_FREE
    # Search effort (issue 13: < 3 s per 70 s diagnosis on one core). Where a record has
    # lines the names rest on the describing function; this buys the control-spectrum fits
    # the report shows. With one gain level (0.5) and one restart of 20 evaluations a
    # candidate's fit ended where a file's last digits sent it: the log-spectral RMS after
    # the fits moved by up to 2.75 dB between readings of one trial that differ by 1e-12,
    # 0.39 dB with these settings, and its mean over 20 trials fell from 4.13 to 3.88 dB at
    # 9 % more CPU (benchmarks/bench_fit_stability.py, SYNTHETIC).
    grid: int = 6
    gain_levels: tuple[float, ...] = (0.05, 0.2, 0.5)
    starts: int = 3
    max_evaluations: int = 40
    max_lag: int = 25
    plant_fit_ok: float = PLANT_FIT_OK
    resolution_db: float = 0.1
    dynamic_range_db: float = 40.0
    weighting: str = "random-share"
    k: int = 1
    #: Level of the describing-function motion test (one pre-planned test per diagnosis;
    #: the motion test's own level, which compare-pilots uses too). 0.01: at 0.05 a
    #: baseline's structural mismatch passed for a vestibular path in 2 of 20 development runs
    #: (seeds 100-104), while the motion runs' p-values were mostly far below 0.01.
    motion_alpha: float = MOTION_ALPHA
    #: Longest visual delay of a human pilot as the describing-function fit sees it, s:
    #: tracking studies report up to about 0.35 s (SPEC: 0.2-0.3 s typical), and the fitted
    #: delay of a human-like pilot came out up to 0.05 s above the true one (sampling, model
    #: structure; independent generator's baselines, development seeds 100-104). Only delay
    #: beyond it is named extra_delay (diagnose.motion.delay_bound_test). More than the motion
    #: test's shortest visual delay (``motion_test.MIN_VISUAL_DELAY``, 0.1 s).
    max_pilot_delay: float = 0.40
    #: Spread (standard deviation) of the difference between one pilot's visual delays on
    #: two runs of one condition, s: the paired delay test (a baseline run of the same
    #: pilot) names only a difference beyond it and the joint fit's error. Human operators'
    #: identified delays scatter by 0.01-0.02 s between repeated runs; the describing function
    #: also turns part of a change of the neuromuscular mode into delay. At 0.01 s, 3 of 15
    #: baseline pairs of the independent generator (development seeds 100-104) were named.
    retest_delay_sd: float = 0.02
    #: Share of the control power between multisine lines from which the remnant is named.
    remnant_share: float = 0.01
    display: str = DEFAULT_DISPLAY

    def _checked(self, f: Fields) -> dict:
        # Validated on construction (Python, the command line and TOML alike); from_table maps.
        cands = f.table["candidates"]
        if cands is not None:
            if (not isinstance(cands, (list, tuple)) or not all(isinstance(c, str) and c for c in cands)):
                raise f.error("candidates", "a list of effect ids", cands)
            cands = tuple(cands)
        band = f.numbers("band_hz", length=2)
        if not 0.0 <= band[0] < band[1]:
            raise f.error("band_hz", "[lo, hi] with 0 <= lo < hi", list(band))
        edges = f.numbers("band_edges_hz")
        if len(edges) < 2 or any(b <= a for a, b in zip(edges, edges[1:])) or edges[0] < 0:
            raise f.error("band_edges_hz", "at least two increasing frequencies >= 0", list(edges))
        return dict(candidates=cands, band_hz=band, band_edges_hz=edges,
                    alpha=f.number("alpha", min=0.0, max=0.5, strict_min=True),
                    max_effects=f.integer("max_effects", min=0),
                    free=tuple(_strings(f, "free", ())),
                    grid=f.integer("grid", min=1, max=20),
                    gain_levels=_fractions(f, "gain_levels", ()),
                    starts=f.integer("starts", min=0, max=50),
                    max_evaluations=f.integer("max_evaluations", min=5),
                    max_lag=f.integer("max_lag", min=1),
                    plant_fit_ok=f.number("plant_fit_ok", min=0.0, max=100.0),
                    resolution_db=f.number("resolution_db", min=0.0, strict_min=True),
                    dynamic_range_db=f.number("dynamic_range_db", min=10.0, max=200.0),
                    weighting=f.string("weighting", choices=("random-share", "uniform")),
                    k=f.integer("k", min=1, max=2),
                    motion_alpha=f.number("motion_alpha", min=0.0, max=0.5, strict_min=True),
                    max_pilot_delay=f.number("max_pilot_delay", min=MIN_VISUAL_DELAY, max=2.0, strict_min=True),
                    retest_delay_sd=f.number("retest_delay_sd", min=0.0, max=1.0),
                    remnant_share=f.number("remnant_share", min=0.0, max=1.0),
                    display=f.string("display", choices=DISPLAYS))



def _fractions(f: Fields, key: str, default) -> tuple[float, ...]:
    values = f.numbers(key, list(default))
    if not all(0.0 <= v <= 1.0 for v in values):
        raise f.error(key, "a list of fractions between 0 and 1", list(values))
    return values


def _strings(f: Fields, key: str, default) -> list[str]:
    value = f._get(key, list(default))
    if not isinstance(value, (list, tuple)) or not all(isinstance(v, str) and v for v in value):
        raise f.error(key, "a list of parameter names", value)
    return list(value)
