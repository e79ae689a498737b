"""Stage one: fly the landing approach in JSBSim and record it.

:func:`fly` loads a bundled JSBSim transport, trims it at the paper's
approach condition (AIAA 2009-6032 Table 2: 1300 ft baro, terrain 603 ft,
135 KCAS, heading 180 deg, flaps full, gear down, 3 deg glide slope) and
flies two records from that trim:

``wind.csv``
    The paper's slowly turning side wind (:class:`~hesspipe.flight.wind.SideWind`)
    plus a seeded identification excitation on its lateral component
    (default a 0.02-2 Hz multisine), controls fixed at trim.
``aileron.csv``
    Calm air, a seeded excitation added to the trim aileron command
    ``fcs/aileron-cmd-norm`` (default a 0.02-2 Hz multisine).

The excitation is generated here, not by JSBSim's turbulence model, so the
recorded wind is exactly the wind applied (JSBSim's turbulence also injects
rotational gusts that no lateral-wind record could carry).

Staying airborne: from 697 ft AGL a 3 deg descent reaches the ground after
51-65 s, so after trimming at the paper's condition the terrain below the
aircraft is lowered to the aircraft file's ``record.terrain_ft`` (0 ft by
default, about 1300 ft of clearance). The aircraft's state and air data are
untouched. Each record fails with :class:`~hesspipe.core.errors.HesspipeError`
if the aircraft comes below ``min_agl_ft``, any gear touches the ground, or
the calibrated airspeed leaves ``trim +- max_speed_dev_kts``.

Safety: JSBSim is never pointed at its bundled aircraft files directly. The
aircraft folder is copied into a temporary folder inside the output staging
folder with the top-level ``<input>`` and ``<output>`` elements removed
(the bundled 737 opens telnet/socket inputs on ports 5137 and 5139, the
global5000 writes ``global5000.csv`` into the working directory), and the
copy is deleted before the outputs are published.

Record conventions
------------------
Row ``k`` holds ``time = k * dt`` (s, from 0), the inputs applied during the
step from ``t_k`` to ``t_k + dt`` and the state at the end of that step.
JSBSim uses a new input in the force calculation of the *next* step, so the
state responds to an input one row later (ARX delay ``nk >= 1``).
Signs: ``wind_lateral_fps`` is the horizontal wind component perpendicular to
the actual heading, positive when the air moves towards the aircraft's right
(body +y at wings level); ``wind_north_fps``/``wind_east_fps`` are the total
wind JSBSim applied (direction the air moves towards). ``aileron_cmd`` is
``fcs/aileron-cmd-norm`` (-1..1, positive rolls right). Roll and yaw rates
are body rates (rad/s, positive right wing down / nose right); bank and
sideslip in degrees (positive right wing down / wind from the right).
"""

from __future__ import annotations

import math
import os
import shutil
import tempfile
import xml.etree.ElementTree as ET
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Callable

import numpy as np
import pandas as pd

from ..core.config import Fields, Settings
from ..core.errors import HesspipeError
from ..core.io import staged_output, write_json, write_text
from ..core.provenance import file_hash, versions
from ..core.seeds import check_seed
from .aircraft import AircraftConfig, load_aircraft
from .wind import Excitation, SideWind, heading_to_ned, ned_to_heading

#: Record columns, in file order (pinned: the plants stage reads them by name).
COLUMNS = ("time", "wind_lateral_fps", "wind_north_fps", "wind_east_fps", "aileron_cmd",
           "roll_rate_rps", "yaw_rate_rps", "bank_deg", "sideslip_deg", "heading_deg",
           "vc_kts", "h_agl_ft")

