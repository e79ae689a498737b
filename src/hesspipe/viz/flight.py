"""Figures of the flight records (stage one)."""

from __future__ import annotations

from pathlib import Path

from . import save_figure, subplots

_INPUTS = {"wind": ("wind_lateral_fps", "lateral wind, ft/s (+ = towards right)"),
           "aileron": ("aileron_cmd", "aileron command, normalised")}


def plot_record(record, path: str | Path, *, kind: str, title: str = "") -> Path:
    """Plot one flight record (columns of :data:`hesspipe.flight.approach.COLUMNS`) to `path`.

    Panels: the record's input (`kind` ``"wind"``: lateral wind, ft/s;
    ``"aileron"``: aileron command), roll and yaw rate (rad/s), bank and
    sideslip (deg), calibrated airspeed (kt) and height AGL (ft).

    Parameters
    ----------
    record : mapping
        Columns by name (time in s).
    path : str or Path
        The image file.
    kind : {"wind", "aileron"}
        Which input the record was flown with.
    title : str
        Figure title.
    """
    column, label = _INPUTS[kind]
    t = record["time"]
    fig, axes = subplots(5, 1, figsize=(9, 10), sharex=True)
    axes[0].plot(t, record[column], lw=0.8, color="tab:red" if kind == "aileron" else "tab:blue",
                 label=label)
    axes[0].set_ylabel("input")
    axes[1].plot(t, record["roll_rate_rps"], lw=0.8, label="roll rate p")
    axes[1].plot(t, record["yaw_rate_rps"], lw=0.8, label="yaw rate r")
    axes[1].set_ylabel("rad/s")
    axes[2].plot(t, record["bank_deg"], lw=0.8, label="bank")
    axes[2].plot(t, record["sideslip_deg"], lw=0.8, label="sideslip")
    axes[2].set_ylabel("deg")
    axes[3].plot(t, record["vc_kts"], lw=0.8, label="calibrated airspeed")
    axes[3].set_ylabel("kt")
    axes[4].plot(t, record["h_agl_ft"], lw=0.8, label="height AGL")
    axes[4].set_ylabel("ft")
    axes[4].set_xlabel("time, s")
    for a in axes:
        a.legend(loc="upper left", fontsize=8)
        a.grid(True, alpha=0.3)
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    return save_figure(fig, path)


def draw_flight(folder: str | Path, wind, aileron, *, aircraft: str, seed: int, config) -> list[str]:
    """The figures of :func:`hesspipe.flight.approach.fly` (its ``draw``): ``flight_wind.png``
    and ``flight_aileron.png`` in `folder`; returns their names.

    Parameters
    ----------
    folder : str or Path
        Folder to draw into (the stage's staging folder).
    wind, aileron : pandas.DataFrame
        The two records (columns as in the CSV files).
    aircraft : str
        Aircraft name for the titles.
    seed : int
        The records' seed, for the titles.
    config : hesspipe.flight.approach.FlightConfig
        The flight's settings (excitation kinds in the titles).
    """
    folder = Path(folder)
    plot_record(wind, folder / "flight_wind.png", kind="wind", title=f"{aircraft}: side-wind "
                f"record ({config.wind_excitation.kind} excitation, seed {seed})")
    plot_record(aileron, folder / "flight_aileron.png", kind="aileron", title=f"{aircraft}: "
                f"aileron record ({config.aileron_excitation.kind} excitation, seed {seed})")
    return ["flight_wind.png", "flight_aileron.png"]
