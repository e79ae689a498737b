"""compare-pilots figures: one Fig. 8-style control-PSD plot per pilot."""

from __future__ import annotations

from pathlib import Path

from . import save_figure
from .pilots import plot_psd_comparison

#: Legend labels of the three configurations, in the paper's Fig. 8 wording.
LABELS = {"original": "original Hess",
          "expanded_fixed": "expanded Hess, Km fixed",
          "expanded": "expanded Hess, Km identified"}


def plot_pilot(pilot, path: str | Path) -> Path:
    """Save the measured control PSD against the three configurations of one pilot.

    Parameters
    ----------
    pilot : hesspipe.pilots.compare.PilotComparison
    path : path
        Image file (format from the suffix); stamped "SYNTHETIC DATA" if the run is synthetic.
    """
    sims = {LABELS[name]: pilot.simulated_psd[name] for name in LABELS}
    fits = {LABELS[name]: pilot.configuration(name)["fitness"] for name in LABELS}
    km = pilot.expanded_fixed["parameters"].get("Km")
    title = (f"{pilot.id}{' (synthetic)' if pilot.synthetic else ''}: control PSD; "
             f"improvement {100 * pilot.improvement:.0f} %" + (f", fixed Km = {km:g}" if km is not None else ""))
    fig = plot_psd_comparison(pilot.freq_hz, pilot.measured_psd, sims,
                              band=(0.0, float(pilot.freq_hz[-1])) if len(pilot.freq_hz) else (0.0, 5.0),
                              title=title, fitness=fits,
                              measured_label="synthetic 'measured' control" if pilot.synthetic
                              else "measured control")
    return save_figure(fig, path, synthetic=pilot.synthetic)
