"""The model pilot flies JSBSim: closed-loop roll-rate tracking on the approach.

:func:`fly_pilot_record` trims the aircraft like stage one
(:mod:`hesspipe.flight.approach`: the paper's approach, sanitised aircraft copy, terrain
lowered for the record) and then, at every JSBSim step (120 Hz by default),
lets a :class:`~hesspipe.pilot.discrete.DiscretePilot` read the roll rate
``y`` (``velocities/p-rad_sec``), form the displayed error ``e = r - y`` and
set ``fcs/aileron-cmd-norm = trim + delta`` while the paper's side wind plus
the seeded identification excitation (:class:`~hesspipe.flight.approach.FlightConfig`'s
``side_wind`` and ``wind_excitation``) blows. Nothing of the plants' linear
model is simulated: the plants only set the pilot's gain scale
(:func:`hesspipe.pilot.crossover.gain_scale`) and the motion path.

Pilot side (the pilot model's effects, :mod:`hesspipe.pilot.effects`):

* ``motion_feedback``: ``Km x canals x M(s)`` on the roll rate, where ``M`` is
  the plants' optional ``motion_path`` (SPEC.md "Data formats": controlled
  output → angular velocity the cab imposes), else the paper's platform x
  washout. Canals and Km are the pilot's.
* ``extra_delay``: more samples in the visual delay buffer.
* ``remnant``: ``Kn / (Tn s + 1)`` shaped unit-variance white noise, one draw
  per step from the run's seed (Kn given, or set from a share of the
  control variance by :func:`hesspipe.pilot.remnant.remnant_gain` on the plants).

Aircraft side (:class:`AircraftEffects`, hidden from the pilot model): an
aileron actuator lag and rate limit between the pilot's command and JSBSim,
the yaw damper removed from the aircraft's flight-control system, or an
aircraft other than the one the plants were fitted on.

Record (row k, as in :mod:`hesspipe.flight.approach`): ``time = k dt``; ``control`` the
pilot's command ``fcs/aileron-cmd-norm`` applied over ``[t_k, t_k + dt]``
(before any hidden actuator), ``disturbance`` the lateral wind (ft/s, relative
to the actual heading) applied over the step, ``output`` the roll rate at the
end of the step (rad/s), ``reference`` r. The pilot's command at row k uses
the output and the reference of row k-1, so the recorded loop holds one sample (8.3 ms) of
sampling delay on top of the pilot's ``tau0``, from the output and the reference alike.

Limits: the record fails with a one-line :class:`~hesspipe.core.errors.HesspipeError`
naming the limit and the time when the airspeed leaves trim +-
``max_speed_dev_kts``, the aircraft comes below ``min_agl_ft`` (or a gear
touches), or the bank leaves +- ``max_bank_deg``; nothing is written then.
"""

from __future__ import annotations

import json
import math
import os
import tempfile
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Mapping

import numpy as np

from ..core.errors import HesspipeError
from ..core.formats import Plants, Run, tf_coefficients, write_run
from ..core.io import check_output_dir, staged_output, write_json
from ..core.provenance import versions
from ..core.seeds import derive_seed
from ..pilot.blocks import Loop, from_tf
from ..pilot.crossover import gain_scale
from ..pilot.discrete import DiscretePilot
from ..pilot.hess import model_from_name
from ..pilot.motion import motion_block, with_motion_path
from ..pilot.remnant import remnant_gain_of_loops
from ..pilot.simulation import Simulator
from .aircraft import AircraftConfig, load_aircraft
from .approach import FlightConfig, _check_seed, _jsbsim, _load, _quiet_logger, _sanitised_aircraft, _trim
from .target import TargetForcing, record_flight
from .wind import heading_to_ned, ned_to_heading

