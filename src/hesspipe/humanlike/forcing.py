"""Multisine forcing functions (TU Delft style) for the independent generator.

Every line is an integer multiple k of the base frequency 2*pi/T_m, so the
measurement window of T_m seconds holds whole periods of every sine and each
line falls exactly on a DFT bin of the logged record. Disturbance and target
use disjoint, interleaved sets of k.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..core.errors import HesspipeError


@dataclass(frozen=True)
class Multisine:
    """A sum of sines ``sum_i a_i sin(w_i t + phi_i)``.

    Attributes
    ----------
    k : ndarray of int
        Line numbers (multiples of the base frequency 2*pi/T_m).
    w : ndarray
        Line frequencies, rad/s.
    a : ndarray
        Amplitudes, units of the signal.
    phase : ndarray
        Phases, rad.
    """

    k: np.ndarray
    w: np.ndarray
    a: np.ndarray
    phase: np.ndarray

    def __call__(self, t) -> np.ndarray:
        t = np.asarray(t, dtype=float)
        out = np.zeros(t.shape)
        for w, a, p in zip(self.w, self.a, self.phase):
            out += a * np.sin(w * t + p)
        return out

    def rms(self) -> float:
        """RMS of the signal over a whole period, the signal's units."""
        return float(np.sqrt(np.sum(self.a ** 2) / 2.0))

    def as_dict(self) -> dict:
        """The lines as JSON-ready lists (k, rad/s, amplitude, rad)."""
        return {"k": self.k.tolist(), "frequency_rad_s": self.w.tolist(),
                "amplitude": self.a.tolist(), "phase_rad": self.phase.tolist()}


SPARSE_LAYOUT = dict(fs=100.0, T_m=81.92, line_bins=((5, 11, 23, 37, 51, 71, 101, 137, 171, 226),
                                                     (6, 13, 27, 41, 53, 73, 103, 139, 194, 229)))
"""A sparser two-input layout than :func:`line_sets`' (``draw_trial`` options): 81.92 s at
100 Hz, ten lines per set from 0.38 to 17.6 rad/s, each target line 1-23 bins from its
disturbance line. Modelled on the designs of two-input tracking experiments, not copied
from one; few of a line's neighbouring bins hold the other set's lines."""


def line_sets(T_m: float, n_lines: int, w_lo: float = 0.1, w_hi: float = 20.0):
    """Disturbance and interleaved target line numbers.

    Disturbance lines are log-spaced between `w_lo` and `w_hi` (rad/s), at least
    two apart and never below k = 2 (a record then holds two periods of the
    lowest line); the target uses k + 1 of each, so the sets are disjoint.

    Parameters
    ----------
    T_m : float
        Measurement period, s (lines at multiples of ``2 pi / T_m``).
    n_lines : int
        Lines per set.
    w_lo, w_hi : float
        Frequency range, rad/s.

    Returns
    -------
    k_disturbance, k_target : ndarray of int
    """
    w0 = 2 * np.pi / T_m
    k_lo = max(2, int(round(w_lo / w0)))
    k_hi = int(round(w_hi / w0))
    if k_hi < k_lo + 2 * (n_lines - 1):
        raise HesspipeError(f"n_lines: {n_lines} lines two apart do not fit between "
                            f"{k_lo * w0:.3g} and {w_hi:g} rad/s for T_m = {T_m:g} s")
    k = np.round(np.geomspace(k_lo, k_hi, n_lines)).astype(int)
    for i in range(1, n_lines):
        k[i] = max(k[i], k[i - 1] + 2)
    # Squeeze from the top if the spacing rule pushed the last lines past k_hi.
    for i in range(n_lines - 1, 0, -1):
        if k[i] > k_hi - 2 * (n_lines - 1 - i):
            k[i] = k_hi - 2 * (n_lines - 1 - i)
    return k, k + 1


def design(k, T_m: float, rms: float, rng: np.random.Generator, *, w_corner: float,
           t_a: float = 0.1, through=None) -> Multisine:
    """Multisine on lines `k` with low-passed amplitudes and random phases.

    Amplitudes follow ``|(1 + t_a jw)^2 / (1 + jw/w_corner)^2|`` (flat below
    `w_corner`, about 1.5-2 rad/s, reduced by 20-30 times at 20 rad/s), scaled so
    that the signal's RMS is `rms`. Phases uniform on [0, 2 pi).

    Parameters
    ----------
    k : array of int
        Line numbers.
    T_m : float
        Measurement period, s.
    rms : float
        RMS of the signal, its units.
    rng : numpy.random.Generator
        Source of the phases.
    w_corner : float
        Corner of the amplitude shape, rad/s.
    t_a : float
        Lead time constant of the shape, s.
    through : callable, optional
        ``through(w)``: the complex response (rad/s in) of the path the signal drives.
        Given, the shaped amplitudes are divided by its magnitude, so that the signal's
        effect *after* that path has the shape and RMS `rms` (an output-equivalent
        disturbance: `rms` is then in the path's output units).
    """
    k = np.asarray(k, dtype=int)
    w = k * 2 * np.pi / T_m
    shape = np.abs((1 + 1j * w * t_a) ** 2 / (1 + 1j * w / w_corner) ** 2)
    a = shape * rms / np.sqrt(np.sum(shape ** 2) / 2.0)
    if through is not None:
        a = a / np.abs(np.asarray(through(w), dtype=complex))
    phase = rng.uniform(0.0, 2 * np.pi, k.size)
    return Multisine(k, w, a, phase)


def fade(t, t_start: float, length: float) -> np.ndarray:
    """Raised-cosine fade-in from 0 at `t_start` to 1 at `t_start + length` (s).

    Parameters
    ----------
    t : array
        Times, s.
    t_start : float
        Start of the fade, s.
    length : float
        Its length, s (> 0).
    """
    x = np.clip((np.asarray(t, dtype=float) - t_start) / length, 0.0, 1.0)
    return 0.5 - 0.5 * np.cos(np.pi * x)
