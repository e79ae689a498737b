"""The pilot's two channels, separated without a model: the response to the displayed error
and the response to the output itself (on a compensatory display with motion, the
vestibular path), from a record with target and disturbance on their own lines.

Multimodal tracking experiments model the control as::

    U = Hpe E - Hpy Y        (E = R - Y)

with Hpe the visual response to the displayed error and Hpy the response to the controlled
output through any other channel: with a compensatory display and a moving cab, the
vestibular path times the cab's motion per unit output (the SPEC's ``motion_path``), so a
stabilising motion feedback has the same sign as the visual feedback on -y; a pursuit
display's feedforward on the target, ``Hff R = Hff (E + Y)``, appears as ``-Hff``. Without
either, Hpy is zero.

At the disturbance lines R has no power, E = -Y, and the measured U/E is their sum
``Hsum = Hpe + Hpy`` (the disturbance loop's pilot). At a target line
``U/E = Hsum - Hpy R/E``, so with Hsum interpolated from the neighbouring disturbance lines::

    Hpy(w_t) = (Hsum(w_t) - (U/E)(w_t)) * (E/R)(w_t),    Hpe = Hsum - Hpy

(two independent forcings let two responses be told apart: the reason motion experiments
force target and disturbance, e.g. Zaal et al. 2009, J. Guid. Control Dyn. 32(4); the
interpolation is this module's choice). Hsum is interpolated linearly in ln w, its log
magnitude and unwrapped phase apart;
target lines outside the disturbance lines' range are not estimated. The interpolation is
exact only where Hsum is straight in those coordinates between two lines: elsewhere it
leaves a bias in Hpy (under 2 % of |Hpe| at 1-5 rad/s on the built records of
``tests/test_frf_channels.py``, 1-7 % on remnant-free generator runs), which the remnant's
own floor exceeds on measured runs (``benchmarks/bench_channels.py``).

Uncertainty: the target line's own sigma and the interpolated one (the bracketing lines'
relative sigmas weighted by the interpolation's weights) add in quadrature, times
``|E/R|``; the interpolation's bias is not in it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..core.errors import HesspipeError

BAND_RAD_S = (1.0, 5.0)
"""Where a vestibular path changes the pilot's gain and phase most (rad/s): the summary's
band (:attr:`Channels.ratio_median`)."""


@dataclass(frozen=True)
class Channels:
    """Result of :func:`separate_channels`.

    Attributes
    ----------
    freq_rad_s : ndarray
        The target lines estimated, rad/s.
    Hpe : ndarray, complex
        Response to the displayed error (control units per output unit).
    Hpy : ndarray, complex
        Response to the output other than through the error (control units per output
        unit; ``U = Hpe E - Hpy Y``).
    sigma_Hpy : ndarray
        Standard deviation of Hpy's complex error from the remnant (same units).
    ratio_median : float
        Median of ``|Hpy| / |Hpe|`` over the lines in :data:`BAND_RAD_S` (NaN if none).
    lines_in_band : int
        How many lines that median rests on.
    """

    freq_rad_s: np.ndarray
    Hpe: np.ndarray
    Hpy: np.ndarray
    sigma_Hpy: np.ndarray
    ratio_median: float
    lines_in_band: int

    def to_dict(self) -> dict:
        """JSON-ready: per line the frequency (rad/s), both channels' magnitude (linear) and
        phase (deg), Hpy's sigma, and the band's median ratio."""
        return {"definition": "U = Hpe E - Hpy Y at the target lines, Hpe + Hpy interpolated "
                              "from the disturbance lines (ln w, log magnitude and unwrapped phase)",
                "frequency_rad_s": self.freq_rad_s.tolist(),
                "Hpe_magnitude": np.abs(self.Hpe).tolist(),
                "Hpe_phase_deg": np.degrees(np.angle(self.Hpe)).tolist(),
                "Hpy_magnitude": np.abs(self.Hpy).tolist(),
                "Hpy_phase_deg": np.degrees(np.angle(self.Hpy)).tolist(),
                "Hpy_sigma": self.sigma_Hpy.tolist(),
                "band_rad_s": list(BAND_RAD_S),
                "ratio_median_in_band": self.ratio_median,
                "lines_in_band": self.lines_in_band}


def _interpolate(w_from, H, sigma, w_to):
    # Hsum and its sigma at w_to, linear in ln w on log|H| and the unwrapped phase, the
    # relative sigmas with the same weights; NaN outside [w_from[0], w_from[-1]].
    lw, lt = np.log(w_from), np.log(w_to)
    i = np.clip(np.searchsorted(lw, lt) - 1, 0, lw.size - 2)
    a = np.clip((lt - lw[i]) / (lw[i + 1] - lw[i]), 0.0, 1.0)
    inside = (lt >= lw[0]) & (lt <= lw[-1])

    def lerp(v):
        return np.where(inside, (1 - a) * v[i] + a * v[i + 1], np.nan)

    H_t = np.exp(lerp(np.log(np.abs(H))) + 1j * lerp(np.unwrap(np.angle(H))))
    rel = sigma / np.abs(H)
    return H_t, np.hypot((1 - a) * rel[i], a * rel[i + 1]) * np.abs(H_t)


def separate_channels(frf) -> Channels:
    """The error and output channels of a two-input record's describing function (module doc).

    Parameters
    ----------
    frf : hesspipe.identification.frf.Frf
        From :func:`~hesspipe.identification.frf.estimate_frf` or
        :func:`~hesspipe.identification.frf_average.average_frf`: a multisine record with
        disturbance and target lines.

    Returns
    -------
    Channels

    Raises
    ------
    HesspipeError
        Without both line sets (Welch, or one forcing), or with fewer than two disturbance
        lines, or no target line between them.
    """
    if frf.method != "multisine" or frf.reference is None or frf.reference.error_per_forcing is None:
        raise HesspipeError(f"run {frf.run_id or '?'}: the channels need target and disturbance on "
                            "their own multisine lines; expected both line sets")
    fb, ref = frf.feedback, frf.reference
    if fb.freq_rad_s.size < 2:
        raise HesspipeError(f"run {frf.run_id or '?'}: {fb.freq_rad_s.size} disturbance line(s); "
                            "expected at least two to interpolate between")
    Hsum, s_sum = _interpolate(fb.freq_rad_s, fb.H, fb.sigma, ref.freq_rad_s)
    keep = np.isfinite(Hsum)
    if not keep.any():
        raise HesspipeError(f"run {frf.run_id or '?'}: no target line lies between the disturbance "
                            "lines; expected interleaved line sets")
    w, Hsum, s_sum = ref.freq_rad_s[keep], Hsum[keep], s_sum[keep]
    e_over_r = ref.error_per_forcing[keep]
    Hpy = (Hsum - ref.H[keep]) * e_over_r
    sigma = np.hypot(s_sum, ref.sigma[keep]) * np.abs(e_over_r)
    Hpe = Hsum - Hpy
    band = (w >= BAND_RAD_S[0]) & (w <= BAND_RAD_S[1])
    ratio = np.abs(Hpy[band]) / np.abs(Hpe[band])
    return Channels(w, Hpe, Hpy, sigma, float(np.median(ratio)) if ratio.size else float("nan"),
                    int(band.sum()))