#: JSBSim properties read every step, by record column.
_PROPS = {
    "wind_north_fps": "atmosphere/total-wind-north-fps",
    "wind_east_fps": "atmosphere/total-wind-east-fps",
    "aileron_cmd": "fcs/aileron-cmd-norm",
    "roll_rate_rps": "velocities/p-rad_sec",
    "yaw_rate_rps": "velocities/r-rad_sec",
    "bank_deg": "attitude/phi-deg",
    "sideslip_deg": "aero/beta-deg",
    "heading_rad": "attitude/psi-rad",
    "vc_kts": "velocities/vc-kts",
    "h_agl_ft": "position/h-agl-ft",
    "wow": "gear/wow",
}

_DEFAULT_WIND_EXCITATION = Excitation(kind="multisine", rms=3.0, f_min_hz=0.02, f_max_hz=2.0)
_DEFAULT_AILERON_EXCITATION = Excitation(kind="multisine", rms=0.05, f_min_hz=0.02, f_max_hz=2.0)


@dataclass(frozen=True)
class FlightConfig(Settings):
    """Settings of stage one (the ``[flight]`` table).

    Attributes
    ----------
    duration_s : float
        Length of each record, s (> 0).
    dt_s : float
        JSBSim integration step, s.
    record_every : int
        Keep every n-th step in the records (1 = every step).
    max_speed_dev_kts : float
        Allowed deviation of calibrated airspeed from trim during a record, kt.
    min_agl_ft : float
        Lowest allowed height above the (record) terrain, ft.
    record_terrain_ft : float or None
        Terrain elevation during the records, ft; None takes the aircraft
        file's ``record.terrain_ft``.
    side_wind : SideWind
        The paper's turning wind (``[flight.side_wind]``).
    wind_excitation : Excitation
        Added to the lateral wind of the wind record, ft/s
        (``[flight.wind_excitation]``).
    aileron_excitation : Excitation
        Added to the trim aileron command of the aileron record, normalised
        (``[flight.aileron_excitation]``).
    """

    TABLE = "flight"

    duration_s: float = 70.0
    dt_s: float = 1.0 / 120.0
    record_every: int = 1
    max_speed_dev_kts: float = 10.0
    min_agl_ft: float = 50.0
    record_terrain_ft: float | None = None
    side_wind: SideWind = field(default_factory=SideWind)
    wind_excitation: Excitation = _DEFAULT_WIND_EXCITATION
    aileron_excitation: Excitation = _DEFAULT_AILERON_EXCITATION

    def _checked(self, f: Fields) -> dict:
        out = dict(
            duration_s=f.number("duration_s", min=0, strict_min=True, max=3600),
            dt_s=f.number("dt_s", min=0, strict_min=True, max=0.05),
            record_every=f.integer("record_every", min=1),
            max_speed_dev_kts=f.number("max_speed_dev_kts", min=0, strict_min=True),
            min_agl_ft=f.number("min_agl_ft", min=0),
            record_terrain_ft=f.number("record_terrain_ft", None, max=30000))
        for key, kind in (("side_wind", SideWind), ("wind_excitation", Excitation),
                          ("aileron_excitation", Excitation)):
            if not isinstance(f.table[key], kind):
                raise f.error(key, f"a {kind.__name__}", f.table[key])
        if out["duration_s"] < 2 * out["dt_s"] * out["record_every"]:
            raise f.error("duration_s", f"a number >= {2 * out['dt_s'] * out['record_every']:g} "
                          "(at least two recorded samples)", out["duration_s"])
        return out

    @classmethod
    def _table_values(cls, f: Fields) -> dict:
        """The sub-tables ``side_wind``, ``wind_excitation`` and ``aileron_excitation``, built."""
        d = cls()
        return dict(side_wind=SideWind.from_fields(f.table_("side_wind")),
                    wind_excitation=Excitation.from_fields(f.table_("wind_excitation"), d.wind_excitation),
                    aileron_excitation=Excitation.from_fields(f.table_("aileron_excitation"),
                                                              d.aileron_excitation))

    def to_dict(self) -> dict:
        """Plain dict (for manifests); None values are left out."""
        return {k: v for k, v in asdict(self).items() if v is not None}