#: Largest bank angle a record may reach, deg (a pilot nulling roll rate lets the bank wander).
MAX_BANK_DEG = 15.0
#: Pilot-side effects a flown pilot can have (aircraft effects are the aircraft's own business).
PILOT_EFFECTS = ("motion_feedback", "otoliths", "extra_delay", "remnant")
#: The pilot at step k reads the state JSBSim reached at the end of step k - 1, which the
#: record (like stage one's, from which the plants are fitted) files as row k - 1: one
#: sample of the loop's delay is the sampling's, taken off the pilot's visual buffer.
SAMPLE_LAG = 1
#: Default remnant share of the pilot's control variance when Kn is not given.
DEFAULT_REMNANT_SHARE = 0.1


@dataclass(frozen=True)
class AircraftEffects:
    """Aircraft-side effects hidden from the pilot model.

    Attributes
    ----------
    actuator_lag_s : float
        Time constant of a first-order aileron actuator between the pilot's
        command and ``fcs/aileron-cmd-norm``, s (0: none).
    rate_limit_per_s : float or None
        Largest rate of the actuated command, normalised command per s
        (None: none).
    yaw_damper : bool
        False removes the yaw damper's input to the rudder from the
        (sanitised copy of the) aircraft's flight-control system.
    """

    actuator_lag_s: float = 0.0
    rate_limit_per_s: float | None = None
    yaw_damper: bool = True

    def __post_init__(self):
        if not (math.isfinite(self.actuator_lag_s) and self.actuator_lag_s >= 0):
            raise HesspipeError(f"actuator_lag_s: expected a time constant >= 0 s, got "
                                f"{self.actuator_lag_s!r}")
        if self.rate_limit_per_s is not None and not (math.isfinite(self.rate_limit_per_s)
                                                      and self.rate_limit_per_s > 0):
            raise HesspipeError(f"rate_limit_per_s: expected a rate > 0 (normalised command per s), "
                                f"got {self.rate_limit_per_s!r}")

    @property
    def actuator(self) -> bool:
        """True if a hidden actuator (lag or rate limit) sits between the pilot and JSBSim."""
        return self.actuator_lag_s > 0 or self.rate_limit_per_s is not None

    def to_dict(self) -> dict:
        """The switched-on effects only ({} for the plain aircraft)."""
        out = {}
        if self.actuator_lag_s > 0:
            out["actuator_lag_s"] = self.actuator_lag_s
        if self.rate_limit_per_s is not None:
            out["rate_limit_per_s"] = self.rate_limit_per_s
        if not self.yaw_damper:
            out["yaw_damper"] = "off"
        return out


@dataclass(frozen=True)
class PilotFlight:
    """What :func:`fly_pilot_record` produced.

    Attributes
    ----------
    run : hesspipe.core.formats.Run
        The measured-run columns (synthetic), at the recorded rate.
    record : dict of ndarray
        Every step (full rate): time, disturbance, output, control, reference,
        ``applied`` (command JSBSim got after the hidden actuator), bank_deg,
        vc_kts, h_agl_ft.
    trim : dict
    truth : dict
        Parameters, effects, seeds, aircraft ("simulator": "jsbsim").
    """

    run: Run
    record: dict
    trim: dict
    truth: dict


# --------------------------------------------------------------------------- pilot

def pilot_loop(model, params: Mapping[str, float], plants: Plants | None = None) -> Loop:
    """The loop of `model` with complete `params`, its vestibular feedback acting through
    the plants' ``motion_path`` (:func:`hesspipe.pilot.motion.with_motion_path`; absent: the
    paper's platform × washout).

    Parameters
    ----------
    model : hesspipe.pilot.hess.PilotModel
        The pilot model (with its effects).
    params : mapping of str to float
        A complete parameter set of `model`.
    plants : hesspipe.core.formats.Plants, optional
        Plants whose ``motion_path`` (if any) replaces the paper's motion path; None
        keeps the paper's.

    Returns
    -------
    Loop
        ``model.loop(params)``, its vestibular feedback through the plants' motion path.
    """
    loop = model.loop(params)
    return loop if plants is None else with_motion_path(loop, motion_block(plants))


