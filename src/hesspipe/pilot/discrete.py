"""The Hess pilot model as a sampled-data controller, for time-domain closed-loop flight.

:class:`DiscretePilot` turns the :class:`~hesspipe.pilot.blocks.Loop` of a pilot model
(SPEC.md "Stage three", ``delta = NM (visual e - PF delta - vestibular y) + n``)
into a per-sample controller at a fixed step ``dt``:

``delta = H1 visual(e) - H1 vestibular(y) + H2 N(w)``,
``H1 = NM / (1 + NM PF)``, ``H2 = 1 / (1 + NM PF)``

with ``w`` a unit-variance white sequence (one draw per sample, as in
:class:`hesspipe.pilot.simulation.Simulator`). Closing the neuromuscular/proprioceptive
loop analytically first keeps the discrete controller free of algebraic
loops. Each path's rational part is discretised by the bilinear (Tustin)
map of its poles and zeros, precomputed once and run as second-order
sections in plain Python floats (a few microseconds per sample). Tustin
keeps the frequency response within about ``(w dt)^2 / 12`` of the
continuous one (under 0.06 % at 10 rad/s and 120 Hz), where a zero-order
hold would add half a sample of lag.

Delays are a sample buffer, not an approximation: ``tau / dt = m + f``
reads the visual input ``m`` samples back, interpolated linearly between
samples ``m`` and ``m + 1`` when ``f > 0`` (Table 1's 0.1 s is exactly 12
samples at 120 Hz, so the buffer is then exact).
"""

from __future__ import annotations

import math

import numpy as np
import scipy.signal as ss

from ..core.errors import HesspipeError
from .blocks import ONE, Block, Loop, _padd, _pmul


def _rational(block: Block, what: str) -> tuple[np.ndarray, np.ndarray]:
    if any(t.delay for t in block.terms):
        raise HesspipeError(f"pilot model: the {what} block has a transport delay; only the visual "
                            "path may carry delays in the time-domain pilot")
    return block.rational()


def tustin_sections(num, den, dt: float) -> list[list[float]]:
    """Second-order sections of the bilinear (Tustin) discretisation of ``num(s)/den(s)``.

    Each section is ``[b0, b1, b2, a1, a2, z1, z2]`` (transposed direct form II,
    states last, initially zero).

    Parameters
    ----------
    num, den : array
        Continuous transfer function, descending powers of s.
    dt : float
        Sample interval, s.

    Raises
    ------
    HesspipeError
        Improper transfer function.
    """
    num = np.trim_zeros(np.atleast_1d(np.asarray(num, dtype=float)), "f")
    den = np.trim_zeros(np.atleast_1d(np.asarray(den, dtype=float)), "f")
    if num.size == 0:
        return []
    if num.size > den.size:
        raise HesspipeError("pilot model: improper block (more zeros than poles)")
    z, p, k = ss.tf2zpk(num, den)
    zd, pd, kd = ss.bilinear_zpk(z, p, k, 1.0 / dt)
    if len(pd) == 0:
        return [[float(kd), 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]]
    sos = ss.zpk2sos(zd, pd, kd)
    return [[float(s[0]), float(s[1]), float(s[2]), float(s[4]), float(s[5]), 0.0, 0.0] for s in sos]


def _run_sections(secs: list[list[float]], x: float) -> float:
    for s in secs:
        y = s[0] * x + s[5]
        s[5] = s[1] * x - s[3] * y + s[6]
        s[6] = s[2] * x - s[4] * y
        x = y
    return x


def sections_response(secs: list[list[float]], omega, dt: float) -> np.ndarray:
    """Frequency response of a section cascade at ``z = exp(j omega dt)`` (omega in rad/s).

    Parameters
    ----------
    secs : list of list of float
        Sections from :func:`tustin_sections`.
    omega : array
        Angular frequencies, rad/s.
    dt : float
        Sample interval, s.
    """
    z = np.exp(1j * np.asarray(omega, dtype=float) * dt)
    out = np.ones(z.shape, dtype=complex)
    for b0, b1, b2, a1, a2, _, _ in secs:
        out *= (b0 + b1 / z + b2 / z ** 2) / (1.0 + a1 / z + a2 / z ** 2)
    return out