@dataclass(frozen=True)
class FlightResult:
    """What :func:`fly` produced.

    Attributes
    ----------
    aircraft : str
    seed : int
    trim : dict
        The content of ``trim.json``.
    wind, aileron : pandas.DataFrame
        The two records, columns :data:`COLUMNS`.
    files : dict
        Output file name -> path in the output folder.
    """

    aircraft: str
    seed: int
    trim: dict
    wind: pd.DataFrame
    aileron: pd.DataFrame
    files: dict


# --------------------------------------------------------------------------- JSBSim

def _jsbsim():
    import jsbsim  # imported late: the CLI should start without it

    return jsbsim


def _sanitised_aircraft(model: str, root: Path) -> Path:
    """Copy the bundled aircraft folder of `model` into `root`, I/O elements removed.

    Returns the aircraft path to give JSBSim (``root``). Only the top-level
    ``<input>`` (socket servers) and ``<output>`` (files, sockets) elements
    of ``fdm_config`` files are removed; ``<output>`` inside flight-control
    components is a property name and stays.
    """
    src = Path(_jsbsim().get_default_root_dir()) / "aircraft" / model
    if not (src / f"{model}.xml").is_file():
        raise HesspipeError(f"JSBSim model {model!r} not found in {src.parent}")
    dst = root / model
    shutil.copytree(src, dst)
    for xml in dst.rglob("*.xml"):
        try:
            tree = ET.parse(xml)
        except ET.ParseError:
            continue  # not loaded by JSBSim as a model file
        top = tree.getroot()
        if top.tag != "fdm_config":
            continue
        io_elements = [el for el in top if el.tag in ("input", "output")]
        if io_elements:
            for el in io_elements:
                top.remove(el)
            tree.write(xml, encoding="utf-8", xml_declaration=True)
    return root


def _quiet_logger():
    jsbsim = _jsbsim()

    class _Collect(jsbsim.FGLogger):
        """Keeps JSBSim's console chatter off stdout; keeps errors for messages."""

        def __init__(self):
            super().__init__()
            self.level = 0
            self.errors: list[str] = []

        def set_level(self, level):
            self.level = int(level)

        def file_location(self, filename, line):
            pass

        def message(self, message):
            if self.level >= int(jsbsim.LogLevel.ERROR) and self.level != int(jsbsim.LogLevel.STDOUT):
                self.errors.append(" ".join(str(message).split()))

        def format(self, fmt):
            pass

        def flush(self):
            pass

    return _Collect()


def _load(ac: AircraftConfig, workdir: Path, logger=None):
    """A fresh FGFDMExec with the sanitised copy of `ac`'s model loaded."""
    jsbsim = _jsbsim()
    root = Path(jsbsim.get_default_root_dir())
    workdir = Path(workdir).resolve()
    aircraft_path = workdir / "aircraft"
    if not (aircraft_path / ac.model).exists():
        aircraft_path.mkdir(parents=True, exist_ok=True)
        _sanitised_aircraft(ac.model, aircraft_path)
    fdm = jsbsim.FGFDMExec(str(root))
    fdm.set_debug_level(0)
    fdm.set_output_path(str(workdir))
    ok = fdm.load_model_with_paths(ac.model, str(aircraft_path), str(root / "engine"),
                                   str(root / "systems"), True)
    if not ok:
        detail = "; ".join(logger.errors[-2:]) if logger is not None and logger.errors else "no detail"
        raise HesspipeError(f"JSBSim could not load model {ac.model!r} ({ac.path.name}): {detail}")
    fdm.disable_output()
    return fdm


