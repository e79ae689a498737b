"""compare-pilots figures: one Fig. 8-style control-PSD plot per pilot."""

from __future__ import annotations

from pathlib import Path

from ..core.paper import FITNESS_BAND_HZ
from ..identification.criteria import model_df
from ..pilot.hess import model_from_name
from . import save_figure
from .frf import frf_figure
from .pilots import plot_psd_comparison

#: Legend labels of the three configurations, in the paper's Fig. 8 wording.
LABELS = {"original": "original Hess",
          "expanded_fixed": "expanded Hess, Km fixed",
          "expanded": "expanded Hess, Km identified"}


def plot_pilot(pilot, path: str | Path) -> Path:
    """Save the measured control PSD against the three configurations of one pilot.

    Parameters
    ----------
    pilot : hesspipe.pilots.results.PilotComparison
    path : path
        Image file (format from the suffix); stamped "SYNTHETIC DATA" if the run is synthetic.
    """
    sims = {LABELS[name]: pilot.simulated_psd[name] for name in LABELS}
    fits = {LABELS[name]: pilot.configuration(name)["fitness"] for name in LABELS}
    km = pilot.expanded_fixed["parameters"].get("Km")
    title = (f"{pilot.id}{' (synthetic)' if pilot.synthetic else ''}: control PSD; "
             f"improvement {100 * pilot.improvement:.0f} %" + (f", fixed Km = {km:g}" if km is not None else ""))
    fig = plot_psd_comparison(pilot.freq_hz, pilot.measured_psd, sims,
                              band=(0.0, float(pilot.freq_hz[-1])) if len(pilot.freq_hz) else FITNESS_BAND_HZ,
                              title=title, fitness=fits,
                              measured_label="synthetic 'measured' control" if pilot.synthetic
                              else "measured control")
    return save_figure(fig, path, synthetic=pilot.synthetic)


def plot_df(pilot, path: str | Path) -> Path:
    """The identified models' describing functions over the pilot's measured one (``pilot.frf``).

    Parameters
    ----------
    pilot : hesspipe.pilots.results.PilotComparison
        With ``frf`` (the nonparametric describing function) and both identified models.
    path : str or Path
        PNG to write.
    """

    models = {}
    for name in ("original", "expanded"):
        d = getattr(pilot, name)
        loop = model_from_name(d["model"]).loop(d["parameters"])
        models[name] = (lambda lp: (lambda s: model_df(lp, s)))(loop)
    return frf_figure(path, pilot.frf, models)


def draw_pilots(folder: str | Path, pilots) -> list[str]:
    """``<pilot>.png`` (and ``<pilot>_df.png`` when the pilot has a describing function)
    for each pilot in `folder`; returns their names.

    Parameters
    ----------
    folder : str or Path
        Folder to draw into.
    pilots : sequence of hesspipe.pilots.results.PilotComparison
        The compared pilots.
    """
    folder = Path(folder)
    names = []
    for p in pilots:
        names.append(plot_pilot(p, folder / f"{p.id}.png").name)
        if p.frf is not None:
            names.append(plot_df(p, folder / f"{p.id}_df.png").name)
    return names


def draw_comparison(folder: str | Path, comparison) -> list[str]:
    """The figures of :func:`hesspipe.pilots.compare.write_comparison` (its ``draw``):
    :func:`draw_pilots` into ``folder/figures``; returns names relative to `folder`.

    Parameters
    ----------
    folder : str or Path
        The comparison's (staging) folder.
    comparison : hesspipe.pilots.results.Comparison
        The compared pilots.
    """
    return [f"figures/{name}" for name in draw_pilots(Path(folder) / "figures", comparison.pilots)]
