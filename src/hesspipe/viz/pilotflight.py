"""Figure of a closed-loop flight of the pilot model in JSBSim (SYNTHETIC)."""

from __future__ import annotations

from pathlib import Path

from . import save_figure, subplots


def plot_pilot_flight(flight, path: str | Path) -> Path:
    """Plot :class:`hesspipe.flight.closed_loop.PilotFlight` to `path`, stamped SYNTHETIC DATA.

    Panels: lateral wind (ft/s), roll rate and reference (rad/s), the pilot's
    aileron command and the command JSBSim got after any hidden actuator
    (normalised), bank (deg), airspeed (kt) and height above the record
    terrain (ft).

    Parameters
    ----------
    flight : hesspipe.flight.closed_loop.PilotFlight
    path : str or Path
        The image file.
    """
    rec, tr = flight.record, flight.truth
    t = rec["time"]
    fig, axes = subplots(5, 1, figsize=(9, 10), sharex=True)
    axes[0].plot(t, rec["disturbance"], lw=0.8, label="lateral wind, ft/s (+ = towards right)")
    axes[1].plot(t, rec["output"], lw=0.8, label="roll rate p, rad/s")
    axes[1].plot(t, rec["reference"], lw=0.8, label="reference r, rad/s")
    axes[2].plot(t, rec["control"], lw=0.8, color="tab:red", label="pilot's aileron command")
    if tr.get("aircraft_effects"):
        axes[2].plot(t, rec["applied"], lw=0.8, color="k", alpha=0.6, label="after the hidden actuator")
    axes[3].plot(t, rec["bank_deg"], lw=0.8, label="bank, deg")
    axes[4].plot(t, rec["vc_kts"], lw=0.8, label="calibrated airspeed, kt")
    ax = axes[4].twinx()
    ax.plot(t, rec["h_agl_ft"], lw=0.8, color="tab:green", label="height AGL, ft")
    ax.legend(loc="upper right", fontsize=8)
    axes[4].set_xlabel("time, s")
    for a in axes:
        a.legend(loc="upper left", fontsize=8)
        a.grid(True, alpha=0.3)
    effects = tr.get("aircraft_effects") or {}
    fig.suptitle(f"SYNTHETIC: {tr['model']} pilot model flying JSBSim {tr['aircraft']} (seed {tr['seed']})"
                 + (f"\naircraft effects: {', '.join(f'{k}={v}' for k, v in effects.items() if k != 'yaw_damper_inputs_removed')}"
                    if effects else ""), fontsize=10)
    fig.tight_layout()
    return save_figure(fig, path, synthetic=True)


def draw_pilot_flight(folder: str | Path, flight) -> list[str]:
    """The figure of :func:`hesspipe.flight.closed_loop.fly_pilot` (its ``draw``):
    ``<run id>.png`` in `folder`; returns its name.

    Parameters
    ----------
    folder : str or Path
        Folder to draw into.
    flight : hesspipe.flight.closed_loop.PilotFlight
        The closed-loop flight (record and truth).
    """
    name = f"{flight.run.id}.png"
    plot_pilot_flight(flight, Path(folder) / name)
    return [name]
