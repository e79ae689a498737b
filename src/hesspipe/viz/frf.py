"""Bode figure of the pilot's nonparametric describing function, with model curves over it."""

from __future__ import annotations

from pathlib import Path
from typing import Mapping

import numpy as np

from ..identification.frf_smooth import describing_function
from . import save_figure, subplots

_COLORS = ("r", "g", "m", "c", "orange")


def frf_figure(path: str | Path, frf, models: Mapping[str, object] | None = None, *,
               title: str | None = None) -> Path:
    """Save the Bode plot of `frf` (points with 1-sigma bars), model DFs drawn over it.

    Parameters
    ----------
    frf : hesspipe.identification.frf.Frf
    models : mapping, optional
        Label → callable ``H(s)`` (complex describing function U/E at ``s = j w``).
    """
    resp = frf.feedback
    w = resp.freq_rad_s
    mag = np.abs(resp.H)
    rel = np.clip(resp.sigma / np.maximum(mag, 1e-300), 0, 0.999)
    fig, (a1, a2) = subplots(2, 1, figsize=(7.0, 6.0), sharex=True)
    db = 20 * np.log10(mag)
    db_err = [db - 20 * np.log10(mag * (1 - rel)), 20 * np.log10(mag * (1 + rel)) - db]
    ph = np.degrees(np.unwrap(np.angle(resp.H)))
    style = dict(fmt="o", ms=4, capsize=2) if frf.method == "multisine" else dict(fmt=".", ms=3)
    label = "measured H = U/E (" + ("disturbance lines" if frf.method == "multisine" else "Welch") + ")"
    a1.errorbar(w, db, yerr=db_err, color="b", label=label, **style)
    a2.errorbar(w, ph, yerr=np.degrees(np.arcsin(rel)), color="b", **style)
    if frf.reference is not None:
        r = frf.reference
        a1.plot(r.freq_rad_s, 20 * np.log10(np.abs(r.H)), "s", color="gray", ms=4,
                label="reference lines")
        a2.plot(r.freq_rad_s, np.degrees(np.unwrap(np.angle(r.H))), "s", color="gray", ms=4)
    ch = frf.channels
    if ch is not None:
        # The response to the output itself (the vestibular path with a moving cab), apart
        # from the error's: identification.frf_channels.
        a1.plot(ch.freq_rad_s, 20 * np.log10(np.abs(ch.Hpy)), "^", color="purple", ms=5,
                label="output channel Hpy (U = Hpe E - Hpy Y)")
        a2.plot(ch.freq_rad_s, np.degrees(np.angle(ch.Hpy)), "^", color="purple", ms=5)
    wf = np.logspace(np.log10(w.min() / 1.5), np.log10(w.max() * 1.5), 300)
    if frf.crossover.estimate == "smoothed":
        # the fit the headline crossover comes from, so a reader can judge it against the points
        models = {"smoothed fit (crossover estimate)":
                  describing_function(frf.crossover.smooth["parameters"]), **(models or {})}
    for i, (lab, fn) in enumerate((models or {}).items()):
        h = fn(1j * wf)
        p = np.degrees(np.unwrap(np.angle(h)))
        # Put the model's phase on the measured branch at the lowest line.
        p0 = np.degrees(np.angle(fn(1j * w[:1])))[0]
        p += np.round((ph[0] - p0) / 360.0) * 360.0 if np.isfinite(p0) else 0.0
        a1.semilogx(wf, 20 * np.log10(np.abs(h)), color=_COLORS[i % len(_COLORS)], label=lab)
        a2.semilogx(wf, p, color=_COLORS[i % len(_COLORS)])
    c = frf.crossover
    if np.isfinite(c.frequency_rad_s):
        for a in (a1, a2):
            a.axvline(c.frequency_rad_s, color="k", ls=":", lw=1)
        a1.set_title(title or f"{frf.run_id}: pilot describing function\nnonparametric crossover "
                     f"{c.frequency_rad_s:.2f} ± {c.frequency_std:.2f} rad/s, PM "
                     f"{c.phase_margin_deg:.0f} ± {c.phase_margin_std_deg:.0f} deg"
                     + (" (ill-defined: |L| flat near 1)" if c.ill_defined else ""), fontsize=9)
    else:
        a1.set_title(title or f"{frf.run_id}: pilot describing function", fontsize=9)
    a1.set_xscale("log")
    a1.set_ylabel("|H|, dB")
    a2.set_ylabel("phase, deg")
    a2.set_xlabel("frequency, rad/s")
    for a in (a1, a2):
        a.grid(alpha=0.3, which="both")
    a1.legend(fontsize=8)
    fig.tight_layout()
    return save_figure(fig, path, synthetic=frf.synthetic)