class DiscretePilot:
    """A pilot model's loop as a controller stepped once per sample.

    Parameters
    ----------
    loop : hesspipe.pilot.blocks.Loop
        From ``PilotModel.loop(params)`` (or built with a custom motion path).
        Its ``plant`` factor must be one: aircraft-side effects belong to the
        simulated aircraft, not to the pilot.
    dt : float
        Step, s.
    sample_lag : int
        Samples of delay the surrounding loop already puts between the output
        and the controller (a sampled plant whose recorded output at row k is
        the state at the end of step k, seen by the pilot at step k + 1: one
        sample). They are taken off the visual delay buffer, so that the
        recorded loop shows exactly ``tau0`` from output to control; the
        motion path, which has no delay to take them from, gets the output
        extrapolated linearly over them (``y + lag (y - y_prev)``: exact to
        second order in ``w dt``, 0.7 % at 10 rad/s and 120 Hz).

    Call :meth:`step` once per sample with the displayed error ``e = r - y``,
    the controlled output ``y`` (roll rate, rad/s; for the motion path) and
    the sample of unit white noise ``w`` (remnant); it returns the control
    deviation ``delta`` (plant input units, e.g. normalised aileron command).
    """

    def __init__(self, loop: Loop, dt: float, sample_lag: int = 0):
        if loop.plant.terms != ONE.terms:
            raise HesspipeError("pilot model: an aircraft-side effect (plant factor, e.g. dutch_roll) "
                                "cannot be part of the pilot flying a simulated aircraft; the "
                                "aircraft brings its own dynamics")
        if not (dt > 0 and math.isfinite(dt)):
            raise HesspipeError(f"dt: expected a positive step in s, got {dt!r}")
        self.dt = float(dt)
        self.sample_lag = int(sample_lag)
        self._y_prev = 0.0
        a, b = _rational(loop.neuromuscular, "neuromuscular")
        c, d = _rational(loop.proprioceptive, "proprioceptive")
        den = _padd(_pmul(b, d), _pmul(a, c))       # 1 + NM PF, over b d
        h1_num = _pmul(a, d)                         # H1 = a d / (b d + a c)
        self._visual = []
        for t in loop.visual.terms:
            if t.gain == 0:
                continue
            delay = t.delay / self.dt - sample_lag
            if delay < 0:
                raise HesspipeError(f"pilot model: visual delay {t.delay:g} s is shorter than the "
                                    f"{sample_lag} sample(s) the loop's sampling already takes "
                                    f"({sample_lag * self.dt:g} s); expected tau0 >= {sample_lag * self.dt:g} s")
            m = int(math.floor(delay + 1e-9))
            frac = delay - m
            frac = 0.0 if frac < 1e-9 else frac
            secs = tustin_sections(t.gain * _pmul(h1_num, t.num), _pmul(den, t.den), self.dt)
            self._visual.append((m, frac, secs))
        self._vestibular = []
        if not loop.vestibular.is_zero:
            vn, vd = _rational(loop.vestibular, "vestibular")
            self._vestibular = tustin_sections(-_pmul(h1_num, vn), _pmul(den, vd), self.dt)
        self._noise = []
        if not loop.noise.is_zero:
            nn, nd = _rational(loop.noise, "remnant")
            self._noise = tustin_sections(_pmul(_pmul(b, d), nn), _pmul(den, nd), self.dt)
        self._history: list[float] = []
        self.max_delay_samples = max((m + (f > 0) for m, f, _ in self._visual), default=0)

    def _delayed(self, m: int, frac: float) -> float:
        h = self._history
        i = len(h) - 1 - m
        x0 = h[i] if i >= 0 else 0.0
        if frac == 0.0:
            return x0
        x1 = h[i - 1] if i >= 1 else 0.0
        return (1.0 - frac) * x0 + frac * x1

    def step(self, e: float, y: float = 0.0, w: float = 0.0) -> float:
        """Control deviation for this sample (see the class docstring).

        Parameters
        ----------
        e : float
            Displayed error this sample (reference minus output), output units.
        y : float
            Plant output this sample (for the vestibular path), output units.
        w : float
            Unit-variance white remnant sample (for the noise path).

        Returns
        -------
        float
            Control deviation from trim, control units.
        """
        self._history.append(e)
        out = 0.0
        for m, frac, secs in self._visual:
            out += _run_sections(secs, self._delayed(m, frac))
        if self._vestibular:
            y_hat = y + self.sample_lag * (y - self._y_prev) if self.sample_lag else y
            self._y_prev = y
            out += _run_sections(self._vestibular, y_hat)
        if self._noise:
            out += _run_sections(self._noise, w)
        return out

    def simulate(self, e, y=None, w=None) -> np.ndarray:
        """Run :meth:`step` over whole sequences (open loop; for tests and checks).

        Parameters
        ----------
        e, y, w : array
            Error, output and remnant sequences as in :meth:`step` (`y`, `w`
            default to zeros).

        Returns
        -------
        ndarray
            Control deviations, control units.
        """
        e = np.asarray(e, dtype=float)
        y = np.zeros_like(e) if y is None else np.asarray(y, dtype=float)
        w = np.zeros_like(e) if w is None else np.asarray(w, dtype=float)
        return np.array([self.step(float(a), float(b), float(c)) for a, b, c in zip(e, y, w)])

    def response(self, omega, path: str = "visual") -> np.ndarray:
        """Frequency response (delays included) of one path at rad/s `omega`.

        `path`: "visual" (e → delta), "vestibular" (y → delta) or "noise" (w → delta).
        With a `sample_lag`, the response from the output as the loop records it
        (the lag samples included), i.e. what should match the continuous path.

        Parameters
        ----------
        omega : array
            Angular frequencies, rad/s.
        path : {"visual", "vestibular", "noise"}
            Which input's path.

        Returns
        -------
        ndarray of complex
            Control units per input unit; the vestibular path carries its negative
            feedback sign.
        """
        omega = np.asarray(omega, dtype=float)
        z1 = np.exp(-1j * omega * self.dt)
        lag = z1 ** self.sample_lag
        if path == "visual":
            out = np.zeros(omega.shape, dtype=complex)
            for m, frac, secs in self._visual:
                buf = z1 ** m * ((1.0 - frac) + frac * z1)
                out += buf * sections_response(secs, omega, self.dt)
            return lag * out
        secs = {"vestibular": self._vestibular, "noise": self._noise}[path]
        if not secs:
            return np.zeros(omega.shape, dtype=complex)
        if path == "vestibular" and self.sample_lag:
            lag = lag * ((1 + self.sample_lag) - self.sample_lag * z1)
        elif path == "noise":
            lag = 1.0  # the remnant is generated in the pilot: no sampling lag
        return lag * sections_response(secs, omega, self.dt)


def continuous_paths(loop: Loop, omega) -> dict[str, np.ndarray]:
    """The continuous-time responses :class:`DiscretePilot` discretises, at rad/s `omega`.

    Parameters
    ----------
    loop : Loop
        The pilot's blocks.
    omega : array
        Angular frequencies, rad/s.

    Returns
    -------
    dict
        ``"visual"`` (e to delta), ``"vestibular"`` (y to delta, sign included:
        negative feedback), ``"noise"`` (w to delta), complex arrays.
    """
    s = 1j * np.asarray(omega, dtype=float)
    nm, inner = loop.neuromuscular.response(s), loop.return_difference(s, None)
    h1 = nm / inner
    return {"visual": h1 * loop.visual.response(s),
            "vestibular": -h1 * loop.vestibular.response(s),
            "noise": loop.noise.response(s) / inner}
