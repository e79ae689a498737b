"""Figures of stage two: validation overlay, Bode (continuous vs discrete), residuals."""

from __future__ import annotations

from pathlib import Path

import control as ct
import numpy as np

from ..plants.d2c import frequency_response
from ..plants.report import PAPER_EQ16
from . import save_figure, subplots


def plot_validation(fits: dict, path: str | Path, *, synthetic: bool = False) -> Path:
    """Measured vs simulated roll rate for each channel; validation tail shaded.

    Parameters
    ----------
    fits : dict
        :class:`hesspipe.plants.fit.ChannelFit` by channel key.
    path : str or Path
        The image file.
    synthetic : bool
        Stamp "SYNTHETIC DATA".
    """
    fig, axes = subplots(len(fits), 1, figsize=(9, 3.2 * len(fits)), squeeze=False)
    for ax, fit in zip(axes[:, 0], fits.values()):
        t = fit.time
        ax.plot(t, fit.output, color="k", lw=1.0, label="recorded")
        ax.plot(t, fit.simulated, color="tab:blue", lw=0.9, label=f"ARX{fit.model.orders} simulated")
        ax.plot(t, fit.simulated_continuous, color="tab:orange", lw=0.8, ls="--",
                label="continuous model simulated")
        ax.axvspan(fit.validation_start_s, t[-1], color="0.9", zorder=0)
        ax.set_title(f"{fit.channel.title}: validation fit {fit.fit_validation:.1f} % "
                     f"(shaded: validation data)", fontsize=10)
        ax.set_ylabel("roll rate dev. (rad/s)")
        ax.legend(fontsize=8, loc="upper left")
    axes[-1, 0].set_xlabel("time (s)")
    fig.tight_layout()
    return save_figure(fig, path, synthetic=synthetic)


def plot_bode(fits: dict, path: str | Path, *, synthetic: bool = False, reference=None) -> Path:
    """Bode of discrete ARX and continuous conversion per channel, check band marked.

    `reference` (a continuous tf, e.g. the paper's Eq. 16) is drawn on the
    wind channel for comparison.

    Parameters
    ----------
    fits : dict
        :class:`hesspipe.plants.fit.ChannelFit` by channel key.
    path : str or Path
        The image file.
    synthetic : bool
        Stamp "SYNTHETIC DATA".
    reference : control.TransferFunction, optional
        A continuous tf to draw on the wind channel.
    """
    fig, axes = subplots(2, len(fits), figsize=(5.5 * len(fits), 6), squeeze=False, sharex="col")
    for j, (key, fit) in enumerate(fits.items()):
        nyq = 0.5 / fit.model.dt
        f = np.logspace(-2.5, np.log10(nyq * 0.999), 500)
        hd = frequency_response(fit.discrete, f)
        hc = frequency_response(fit.continuous, f)
        mag, ph = axes[0, j], axes[1, j]
        mag.semilogx(f, 20 * np.log10(np.abs(hd)), color="tab:blue", label=f"discrete ARX{fit.model.orders}")
        mag.semilogx(f, 20 * np.log10(np.abs(hc)), color="tab:orange", ls="--", label="continuous (Tustin)")
        ph.semilogx(f, np.degrees(np.unwrap(np.angle(hd))), color="tab:blue")
        ph.semilogx(f, np.degrees(np.unwrap(np.angle(hc))), color="tab:orange", ls="--")
        if reference is not None and key == "disturbance_to_output":
            hr = frequency_response(reference, f)
            mag.semilogx(f, 20 * np.log10(np.abs(hr)), color="0.5", lw=0.8, label="paper Eq. 16 (B757)")
            ph.semilogx(f, np.degrees(np.unwrap(np.angle(hr))), color="0.5", lw=0.8)
        for ax in (mag, ph):
            ax.axvspan(*fit.check.band_hz, color="0.93", zorder=0)
            ax.grid(True, which="both", lw=0.3)
        chk = fit.check
        mag.set_title(f"{fit.channel.title}\nmax diff in band {chk.max_gain_error_db:.2f} dB, "
                      f"{chk.max_phase_error_deg:.1f} deg", fontsize=9)
        mag.set_ylabel("gain (dB)")
        ph.set_ylabel("phase (deg)")
        ph.set_xlabel("frequency (Hz)")
        mag.legend(fontsize=7)
    fig.tight_layout()
    return save_figure(fig, path, synthetic=synthetic)


