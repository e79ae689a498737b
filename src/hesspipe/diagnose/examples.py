"""Test data for the diagnosis (SYNTHETIC): the paper's Eq. 16 plants, a disturbance and runs
with a hidden effect made by hesspipe's own simulator. Independent checks use
:mod:`hesspipe.humanlike` instead."""

from __future__ import annotations

import math
from dataclasses import replace
from typing import Mapping, Sequence

import control as ct
import numpy as np
import scipy.optimize
import scipy.signal
import scipy.special
import scipy.stats

from ..core.errors import HesspipeError
from ..core.formats import Plants, Run
from ..core.paper import EQ14, EQ16
from ..core.seeds import derive_seed
from ..pilot.hess import PilotModel
from ..pilot.simulation import synthetic_run

# -- hidden-effect validation data ------------------------------------------------------------

#: Eq. 16 wind → roll-rate plant of the paper (SPEC.md), 1/s per ft/s.
EQ16_NUM, EQ16_DEN = EQ16


def validation_plants() -> Plants:
    """Plants of the hidden-effect tests: Yc = 2.436/(s + 1.0496) (Table 4 rolling
    approximation), Yd = the paper's Eq. 16."""

    return Plants(ct.tf(*(list(c) for c in EQ14)), ct.tf(list(EQ16_NUM), list(EQ16_DEN)),
                  {"source": "validation plants: Table 4 rolling approximation and Eq. 16"})


def validation_disturbance(n: int, dt: float, *, seed: int, rms: float = 5.0,
                           corner_hz: float = 2.0) -> np.ndarray:
    """Lateral wind for validation runs: white noise low-passed (4th-order Butterworth at
    `corner_hz`) and scaled to `rms` ft/s.

    Parameters
    ----------
    n : int
        Number of samples.
    dt : float
        Sample step, s.
    seed : int
        Seed of the white noise.
    rms : float
        RMS of the returned wind, ft/s.
    corner_hz : float
        Low-pass corner, Hz.

    Returns
    -------
    ndarray
        `n` samples of lateral wind, ft/s (SYNTHETIC).
    """
    rng = np.random.default_rng(seed)
    b, a = scipy.signal.butter(4, corner_hz, fs=1.0 / dt)
    w = scipy.signal.lfilter(b, a, rng.standard_normal(n + 500))[500:]
    return rms * w / np.std(w)


def hidden_effect_run(plants: Plants, effect: str | Sequence[str] | None = None, *, seed: int,
                      parameters: Mapping[str, float] | None = None, noise: float = 0.0,
                      control_noise: float = 0.0, duration: float = 70.0, dt: float = 0.02,
                      remnant_share: float | None = None) -> Run:
    """A synthetic run from the original model plus hidden effect(s) (None: baseline).

    `effect` is one effect id or a sequence of them (several hidden effects at once).
    `parameters` override the model defaults. `remnant_share` (with the remnant among
    the effects) sets Kn so that the remnant makes up that share of the control's
    variance (the loop is linear: control = u0 + Kn u1 for the same noise draw), the
    level convention of the synthetic cohort. `noise` and `control_noise` add white
    recording noise to the output (roll-rate sensor) and to the control (stick sensor),
    each as a fraction of the signal's RMS; it is outside the loop. White noise on the
    recorded control is, to a control spectrum, broadband control noise, i.e. a remnant
    with Tn = 0: large enough, it is rightly named ``remnant``.
    The run is labelled synthetic and its comments name the hidden effects.

    Parameters
    ----------
    plants : hesspipe.core.formats.Plants
        Plants the model flies (e.g. :func:`validation_plants`).
    effect : str or sequence of str or None
        Hidden effect id(s) of :meth:`hesspipe.pilot.hess.PilotModel.with_effect`; None
        for the baseline model.
    seed : int
        Seed; the wind, remnant and sensor-noise seeds are derived from it.
    parameters : mapping of str to float, optional
        Model parameters overriding the defaults.
    noise, control_noise : float
        White recording noise on the output and on the control, fraction of each
        signal's RMS (0: none).
    duration : float
        Run length, s.
    dt : float
        Sample step, s.
    remnant_share : float, optional
        Share in (0, 1) of the control variance made up by the remnant; needs
        "remnant" among the effects.

    Returns
    -------
    hesspipe.core.formats.Run
        The synthetic run (lateral wind ft/s, roll rate rad/s).

    Raises
    ------
    HesspipeError
        If `remnant_share` is outside (0, 1) or the remnant is not among the effects.
    """

    effects = () if effect is None else (effect,) if isinstance(effect, str) else tuple(effect)
    model = PilotModel()
    for e in effects:
        model = model.with_effect(e)
    label = "+".join(effects) or "none"
    params = {**model.defaults(k=1), **dict(parameters or {})}
    n = int(round(duration / dt))
    w = validation_disturbance(n, dt, seed=derive_seed(seed, "wind"))

    def simulate(p):
        return synthetic_run(model, p, plants, w, dt, seed=derive_seed(seed, "remnant"),
                             run_id=f"hidden-{label}-{seed}")

    if remnant_share is not None:
        if "remnant" not in effects or not 0.0 < remnant_share < 1.0:
            raise HesspipeError(f"hidden_effect_run: remnant_share: expected a share in (0, 1) and the "
                                f"remnant among the effects, got {remnant_share!r} with {label}")
        u0 = simulate({**params, "Kn": 0.0}).control
        u1 = simulate({**params, "Kn": 1.0}).control - u0
        params["Kn"] = math.sqrt(remnant_share / (1.0 - remnant_share) * float(np.var(u0) / np.var(u1)))
    run = simulate(params)
    rng = np.random.default_rng(derive_seed(seed, "sensor"))

    def noisy(x, level):
        return x + level * float(np.std(x)) * rng.standard_normal(len(x)) if level > 0 else x

    run = replace(run, output=noisy(run.output, noise), control=noisy(run.control, control_noise))
    return replace(run, comments=tuple(run.comments) + (
        f"synthetic hidden-effect run: effect={label} output noise={noise:g} "
        f"control noise={control_noise:g} seed={seed}",))
