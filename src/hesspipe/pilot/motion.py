"""The simulator's motion path: controlled output → angular velocity of the cab.

A plants file may carry ``motion_path`` (SPEC.md "Data formats"): the
transfer function M from the controlled output y to the angular velocity
(rad/s) the cab imposes on the pilot, platform and motion filter included.
The pilot's vestibular part stays in the pilot model (:mod:`hesspipe.pilot.effects`):
canals and Km on the cab's angular velocity, otoliths on its tilt angle (the
integral of that angular velocity). So the vestibular feedback of the loop is

    u_v = Km Y_SCC M y  (+ Ko Y_OTO M/s y)

Absent, M is the paper's platform × washout acting on a roll-rate output, and
the loop is exactly the one effects build by default (``Y_MP Y_WO``).
For a roll-angle task on a simulator without washout, M = s/(0.01 s + 1)
(differentiate the angle; a fast first-order platform).

Effects record their cab-side part in :attr:`hesspipe.pilot.blocks.Loop.sensation`;
:func:`with_motion_path` rebuilds :attr:`~hesspipe.pilot.blocks.Loop.vestibular`
from it for another M.
"""

from __future__ import annotations

import functools

import control as ct
import numpy as np

from .blocks import Block, Loop, Term, _poly, from_tf
from .effects import PLATFORM, WASHOUT

PAPER_MOTION_PATH = PLATFORM * WASHOUT
"""The paper's simulator (SPEC.md "Expanded model"): platform × washout, roll rate in, cab
roll rate out (rad/s per rad/s)."""

ANGLE_NO_WASHOUT = ([1.0, 0.0], [0.01, 1.0])
"""``s / (0.01 s + 1)``: an angle output, a simulator without washout (rad/s per rad)."""


def paper_motion_path() -> ct.TransferFunction:
    """The paper's platform × washout as a python-control TF (for a plants file)."""
    t = PAPER_MOTION_PATH.terms[0]
    return ct.tf(np.asarray(t.num) * t.gain, np.asarray(t.den))


def motion_block(plants) -> Block | None:
    """The plants' ``motion_path`` as a :class:`~hesspipe.pilot.blocks.Block`, or None if absent.

    Parameters
    ----------
    plants : hesspipe.core.formats.Plants
        Plants, with or without ``motion_path`` (cab angular velocity, rad/s,
        per unit plant output).
    """
    mp = getattr(plants, "motion_path", None)
    return None if mp is None else from_tf(mp)


def motion_path_note(plants) -> str | None:
    """Why a plants file without ``motion_path`` may be wrong for the motion test, or None.

    Absent, the cab's angular velocity is the paper's platform × washout acting on the
    output, which must then be an angular rate (SPEC.md "Data formats"). A controlled
    element with a free integrator (a pole at s = 0) usually displays an angle, for which
    the cab's rate is the output differentiated: the vestibular path would then be
    modelled one integration off, and the motion test and Km would mean nothing.

    Parameters
    ----------
    plants : hesspipe.core.formats.Plants
    """
    if getattr(plants, "motion_path", None) is not None:
        return None
    den = np.atleast_1d(np.asarray(plants.control_to_output.den[0][0], dtype=float))
    if den.size < 2 or abs(den[-1]) > 1e-12 * float(np.max(np.abs(den))):
        return None
    return ("no motion_path, so the vestibular path takes the output for the cab's angular rate "
            "(the paper's washout and platform); the controlled element integrates, as on an angle "
            "display: if the cab turns with the displayed angle one to one, add \"motion_path\": "
            "{\"num\": [1, 0], \"den\": [0.01, 1]}, times the cab's washout and motion gain if it has "
            "them (README \"Your own recordings\": left out, a washout can hide the motion)")


@functools.lru_cache(maxsize=512)
def _product(num_a, den_a, num_b, den_b) -> tuple[tuple, tuple]:
    """``(num_a num_b, den_a den_b)`` with common roots at s = 0 cancelled.

    Cancelling at the origin matters: the otolith path integrates the cab's
    angular velocity (1/s) and a motion path with a differentiator (s) would
    otherwise leave a pole-zero pair at 0 that the stability test reads as a
    marginal mode.
    """
    num = np.convolve(num_a, num_b)
    den = np.convolve(den_a, den_b)
    while num.size > 1 and den.size > 1 and num[-1] == 0.0 and den[-1] == 0.0:
        num, den = num[:-1], den[:-1]
    return _poly(num), _poly(den)


def with_motion_path(loop: Loop, cab: Block | None) -> Loop:
    """`loop` with its vestibular feedback acting through the motion path `cab`.

    Parameters
    ----------
    loop : Loop
        Built by a pilot model; its :attr:`~hesspipe.pilot.blocks.Loop.sensation`
        maps the cab's angular velocity (rad/s) to the vestibular signal u_v.
    cab : Block or None
        Output → cab angular velocity (single term, e.g. :func:`motion_block`).
        None: the loop as built (the paper's platform × washout).

    Returns
    -------
    Loop
        With ``vestibular = sensation × cab`` (unchanged without sensation or cab).
    """
    if cab is None or loop.sensation.is_zero:
        return loop
    (c,) = cab.terms
    terms = []
    for t in loop.sensation.terms:
        num, den = _product(t.num, t.den, c.num, c.den)
        terms.append(Term(num, den, t.delay + c.delay, t.gain * c.gain))
    return loop.replace(vestibular=Block(tuple(terms)))