def _trim(fdm, ac: AircraftConfig) -> dict:
    """Trim `fdm` at `ac.approach`; return the trim.json content."""
    jsbsim = _jsbsim()
    a = ac.approach
    # Order matters to FGInitialCondition: speed before flight-path angle, and
    # nothing that moves the aircraft (position) after the speed.
    fdm["ic/terrain-elevation-ft"] = a.terrain_ft
    fdm["ic/h-sl-ft"] = a.h_sl_ft
    fdm["ic/vc-kts"] = a.vc_kts
    fdm["ic/psi-true-deg"] = a.psi_deg
    fdm["ic/gamma-deg"] = a.gamma_deg
    fdm["fcs/flap-cmd-norm"] = a.flaps_norm
    fdm["gear/gear-cmd-norm"] = a.gear_norm
    fdm.run_ic()
    fdm["propulsion/set-running"] = -1
    try:
        fdm["simulation/do_simple_trim"] = 1  # full trim
    except jsbsim.TrimFailureError:
        raise HesspipeError(f"aircraft {ac.name!r}: JSBSim trim failed at {a.vc_kts:g} KCAS, "
                            f"{a.h_sl_ft:g} ft, flaps {a.flaps_norm:g}, gear {a.gear_norm:g}, "
                            f"gamma {a.gamma_deg:g} deg ({ac.path.name}); expected a condition "
                            "the model can fly") from None
    g = fdm.get_property_value
    trim = {
        "aircraft": ac.name,
        "jsbsim_model": ac.model,
        "vc_kts": g("velocities/vc-kts"),
        "vtrue_kts": g("velocities/vtrue-kts"),
        "gamma_deg": g("flight-path/gamma-deg"),
        "psi_deg": g("attitude/psi-deg"),
        "flaps_norm": g("fcs/flap-pos-norm"),
        "gear_norm": g("gear/gear-pos-norm"),
        "h_sl_ft": g("position/h-sl-ft"),
        "h_agl_ft": g("position/h-agl-ft"),
        "terrain_ft": g("position/terrain-elevation-asl-ft"),
        "alpha_deg": g("aero/alpha-deg"),
        "theta_deg": g("attitude/theta-deg"),
        "phi_deg": g("attitude/phi-deg"),
        "beta_deg": g("aero/beta-deg"),
        "throttle": g("fcs/throttle-cmd-norm"),
        # JSBSim's trim moves the pitch trim; the total normalised elevator
        # command is pitch trim plus elevator command.
        "elevator_norm": g("fcs/pitch-trim-cmd-norm") + g("fcs/elevator-cmd-norm"),
        "pitch_trim_norm": g("fcs/pitch-trim-cmd-norm"),
        "aileron_norm": g("fcs/aileron-cmd-norm"),
        "rudder_norm": g("fcs/rudder-cmd-norm"),
        "weight_lbs": g("inertia/weight-lbs"),
    }
    off = []
    if abs(trim["vc_kts"] - a.vc_kts) > 1.0:
        off.append(f"vc {trim['vc_kts']:.2f} kt (wanted {a.vc_kts:g} +- 1)")
    if abs(trim["gamma_deg"] - a.gamma_deg) > 0.2:
        off.append(f"gamma {trim['gamma_deg']:.2f} deg (wanted {a.gamma_deg:g} +- 0.2)")
    if abs((trim["psi_deg"] - a.psi_deg + 180.0) % 360.0 - 180.0) > 0.5:
        off.append(f"heading {trim['psi_deg']:.2f} deg (wanted {a.psi_deg:g} +- 0.5)")
    if abs(trim["flaps_norm"] - a.flaps_norm) > 0.01 or abs(trim["gear_norm"] - a.gear_norm) > 0.01:
        off.append(f"flaps {trim['flaps_norm']:.2f} / gear {trim['gear_norm']:.2f}")
    if off:
        raise HesspipeError(f"aircraft {ac.name!r}: trim ended off the approach condition: "
                            f"{'; '.join(off)} ({ac.path.name})")
    return trim