def plot_residuals(fits: dict, path: str | Path, *, synthetic: bool = False) -> Path:
    """Residual autocorrelation and residual/input cross-correlation with bounds.

    Parameters
    ----------
    fits : dict
        :class:`hesspipe.plants.fit.ChannelFit` by channel key.
    path : str or Path
        The image file.
    synthetic : bool
        Stamp "SYNTHETIC DATA".
    """
    fig, axes = subplots(len(fits), 2, figsize=(10, 3 * len(fits)), squeeze=False)
    for i, fit in enumerate(fits.values()):
        r = fit.residuals
        a, c = axes[i, 0], axes[i, 1]
        a.stem(r.lags, r.autocorrelation, basefmt=" ")
        a.axhspan(-r.autocorrelation_bound, r.autocorrelation_bound, color="tab:green", alpha=0.2)
        a.set_title(f"{fit.channel.title}: residual autocorrelation "
                    f"({'white' if r.white else 'NOT white'})", fontsize=9)
        c.stem(r.cross_lags, r.cross_correlation, basefmt=" ")
        c.axhspan(-r.cross_correlation_bound, r.cross_correlation_bound, color="tab:green", alpha=0.2)
        c.set_title(f"residual/input cross-correlation "
                    f"({'independent' if r.independent else 'NOT independent'})", fontsize=9)
        for ax in (a, c):
            ax.set_xlabel(f"lag (samples of {fit.model.dt:.3g} s)")
    fig.tight_layout()
    return save_figure(fig, path, synthetic=synthetic)


def plot_analytic(ap, path: str | Path) -> Path:
    """Bode of the analytic aircraft: full model and rolling approximation, both inputs.

    Parameters
    ----------
    ap : hesspipe.plants.analytic.AnalyticPlants
    path : str or Path
        The image file.
    """
    f = np.logspace(-3, 1, 500)
    fig, axes = subplots(2, 2, figsize=(11, 6), sharex=True)
    pairs = (("aileron (rad) -> roll rate", ap.full_control, ap.rolling_control),
             ("lateral wind (ft/s) -> roll rate", ap.full_disturbance, ap.rolling_disturbance))
    for j, (title, full, rolling) in enumerate(pairs):
        for sys, style, label in ((full, "-", "full (Eqs. 11-13)"), (rolling, "--", "rolling approx. (Eq. 14)")):
            h = frequency_response(sys, f)
            axes[0, j].semilogx(f, 20 * np.log10(np.abs(h)), ls=style, label=label)
            axes[1, j].semilogx(f, np.degrees(np.unwrap(np.angle(h))), ls=style)
        axes[0, j].set_title(f"{ap.aircraft.name}: {title}", fontsize=10)
        axes[0, j].legend(fontsize=8)
        axes[0, j].set_ylabel("gain (dB)")
        axes[1, j].set_ylabel("phase (deg)")
        axes[1, j].set_xlabel("frequency (Hz)")
        for ax in axes[:, j]:
            ax.grid(True, which="both", lw=0.3)
    fig.tight_layout()
    return save_figure(fig, path)


def draw_plants(folder: str | Path, fits: dict, *, synthetic: bool = False) -> list[str]:
    """The figures of :func:`hesspipe.plants.fit.fit_plants` (its ``draw``) in `folder`:
    validation, Bode (with the paper's Eq. 16) and residuals; returns their names.

    Parameters
    ----------
    folder : str or Path
        Folder to draw into.
    fits : dict
        Channel name -> :class:`hesspipe.plants.fit.ChannelFit`.
    synthetic : bool
        Label the figures SYNTHETIC.
    """

    folder = Path(folder)
    plot_validation(fits, folder / "plants_validation.png", synthetic=synthetic)
    plot_bode(fits, folder / "plants_bode.png", synthetic=synthetic, reference=ct.tf(*PAPER_EQ16))
    plot_residuals(fits, folder / "plants_residuals.png", synthetic=synthetic)
    return ["plants_validation.png", "plants_bode.png", "plants_residuals.png"]


def draw_analytic(folder: str | Path, ap) -> list[str]:
    """The figure of :func:`hesspipe.plants.fit.analytic_plants` (its ``draw``): ``analytic_bode.png``.

    Parameters
    ----------
    folder : str or Path
        Folder to draw into.
    ap : hesspipe.plants.analytic.AnalyticPlants
        The analytic aircraft's transfer functions.
    """
    plot_analytic(ap, Path(folder) / "analytic_bode.png")
    return ["analytic_bode.png"]