def _remnant_gain(model, p, plants, wind, r, dt, noise_seed, share) -> float:
    """Kn making remnant `share` of the control variance, estimated on the plants' linear loop.

    The same white sequence as the flight (the Simulator draws it from the same
    seed), so the flown share differs from `share` by the plant error only. The
    Simulator accepts a loop whose slowest mode grows too slowly to matter within
    the record (a high-gain pilot against the fitted 737 plants' slow
    right-half-plane zero), as the cohort does.
    """

    loop0, loop1 = (pilot_loop(model, {**p, "Kn": kn}, plants) for kn in (0.0, 1.0))
    sim = Simulator(plants, wind, dt, reference=r, noise_seed=noise_seed)
    return remnant_gain_of_loops(loop0, loop1, sim, share)


def _check_pilot_effects(model) -> None:
    bad = [e for e in model.effects if e not in PILOT_EFFECTS]
    if bad:
        raise HesspipeError(f"effect {bad[0]!r} acts on the aircraft, not the pilot; a pilot flying "
                            f"JSBSim can have {', '.join(PILOT_EFFECTS)} (aircraft-side effects: "
                            "actuator lag, rate limit, yaw damper off, another aircraft)")


# --------------------------------------------------------------------------- aircraft

def _disable_yaw_damper(aircraft_dir: Path, ac: AircraftConfig) -> list[str]:
    """Remove the yaw damper's inputs to other FCS components in the sanitised copy.

    Returns ``component <- property`` descriptions of what was removed.
    """
    xml = aircraft_dir / ac.model / f"{ac.model}.xml"
    tree = ET.parse(xml)
    removed = []
    for comp in tree.getroot().iter():
        name = (comp.get("name") or "").lower()
        if "damper" in name:
            continue
        for inp in [c for c in comp if c.tag == "input"]:
            prop = (inp.text or "").strip().lstrip("-")
            if "yaw-damper" in prop or "yaw_damper" in prop:
                comp.remove(inp)
                removed.append(f"{comp.get('name')} <- {prop}")
    if not removed:
        raise HesspipeError(f"aircraft {ac.name!r}: no yaw damper found in the flight-control system "
                            f"of JSBSim model {ac.model}; expected a component feeding a yaw-damper "
                            "property to the rudder")
    tree.write(xml, encoding="utf-8", xml_declaration=True)
    return removed


def _limit(label: str, what: str, t: float) -> HesspipeError:
    return HesspipeError(f"{label}: {what} at t = {t:.2f} s; expected the pilot to keep the aircraft "
                         "on speed, airborne and within the bank limit")


def _forcing(config: FlightConfig, plants: Plants, target, reference, t: np.ndarray, gust_seed: int):
    # (along, lateral) wind (ft/s) and the reference r at every step of `t`: the paper's
    # side wind plus the excitation, or a two-input forcing's wind and target lines.
    n = t.size
    along, lateral = config.side_wind(t, config.duration_s)
    if target is not None:
        if reference is not None:
            raise HesspipeError("reference: expected either a reference or a target forcing, not both")
        wind, reference = target.signals(t, gust_seed,
                                         from_tf(plants.disturbance_to_output).response)
        if not target.paper_side_wind:  # its drift would hide the low wind lines
            along, lateral = np.zeros(n), np.zeros(n)
        lateral = lateral + wind
    else:
        lateral = lateral + config.wind_excitation.signal(t, gust_seed)
    r = np.zeros(n) if reference is None else np.asarray(reference, dtype=float)
    if r.shape != (n,) or not np.isfinite(r).all():
        raise HesspipeError(f"reference: expected {n} finite samples (one per step), got shape {r.shape}")
    return along, lateral, r


