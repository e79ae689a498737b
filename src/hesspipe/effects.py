"""Effects: augmentations of the pilot-vehicle loop, each with its own parameters.

An effect is a named change to the :class:`~hesspipe.blocks.Loop` built by the
core Hess model: a motion path, an extra delay, remnant noise, a plant mode.
The discrepancy workflow tries them one by one, so each carries its
parameters' defaults, bounds (the identification search box), APID bit
fields and a short physical description. Parameter names are unique across
effects and the core.

Registry ids (SPEC.md "The discrepancy workflow"): ``motion_feedback``,
``extra_delay``, ``remnant``, ``dutch_roll``, plus ``otoliths``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable, Mapping

from .blocks import Loop, delay, gain, tf
from .errors import HesspipeError

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
# Loop.sensation, so that hesspipe.motion can put another simulator's motion path behind it;
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


def _dutch_roll(loop: Loop, p) -> Loop:
    wd, zd, r = p["w_dr"], p["z_dr"], p["r_dr"]
    wphi = r * wd
    # Pole pair with a nearby zero pair (ratio r), unit DC gain so the
    # rolling approximation's gain is kept.
    mode = tf([1.0, 2 * zd * wphi, wphi ** 2], [1.0, 2 * zd * wd, wd ** 2]) * gain(1.0 / r ** 2)
    return loop.replace(plant=loop.plant * mode)


EFFECTS: dict[str, Effect] = {e.id: e for e in (
    Effect("motion_feedback", "pilot",
           "Vestibular sensation of the simulator's roll: semicircular canals x motion platform x "
           "washout acting on roll rate, gain Km, fed back beside the visual error (Cardullo 2006).",
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
)}


def get_effect(effect_id: str) -> Effect:
    """The effect registered as `effect_id`.

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