def _fly_record(fdm, *, n: int, psi_ref_rad: float, wind_along, wind_lateral, aileron,
                vc_trim: float, config: FlightConfig, label: str) -> pd.DataFrame:
    """Step `fdm` `n` times with the given per-step inputs; return the record."""
    pm = fdm.get_property_manager()
    node = {k: pm.get_node(p) for k, p in _PROPS.items()}
    north_in = pm.get_node("atmosphere/wind-north-fps")
    east_in = pm.get_node("atmosphere/wind-east-fps")
    ail_in = pm.get_node("fcs/aileron-cmd-norm")
    north, east = heading_to_ned(wind_along, wind_lateral, psi_ref_rad)
    names = [k for k in _PROPS]
    out = np.empty((n, len(names)))
    read = [node[k].get_double_value for k in names]
    for k in range(n):
        north_in.set_double_value(float(north[k]))
        east_in.set_double_value(float(east[k]))
        ail_in.set_double_value(float(aileron[k]))
        fdm.run()
        out[k] = [f() for f in read]
    rec = dict(zip(names, out.T))
    t = np.arange(n) * config.dt_s
    _check_envelope(t, rec, vc_trim, config, label)
    _, lateral = ned_to_heading(rec["wind_north_fps"], rec["wind_east_fps"], rec["heading_rad"])
    cols = {
        "time": t,
        "wind_lateral_fps": lateral,
        "wind_north_fps": rec["wind_north_fps"],
        "wind_east_fps": rec["wind_east_fps"],
        "aileron_cmd": rec["aileron_cmd"],
        "roll_rate_rps": rec["roll_rate_rps"],
        "yaw_rate_rps": rec["yaw_rate_rps"],
        "bank_deg": rec["bank_deg"],
        "sideslip_deg": rec["sideslip_deg"],
        "heading_deg": np.rad2deg(rec["heading_rad"]) % 360.0,
        "vc_kts": rec["vc_kts"],
        "h_agl_ft": rec["h_agl_ft"],
    }
    df = pd.DataFrame(cols, columns=list(COLUMNS))
    return df.iloc[::config.record_every].reset_index(drop=True)


def _check_envelope(t, rec, vc_trim, config: FlightConfig, label: str) -> None:
    bad_num = ~np.isfinite(rec["vc_kts"]) | ~np.isfinite(rec["roll_rate_rps"])
    ground = (rec["wow"] > 0) | (rec["h_agl_ft"] < config.min_agl_ft)
    speed = np.abs(rec["vc_kts"] - vc_trim) > config.max_speed_dev_kts
    for mask, what in ((bad_num, "the simulation diverged (non-finite state)"),
                       (ground, None), (speed, None)):
        if mask.any():
            i = int(np.argmax(mask))
            if what is None and mask is ground:
                what = (f"ground contact: {rec['h_agl_ft'][i]:.0f} ft AGL (minimum "
                        f"{config.min_agl_ft:g} ft, gear on ground: {bool(rec['wow'][i] > 0)})")
            elif what is None:
                what = (f"airspeed {rec['vc_kts'][i]:.1f} kt left trim {vc_trim:.1f} "
                        f"+- {config.max_speed_dev_kts:g} kt")
            raise HesspipeError(f"{label} record: {what} at t = {t[i]:.2f} s; expected the aircraft "
                                "airborne and on speed for the whole record (shorten duration_s, "
                                "lower record_terrain_ft or reduce the excitation)")


# --------------------------------------------------------------------------- public

def _check_seed(seed) -> int:

    return check_seed(seed)


def record_seeds(seed: int) -> tuple[np.random.SeedSequence, np.random.SeedSequence]:
    """Independent seeds of the wind and aileron excitations derived from `seed`.

    Parameters
    ----------
    seed : int
        The flight seed (as given to :func:`fly`).

    Returns
    -------
    wind, aileron : numpy.random.SeedSequence
        The two children spawned from ``SeedSequence(seed)``, in that order.
    """
    wind, aileron = np.random.SeedSequence(seed).spawn(2)
    return wind, aileron