def _fly(ac: AircraftConfig, workdir: Path, config: FlightConfig, aircraft_effects: AircraftEffects,
         pilot, signals: tuple, max_bank_deg: float, label: str):
    # JSBSim trimmed and flown in closed loop with `pilot` through `signals` (t, along,
    # lateral, r, white), its own log silenced: (record, trim, terrain ft, yaw-damper edits).
    jsbsim = _jsbsim()
    logger = _quiet_logger()
    previous = jsbsim.get_logger()
    jsbsim.set_logger(logger)
    try:
        workdir = workdir.resolve()
        aircraft_dir = workdir / "aircraft"
        aircraft_dir.mkdir(parents=True, exist_ok=True)
        if not (aircraft_dir / ac.model).exists():
            _sanitised_aircraft(ac.model, aircraft_dir)
        damper = [] if aircraft_effects.yaw_damper else _disable_yaw_damper(aircraft_dir, ac)
        fdm = _load(ac, workdir, logger)
        fdm.set_dt(config.dt_s)
        trim = _trim(fdm, ac)
        terrain = ac.record_terrain_ft if config.record_terrain_ft is None else config.record_terrain_ft
        fdm["position/terrain-elevation-asl-ft"] = terrain
        rec = _closed_loop(fdm, pilot, trim, *signals, config, aircraft_effects, max_bank_deg, label)
    finally:
        jsbsim.set_logger(previous)
    return rec, trim, terrain, damper


