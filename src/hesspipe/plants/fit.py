"""Stage two: identify the plants from a flight folder, or build the analytic ones.

:func:`fit_plants` reads the two stage-one records of a flight folder and
identifies, for each channel, an ARX model, converts it to a continuous
transfer function and validates both:

=========================  ==============  ====================  ==================
plant (plants.json key)    record          input                 output
=========================  ==============  ====================  ==================
``disturbance_to_output``  ``wind.csv``    ``wind_lateral_fps``  ``roll_rate_rps``
``control_to_output``      ``aileron.csv`` ``aileron_cmd``       ``roll_rate_rps``
=========================  ==============  ====================  ==================

Units and signs: lateral wind in ft/s, positive when the air moves towards
the right wing; aileron command normalised -1..1, positive gives positive
roll rate; roll rate in rad/s, positive right wing down.

Steps per channel (all configurable in ``[plants]``, see :class:`PlantsConfig`):

1. Deviations from trim: the first sample (the trimmed state) is subtracted
   from input and output, and simulations start from a zero state, so a
   record must start in trim (stage one's excitations fade in over 1 s).
2. Decimation by ``decimate`` (default 6: 120 Hz → 20 Hz, Nyquist 10 Hz, five
   times the 2 Hz check band) with scipy's zero-phase order-8 Chebyshev
   anti-alias filter, applied identically to input and output so their
   relation is unchanged. At 120 Hz an ARX model spends its parameters on
   the band above the excitation (stage one's multisines stop at 2 Hz) and
   its regressors are nearly collinear; much coarser sampling warps the
   Tustin conversion (see ``benchmarks/bench_plants.py`` for 4, 6 and 8).
3. Split: the first ``1 - validation_fraction`` of the record is estimation
   data, the tail (default the last 30 %, about 21 s of 70) is validation
   data, never used for estimation or order selection.
4. Persistent excitation check of the estimation input, then order and
   delay selection over ``na <= na_max, nb <= nb_max, nk_min <= nk <= nk_max``
   by ``criterion`` (AIC, BIC or FPE) on the estimation data, each candidate
   fitted with ``focus`` (default ``"simulation"``: least squares on
   1/A-prefiltered data, see :func:`hesspipe.plants.arx.arx_fit`; plain one-step
   least squares underweights the slow Dutch-roll/spiral band and gave
   validation fits of only 80-85 % on the 737 aileron record). Unstable
   candidates cannot be chosen.
5. Validation: simulated output (the model driven by the input alone from
   the trim state through the whole record) scored by the fit percent on
   the validation tail; residual whiteness and residual/input independence
   on the validation tail.
6. Tustin discrete → continuous conversion (:mod:`hesspipe.d2c`), checked
   against the discrete frequency response on ``check_band_hz``; the
   continuous model's own simulated validation fit is reported too.
7. Roots below the record's resolution. A record of duration T cannot
   place a root ``s = a`` with ``|a| < ln 2 / T`` (0.0099 1/s for 70 s;
   :func:`hesspipe.pilot.simulation.growth_limit`): its time constant is longer than
   the record, within which it is a factor two of a constant or an
   integrator. Two consequences. Order selection (step 4) accepts
   candidates whose poles grow slower than ``ln 2 / T`` ("stable on the
   record", as the closed loop is judged in :mod:`hesspipe.pilot.hess`): refusing
   them left the MD11's wind channel, whose Dutch roll is neutrally damped,
   with a bad low-order fit (27.7 % validation) whose notch near 2 Hz then
   failed the Tustin check by 2.55 dB / 23 deg. And every right-half-plane
   pole or zero slower than ``ln 2 / T`` is listed in the report with the
   continuous validation fit as fitted and with it reflected into the left
   half plane (``s -> -conj(s)``: gain response unchanged, phase moved by
   ``2 atan(a / w)``); ``slow_roots`` chooses which goes into plants.json.
   The default ``"keep"`` is what the held-out data prefer: the 737
   aileron channel's zero near +0.007 rad/s scores 99.4 % as fitted and
   97.6 % reflected (seed 0), so the data do carry it, and the closed loops
   it gives grow at 1e-3 1/s at most, which is stable on the record.
   ``"reflect"`` makes the plants minimum phase and stable at that cost.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Callable

import control as ct
import numpy as np
from scipy import signal

from ..core.config import aircraft_file
from ..core.errors import HesspipeError
from ..core.formats import Plants, read_csv_columns, sample_interval, write_plants
from ..core.io import staged_output, write_json, write_text
from ..core.provenance import file_hash, says_synthetic, versions
from ..pilot.motion import paper_motion_path
from ..pilot.simulation import growth_limit
from . import arx as _arx
from . import order as _order
from . import validation as _validation
from .analytic import analytic_transfer_functions, load_analytic
from .d2c import FrequencyCheck, compare_frequency_response, tustin_d2c

# The report's text lives in .report; PAPER_EQ16, describe_tf, format_tf, roots_table are
# imported here too, where users and older code look for them.
from .report import (  # noqa: F401
    PAPER_EQ16,
    UNITS,
    _analytic_markdown,
    _analytic_report,
    _channel_report,
    _eq16_report,
    _markdown,
    describe_tf,
    format_tf,
    roots_table,
)
from .settings import CHANNELS, AnalyticConfig, Channel, PlantsConfig
from .slow_roots import SlowRoots, phase_change, reflect_slow_roots


@dataclass(frozen=True)
class Record:
    """One channel's data as read from a flight file (full rate, raw values).

    Attributes
    ----------
    time : ndarray
        Sample times, s.
    input, output : ndarray
        The plant's input and output, the file's units.
    path : str
        The CSV file.
    comments : tuple of str
        Its ``#`` comment lines.
    """

    time: np.ndarray
    input: np.ndarray
    output: np.ndarray
    path: str
    comments: tuple[str, ...]

    @property
    def synthetic(self) -> bool:
        """True if a comment labels the record synthetic."""
        return says_synthetic(self.comments)


def read_record(path: str | Path, input_column: str, output_column: str, *,
                rtol: float = 1e-4) -> Record:
    """Read `time`, `input_column` and `output_column` from a flight-record CSV.

    Parameters
    ----------
    path : str or Path
        The CSV file.
    input_column, output_column : str
        Column names.
    rtol : float
        Relative tolerance of uniform sampling.

    Raises
    ------
    HesspipeError
        File missing, a column missing, non-finite values, or time not
        strictly increasing and uniform (within `rtol` of the median step).
    """
    path = Path(path)
    names = {"time": "time", input_column: input_column, output_column: output_column}
    data, comments = read_csv_columns(path, names, what="a stage-one flight record CSV")
    t = data["time"]
    if len(t) < 2:
        raise HesspipeError(f"{path}: {len(t)} samples; expected a record")
    dt, uniform = sample_interval(path, t, rtol=rtol)
    if not uniform:
        steps = np.diff(t)
        raise HesspipeError(f"{path}: column 'time': expected uniform sampling (interval {dt:g} s), "
                            f"found intervals from {steps.min():g} to {steps.max():g} s")
    if np.any(np.diff(t) <= 0):   # times written more coarsely than they advance: their grid
        t = t[0] + dt * np.arange(t.size, dtype=float)
    return Record(time=t, input=data[input_column], output=data[output_column], path=str(path),
                  comments=comments)


@dataclass(frozen=True)
class ChannelFit:
    """Everything identified and checked for one plant.

    The arrays are on the decimated grid, as deviations from trim.

    Attributes
    ----------
    channel : Channel
    source : str
        The CSV file.
    raw_dt : float
        Sample interval of the file, s.
    time, input, output : ndarray
        Decimated grid (s) and trim-removed input and output.
    n_estimation : int
        Samples used for estimation (the rest validate).
    selection : OrderSelection
        The ARX order selection.
    continuous : control.TransferFunction
        The plant in continuous time (what ``plants.json`` holds).
    conversion_notes : tuple of str
        How the discrete-to-continuous conversion handled awkward poles.
    check : FrequencyCheck
        Continuous vs discrete frequency response.
    simulated, simulated_continuous : ndarray
        Simulated output of the discrete and continuous models.
    fit_estimation, fit_validation, fit_validation_continuous : float
        Fit percent (100 perfect, may be negative).
    residuals : ResidualTests
    trim_input, trim_output : float
        Removed trim values, the file's units.
    synthetic : bool
        The record is labelled synthetic.
    slow_roots : SlowRoots, optional
        Right-half-plane roots the record cannot place.
    """

    channel: Channel
    source: str
    raw_dt: float
    time: np.ndarray
    input: np.ndarray
    output: np.ndarray
    n_estimation: int
    selection: _order.OrderSelection
    continuous: ct.TransferFunction
    conversion_notes: tuple[str, ...]
    check: FrequencyCheck
    simulated: np.ndarray
    simulated_continuous: np.ndarray
    fit_estimation: float
    fit_validation: float
    fit_validation_continuous: float
    residuals: _validation.ResidualTests
    trim_input: float
    trim_output: float
    synthetic: bool = False
    slow_roots: SlowRoots | None = None

    @property
    def model(self) -> _arx.ArxModel:
        """The chosen ARX model."""
        return self.selection.model

    @property
    def discrete(self) -> ct.TransferFunction:
        """The ARX model as a discrete transfer function (sample time in s)."""
        return self.model.tf()

    @property
    def validation_start_s(self) -> float:
        """Time of the first validation sample, s."""
        return float(self.time[self.n_estimation])


def _decimate(x: np.ndarray, q: int) -> np.ndarray:
    if q == 1:
        return x.copy()
    return signal.decimate(x, q, ftype="iir", zero_phase=True)


@dataclass(frozen=True)
class Prepared:
    """A record after steps 1–3: trim removed, decimated, split (checked, not yet fitted).""

    Attributes
    ----------
    time, input, output : ndarray
        Decimated grid (s), trim-removed input and output.
    raw_dt, dt : float
        Sample interval before and after decimation, s.
    n_estimation : int
        Estimation samples (the rest validate).
    trim_input, trim_output : float
        Removed trim values.
    label : str
        How messages name the data.
    """

    time: np.ndarray
    input: np.ndarray
    output: np.ndarray
    raw_dt: float
    dt: float
    n_estimation: int
    trim_input: float
    trim_output: float
    label: str


def prepare(record: Record, channel: Channel, config: PlantsConfig) -> Prepared:
    """Steps 1–3 and the data checks, so a bad record fails before any fitting.""

    Parameters
    ----------
    record : Record
    channel : Channel
    config : PlantsConfig
    """
    label = f"{record.path}: column '{channel.input}'"
    # The span over the count is exact to the CSV's precision; a single step is not.
    raw_dt = float(record.time[-1] - record.time[0]) / (len(record.time) - 1)
    q = config.decimate
    if len(record.time) < 30 * q:
        raise HesspipeError(f"{record.path}: record too short: {len(record.time)} samples, expected "
                            f"many more than 30 x decimate = {30 * q}")
    u0, y0 = float(record.input[0]), float(record.output[0])
    u = _decimate(record.input - u0, q)
    y = _decimate(record.output - y0, q)
    dt = raw_dt * q
    n_est = int(round(len(u) * (1 - config.validation_fraction)))
    if len(u) - n_est < 2 * config.residual_max_lag:
        raise HesspipeError(f"{record.path}: record too short: {len(record.time)} samples leave "
                            f"{len(u) - n_est} decimated validation samples, expected at least "
                            f"{2 * config.residual_max_lag}")
    nyq = 0.5 / dt
    if config.check_band_hz[1] >= nyq:
        raise HesspipeError(f"plants: field 'check_band_hz': upper limit {config.check_band_hz[1]:g} Hz "
                            f"is not below the Nyquist frequency {nyq:g} Hz after decimation by {q}")
    _order.check_data(u[:n_est], y[:n_est], na_max=config.na_max, nb_max=config.nb_max,
                    nk_max=config.nk_max, min_excitation=config.min_excitation_order,
                    rcond=config.excitation_rcond, label=label)
    return Prepared(time=record.time[0] + dt * np.arange(len(u)), input=u, output=y, raw_dt=raw_dt,
                    dt=dt, n_estimation=n_est, trim_input=u0, trim_output=y0, label=label)


def identify_channel(record: Record, channel: Channel, config: PlantsConfig,
                     prepared: Prepared | None = None) -> ChannelFit:
    """Identify, convert and validate one plant from one record (steps 1–6 of the module doc).""

    Parameters
    ----------
    record : Record
    channel : Channel
    config : PlantsConfig
    prepared : Prepared, optional
        The result of :func:`prepare` if already computed.
    """
    p = prepared or prepare(record, channel, config)
    u, y, t, dt, n_est, label = p.input, p.output, p.time, p.dt, p.n_estimation, p.label
    limit = growth_limit(dt * len(u))
    selection = _order.select_order(u[:n_est], y[:n_est], na_max=config.na_max, nb_max=config.nb_max,
                                  nk_min=config.nk_min, nk_max=config.nk_max,
                                  criterion=config.criterion, dt=dt,
                                  min_excitation=config.min_excitation_order,
                                  rcond=config.excitation_rcond, focus=config.focus,
                                  iterations=config.iterations, max_growth=limit, label=label)
    model = selection.model
    y_sim = model.simulate(u)
    val = slice(n_est, None)
    residuals = (y - model.predict(u, y))[val]
    tests = _validation.residual_tests(residuals, u[val], max_lag=config.residual_max_lag,
                                confidence=config.residual_confidence)
    sysd = model.tf()
    sysc, notes = tustin_d2c(sysd, label=f"{record.path}: {channel.title} ARX{model.orders}")
    check = compare_frequency_response(sysd, sysc, band_hz=tuple(config.check_band_hz),
                                       gain_limit_db=config.check_gain_db,
                                       phase_limit_deg=config.check_phase_deg)
    if not check.passed and config.on_check_failure == "error":
        raise HesspipeError(
            f"{record.path}: continuous {channel.title} model differs from the discrete ARX{model.orders} "
            f"by {check.max_gain_error_db:.2f} dB / {check.max_phase_error_deg:.1f} deg within "
            f"{check.band_hz[0]:g}-{check.band_hz[1]:g} Hz (limits {config.check_gain_db:g} dB / "
            f"{config.check_phase_deg:g} deg); lower 'decimate' or set on_check_failure = 'warn'")
    y_sim_c = np.asarray(ct.forced_response(sysc, T=t - t[0], U=u).outputs).reshape(-1)
    resolved, reflected = reflect_slow_roots(sysc, limit)
    y_res = y_sim_c
    if reflected:
        y_res = np.asarray(ct.forced_response(resolved, T=t - t[0], U=u).outputs).reshape(-1)
    slow = SlowRoots(limit=limit, roots=tuple(reflected), applied=config.slow_roots,
                     fit_validation_before=_validation.fit_percent(y[val], y_sim_c[val]),
                     fit_validation_after=_validation.fit_percent(y[val], y_res[val]),
                     max_phase_change_deg=phase_change(sysc, resolved, config.check_band_hz))
    if config.slow_roots == "reflect":
        sysc, y_sim_c = resolved, y_res
    return ChannelFit(
        channel=channel, source=record.path, raw_dt=p.raw_dt, time=t, input=u, output=y,
        n_estimation=n_est, selection=selection, continuous=sysc, conversion_notes=tuple(notes),
        check=check, simulated=y_sim, simulated_continuous=y_sim_c,
        fit_estimation=_validation.fit_percent(y[:n_est], y_sim[:n_est]),
        fit_validation=_validation.fit_percent(y[val], y_sim[val]),
        fit_validation_continuous=_validation.fit_percent(y[val], y_sim_c[val]),
        residuals=tests, trim_input=p.trim_input, trim_output=p.trim_output,
        synthetic=record.synthetic, slow_roots=slow)


# -- the stage -----------------------------------------------------------------------------

@dataclass(frozen=True)
class PlantsResult:
    """What :func:`fit_plants` produced.

    Attributes
    ----------
    plants : Plants
    fits : dict
        :class:`ChannelFit` by channel key.
    report : dict
        What ``plants_report.json`` holds.
    files : dict
        Written files by role.
    """

    plants: Plants
    fits: dict
    report: dict
    files: dict = field(default_factory=dict)


def fit_plants(flight_dir: str | Path, out_dir: str | Path, config: PlantsConfig | None = None, *,
               draw: Callable | None = None) -> PlantsResult:
    """Stage two: identify both plants from a flight folder and write the outputs.

    Writes ``plants.json`` (SPEC.md format, plus ``units``, ``orders``, ``fit``,
    ``source``), ``plants_report.md``, ``plants_report.json``, the figures
    `draw` makes (:func:`hesspipe.viz.plants.draw_plants`: ``plants_validation.png``,
    ``plants_bode.png``, ``plants_residuals.png``) and ``manifest.json`` into
    `out_dir`, all or none.

    Parameters
    ----------
    flight_dir : path
        A stage-one folder holding ``wind.csv`` and ``aileron.csv``
        (lateral wind ft/s, aileron command normalised, roll rate rad/s).
    out_dir : path
        Output folder (new, empty, or a plants folder hesspipe wrote).
    config : PlantsConfig, optional
        Decimation, hold-out share, order ranges, slow-root handling
        (default: ``PlantsConfig()``).
    draw : callable, optional
        ``draw(folder, fits, synthetic=bool)`` writes figures into the staging
        folder `folder` and returns their file names (None: no figures).

    Returns
    -------
    PlantsResult
        The fitted plants (continuous transfer functions, rad/s per input
        unit) with their validation.

    Raises
    ------
    HesspipeError
        A missing file or column, bad time or values, a record too short for
        the orders, an input not persistently exciting, or a failed
        continuous conversion check (unless ``on_check_failure = "warn"``).
    """
    config = config or PlantsConfig()
    flight_dir = Path(flight_dir)
    if not flight_dir.is_dir():
        what = "a file, not a folder" if flight_dir.exists() else "flight folder not found"
        raise HesspipeError(f"{flight_dir}: {what}; expected the flight stage's output folder "
                            "(wind.csv, aileron.csv)")
    records = {ch.key: read_record(flight_dir / ch.file, ch.input, ch.output) for ch in CHANNELS}
    prepared = {ch.key: prepare(records[ch.key], ch, config) for ch in CHANNELS}
    fits = {ch.key: identify_channel(records[ch.key], ch, config, prepared[ch.key]) for ch in CHANNELS}
    synthetic = any(f.synthetic for f in fits.values())
    inputs = {ch.file: file_hash(flight_dir / ch.file) for ch in CHANNELS}
    # Data files only: a manifest holds wall times, and hashing it would make these
    # outputs differ between two runs on the same records.
    if (flight_dir / "trim.json").is_file():
        inputs["trim.json"] = file_hash(flight_dir / "trim.json")
    frac = config.validation_fraction
    report = {
        "stage": "plants", "synthetic": synthetic,
        "source": {"flight_dir": str(flight_dir), "inputs": inputs},
        "validation_data": (f"held-out tail of each record: the last {100 * frac:g} % (never used for "
                            "estimation or order selection); the model is simulated from the trim "
                            "state through the whole record and scored on the tail"),
        "config": config.to_dict(),
        "channels": {k: _channel_report(f, config) for k, f in fits.items()},
        "paper_eq16": _eq16_report(),
    }
    # The output is roll rate on the paper's simulator: its platform x washout is the motion
    # path, written explicitly so the file says what the cab did (SPEC "Data formats").
    plants = Plants(fits["control_to_output"].continuous, fits["disturbance_to_output"].continuous,
                    motion_path=paper_motion_path())
    out_dir = Path(out_dir)
    names = ["plants.json", "plants_report.md", "plants_report.json", "manifest.json"]
    with staged_output(out_dir, kind="plants") as stage:
        write_plants(stage / "plants.json", plants, units=UNITS,
                     orders={k: report["channels"][k]["orders"] | {"dt_s": f.model.dt}
                             for k, f in fits.items()},
                     fit={k: report["channels"][k]["fit_percent"] for k in fits},
                     source={"kind": "arx", "flight_dir": str(flight_dir), "inputs": inputs,
                             "conversion": "tustin"},
                     synthetic=synthetic)
        write_json(stage / "plants_report.json", report)
        write_text(stage / "plants_report.md", _markdown(report, synthetic))
        if draw is not None:
            names[3:3] = list(draw(stage, fits, synthetic=synthetic))
        write_json(stage / "manifest.json", {
            "stage": "plants", "inputs": inputs, "flight_dir": str(flight_dir),
            "config": config.to_dict(), "synthetic": synthetic, "files": names, "versions": versions()})
    return PlantsResult(plants=plants, fits=fits, report=report,
                        files={n: out_dir / n for n in names})


# -- the analytic aircraft ------------------------------------------------------------------



def analytic_plants(name_or_path: str | Path, out_dir: str | Path,
                    config: AnalyticConfig | None = None, *, draw: Callable | None = None) -> Plants:
    """Write the analytic aircraft's plants: ``plants.json``, ``plants_report.md``,
    ``plants_report.json``, the figures of ``draw(folder, analytic_plants) -> names``
    (:func:`hesspipe.viz.plants.draw_analytic`: ``analytic_bode.png``) and
    ``manifest.json`` (all or none).

    Parameters
    ----------
    name_or_path : str or Path
        An aircraft in ``aircraft/`` with the paper's Table 3-4 data (``roskam``) or its file.
    out_dir : str or Path
        Output folder (new, empty, or one hesspipe wrote).
    config : AnalyticConfig, optional
        Which analytic models are the plants (default: the paper's choice).
    draw : callable, optional
        ``draw(folder, analytic_plants) -> file names``; no figures when None.

    Returns
    -------
    Plants
        Yc (aileron, rad -> roll rate, rad/s) and Yd (side wind, ft/s -> roll rate, rad/s).
    """
    config = config or AnalyticConfig()
    ac = load_analytic(name_or_path)
    ap = analytic_transfer_functions(ac)
    report = _analytic_report(ap, config)
    yc = ap.rolling_control if config.control == "rolling" else ap.full_control
    yd = ap.full_disturbance if config.disturbance == "full" else ap.rolling_disturbance
    plants = Plants(yc, yd, motion_path=paper_motion_path())   # roll rate, the paper's cab
    path = aircraft_file(name_or_path)
    names = ["plants.json", "plants_report.md", "plants_report.json", "manifest.json"]
    with staged_output(out_dir, kind="analytic") as stage:
        write_plants(stage / "plants.json", plants, units=report["units"],
                     orders={key: {"model": choice, "n_poles": len(describe_tf(tf)["den"]) - 1,
                                   "n_zeros": len(np.trim_zeros(describe_tf(tf)["num"], "f")) - 1}
                             for key, choice, tf in (("control_to_output", config.control, yc),
                                                     ("disturbance_to_output", config.disturbance, yd))},
                     fit=None, source={"kind": "analytic", "aircraft": ac.name, "file": ac.path,
                                       "equations": "paper Tables 3-4, Eqs. 11-14"},
                     models={k: {"num": v["num"], "den": v["den"]} for k, v in report["models"].items()},
                     synthetic=False)
        write_json(stage / "plants_report.json", report)
        write_text(stage / "plants_report.md", _analytic_markdown(report))
        if draw is not None:
            names[3:3] = list(draw(stage, ap))
        write_json(stage / "manifest.json", {
            "stage": "analytic", "inputs": {str(path): file_hash(path)}, "config": asdict(config),
            "files": names, "versions": versions()})
    return plants
