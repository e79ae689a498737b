"""Effects: augmentations of the pilot-vehicle loop, each with its own parameters.

An effect is a named change to the :class:`~hesspipe.pilot.blocks.Loop` built by the
core Hess model: a motion path, an extra delay, remnant noise, a plant mode.
The discrepancy workflow tries them one by one, so each carries its
parameters' defaults, bounds (the identification search box), APID bit
fields and a short physical description. Parameter names are unique across
effects and the core.

Registry ids (SPEC.md "The discrepancy workflow"): ``motion_feedback``,
``extra_delay``, ``remnant``, ``dutch_roll``, plus ``otoliths`` and the aircraft-side
``roll_mode`` and ``actuator_lag`` (tried on the plant check by
:mod:`hesspipe.diagnose.aircraft`, with the nonlinear ``rate_limit``).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable, Mapping

from ..core.errors import HesspipeError
from .blocks import Loop, delay, gain, tf

# Fixed vestibular and platform dynamics of SPEC.md "Expanded model".
W_WO, Z_WO = 1.02, 1.0          # washout, rad/s
W_MP, Z_MP = 31.4, 0.7          # motion platform, rad/s
T_SCC_LONG, T_SCC_SHORT = 80.0, 5.73   # semicircular canals, s

WASHOUT = tf([1.0, 0.0, 0.0], [1.0, 2 * Z_WO * W_WO, W_WO ** 2])
PLATFORM = tf([W_MP ** 2], [1.0, 2 * Z_MP * W_MP, W_MP ** 2])
# Canal numerator s^2 (angular velocity in, perceived angular velocity out;
# SPEC.md adopts s^2 where the paper's text prints s).
CANALS = tf([T_SCC_LONG * T_SCC_SHORT, 0.0, 0.0],
            [T_SCC_LONG * T_SCC_SHORT, T_SCC_LONG + T_SCC_SHORT, 1.0])
OTOLITHS = tf([4.0, 0.4], [0.08, 5.016, 1.0])
# Roll angle (the cab's tilt, washed out) from roll rate: s / (s^2 + 2 z w s + w^2).
TILT = tf([1.0, 0.0], [1.0, 2 * Z_WO * W_WO, W_WO ** 2])
MOTION = CANALS * PLATFORM * WASHOUT       # the fixed shape of the motion path
OTOLITH_PATH = OTOLITHS * PLATFORM * TILT


@dataclass(frozen=True)
class Effect:
    """One augmentation of the loop.

    Attributes
    ----------
    id : str
        Registry key.
    where : str
        "pilot", "aircraft" or "simulator".
    description : str
        One or two sentences: what it adds, physically.
    parameters : dict
        name → (default, lo, hi): value used when the effect is added, and the
        admissible search box.
    fields : dict
        name → (bits, scale, offset): default APID bit field, spanning the box.
    units : dict
        name → unit string.
    apply : callable
        ``apply(loop, params) -> Loop``.
    """

    id: str
    where: str
    description: str
    parameters: Mapping[str, tuple[float, float, float]]
    fields: Mapping[str, tuple[int, float, float]]
    units: Mapping[str, str]
    apply: Callable[[Loop, Mapping[str, float]], Loop] = field(repr=False)


# Each vestibular effect records its pilot-side part (from the cab's angular velocity) in
# Loop.sensation, so that hesspipe.pilot.motion can put another simulator's motion path behind it;
# the vestibular block itself is built with the paper's path, exactly as before.
def _motion(loop: Loop, p) -> Loop:
    path = gain(p["Km"]) * MOTION
    return loop.replace(vestibular=loop.vestibular + path,
                        sensation=loop.sensation + gain(p["Km"]) * CANALS)


def _otoliths(loop: Loop, p) -> Loop:
    path = gain(p["Ko"]) * OTOLITH_PATH
    # Tilt angle = integral of the cab's angular velocity.
    return loop.replace(vestibular=loop.vestibular + path,
                        sensation=loop.sensation + gain(p["Ko"]) * OTOLITHS * tf([1.0], [1.0, 0.0]))


def _extra_delay(loop: Loop, p) -> Loop:
    return loop.replace(visual=loop.visual * delay(p["tau_x"]))


def _remnant(loop: Loop, p) -> Loop:
    return loop.replace(noise=loop.noise + gain(p["Kn"]) * tf([1.0], [p["Tn"], 1.0]))


def dutch_roll_factor(w_dr: float, z_dr: float, r_dr: float):
    """Factor of the control plant for a Dutch-roll pair: poles (w_dr rad/s, z_dr), zeros at
    r_dr * w_dr with the same damping, unit DC gain so the rolling approximation's gain is kept.

    Parameters
    ----------
    w_dr : float
        Dutch-roll natural frequency, rad/s (> 0).
    z_dr : float
        Its damping ratio (dimensionless).
    r_dr : float
        Ratio of the zeros' frequency to w_dr (> 0).

    Returns
    -------
    Block
    """
    wphi = r_dr * w_dr
    return tf([1.0, 2 * z_dr * wphi, wphi ** 2], [1.0, 2 * z_dr * w_dr, w_dr ** 2]) * gain(1.0 / r_dr ** 2)


def roll_mode_factor(K_rm: float, a_rm: float, p_rm: float):
    """Factor moving the plant's roll-mode pole from -p_rm to -a_rm * p_rm (rad/s) and scaling
    its high-frequency gain by K_rm: ``K_rm (s + p_rm) / (s + a_rm p_rm)``.

    Parameters
    ----------
    K_rm : float
        High-frequency gain factor (dimensionless).
    a_rm : float
        Ratio of the new roll-mode pole to the old (dimensionless, > 0).
    p_rm : float
        The plant's roll-mode pole magnitude, rad/s (> 0).

    Returns
    -------
    Block
    """
    return gain(K_rm) * tf([1.0, p_rm], [1.0, a_rm * p_rm])


def actuator_lag_factor(tau_a: float):
    """First-order actuator ``1 / (tau_a s + 1)`` between the pilot's control and the
    aircraft (tau_a in s; 0 = none).

    Parameters
    ----------
    tau_a : float
        Actuator time constant, s (<= 0: no lag).

    Returns
    -------
    Block
    """
    return tf([1.0], [tau_a, 1.0]) if tau_a > 0 else gain(1.0)


def _dutch_roll(loop: Loop, p) -> Loop:
    return loop.replace(plant=loop.plant * dutch_roll_factor(p["w_dr"], p["z_dr"], p["r_dr"]))


def _roll_mode(loop: Loop, p) -> Loop:
    return loop.replace(plant=loop.plant * roll_mode_factor(p["K_rm"], p["a_rm"], p["p_rm"]))


def _actuator_lag(loop: Loop, p) -> Loop:
    return loop.replace(plant=loop.plant * actuator_lag_factor(p["tau_a"]))


EFFECTS: dict[str, Effect] = {e.id: e for e in (
    Effect("motion_feedback", "pilot",
           "Vestibular sensation of the cab's rotation: semicircular canals x the plants' motion "
           "path (default: the paper's platform x washout acting on roll rate), gain Km, fed back "
           "beside the visual error (Cardullo 2006).",
           {"Km": (0.1, 0.0, 20.47)}, {"Km": (11, 100.0, 0.0)}, {"Km": "1"}, _motion),
    Effect("otoliths", "pilot",
           "Otolith sensation of the cab's washed-out tilt (lateral specific force, in g, from roll "
           "angle), gain Ko, added to the vestibular feedback.",
           {"Ko": (0.1, 0.0, 20.47)}, {"Ko": (11, 100.0, 0.0)}, {"Ko": "1/g"}, _otoliths),
    Effect("extra_delay", "simulator",
           "An additional transport delay tau_x in the visual path (display/computation latency "
           "or a slower pilot).",
           {"tau_x": (0.05, 0.0, 1.023)}, {"tau_x": (10, 1000.0, 0.0)}, {"tau_x": "s"}, _extra_delay),
    Effect("remnant", "pilot",
           "Broadband control noise: a unit-variance white sequence shaped by Kn / (Tn s + 1) and "
           "added to the control (the pilot's nonlinear, time-varying part).",
           {"Kn": (0.02, 0.0, 1.023), "Tn": (0.5, 0.0, 10.23)},
           {"Kn": (10, 1000.0, 0.0), "Tn": (10, 100.0, 0.0)}, {"Kn": "control", "Tn": "s"},
           _remnant),
    Effect("dutch_roll", "aircraft",
           "The lightly damped lateral-directional pair the rolling approximation omits: poles "
           "(w_dr, z_dr) and zeros at r_dr * w_dr in the control-to-roll-rate plant, unit DC gain.",
           {"w_dr": (0.74, 0.1, 4.195), "z_dr": (0.05, 0.0, 1.023), "r_dr": (0.9, 0.5, 1.523)},
           {"w_dr": (12, 1000.0, 0.1), "z_dr": (10, 1000.0, 0.0), "r_dr": (10, 1000.0, 0.5)},
           {"w_dr": "rad/s", "z_dr": "1", "r_dr": "1"}, _dutch_roll),
    Effect("roll_mode", "aircraft",
           "A roll mode other than the plants': the pole moves from -p_rm to -a_rm p_rm (rad/s) and "
           "the control power scales by K_rm (a different L_p or L_da than the model's).",
           {"K_rm": (1.0, 0.2, 5.0), "a_rm": (1.0, 0.2, 5.0), "p_rm": (1.0, 0.01, 20.0)},
           {"K_rm": (10, 200.0, 0.2), "a_rm": (10, 200.0, 0.2), "p_rm": (12, 200.0, 0.01)},
           {"K_rm": "1", "a_rm": "1", "p_rm": "rad/s"}, _roll_mode),
    Effect("actuator_lag", "aircraft",
           "A first-order actuator 1 / (tau_a s + 1) between the pilot's control and the aircraft "
           "that the plants omit.",
           {"tau_a": (0.1, 0.0, 0.5)}, {"tau_a": (10, 2000.0, 0.0)}, {"tau_a": "s"}, _actuator_lag),
)}

#: Aircraft-side findings that are not a linear change of the loop (no :class:`Effect`):
#: named by :mod:`hesspipe.diagnose.aircraft` from the plant check alone.
NONLINEAR_AIRCRAFT = {
    "rate_limit": "The control surface cannot move faster than a limit: the actuator follows the "
                  "pilot's command at a bounded rate (command units per s).",
}


def get_effect(effect_id: str) -> Effect:
    """The effect registered as `effect_id`.

    Parameters
    ----------
    effect_id : str
        An id of :data:`EFFECTS`, e.g. ``"dutch_roll"``.

    Raises
    ------
    HesspipeError
        Unknown id (the message lists the known ids).
    """
    try:
        return EFFECTS[effect_id]
    except (KeyError, TypeError):
        raise HesspipeError(f"unknown effect {effect_id!r}; known effects: "
                            f"{', '.join(EFFECTS)}") from None