def fly_pilot_record(aircraft: str | AircraftConfig, plants: Plants, model, params: Mapping[str, float],
                     *, seed: int, workdir: Path, config: FlightConfig = FlightConfig(),
                     aircraft_effects: AircraftEffects = AircraftEffects(), reference=None,
                     max_bank_deg: float = MAX_BANK_DEG, record_every: int = 1,
                     remnant_share: float | None = None, run_id: str = "pilot",
                     target=None) -> PilotFlight:
    """Fly one closed-loop record with the pilot model in JSBSim.

    Parameters
    ----------
    aircraft : str or AircraftConfig
        Aircraft file name in ``aircraft/`` (may differ from the plants' aircraft).
    plants : Plants
        Fitted plants: the pilot's gain scale and optional ``motion_path``.
    model : PilotModel or str
        "original", "expanded" or "+"-joined effects (pilot-side only).
    params : mapping
        Parameter values; missing ones take Table 1 on the plants' scale
        (``crossover.gain_scale``). Without ``Kn`` a remnant is scaled to
        `remnant_share` of the control variance.
    seed : int
        Seeds of the wind excitation and the remnant noise.
    workdir : Path
        Where JSBSim's sanitised aircraft copy lives (inside the output's staging folder).
    config : FlightConfig
        Step, duration, speed/ground limits, side wind and wind excitation.
    aircraft_effects : AircraftEffects
    reference : array, optional
        r at every step (rad/s, default 0).
    max_bank_deg : float
    record_every : int
        Keep every n-th step in :attr:`PilotFlight.run`.
    remnant_share : float, optional
        Share of control variance for the remnant when Kn is not given
        (default :data:`DEFAULT_REMNANT_SHARE`).
    target : hesspipe.flight.target.TargetForcing, optional
        Two-input forcing: its wind lines replace ``config.wind_excitation`` and its
        target lines are the reference (then `reference` must not be given); its run-in
        is flown but not recorded (the record starts at ``run_in_s``); without
        ``target.paper_side_wind`` the paper's turning side wind is left out.

    Raises
    ------
    HesspipeError
        Bad parameters, trim failure, or a limit left (one line, limit and time).
    """

    ac = aircraft if isinstance(aircraft, AircraftConfig) else load_aircraft(aircraft)
    seed = _check_seed(seed)
    model = model_from_name(model)
    _check_pilot_effects(model)
    k_order = int(round(float(params.get("k", 1)))) if params else 1
    g = gain_scale(plants, k_order)
    p = model.complete(params, k_order, gain=g)
    dt = config.dt_s
    n = int(round(config.duration_s / dt))
    t = np.arange(n) * dt
    gust_seed, remnant_seed = derive_seed(seed, "gust"), derive_seed(seed, "remnant")
    along, lateral, r = _forcing(config, plants, target, reference, t, gust_seed)
    white = np.zeros(n)
    share = None
    if "remnant" in model.effects:
        white = np.random.default_rng(remnant_seed).standard_normal(n)
        if params is None or "Kn" not in params:
            share = DEFAULT_REMNANT_SHARE if remnant_share is None else float(remnant_share)
            if not 0 < share < 1:
                raise HesspipeError(f"remnant_share: expected a share in (0, 1), got {share!r}")
            p["Kn"] = _remnant_gain(model, p, plants, lateral, r, dt, remnant_seed, share)
    pilot = DiscretePilot(pilot_loop(model, p, plants), dt, sample_lag=SAMPLE_LAG)

    rec, trim, terrain, damper = _fly(ac, Path(workdir), config, aircraft_effects, pilot,
                                      (t, along, lateral, r, white), max_bank_deg,
                                      f"{ac.name} closed-loop pilot record (seed {seed})")
    first = int(round(target.run_in_s / dt)) if target is not None else 0
    trim = dict(trim, record_terrain_ft=terrain, record_h_agl_ft=trim["h_sl_ft"] - terrain)
    plants_aircraft = _plants_aircraft(plants)
    truth = {
        "id": run_id,
        "synthetic": True,
        "simulator": "jsbsim",
        "note": "SYNTHETIC DATA: the Hess pilot model flying the JSBSim aircraft in closed loop, "
                "not a human pilot",
        "aircraft": ac.name,
        "jsbsim_model": ac.model,
        "plants_aircraft": plants_aircraft,
        "aircraft_differs_from_plants": (None if plants_aircraft is None else plants_aircraft != ac.name),
        "model": model.name,
        "effects": list(model.effects),
        "parameters": {name: p[name] for name in model.parameter_names()},
        "gain_scale": g,
        "remnant_share": share,
        "aircraft_effects": dict(aircraft_effects.to_dict(),
                                 **({"yaw_damper_inputs_removed": damper} if damper else {})),
        "motion_path": ("plants" if plants.motion_path is not None else "platform x washout (paper)")
        if "motion_feedback" in model.effects else None,
        "seed": seed,
        "seeds": {"gust": gust_seed, "remnant": remnant_seed},
        "dt_s": dt * record_every,
        "simulation_dt_s": dt,
        "duration_s": config.duration_s,
        "disturbance": {"side_wind": (vars(config.side_wind) if target is None or target.paper_side_wind
                                      else "none (two-input forcing without the paper's side wind)"),
                        "excitation": (config.wind_excitation.describe("ft/s") if target is None
                                       else "interleaved multisine (see target)"),
                        "signal": "lateral wind relative to the actual heading, ft/s"},
        "target": None if target is None else target.describe(),
        "record_start_s": float(t[first]),
        "envelope": {"speed_kts": [float(rec["vc_kts"].min()), float(rec["vc_kts"].max())],
                     "trim_speed_kts": trim["vc_kts"],
                     "min_agl_ft": float(rec["h_agl_ft"].min()),
                     "max_abs_bank_deg": float(np.abs(rec["bank_deg"]).max())},
    }
    text = ", ".join(f"{name}={p[name]:.6g}" for name in model.parameter_names())
    comments = ("synthetic data: the Hess pilot model flying JSBSim in closed loop, not a human pilot",
                f"simulator: jsbsim, aircraft {ac.name} (model {ac.model}); plants of "
                f"{plants_aircraft or 'unknown aircraft'}",
                f"model: {model.name}", f"parameters: {text}",
                f"aircraft effects: {aircraft_effects.to_dict() or 'none'}", f"seed: {seed}",
                "signs: disturbance = lateral wind ft/s (+ towards the right wing), output = roll "
                "rate rad/s, control = fcs/aileron-cmd-norm (pilot's command, + rolls right)",
                "timing: row k = input over [t_k, t_k + dt], output at t_k + dt")
    if target is not None:
        comments += (f"forcing: two-input, wind and roll-rate target multisines on interleaved lines; "
                     f"{target.run_in_s:g} s run-in flown before the record"
                     + ("" if target.paper_side_wind else "; no paper's side wind"),)
    # The run-in is flown but not recorded: the record is the forcing's last whole period,
    # so the start-up transient stays out of it and the lines fall on its bins.
    sl = slice(first, None, record_every)
    run = Run(time=rec["time"][sl], disturbance=rec["disturbance"][sl], output=rec["output"][sl],
              control=rec["control"][sl], reference=rec["reference"][sl], id=run_id, synthetic=True,
              comments=comments)
    return PilotFlight(run=run, record=rec, trim=trim, truth=truth)


