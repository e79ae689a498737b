"""Pilot-model figures: control PSDs, measured against identified models (paper Fig. 8)."""

from __future__ import annotations

from pathlib import Path
from typing import Mapping, Sequence

import numpy as np

from ..core.paper import FITNESS_BAND_HZ
from . import save_figure, subplots

_STYLES = [dict(color="k", ls=":", lw=1.8), dict(color="m", ls="-.", lw=1.5),
           dict(color="r", ls="--", lw=1.5), dict(color="g", ls="-", lw=1.0),
           dict(color="c", ls="--", lw=1.0), dict(color="orange", ls="-.", lw=1.0)]


def plot_psd_comparison(freq_hz, measured, simulated: Mapping[str, np.ndarray], *,
                        band=FITNESS_BAND_HZ, title: str | None = None, ax=None,
                        measured_label: str = "measured control", fitness: Mapping[str, float] | None = None):
    """Draw a measured control PSD against simulated ones, on `ax` (new figure if None).

    Parameters
    ----------
    freq_hz : array
        Bin frequencies, Hz.
    measured : array
        Measured PSD (blue solid, as in the paper).
    simulated : mapping
        Label → simulated PSD (NaN arrays, e.g. unstable, are skipped).
    band : (lo, hi)
        Frequency range shown, Hz.
    fitness : mapping, optional
        Label → fitness, appended to the legend.

    Returns
    -------
    matplotlib.figure.Figure
    """
    if ax is None:
        fig, ax = subplots(figsize=(7.0, 4.2))
    else:
        fig = ax.figure
    f = np.asarray(freq_hz)
    m = (f >= band[0]) & (f <= band[1] + 1e-9)
    ax.plot(f[m], np.asarray(measured)[m], color="b", lw=2.0, label=measured_label)
    for i, (label, psd) in enumerate(simulated.items()):
        psd = np.asarray(psd)
        if not np.all(np.isfinite(psd[m])):
            continue
        text = label if not fitness or label not in fitness else f"{label} (fitness {fitness[label]:.3g})"
        ax.plot(f[m], psd[m], label=text, **_STYLES[i % len(_STYLES)])
    ax.set_xlabel("Frequency, Hz")
    ax.set_ylabel("Control PSD")
    ax.set_xlim(band)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    if title:
        ax.set_title(title)
    fig.tight_layout()
    return fig


def identification_figure(path: str | Path, identifications: Sequence, *, title: str | None = None,
                          labels: Sequence[str] | None = None) -> Path:
    """Save a Fig. 8-style figure of one run's identifications (same run, several models).

    `identifications` are :class:`hesspipe.identification.fit.Identification` results
    sharing the measured spectrum; the figure is stamped synthetic if the run is.

    Parameters
    ----------
    path : str or Path
        The image file.
    identifications : sequence of Identification
        Results for the same run.
    title : str, optional
        Figure title.
    labels : sequence of str, optional
        Legend labels (default: the model names).
    """
    first = identifications[0]
    labels = list(labels) if labels else [i.model for i in identifications]
    sims = {lab: i.simulated_psd for lab, i in zip(labels, identifications)}
    fits = {lab: i.fitness for lab, i in zip(labels, identifications)}
    fig = plot_psd_comparison(first.freq_hz, first.measured_psd, sims, band=first.band,
                              title=title or f"{first.run_id}: control PSD, measured vs identified",
                              fitness=fits)
    return save_figure(fig, path, synthetic=any(i.synthetic for i in identifications))
