"""Aircraft configuration: one TOML file per aircraft in ``aircraft/``.

Each file names the bundled JSBSim model, the approach condition it is
trimmed at (the paper's Table 2 by default) and how the record is kept
airborne. A model known not to fly the condition carries an ``unsupported``
reason instead, which :func:`load_aircraft` raises as the error.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from ..core.config import Fields, aircraft_file, data_dir, load_toml
from ..core.errors import HesspipeError

#: The aircraft flown when none is named: the closest bundled type to the paper's 757.
DEFAULT_AIRCRAFT = "737"


@dataclass(frozen=True)
class Approach:
    """Trim condition. Units: ft, kt (calibrated), deg; flaps/gear normalised 0..1.

    Attributes
    ----------
    h_sl_ft : float
        Altitude above sea level, ft.
    terrain_ft : float
        Terrain elevation, ft.
    vc_kts : float
        Calibrated airspeed, kt.
    psi_deg : float
        True heading, deg (clockwise from north).
    gamma_deg : float
        Flight-path angle, deg (negative: descending).
    flaps_norm, gear_norm : float
        Flap and gear positions, 0 (up) to 1 (down).
    """

    h_sl_ft: float = 1300.0
    terrain_ft: float = 603.0
    vc_kts: float = 135.0
    psi_deg: float = 180.0
    gamma_deg: float = -3.0
    flaps_norm: float = 1.0
    gear_norm: float = 1.0


@dataclass(frozen=True)
class AircraftConfig:
    """One aircraft file.

    Attributes
    ----------
    name : str
        The file stem (what ``--aircraft`` takes).
    model : str
        JSBSim model name in the wheel's ``aircraft/`` folder.
    approach : Approach
        Trim condition.
    record_terrain_ft : float
        Terrain elevation under the aircraft while the records are flown (ft);
        lowered from the trim terrain so a 70 s 3-deg descent stays airborne.
    path : Path
        The TOML file (hashed into manifests).
    """

    name: str
    model: str
    approach: Approach
    record_terrain_ft: float
    path: Path


def known_aircraft() -> list[str]:
    """Names of the JSBSim aircraft files in ``aircraft/`` (supported or not), sorted.

    Files without a ``[jsbsim]`` table (the paper's analytic aircraft) are
    not flyable and are left out.
    """
    return sorted(p.stem for p in data_dir("aircraft").glob("*.toml") if "jsbsim" in load_toml(p))


def load_aircraft(name: str) -> AircraftConfig:
    """Load ``aircraft/<name>.toml``.

    Parameters
    ----------
    name : str
        A file name in ``aircraft/`` without ``.toml``.

    Raises
    ------
    HesspipeError
        Unknown name (the message lists the known ones), a malformed file, or
        an aircraft marked ``unsupported`` (the message gives the reason).
    """
    known = known_aircraft()
    if not isinstance(name, str) or name not in known:
        raise HesspipeError(f"unknown aircraft {name!r}; expected one of: {', '.join(known)}")
    path = aircraft_file(name)
    f = Fields(load_toml(path), path)
    j = f.table_("jsbsim")
    model = j.string("model")
    j.reject_unknown()
    if "unsupported" in f.table:
        reason = f.string("unsupported")
        raise HesspipeError(f"aircraft {name!r} ({path.name}) is not supported: {reason}")
    a = f.table_("approach")
    d = Approach()
    approach = Approach(
        h_sl_ft=a.number("h_sl_ft", d.h_sl_ft),
        terrain_ft=a.number("terrain_ft", d.terrain_ft),
        vc_kts=a.number("vc_kts", d.vc_kts, min=0, strict_min=True),
        psi_deg=a.number("psi_deg", d.psi_deg, min=0, max=360),
        gamma_deg=a.number("gamma_deg", d.gamma_deg, min=-10, max=10),
        flaps_norm=a.number("flaps_norm", d.flaps_norm, min=0, max=1),
        gear_norm=a.number("gear_norm", d.gear_norm, min=0, max=1),
    )
    if approach.h_sl_ft <= approach.terrain_ft:
        raise a.error("h_sl_ft", f"a number > terrain_ft = {approach.terrain_ft:g}", approach.h_sl_ft)
    a.reject_unknown()
    r = f.table_("record")
    record_terrain = r.number("terrain_ft", approach.terrain_ft, max=approach.h_sl_ft)
    r.reject_unknown()
    f.reject_unknown()
    return AircraftConfig(name=name, model=model, approach=approach,
                          record_terrain_ft=record_terrain, path=Path(path))