def fly_records(aircraft: str | AircraftConfig, config: FlightConfig, seed: int, workdir: Path):
    """Load, trim and fly both records in memory; JSBSim's files live in `workdir`.

    Use :func:`fly` to also write the outputs.

    Parameters
    ----------
    aircraft : str or AircraftConfig
        Name of a file in ``aircraft/`` (e.g. ``"737"``) or a loaded aircraft.
    config : FlightConfig
        Record length and step (s), envelope limits, side wind and excitations.
    seed : int
        Seed of the excitation signals (split by :func:`record_seeds`).
    workdir : Path
        Folder for the sanitised copy of the JSBSim aircraft files.

    Returns
    -------
    trim : dict
        The ``trim.json`` content, plus ``record_terrain_ft`` and
        ``record_h_agl_ft`` (ft) of the records.
    wind_record, aileron_record : pandas.DataFrame
        The two records, columns :data:`COLUMNS` (units and signs in the
        module docstring).

    Raises
    ------
    HesspipeError
        Bad seed, trim failure, ground contact, speed excursion or a diverged
        simulation.
    """
    ac = aircraft if isinstance(aircraft, AircraftConfig) else load_aircraft(aircraft)
    seed = _check_seed(seed)
    jsbsim = _jsbsim()
    logger = _quiet_logger()
    previous = jsbsim.get_logger()
    jsbsim.set_logger(logger)
    try:
        n = int(round(config.duration_s / config.dt_s))
        t = np.arange(n) * config.dt_s
        s_wind, s_ail = record_seeds(seed)
        along, lateral = config.side_wind(t, config.duration_s)
        lateral = lateral + config.wind_excitation.signal(t, s_wind)
        terrain = ac.record_terrain_ft if config.record_terrain_ft is None else config.record_terrain_ft

        records = []
        trim = None
        for label, wa, wl, ail_exc in (("wind", along, lateral, np.zeros(n)),
                                       ("aileron", np.zeros(n), np.zeros(n),
                                        config.aileron_excitation.signal(t, s_ail))):
            fdm = _load(ac, workdir, logger)
            fdm.set_dt(config.dt_s)
            trim_k = _trim(fdm, ac)
            trim = trim or trim_k
            # Lower the terrain only now: the trim is flown over the paper's terrain.
            fdm["position/terrain-elevation-asl-ft"] = terrain
            records.append(_fly_record(
                fdm, n=n, psi_ref_rad=math.radians(trim_k["psi_deg"]), wind_along=wa,
                wind_lateral=wl, aileron=trim_k["aileron_norm"] + ail_exc,
                vc_trim=trim_k["vc_kts"], config=config, label=f"{ac.name} {label}"))
        trim = dict(trim, record_terrain_ft=terrain, record_h_agl_ft=trim["h_sl_ft"] - terrain)
        return trim, records[0], records[1]
    finally:
        jsbsim.set_logger(previous)


def _csv_text(df: pd.DataFrame, comments: list[str]) -> str:
    head = "".join(f"# {c}\n" for c in comments)
    return head + df.to_csv(index=False, float_format="%.10g", lineterminator="\n")


