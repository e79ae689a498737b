"""Settings of the plants and analytic stages: frozen dataclasses validated on
construction, built alike from TOML, the command line and Python."""

from __future__ import annotations

from dataclasses import asdict, dataclass

from ..core.config import Fields, Settings
from . import arx as _arx


@dataclass(frozen=True)
class Channel:
    """Where one plant's data live in a flight folder.

    Attributes
    ----------
    key : str
        ``"control_to_output"`` or ``"disturbance_to_output"``.
    file : str
        CSV file name inside the flight folder.
    input, output : str
        Column names of the plant's input and output.
    title : str
        Human-readable name (reports, figures).
    """

    key: str
    file: str
    input: str
    output: str
    title: str


CHANNELS = (
    Channel("disturbance_to_output", "wind.csv", "wind_lateral_fps", "roll_rate_rps",
            "lateral wind -> roll rate"),
    Channel("control_to_output", "aileron.csv", "aileron_cmd", "roll_rate_rps",
            "aileron -> roll rate"),
)


@dataclass(frozen=True)
class PlantsConfig(Settings):
    """Configuration of stage two (the ``[plants]`` table).

    Attributes
    ----------
    decimate : int
        Decimation factor before identification (1 = none).
    criterion : {"aic", "bic", "fpe"}
        Information criterion for order and delay selection.
    focus : {"simulation", "prediction"}
        Least-squares weighting (:func:`hesspipe.plants.arx.arx_fit`): ``"simulation"``
        (default) prefilters by 1/A (Steiglitz–McBride) so the fit is not
        biased away from low frequencies; the criterion then uses the
        simulation-error variance.
    iterations : int
        Prefiltering iterations of the simulation focus.
    na_max, nb_max : int
        Largest orders of A(q) and B(q) in the grid.
    nk_min, nk_max : int
        Delay range of the grid, in (decimated) samples.
    validation_fraction : float
        Held-out tail of each record used only for validation.
    min_excitation_order : int
        Fewest independent input lags (persistent excitation order) accepted.
    excitation_rcond : float
        Relative singular-value threshold of the excitation test.
    residual_max_lag : int
        Largest lag of the residual tests (decimated samples).
    residual_confidence : float
        Confidence level of the residual bounds and tests.
    check_band_hz : (float, float)
        Band of the continuous-vs-discrete frequency check.
    check_gain_db, check_phase_deg : float
        Largest accepted gain and phase difference in that band.
    on_check_failure : {"error", "warn"}
        A failed frequency check raises (default) or is only reported.
    slow_roots : {"keep", "reflect"}
        Right-half-plane poles and zeros slower than the record resolves
        (step 7 of the module docstring): kept as fitted (default) or
        reflected into the left half plane. Both fits are reported.
    """

    TABLE = "plants"

    decimate: int = 6
    criterion: str = "bic"
    focus: str = "simulation"
    iterations: int = 10
    na_max: int = 6
    nb_max: int = 6
    nk_min: int = 1
    nk_max: int = 3
    validation_fraction: float = 0.3
    min_excitation_order: int = 4
    excitation_rcond: float = 1e-4
    residual_max_lag: int = 25
    residual_confidence: float = 0.99
    check_band_hz: tuple[float, float] = (0.01, 2.0)
    check_gain_db: float = 1.0
    check_phase_deg: float = 5.0
    on_check_failure: str = "error"
    slow_roots: str = "keep"

    def _checked(self, f: Fields) -> dict:
        cfg = dict(
            decimate=f.integer("decimate", min=1, max=50),
            criterion=f.string("criterion", choices=_arx.CRITERIA),
            focus=f.string("focus", choices=_arx.FOCUS),
            iterations=f.integer("iterations", min=1, max=200),
            na_max=f.integer("na_max", min=1, max=30),
            nb_max=f.integer("nb_max", min=1, max=30),
            nk_min=f.integer("nk_min", min=0, max=50),
            nk_max=f.integer("nk_max", min=0, max=50),
            validation_fraction=f.number("validation_fraction", min=0.05, max=0.8),
            min_excitation_order=f.integer("min_excitation_order", min=1, max=30),
            excitation_rcond=f.number("excitation_rcond", min=0, max=0.5, strict_min=True),
            residual_max_lag=f.integer("residual_max_lag", min=1, max=1000),
            residual_confidence=f.number("residual_confidence", min=0.5, max=0.9999),
            check_band_hz=f.numbers("check_band_hz", length=2),
            check_gain_db=f.number("check_gain_db", min=0, strict_min=True),
            check_phase_deg=f.number("check_phase_deg", min=0, strict_min=True),
            on_check_failure=f.string("on_check_failure", choices=("error", "warn")),
            slow_roots=f.string("slow_roots", choices=("keep", "reflect")),
        )
        if cfg["nk_max"] < cfg["nk_min"]:
            raise f.error("nk_max", f"an integer >= nk_min = {cfg['nk_min']}", cfg["nk_max"])
        lo, hi = cfg["check_band_hz"]
        if not 0 < lo < hi:
            raise f.error("check_band_hz", "[low, high] with 0 < low < high (Hz)", list(cfg["check_band_hz"]))
        return cfg


    def to_dict(self) -> dict:
        """The settings as JSON-ready values."""
        out = asdict(self)
        out["check_band_hz"] = list(self.check_band_hz)
        return out


@dataclass(frozen=True)
class AnalyticConfig(Settings):
    """The ``[analytic]`` table.

    Attributes
    ----------
    model : str
        Analytic aircraft file name in ``aircraft/`` (or a path).
    control : {"rolling", "full"}
        Which aileron → roll-rate plant goes into ``control_to_output``:
        the paper's rolling approximation (Eq. 14, default) or the full model.
    disturbance : {"full", "rolling"}
        Which wind → roll-rate plant goes into ``disturbance_to_output``: the
        full model (default; the wind acts through sideslip, which the
        rolling approximation does not have) or ``-(Lb/U) / (s - Lp)``.
    """

    TABLE = "analytic"

    model: str = "roskam"
    control: str = "rolling"
    disturbance: str = "full"

    def _checked(self, f: Fields) -> dict:
        return dict(model=f.string("model"), control=f.string("control", choices=("rolling", "full")),
                    disturbance=f.string("disturbance", choices=("full", "rolling")))

