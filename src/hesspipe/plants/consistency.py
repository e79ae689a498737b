"""Does a run belong to its plants? Signs and units of the columns, checked before a fit.

A laboratory's stick convention or units can differ from the plants file's: a control logged
with the opposite sign, an output in degrees against plants in radians. Identification then
fits nonsense without complaint (a sign-flipped generator cohort got Ke at its lower bound
and a motion verdict of "yes" for motion pilots and none alike). Here the plants predict the
output from the logged control and disturbance on the record's strongly forced frequency
bins; the run is refused only on evidence, when flipping a sign or a units-size scale makes
them explain it and the run as written does not. Plants that miss part of the dynamics
(a Dutch roll behind a rolling approximation) are not refused: that is diagnose's finding.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..core.errors import HesspipeError
from ..core.formats import Plants, Run
from ..pilot.blocks import from_tf

EXPLAINED = 0.5
"""Share of the output power at the strong bins the plants must leave unexplained before a
run is questioned at all (as written)."""
CONVINCING = 0.1
"""Share a flipped or rescaled reading must leave at most to be named."""
UNITS_SIZE = 3.0
"""A scale beyond this factor (either way) is a units mistake, not a gain the plants missed."""
PATH_SHARE = 1e-9
"""Share of the predicted power at the strong bins a path needs for its own scale to be
judged: a column of zeros (a task without a disturbance) has no path to scale, while a
column in a unit 57.3 times too small still carries 3e-4 of it."""


@dataclass(frozen=True)
class Consistency:
    """How well the plants explain a run's output at its strong bins, as written and read
    otherwise.

    Attributes
    ----------
    unexplained : float
        Output power at the strong bins the plants leave, over the output's power there (0 is
        a perfect match; above 1 worse than predicting nothing).
    flipped : dict of str to float
        The same with the sign of "control", "disturbance" or "output" flipped.
    scale : float
        Least-squares factor from the plants' prediction to the output.
    scaled : float
        The share left with that factor.
    n_bins : int
        Bins compared.
    path_scales : (float, float)
        Least-squares factors of the control's and the disturbance's predictions, each
        path its own (a column logged in another unit than the plants assume); NaN for a
        path that carries under :data:`PATH_SHARE` of the predicted power (not judged).
    paths_scaled : float
        The share left with those two factors.
    swapped : dict of str to float
        The same with two columns' roles exchanged: ``"control and disturbance"`` (or the
        plants' two paths) and ``"control and output"`` (then the share of the logged
        control's power the plants leave, predicting it from the logged output).
    """

    unexplained: float
    flipped: dict
    scale: float
    scaled: float
    n_bins: int
    path_scales: tuple = (1.0, 1.0)
    paths_scaled: float = math.inf
    swapped: dict = field(default_factory=dict)

    def problem(self) -> str | None:
        """The columns' sign or units mistake the evidence names, or None."""
        if not self.unexplained > EXPLAINED:
            return None
        which, left = min(self.flipped.items(), key=lambda kv: kv[1])
        if left <= CONVINCING and left <= self.unexplained / 5:
            what = {"control": "the control's sign is opposite to the plants' (stick convention)",
                    "disturbance": "the disturbance's sign is opposite to the plants'",
                    "output": "the output's sign is opposite to the plants' (or both inputs' are)"}[which]
            return (f"{what}: with that sign flipped the plants leave {100 * left:.0f} % of the "
                    f"output's power at the forcing unexplained, as written {100 * self.unexplained:.0f} %; "
                    f"map it with columns {which}=-NAME")
        g = abs(self.scale)
        if self.scaled <= CONVINCING and not 1 / UNITS_SIZE <= g <= UNITS_SIZE:
            return (f"the output is {g:.3g} times what the plants predict from the control and "
                    f"disturbance{radians_hint(g)}: the columns' units differ from the plants' (scaled, the plants "
                    f"leave {100 * self.scaled:.0f} % of the output's power at the forcing unexplained, "
                    f"as written {100 * self.unexplained:.0f} %); write every column's unit in the "
                    f"header (e.g. 'Yaw [deg]'; a column without one is read as written) or rescale "
                    f"the plants")
        swap, left = min(self.swapped.items(), key=lambda kv: kv[1], default=("", math.inf))
        if left <= CONVINCING and left <= self.unexplained / 5:
            also = " (or the plants' control_to_output and disturbance_to_output)" if "disturbance" in swap else ""
            return (f"the {swap} columns look swapped{also}: read the other way round the plants leave "
                    f"{100 * left:.0f} % of the power at the forcing unexplained, as written "
                    f"{100 * self.unexplained:.0f} %; map each role to its column with columns "
                    f"control=NAME,...")
        # One column in another unit (a stick in per cent, one angle left in degrees): the
        # joint factor above cannot show it, since the other path's prediction is right.
        off = [(r, g) for r, g in zip(("control", "disturbance"), self.path_scales)
               if math.isfinite(g) and not 1 / UNITS_SIZE <= abs(g) <= UNITS_SIZE]
        if off and self.paths_scaled <= CONVINCING and self.paths_scaled <= self.unexplained / 5:
            role, g = off[0] if len(off) == 1 else max(off, key=lambda rg: abs(math.log(abs(rg[1]))))
            path = {"control": "control_to_output", "disturbance": "disturbance_to_output"}[role]
            return (f"the {role}'s units differ from the plants': the plants explain the output with "
                    f"the {role} times {abs(g):.3g}{radians_hint(abs(g))} (so scaled they leave "
                    f"{100 * self.paths_scaled:.0f} % of the output's power at the forcing "
                    f"unexplained, as written {100 * self.unexplained:.0f} %); write the {role}'s "
                    f"unit in the header or rescale the plants' {path}")
        return None


