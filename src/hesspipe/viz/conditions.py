"""Figure of two conditions flown by the same persons: each person's metric in both, joined."""

from __future__ import annotations

import math
from pathlib import Path

from ..pilots.conditions import METRICS, MIN_PERSONS
from . import save_figure, subplots


def conditions_figure(path: str | Path, result) -> Path:
    """Save one panel per metric: each person's value in the first and in the second
    condition, joined by a line (the paired design), with the crossover's and the phase
    margin's 1-sigma bars and the panel's paired test in its title.

    Parameters
    ----------
    path : str or Path
        The image file.
    result : hesspipe.pilots.conditions.ConditionComparison
        From :func:`~hesspipe.pilots.conditions.compare_conditions`.

    Returns
    -------
    Path
        `path`.
    """
    a, b = result.labels
    fig, axes = subplots(1, len(METRICS), figsize=(3.0 * len(METRICS), 3.6))
    bars = {"crossover_rad_s": "crossover_std", "phase_margin_deg": "phase_margin_std_deg"}
    for ax, m in zip(axes, METRICS):
        for person, c in sorted(result.persons.items()):
            pts = [(i, c[label][m.key], c[label].get(bars.get(m.key, ""), math.nan))
                   for i, label in enumerate((a, b)) if label in c and math.isfinite(c[label][m.key])]
            if not pts:
                continue
            x, y, err = zip(*pts)
            scale = 100.0 if m.key == "remnant_share" else 1.0
            # a person left out of this metric's test (an ill-defined crossover) drawn dashed
            out = m.unless and any(c[label].get(m.unless) for label in (a, b) if label in c)
            ax.errorbar(x, [scale * v for v in y], yerr=[e if math.isfinite(e) else 0.0 for e in err],
                        fmt=("o--" if out else "o-") if len(pts) == 2 else "o", ms=4, capsize=2, lw=1,
                        alpha=0.4 if out else 0.8, label=person)
        ax.set_xticks([0, 1], [a, b])
        ax.set_xlim(-0.4, 1.4)
        if m.log:
            ax.set_yscale("log")
        unit = "%" if m.key == "remnant_share" else m.unit
        ax.set_ylabel(f"{m.label} ({unit})" if unit else m.label, fontsize=8)
        t = result.tests.get(m.key)
        held = "" if t is None or t["p_holm"] is None else f", Holm {t['p_holm']:.2g}"
        ax.set_title(f"fewer than {MIN_PERSONS} persons with it in both" if t is None else
                     f"p = {t['p_value']:.2g}{held}\n{t['higher']} of {t['n']} higher", fontsize=8)
        ax.grid(True, alpha=0.3)
    axes[0].legend(fontsize=6, ncol=2)
    fig.suptitle(f"{b} against {a}, person by person", fontsize=10)
    fig.tight_layout()
    return save_figure(fig, path, synthetic=result.synthetic)
