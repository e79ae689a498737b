"""The remnant's gain: how strong a pilot's noise is for a given share of its control power."""

from __future__ import annotations

import math

import numpy as np

from ..core.errors import HesspipeError


def remnant_gain(model, params, sim, share: float) -> float:
    """Kn that makes remnant `share` of the pilot's control variance.

    Parameters
    ----------
    model : hesspipe.pilot.hess.PilotModel
        With the remnant effect.
    params : dict
        Complete parameters (Kn ignored).
    sim : hesspipe.pilot.simulation.Simulator
        Prepared with the pilot's disturbance and remnant noise seed.
    share : float
        In (0, 1): ``var(remnant part) / var(control)``.

    Returns
    -------
    float
        Kn; the loop is linear, so the control is ``u0 + Kn u1`` with ``u0``
        noise free and ``u1`` the response to the unit remnant.
    """
    return remnant_gain_of_loops(model.loop({**params, "Kn": 0.0}), model.loop({**params, "Kn": 1.0}),
                                 sim, share)


def remnant_gain_of_loops(loop0, loop1, sim, share: float) -> float:
    """:func:`remnant_gain` for given loops without (`loop0`) and with unit remnant (`loop1`).

    Parameters
    ----------
    loop0, loop1 : Loop
        The pilot's loop with Kn = 0 and with Kn = 1.
    sim : hesspipe.pilot.simulation.Simulator
        Prepared with the disturbance and the remnant noise seed.
    share : float
        In (0, 1): ``var(remnant part) / var(control)``.
    """
    u0, u1 = sim.control(loop0), sim.control(loop1)
    if u0 is None or u1 is None:
        raise HesspipeError("remnant gain: the closed loop is unstable")
    v0, v1 = float(np.var(u0)), float(np.var(u1 - u0))
    if not (v0 > 0 and v1 > 0):
        raise HesspipeError("remnant gain: the pilot's noise-free control is zero; expected a "
                            "disturbance that moves the aircraft")
    return math.sqrt(share / (1.0 - share) * v0 / v1)
