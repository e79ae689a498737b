"""Figure of a diagnosis: measured, baseline and final control PSDs, disagreement bands."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from . import save_figure, subplots


def plot_diagnosis(diagnosis, path: str | Path) -> Path:
    """Save the diagnosis figure to `path` (PNG/PDF/SVG by suffix).

    Top: measured control PSD with the baseline and final model PSDs (log scale),
    bands where the baseline disagreed beyond chance shaded (green if the final model
    closed them, red if they still disagree). Bottom: model/measured ratio in dB per
    bin for both models, with the final model's residual scatter as a grey band.

    Parameters
    ----------
    diagnosis : hesspipe.diagnose.results.Diagnosis
        The diagnosis (PSDs in control units^2/Hz).
    path : str or Path
        The image file.
    """
    d = diagnosis
    f = np.asarray(d.freq_hz)
    m = (f > 0) & (f <= d.config.band_hz[1]) & (f >= d.config.band_hz[0])
    fig, (ax, ax2) = subplots(2, 1, figsize=(8.0, 6.5), sharex=True,
                                  gridspec_kw={"height_ratios": [2, 1]})
    for before, after in zip(d.bands_before, d.bands_after):
        if before.disagrees:
            color = "tab:green" if not after.disagrees else "tab:red"
            for a in (ax, ax2):
                a.axvspan(before.lo_hz, before.hi_hz, color=color, alpha=0.12, lw=0)
    final_label = d.final_model + (" (final)" if d.named_effects else " (final = baseline)")
    ax.semilogy(f[m], d.measured_psd[m], color="k", lw=2.4, zorder=1, label="measured" + (
        " (synthetic)" if d.synthetic else ""))
    ax.semilogy(f[m], d.baseline_psd[m], color="tab:blue", lw=1.2, ls="--",
                label=f"{d.baseline_model} (baseline), gap {d.gap_before:.3g}")
    if d.named_effects:
        ax.semilogy(f[m], d.final_psd[m], color="tab:orange", lw=1.0, zorder=3,
                    label=f"{final_label}, gap {d.gap_after:.3g}")
    ax.set_ylabel("control PSD (units²/Hz)")
    title = f"Diagnosis of {d.run_id}: named " + (", ".join(d.named_effects) or "nothing")
    ax.set_title(title, fontsize=10)
    ax.legend(fontsize=8, loc="lower left")
    ax.grid(True, which="both", alpha=0.3)

    db = 10.0 / np.log(10.0)
    floor = d.criterion["scatter_db"]
    ax2.axhspan(-floor, floor, color="0.85", lw=0, label="residual scatter of the final model (1 sd)")
    ax2.plot(f[m], db * np.log(d.baseline_psd[m] / d.measured_psd[m]), color="tab:blue", ls="--",
             lw=1.0, label="baseline / measured")
    if d.named_effects:
        ax2.plot(f[m], db * np.log(d.final_psd[m] / d.measured_psd[m]), color="tab:orange", lw=1.0,
                 label="final / measured")
    ax2.axhline(0.0, color="k", lw=0.6)
    ax2.set_ylabel("model / measured (dB)")
    ax2.set_xlabel("frequency (Hz)")
    ax2.legend(fontsize=8, loc="lower left")
    ax2.grid(True, alpha=0.3)
    fig.tight_layout()
    return save_figure(fig, path, synthetic=d.synthetic)
