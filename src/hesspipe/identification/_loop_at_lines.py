"""The Hess loop's blocks at the forcing lines for the describing-function fits (private:
:func:`loop_rows` is what :func:`._line_fit._predict_rows` evaluates thousands of times a fit).

The loop is :meth:`hesspipe.pilot.hess.PilotModel.loop` behind the plants' motion path
(:func:`hesspipe.pilot.motion.with_motion_path`), evaluated by :meth:`Block.response`
(:func:`block_responses`). For the two models the fits use (the original, and with
``motion_feedback``) :func:`loop_rows` evaluates the same terms with the same floating-point
operations without building the blocks, for a whole column of parameter sets at once (a
Jacobian's columns: :func:`hesspipe.identification._lsq.best_least_squares`'s
``resid_rows``). Building the blocks was about half of an evaluation, and a Jacobian made one
evaluation per column. Equal bit for bit to the blocks' path, row by row
(tests/test_loop_at_lines.py), so a search takes the same steps to the same optimum; any
other model, and the few parameter values at which a block leaves a factor out, go the
blocks' way.
"""

from __future__ import annotations

import numpy as np

from ..pilot.blocks import tf
from ..pilot.effects import CANALS, MOTION
from ..pilot.motion import _product, with_motion_path

_DIRECT = {(): False, ("motion_feedback",): True}
"""The models (effect tuples) evaluated directly: whether the loop has the vestibular path."""

_CACHE = "_loop_at_lines"
"""The key under which a fit's `cache` keeps the responses that its parameters do not move
(Block.response's own keys are tuples of polynomials)."""


def loop_rows(rows, model, cab, s, cache=None):
    """(NM, vestibular, visual, 1 + NM PF) at `s` for each parameter set of `rows`: the
    pilot's blocks, complex arrays of ``(len(rows), len(s))``, row i the numbers of
    ``rows[i]`` alone, bit for bit.

    Parameters
    ----------
    rows : sequence of mapping
        Complete parameter sets of `model` (rad/s, s, gains).
    model : hesspipe.pilot.hess.PilotModel
        The pilot model.
    cab : Block or None
        Output → cab angular velocity (a single term), or None: the paper's platform × washout.
    s : ndarray of complex
        ``1j * omega`` at the lines, 1/s.
    cache : dict, optional
        The fit's cache, tied to this `s` (None: nothing kept).

    Returns
    -------
    tuple of ndarray of complex
        NM (command → control), vestibular (output → u_v, the motion path's and the
        sensation's), visual (error → command), and the proprioceptive return difference
        ``1 + NM PF``.
    """
    motion = _DIRECT.get(model.effects)
    if motion is not None and (cab is None or len(cab.terms) == 1):
        kept = {} if cache is None else cache.setdefault(_CACHE, {})
        out = _direct(rows, motion, cab, s, kept)
        if out is not None:
            return out
    return tuple(np.stack(a) for a in zip(*(block_responses(p, model, cab, s, cache) for p in rows)))


_NAMES = ("wn", "zn", "1/T1", "1/T2", "K1", "K2", "Ke", "tau0", "k", "Km")
"""The parameters of the directly evaluated loop, in :func:`_direct`'s order."""


def _direct(rows, motion, cab, s, kept):
    # core_loop's blocks (hesspipe.pilot.hess) and the motion effect's term, a row of
    # parameters each, with the operations Block.response and _shape make: numpy's polyval's
    # Horner steps, and a gain or a delay applied. Where a block leaves a factor out (a gain
    # of exactly 1, no delay) or takes another form (1/T1 = 0), or the rows differ in order,
    # None: the blocks' way.
    names = _NAMES if motion else _NAMES[:-1]
    wn, zn, a1, a2, k1, k2, ke, tau0, k, *km = np.array([[p[n] for n in names] for p in rows], dtype=float).T[:, :, None]
    w2, gain = wn * wn, k1 * k2
    if motion:
        km = km[0] * 1.0
        km_gain = km if cab is None else km * cab.terms[0].gain
    special = (a1 == 0) | (tau0 == 0) | (w2 == 1.0) | (ke == 1.0) | (gain == 1.0) | (k != k[0, 0])
    if motion:
        special |= km_gain == 1.0
    if special.any():
        return None
    nm = w2 * (1.0 / _polyval((1.0, 2.0 * zn * wn, w2), s))
    lead = _constant(kept, ("s",), lambda: np.polyval((1.0, 0.0), s))
    pf = gain * (lead / _polyval((1.0, a1 + a2, a1 * a2) if k[0, 0] == 2 else (1.0, a1), s))
    vis = ke * (_constant(kept, ("1",), lambda: np.ones(np.shape(s), dtype=complex)) * np.exp(-s * tau0))
    if motion:
        ves = km_gain * _constant(kept, ("path", cab), lambda: _path(cab, s))
        zero = km[:, 0] == 0
        if cab is not None and zero.any():
            # with_motion_path leaves a zero sensation (Km = 0) on the paper's path.
            ves[zero] = km[zero] * _constant(kept, ("path", None), lambda: _path(None, s))
    else:
        ves = np.zeros((len(rows), np.size(s)), dtype=complex)
    return nm, ves, vis, 1.0 + nm * pf


def block_responses(params, model, cab, s, cache=None):
    """One parameter set's :func:`loop_rows` through the blocks: the loop built and evaluated
    term by term, each array of ``len(s)``.

    Any model; the reference the direct evaluation equals.

    Parameters
    ----------
    params : mapping
        Complete parameters of `model`.
    model, cab, s
        As :func:`loop_rows`.
    cache : dict, optional
        :meth:`Block.response`'s shape cache, tied to this `s`.
    """
    loop = with_motion_path(model.loop(params), cab)
    return (loop.neuromuscular.response(s, cache), loop.vestibular.response(s, cache),
            loop.visual.response(s, cache), loop.return_difference(s, None, cache))


def _path(cab, s):
    # The vestibular path's shape, evaluated by Block.response: the paper's (MOTION) without a
    # motion path, else the canals times it (with_motion_path's product, its delay).
    if cab is None:
        return MOTION.response(s)
    (c,) = cab.terms
    canals = CANALS.terms[0]
    num, den = _product(canals.num, canals.den, c.num, c.den)
    return tf(num, den, 0.0 + c.delay).response(s)


def _constant(kept, key, evaluate):
    # A response no fitted parameter moves, evaluated once per fit.
    value = kept.get(key)
    if value is None:
        value = kept[key] = evaluate()
    return value


def _polyval(coefficients, s):
    # numpy.polyval's Horner steps, with coefficients that may be columns (a row each).
    y = np.zeros_like(s)
    for c in coefficients:
        y = y * s + (np.float64(c) if isinstance(c, float) else c)
    return y