def _closed_loop(fdm, pilot: DiscretePilot, trim: dict, t, along, lateral, r, white,
                 config: FlightConfig, act: AircraftEffects, max_bank_deg: float, label: str) -> dict:
    """Step JSBSim and the pilot together; return the full-rate record."""
    pm = fdm.get_property_manager()
    get = {k: pm.get_node(p).get_double_value for k, p in (
        ("p", "velocities/p-rad_sec"), ("phi", "attitude/phi-deg"), ("vc", "velocities/vc-kts"),
        ("agl", "position/h-agl-ft"), ("wow", "gear/wow"), ("wn", "atmosphere/total-wind-north-fps"),
        ("we", "atmosphere/total-wind-east-fps"), ("psi", "attitude/psi-rad"))}
    set_north = pm.get_node("atmosphere/wind-north-fps").set_double_value
    set_east = pm.get_node("atmosphere/wind-east-fps").set_double_value
    set_ail = pm.get_node("fcs/aileron-cmd-norm").set_double_value
    north, east = heading_to_ned(along, lateral, math.radians(trim["psi_deg"]))
    north, east = north.tolist(), east.tolist()
    n = len(t)
    out = np.empty((n, 9))
    vc0, trim_ail = trim["vc_kts"], trim["aileron_norm"]
    dv, min_agl = config.max_speed_dev_kts, config.min_agl_ft
    alpha = 1.0 - math.exp(-config.dt_s / act.actuator_lag_s) if act.actuator_lag_s > 0 else 1.0
    max_step = act.rate_limit_per_s * config.dt_s if act.rate_limit_per_s is not None else math.inf
    applied = trim_ail
    r_l, w_l = r.tolist(), white.tolist()
    gp, gphi, gvc, gagl, gwow, gwn, gwe, gpsi = (get[k] for k in
                                                 ("p", "phi", "vc", "agl", "wow", "wn", "we", "psi"))
    step = pilot.step
    y = gp()
    # The pilot at step k reads the output of row k - 1, so it reads that row's reference
    # too: the record's e = r - y, row by row, is then the error it saw, tau0 before its
    # control. Reading r of row k put the target lines 1 step (8.3 ms) closer to the control
    # than the output: 1.5-3.4 % of |U| of equation error at the target lines of flown
    # two-input runs, which no pilot model fits (bench_flown_motion_limit, SYNTHETIC).
    r_seen = r_l[0] if n else 0.0
    for k in range(n):
        cmd = trim_ail + step(r_seen - y, y, w_l[k])
        r_seen = r_l[k]
        if act.actuator:
            move = alpha * (cmd - applied)
            applied += max(-max_step, min(max_step, move))
        else:
            applied = cmd
        set_north(north[k])
        set_east(east[k])
        set_ail(applied)
        fdm.run()
        y, phi, vc, agl = gp(), gphi(), gvc(), gagl()
        out[k] = (cmd, applied, y, phi, vc, agl, gwn(), gwe(), gpsi())
        if not (abs(phi) <= max_bank_deg and abs(vc - vc0) <= dv and agl >= min_agl and gwow() == 0):
            tk = float(t[k])
            if not all(map(math.isfinite, (y, phi, vc, agl))):
                raise _limit(label, "the simulation diverged (non-finite state)", tk)
            if abs(phi) > max_bank_deg:
                raise _limit(label, f"bank {phi:.1f} deg left the limit +-{max_bank_deg:g} deg", tk)
            if abs(vc - vc0) > dv:
                raise _limit(label, f"airspeed {vc:.1f} kt left trim {vc0:.1f} +-{dv:g} kt", tk)
            raise _limit(label, f"ground margin: {agl:.0f} ft AGL (minimum {min_agl:g} ft, gear on "
                         f"ground: {gwow() > 0})", tk)
    _, lat = ned_to_heading(out[:, 6], out[:, 7], out[:, 8])
    return {"time": np.asarray(t, dtype=float), "disturbance": lat, "output": out[:, 2],
            "control": out[:, 0], "reference": np.asarray(r, dtype=float), "applied": out[:, 1],
            "bank_deg": out[:, 3], "vc_kts": out[:, 4], "h_agl_ft": out[:, 5]}


