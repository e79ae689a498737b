"""Wind profiles and identification excitation signals.

The side-wind profile of the paper (AIAA 2009-6032, Figs. 5 and 7) and the
seeded excitation signals added to it (or fed to the aileron) so that an ARX
identification sees a rich, exactly known input. All functions are pure and
work on numpy arrays; randomness enters only through an explicit ``seed``.

Sign conventions
----------------
Wind components describe the direction the air moves *towards* (as JSBSim's
``atmosphere/wind-north-fps`` etc.).

``along``
    Component along the reference heading, positive when the air moves
    forward (a tail wind), ft/s.
``lateral``
    Component perpendicular to the heading, positive when the air moves
    towards the aircraft's right (body +y at wings level), ft/s.
Wind direction ``theta``
    The direction the wind comes *from*, measured clockwise (seen from above)
    from the nose: 0 = head-on, 90 = from the right, 180 = from behind.
    A wind from the right moves the air to the left, so its lateral component
    is negative.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.signal import lfilter

from ..core.config import Fields

#: Excitation kinds understood by :class:`Excitation`.
EXCITATION_KINDS = ("multisine", "prbs", "noise", "none")


# --------------------------------------------------------------------------- frames

def relative_wind(speed_fps, theta_deg):
    """Split a wind of `speed_fps` from direction `theta_deg` into (along, lateral).

    Parameters
    ----------
    speed_fps : array_like
        Wind speed, ft/s (>= 0).
    theta_deg : array_like
        Direction the wind comes from, degrees clockwise from the nose.

    Returns
    -------
    along, lateral : ndarray
        ft/s; see the module docstring for the signs.
    """
    theta = np.deg2rad(np.asarray(theta_deg, dtype=float))
    speed = np.asarray(speed_fps, dtype=float)
    return -speed * np.cos(theta), -speed * np.sin(theta)


def heading_to_ned(along, lateral, psi_rad):
    """Rotate heading-frame wind (along, lateral) into (north, east), ft/s.

    `psi_rad` is the true heading (radians, clockwise from north); it may be
    a scalar or an array matching the components.

    Parameters
    ----------
    along, lateral : float or array
        Components along the heading (positive forward) and across it
        (positive to the right), ft/s.
    psi_rad : float or array
        True heading, rad.
    """
    c, s = np.cos(psi_rad), np.sin(psi_rad)
    along = np.asarray(along, dtype=float)
    lateral = np.asarray(lateral, dtype=float)
    return along * c - lateral * s, along * s + lateral * c


def ned_to_heading(north, east, psi_rad):
    """Inverse of :func:`heading_to_ned`: (north, east) -> (along, lateral), ft/s.

    Parameters
    ----------
    north, east : float or array
        Wind components, ft/s.
    psi_rad : float or array
        True heading, rad.
    """
    c, s = np.cos(psi_rad), np.sin(psi_rad)
    north = np.asarray(north, dtype=float)
    east = np.asarray(east, dtype=float)
    return north * c + east * s, -north * s + east * c


# --------------------------------------------------------------------------- side wind

@dataclass(frozen=True)
class SideWind:
    """The paper's slowly turning wind (Figs. 5 and 7).

    Over the record the wind turns clockwise from `theta_start_deg` to
    `theta_end_deg` (from-direction relative to the reference heading) while
    its speed grows linearly from `speed_start_fps` to `speed_end_fps`. The
    defaults (0 -> 120 deg, 0 -> 20 ft/s) give a wind that turns from head-on
    through a side wind towards a tail wind with a lateral magnitude growing
    almost monotonically to about 17.3 ft/s at 70 s, as in the paper's
    Fig. 7. The paper plots the magnitude; with the clockwise turn the wind
    comes from the right, so the signed lateral component here is negative.
    A negative `theta_end_deg` turns the wind anticlockwise instead.

    Attributes
    ----------
    speed_start_fps, speed_end_fps : float
        Wind speed at the start and end of the record, ft/s (>= 0).
    theta_start_deg, theta_end_deg : float
        Direction the wind comes from relative to the reference heading, deg,
        at the start and end (increasing: clockwise).
    """

    speed_start_fps: float = 0.0
    speed_end_fps: float = 20.0
    theta_start_deg: float = 0.0
    theta_end_deg: float = 120.0

    @classmethod
    def from_fields(cls, f: Fields) -> "SideWind":
        """Build from a TOML table (keys as the attribute names).

        Parameters
        ----------
        f : hesspipe.core.config.Fields
            The ``[wind]`` table.
        """
        out = cls(
            speed_start_fps=f.number("speed_start_fps", cls.speed_start_fps, min=0, max=100),
            speed_end_fps=f.number("speed_end_fps", cls.speed_end_fps, min=0, max=100),
            theta_start_deg=f.number("theta_start_deg", cls.theta_start_deg, min=-360, max=360),
            theta_end_deg=f.number("theta_end_deg", cls.theta_end_deg, min=-360, max=360),
        )
        f.reject_unknown()
        return out

    def __call__(self, t, duration_s: float):
        """(along, lateral) wind in ft/s at times `t` (s) of a `duration_s` record."""
        u = np.clip(np.asarray(t, dtype=float) / duration_s, 0.0, 1.0)
        speed = self.speed_start_fps + (self.speed_end_fps - self.speed_start_fps) * u
        theta = self.theta_start_deg + (self.theta_end_deg - self.theta_start_deg) * u
        return relative_wind(speed, theta)


# --------------------------------------------------------------------------- signals

def multisine(t, *, f_min_hz: float, f_max_hz: float, rms: float, seed, period_s: float | None = None):
    """Random-phase multisine with a flat amplitude spectrum.

    The frequencies are the harmonics ``k / period_s`` inside ``[f_min_hz,
    f_max_hz]`` (the record length by default, so the signal is periodic over
    the record and leaks no power between lines), with phases drawn
    uniformly from `seed`. The result is scaled to exactly `rms` on `t`.

    Parameters
    ----------
    t : array_like
        Uniform sample times, s.
    f_min_hz, f_max_hz : float
        Band, Hz.
    rms : float
        Root-mean-square value of the returned signal (signal units).
    seed : int or numpy.random.SeedSequence
        Seed of the phases.
    period_s : float, optional
        Fundamental period, s; default the span of `t` plus one sample.
    """
    t = np.asarray(t, dtype=float)
    if period_s is None:
        period_s = (t[-1] - t[0]) + (t[1] - t[0]) if t.size > 1 else 1.0
    k = np.arange(max(1, int(np.ceil(f_min_hz * period_s))), int(np.floor(f_max_hz * period_s)) + 1)
    if k.size == 0:
        k = np.array([max(1, int(round(f_min_hz * period_s)))])
    phases = np.random.default_rng(seed).uniform(0.0, 2.0 * np.pi, k.size)
    x = np.sin(2.0 * np.pi * np.outer(t - t[0], k / period_s) + phases).sum(axis=1)
    return _scale_rms(x, rms)


# Feedback taps of maximal-length Fibonacci LFSRs (bit numbers, 1-based).
_LFSR_TAPS = {5: (5, 3), 6: (6, 5), 7: (7, 6), 8: (8, 6, 5, 4), 9: (9, 5), 10: (10, 7),
              11: (11, 9), 12: (12, 11, 10, 4), 13: (13, 12, 11, 8), 14: (14, 13, 12, 2),
              15: (15, 14), 16: (16, 15, 13, 4)}


def prbs(n: int, *, dt: float, clock_s: float, amplitude: float, seed):
    """Maximal-length pseudo-random binary sequence of ``+-amplitude``.

    A linear-feedback shift register whose order is the smallest giving a
    period of at least the record (in clock periods) is started from a
    non-zero state drawn from `seed`; each bit is held for `clock_s`.
    The power is flat up to about ``0.44 / clock_s`` Hz.

    Parameters
    ----------
    n : int
        Samples.
    dt : float
        Sample interval, s.
    clock_s : float
        Bit length, s.
    amplitude : float
        Level of each bit (signal units).
    seed : int or numpy seed
        Seed of the register's start.
    """
    hold = max(1, int(round(clock_s / dt)))
    bits_needed = -(-n // hold)
    order = next((m for m in sorted(_LFSR_TAPS) if 2 ** m - 1 >= bits_needed), max(_LFSR_TAPS))
    taps = _LFSR_TAPS[order]
    state = int(np.random.default_rng(seed).integers(1, 2 ** order))
    bits = np.empty(bits_needed, dtype=float)
    for i in range(bits_needed):
        bits[i] = state & 1
        fb = 0
        for tap in taps:
            fb ^= (state >> (order - tap)) & 1
        state = (state >> 1) | (fb << (order - 1))
    return amplitude * (2.0 * np.repeat(bits, hold)[:n] - 1.0)


def filtered_noise(n: int, *, dt: float, corner_hz: float, rms: float, seed):
    """Gaussian white noise through a first-order low-pass, scaled to `rms`.

    A Dryden-like gust shape: flat to `corner_hz`, then -20 dB/decade.

    Parameters
    ----------
    n : int
        Samples.
    dt : float
        Sample interval, s.
    corner_hz : float
        Low-pass corner, Hz.
    rms : float
        RMS of the result (signal units).
    seed : int or numpy seed
        Seed of the white noise.
    """

    w = np.random.default_rng(seed).standard_normal(n)
    a = np.exp(-2.0 * np.pi * corner_hz * dt)
    return _scale_rms(lfilter([1.0 - a], [1.0, -a], w), rms)


def taper(t, taper_s: float):
    """Raised-cosine fade-in and fade-out of `taper_s` seconds at both ends (0..1).

    Parameters
    ----------
    t : array
        Sample times, s.
    taper_s : float
        Fade length, s (<= 0: no taper).
    """
    t = np.asarray(t, dtype=float)
    if taper_s <= 0 or t.size < 2:
        return np.ones_like(t)
    rel = np.minimum(t - t[0], t[-1] - t)
    return np.where(rel >= taper_s, 1.0, 0.5 - 0.5 * np.cos(np.pi * np.clip(rel, 0, None) / taper_s))


def _scale_rms(x, rms):
    x = x - x.mean()
    r = np.sqrt(np.mean(x ** 2))
    return x * (rms / r) if r > 0 else x


@dataclass(frozen=True)
class Excitation:
    """A seeded identification input.

    Attributes
    ----------
    kind : str
        ``"multisine"`` (flat band `f_min_hz`..`f_max_hz`, random phases),
        ``"prbs"`` (maximal-length PRBS held for `clock_s`), ``"noise"``
        (first-order low-passed white noise, corner `f_max_hz`) or ``"none"``.
    rms : float
        RMS of the signal (the amplitude for ``prbs``), in the units of the
        input it drives (ft/s for wind, normalised command for the aileron).
    f_min_hz, f_max_hz : float
        Band of the multisine; `f_max_hz` is also the noise corner.
    clock_s : float
        PRBS bit length, s.
    taper_s : float
        Raised-cosine fade in/out at the ends of the record, s (avoids a step
        at the start).
    """

    kind: str = "multisine"
    rms: float = 1.0
    f_min_hz: float = 0.02
    f_max_hz: float = 2.0
    clock_s: float = 0.5
    taper_s: float = 1.0

    @classmethod
    def from_fields(cls, f: Fields, defaults: "Excitation") -> "Excitation":
        """Build from a TOML table; absent keys take `defaults`.

        Parameters
        ----------
        f : hesspipe.core.config.Fields
            The excitation's table.
        defaults : Excitation
            Values of absent keys.
        """
        d = defaults
        kind = f.string("kind", d.kind, choices=EXCITATION_KINDS)
        out = cls(
            kind=kind,
            rms=f.number("rms", d.rms, min=0),
            f_min_hz=f.number("f_min_hz", d.f_min_hz, min=0, strict_min=True),
            f_max_hz=f.number("f_max_hz", d.f_max_hz, min=0, strict_min=True),
            clock_s=f.number("clock_s", d.clock_s, min=0, strict_min=True),
            taper_s=f.number("taper_s", d.taper_s, min=0),
        )
        if out.f_max_hz <= out.f_min_hz:
            raise f.error("f_max_hz", f"a number > f_min_hz = {out.f_min_hz:g}", out.f_max_hz)
        f.reject_unknown()
        return out

    def signal(self, t, seed):
        """The excitation sampled at uniform times `t` (s), reproducible from `seed`.

        Parameters
        ----------
        t : array
            Uniform sample times, s.
        seed : int or numpy seed
            Seed of the random phases, register or noise.

        Returns
        -------
        ndarray
            In the excitation's units (e.g. ft/s of wind), tapered at both ends.
        """
        t = np.asarray(t, dtype=float)
        n = t.size
        dt = float(t[1] - t[0]) if n > 1 else 1.0
        if self.kind == "none" or self.rms == 0 or n == 0:
            return np.zeros(n)
        if self.kind == "multisine":
            x = multisine(t, f_min_hz=self.f_min_hz, f_max_hz=self.f_max_hz, rms=self.rms, seed=seed)
        elif self.kind == "prbs":
            x = prbs(n, dt=dt, clock_s=self.clock_s, amplitude=self.rms, seed=seed)
        elif self.kind == "noise":
            x = filtered_noise(n, dt=dt, corner_hz=self.f_max_hz, rms=self.rms, seed=seed)
        else:  # pragma: no cover - guarded by from_fields
            raise ValueError(self.kind)
        return x * taper(t, self.taper_s)

    def describe(self, units: str) -> str:
        """One line for record headers, e.g. ``multisine 0.02-2 Hz, rms 3 ft/s``.

        Parameters
        ----------
        units : str
            Units of the signal, e.g. ``"ft/s"``.
        """
        if self.kind == "none" or self.rms == 0:
            return "none"
        if self.kind == "multisine":
            return (f"multisine {self.f_min_hz:g}-{self.f_max_hz:g} Hz, random phases, "
                    f"rms {self.rms:g} {units}, taper {self.taper_s:g} s")
        if self.kind == "prbs":
            return f"PRBS clock {self.clock_s:g} s, amplitude {self.rms:g} {units}, taper {self.taper_s:g} s"
        return (f"first-order low-passed white noise, corner {self.f_max_hz:g} Hz, "
                f"rms {self.rms:g} {units}, taper {self.taper_s:g} s")