def radians_hint(g: float) -> str:
    """The degrees/radians reading of a units-size factor.

    Parameters
    ----------
    g : float
        A factor between what the plants predict and what the columns hold (positive).

    Returns
    -------
    str
        " (degrees against radians: 57.3)", " (radians against degrees: 1/57.3)" or "".
    """
    if abs(math.log(g / (180 / math.pi))) < 0.1:
        return " (degrees against radians: 57.3)"
    if abs(math.log(g * 180 / math.pi)) < 0.1:
        return " (radians against degrees: 1/57.3)"
    return ""


def consistency(run: Run, plants: Plants, *, band_hz: tuple[float, float] = (0.02, 2.0),
                top: float = 0.1, min_bins: int = 5) -> Consistency:
    """Compare the run's output with the plants' prediction on the strongly forced bins.

    Parameters
    ----------
    run : Run
        Control (plant input units), disturbance and output as logged.
    plants : Plants
        Yc (control → output) and Yd (disturbance → output).
    band_hz : (float, float)
        Frequencies compared, Hz: where tracking tasks are forced.
    top : float
        Share of the band's bins kept: those where the predicted output is strongest
        (a multisine's lines; a broadband record's strongest bins). At least `min_bins`.
    min_bins : int
        Fewest bins compared.

    Returns
    -------
    Consistency
    """
    n = len(run)
    f = np.fft.rfftfreq(n, run.dt)
    band = np.flatnonzero((f >= band_hz[0]) & (f <= band_hz[1]))
    if band.size < min_bins:
        band = np.arange(1, f.size)
    s = 2j * math.pi * f[1:]
    t = np.linspace(-1.0, 1.0, n)
    trend = np.vstack([t ** 0, t, t ** 2]).T

    def detrended_spectrum(x):
        # A record starts mid-run: behind one or two integrators the output carries a
        # polynomial the periodic prediction lacks, whose leakage swamped the low bins
        # (generator angle trials: 20-40 % of the strongest bins' power). The same
        # polynomial fit is removed from the output and from each prediction.
        x = np.asarray(x, float)
        x = x - trend @ np.linalg.lstsq(trend, x, rcond=None)[0]
        return np.fft.rfft(x)[band]

    def predicted(tf, x):
        spec = np.fft.rfft(np.asarray(x, float) - np.mean(x))
        spec[1:] *= from_tf(tf).response(s)
        spec[0] = 0.0
        return detrended_spectrum(np.fft.irfft(spec, n))

    pc = predicted(plants.control_to_output, run.control)
    pd = predicted(plants.disturbance_to_output, run.disturbance)
    y = detrended_spectrum(run.output)
    power = np.abs(pc) ** 2 + np.abs(pd) ** 2
    keep = np.argsort(power)[::-1][:max(min_bins, int(math.ceil(top * band.size)))]
    pc, pd, y = pc[keep], pd[keep], y[keep]

    def left(pred, target=y):
        return float(np.sum(np.abs(target - pred) ** 2)) / (float(np.sum(np.abs(target) ** 2)) or 1.0)

    # Two columns' roles exchanged, on the same bins (a multisine's lines stay its lines).
    swapped = {"control and disturbance": left(predicted(plants.control_to_output, run.disturbance)[keep]
                                               + predicted(plants.disturbance_to_output, run.control)[keep]),
               "control and output": left(predicted(plants.control_to_output, run.output)[keep] + pd,
                                          detrended_spectrum(run.control)[keep])}

    pred = pc + pd
    den = float(np.sum(np.abs(pred) ** 2))
    g = float(np.real(np.vdot(pred, y)) / den) if den > 0 else 1.0
    # Each path its own real factor: closed-loop control and disturbance share bins, but
    # not in a fixed ratio, so the two are told apart (a target's lines carry no disturbance).
    basis = np.stack([pc, pd], axis=1)
    basis = np.concatenate([basis.real, basis.imag])
    gains = np.linalg.lstsq(basis, np.concatenate([y.real, y.imag]), rcond=None)[0]
    shares = np.array([np.sum(np.abs(pc) ** 2), np.sum(np.abs(pd) ** 2)]) / max(float(np.sum(power[keep])), 1e-300)
    gc, gd = (float(v) if share >= PATH_SHARE else math.nan for v, share in zip(gains, shares))
    return Consistency(unexplained=left(pred),
                       flipped={"control": left(-pc + pd), "disturbance": left(pc - pd), "output": left(-pred)},
                       scale=g, scaled=left(g * pred), n_bins=int(keep.size),
                       path_scales=(gc, gd),
                       paths_scaled=left(gains[0] * pc + gains[1] * pd), swapped=swapped)


def check_consistent(run: Run, plants: Plants) -> Consistency:
    """:func:`consistency`, raising on a named sign or units mistake.

    Parameters
    ----------
    run : Run
    plants : Plants

    Returns
    -------
    Consistency
        When no mistake is named.

    Raises
    ------
    HesspipeError
        Naming the run's file and the mistake.
    """
    c = consistency(run, plants)
    problem = c.problem()
    if problem:
        raise HesspipeError(f"{run.source or run.id}: {problem}")
    return c