def fly(aircraft: str, config: FlightConfig, out_dir: str | os.PathLike, seed: int = 0, *,
        draw: Callable | None = None) -> FlightResult:
    """Stage one: trim `aircraft`, fly the wind and aileron records, write them to `out_dir`.

    Writes ``trim.json``, ``wind.csv``, ``aileron.csv``, the figures `draw`
    makes (``flight_wind.png``, ``flight_aileron.png`` with
    :func:`hesspipe.viz.flight.draw_flight`) and ``manifest.json`` (all or none).

    Parameters
    ----------
    aircraft : str
        Name of a file in ``aircraft/`` (e.g. ``"737"``).
    config : FlightConfig
    out_dir : path
        Output folder (created if needed).
    seed : int
        Seed of the excitation signals; the same seed gives identical files.
    draw : callable, optional
        ``draw(folder, wind, aileron, aircraft=name, seed=seed, config=config)``
        writes figures into the staging folder `folder` and returns their file
        names (None: no figures; the library itself never imports matplotlib).

    Raises
    ------
    HesspipeError
        Unknown or unsupported aircraft, trim failure, ground contact or
        speed excursion; nothing is written then.
    """
    ac = load_aircraft(aircraft)
    seed = _check_seed(seed)
    out_dir = Path(out_dir)
    if out_dir.exists() and not out_dir.is_dir():
        raise HesspipeError(f"{out_dir}: exists and is not a folder; expected an output folder")
    with staged_output(out_dir, kind="flight") as stage:
        with tempfile.TemporaryDirectory(prefix=".jsbsim-", dir=stage) as work:
            trim, wind, aileron = fly_records(ac, config, seed, Path(work).resolve())
        common = [f"aircraft: {ac.name} (JSBSim model {ac.model}), trimmed at {trim['vc_kts']:.2f} KCAS, "
                  f"heading {trim['psi_deg']:.2f} deg, gamma {trim['gamma_deg']:.2f} deg",
                  f"seed: {seed}; dt {config.dt_s:.6g} s, every {config.record_every} step(s); "
                  f"record terrain {trim['record_terrain_ft']:g} ft",
                  "signs: wind_lateral_fps > 0 = air moving towards the aircraft's right (body +y), "
                  "relative to the actual heading; wind_north/east_fps = direction the air moves "
                  "towards; aileron_cmd > 0 rolls right; roll/yaw rate body axes rad/s; "
                  "bank > 0 right wing down; sideslip > 0 wind from the right",
                  "timing: row k = input applied over [t_k, t_k + dt], state at t_k + dt; "
                  "inputs affect the state one row later"]
        sw = config.side_wind
        wind_comments = ["record: wind (side wind + lateral excitation, controls fixed at trim)"] + [
            f"side wind: speed {sw.speed_start_fps:g} -> {sw.speed_end_fps:g} ft/s, from "
            f"{sw.theta_start_deg:g} -> {sw.theta_end_deg:g} deg clockwise from the nose over "
            f"{config.duration_s:g} s",
            f"excitation: {config.wind_excitation.describe('ft/s')} on the lateral wind"] + common
        ail_comments = ["record: aileron (calm air, excitation on fcs/aileron-cmd-norm about trim)",
                        f"excitation: {config.aileron_excitation.describe('(normalised command)')}"
                        ] + common
        write_json(stage / "trim.json", trim)
        write_text(stage / "wind.csv", _csv_text(wind, wind_comments))
        write_text(stage / "aileron.csv", _csv_text(aileron, ail_comments))
        figures = []
        if draw is not None:
            figures = list(draw(stage, wind, aileron, aircraft=ac.name, seed=seed, config=config))
        write_json(stage / "manifest.json", {
            "stage": "flight",
            "aircraft": ac.name,
            "jsbsim_model": ac.model,
            "aircraft_file": str(ac.path),
            "aircraft_file_hash": file_hash(ac.path),
            "seed": seed,
            "config": config.to_dict(),
            "excitation": {"wind": config.wind_excitation.describe("ft/s"),
                           "aileron": config.aileron_excitation.describe("(normalised command)")},
            "columns": list(COLUMNS),
            "files": ["trim.json", "wind.csv", "aileron.csv", *figures],
            "source": f"JSBSim {versions().get('jsbsim')} simulation of the bundled {ac.model} model",
            "versions": versions(),
        })
    files = {name: out_dir / name for name in ("trim.json", "wind.csv", "aileron.csv", *figures,
                                                "manifest.json")}
    return FlightResult(aircraft=ac.name, seed=seed, trim=trim, wind=wind, aileron=aileron, files=files)