def _plants_aircraft(plants: Plants) -> str | None:
    """The aircraft the plants were fitted on, if their metadata says (best effort)."""
    meta = plants.meta if isinstance(plants.meta, Mapping) else {}
    if isinstance(meta.get("aircraft"), str):
        return meta["aircraft"]
    src = meta.get("source")
    if isinstance(src, Mapping):
        if isinstance(src.get("aircraft"), str):
            return src["aircraft"]
        folder = src.get("flight_dir")
        if isinstance(folder, str):
            try:
                man = json.loads((Path(folder) / "manifest.json").read_text(encoding="utf-8"))
                return man.get("aircraft") if isinstance(man.get("aircraft"), str) else None
            except (OSError, ValueError):
                return None
    return None


# --------------------------------------------------------------------------- files

def fly_pilot(aircraft: str, plants: Plants, out_dir: str | os.PathLike, *, model="expanded",
              params: Mapping[str, float] | None = None, seed: int = 0,
              config: FlightConfig = FlightConfig(), aircraft_effects: AircraftEffects = AircraftEffects(),
              remnant_share: float | None = None, max_bank_deg: float = MAX_BANK_DEG,
              run_id: str = "pilot", draw: Callable | None = None,
              target: TargetForcing | None = None) -> PilotFlight:
    """Fly one pilot in JSBSim and write ``<run_id>.csv``, ``.truth.json`` and the figures
    of `draw` (:func:`hesspipe.viz.pilotflight.draw_pilot_flight`: ``<run_id>.png``) to `out_dir`.

    All files or none (staged output).

    Parameters
    ----------
    aircraft : str
        Aircraft flown (a name in ``aircraft/``), not necessarily the plants'.
    plants : Plants
        The plants the pilot's gains are scaled to; their optional
        ``motion_path`` drives the pilot's vestibular channel.
    out_dir : path
        Output folder (new, empty, or a fly-pilot folder hesspipe wrote).
    model, params, seed, config, aircraft_effects, remnant_share, max_bank_deg, run_id, target
        As in :func:`fly_pilot_record` (with `target`, the flight lasts its run-in plus
        ``config.duration_s``; the record is the last ``config.duration_s``).
    draw : callable, optional
        ``draw(folder, flight)`` writes figures into the staging folder
        `folder` and returns their file names (None: no figure).

    Returns
    -------
    PilotFlight
        The record (SYNTHETIC) and its truth.
    """
    if not str(run_id).strip():   # the files would be the hidden .csv, .truth.json
        raise HesspipeError(f"run_id: expected a non-empty name for the run's files, got {run_id!r}")
    # Checked before the flight: a folder that cannot take the output loses no result.
    out_dir = check_output_dir(out_dir, "fly-pilot")
    config = record_flight(config, target)
    with staged_output(out_dir, kind="fly-pilot") as stage:
        with tempfile.TemporaryDirectory(prefix=".jsbsim-", dir=stage) as work:
            flight = fly_pilot_record(aircraft, plants, model, params or {}, seed=seed, workdir=Path(work),
                                      config=config, aircraft_effects=aircraft_effects,
                                      remnant_share=remnant_share, max_bank_deg=max_bank_deg,
                                      run_id=run_id, target=target)
        write_run(stage / f"{run_id}.csv", flight.run)
        write_json(stage / f"{run_id}.truth.json", dict(
            flight.truth, trim=flight.trim, versions=versions(),
            plants={"control_to_output": tf_coefficients(plants.control_to_output),
                    "disturbance_to_output": tf_coefficients(plants.disturbance_to_output)}))
        if draw is not None:
            draw(stage, flight)
    return flight
