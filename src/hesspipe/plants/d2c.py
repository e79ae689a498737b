"""Discrete → continuous conversion of identified models, checked in frequency.

An ARX model fitted to anti-alias-filtered, decimated data describes the
plant's frequency response on ``e^(j w T)`` for frequencies well below
Nyquist; what stage three needs is a rational H(s) with (nearly) the same
response at ``j w``. The conversion is the inverse bilinear (Tustin) map
``z = (1 + s T/2) / (1 - s T/2)``, which maps the stable unit disc onto the
left half plane one to one, keeps the order, and changes the response only
by the frequency warping ``w_d = (2/T) atan(w T / 2)`` — small well below
Nyquist, and measured, not assumed: :func:`compare_frequency_response`
checks the result against the discrete model on a band, and the caller
decides what a failed check means.

Explicit handling of the poles a zero-order-hold inverse (matrix logarithm)
cannot convert:

* poles at z = 0 (input delay nk and padding; a delay q^-k is k poles at
  z = 0): Tustin maps each to s = -2/T and the matching zero at z = ∞ to
  s = +2/T, i.e. each sample of delay becomes the first-order Padé all-pass
  ``(2/T - s) / (2/T + s)`` — exact in magnitude, phase error below
  ``(w T)^3 / 12`` rad per sample. Poles *near* z = 0 map near -2/T.
* negative real poles -1 < z < 0 (ringing at the Nyquist frequency, often
  a fitting artefact) map to real poles faster than -2/T; they are kept,
  because removing them would change the in-band response, and listed in
  :attr:`Conversion.notes` so a reader knows they are out-of-band artefacts.
* a pole within `nyquist_tol` of z = -1 has no finite image (s → ∞): the
  conversion raises :class:`~hesspipe.core.errors.HesspipeError`.
* unstable discrete poles (|z| >= 1) map to right-half-plane poles; the
  conversion proceeds and records a note (the caller's validation decides).
"""

from __future__ import annotations

from dataclasses import dataclass

import control as ct
import numpy as np

from ..core.errors import HesspipeError
from ..core.formats import siso_coefficients


def _poly_power(p: np.ndarray, k: int) -> np.ndarray:
    out = np.array([1.0])
    for _ in range(k):
        out = np.polymul(out, p)
    return out


def tustin_d2c(sysd: ct.TransferFunction, *, nyquist_tol: float = 1e-6,
               label: str = "model") -> tuple[ct.TransferFunction, list[str]]:
    """Inverse Tustin transform of a SISO discrete transfer function.

    Parameters
    ----------
    sysd : control.TransferFunction
        Discrete, ``dt > 0``.
    nyquist_tol : float
        Poles closer than this to z = -1 are refused.
    label : str
        Names the model in messages.

    Returns
    -------
    sysc : control.TransferFunction
        Continuous, denominator monic.
    notes : list of str
        How poles at or near z = 0, negative real poles and unstable poles
        were handled.
    """
    dt = sysd.dt
    if dt is None or dt is True or not dt or dt <= 0:
        raise HesspipeError(f"{label}: expected a discrete transfer function with a sample time, got dt={dt!r}")
    num, den = siso_coefficients(sysd)
    n = max(len(num), len(den)) - 1
    num = np.r_[np.zeros(n + 1 - len(num)), num]
    den = np.r_[np.zeros(n + 1 - len(den)), den]
    poles = np.roots(np.trim_zeros(den, "f"))
    notes: list[str] = []
    near_nyquist = poles[np.abs(poles + 1) < nyquist_tol]
    if near_nyquist.size:
        raise HesspipeError(f"{label}: discrete pole at z = {near_nyquist[0]:.6g} (the Nyquist point "
                            "z = -1) has no continuous equivalent; refit with other orders")
    a = dt / 2.0
    plus = np.array([a, 1.0])     # 1 + s T/2, descending powers of s
    minus = np.array([-a, 1.0])   # 1 - s T/2

    def substitute(c):
        # c_k z^(n-k), times (1 - sT/2)^n, is c_k (1 + sT/2)^(n-k) (1 - sT/2)^k: degree n in s.
        out = np.zeros(n + 1)
        for k, ck in enumerate(c):
            out = out + ck * np.polymul(_poly_power(plus, n - k), _poly_power(minus, k))
        return out

    num_s = substitute(num)
    den_s = substitute(den)
    lead = den_s[np.flatnonzero(np.abs(den_s) > 0)[0]]
    num_s, den_s = num_s / lead, den_s / lead
    den_s = np.trim_zeros(den_s, "f")
    num_s = np.trim_zeros(num_s, "f")
    if num_s.size == 0:
        num_s = np.zeros(1)
    n_zero = int(np.sum(np.abs(poles) < 1e-9))
    if n_zero:
        notes.append(f"{n_zero} pole(s) at z = 0 (pure delay) became first-order Padé all-pass "
                     f"factor(s) with pole s = {-2 / dt:.4g} and zero s = {2 / dt:.4g} rad/s")
    near_zero = poles[(np.abs(poles) >= 1e-9) & (np.abs(poles) < 0.05)]
    if near_zero.size:
        notes.append(f"{near_zero.size} pole(s) near z = 0 mapped near s = {-2 / dt:.4g} rad/s")
    neg = poles[(np.abs(poles.imag) < 1e-9) & (poles.real < 0) & (np.abs(poles) >= 0.05)]
    for p in neg:
        s = 2 / dt * (p.real - 1) / (p.real + 1)
        notes.append(f"negative real pole z = {p.real:.4g} (Nyquist-frequency ringing) mapped to "
                     f"s = {s:.4g} rad/s, outside the band; kept so the in-band response is unchanged")
    unstable = poles[np.abs(poles) >= 1]
    if unstable.size:
        notes.append(f"{unstable.size} unstable discrete pole(s) (|z| >= 1) mapped to the right half plane")
    return ct.tf(num_s, den_s), notes


@dataclass(frozen=True)
class FrequencyCheck:
    """Continuous vs discrete frequency response on a band.

    Attributes
    ----------
    freq_hz : ndarray
        Frequencies of the check, Hz.
    discrete, continuous : ndarray of complex
        The two models' responses there.
    max_gain_error_db : float
        Largest ``|20 log10 |Hc / Hd||``, dB.
    max_phase_error_deg : float
        Largest ``|angle(Hc / Hd)|``, deg.
    gain_limit_db, phase_limit_deg : float
        What passes, dB and deg.
    band_hz : (float, float)
        The band, Hz.
    """

    freq_hz: np.ndarray
    discrete: np.ndarray
    continuous: np.ndarray
    max_gain_error_db: float
    max_phase_error_deg: float
    gain_limit_db: float
    phase_limit_deg: float
    band_hz: tuple[float, float]

    @property
    def passed(self) -> bool:
        """True if both errors are within their limits."""
        return (self.max_gain_error_db <= self.gain_limit_db
                and self.max_phase_error_deg <= self.phase_limit_deg)

    def to_dict(self) -> dict:
        """The check as JSON-ready values (band, errors, limits, pass)."""
        return {"band_hz": list(self.band_hz), "max_gain_error_db": self.max_gain_error_db,
                "max_phase_error_deg": self.max_phase_error_deg,
                "gain_limit_db": self.gain_limit_db, "phase_limit_deg": self.phase_limit_deg,
                "pass": self.passed}


def frequency_response(sys: ct.TransferFunction, freq_hz: np.ndarray) -> np.ndarray:
    """Complex response of `sys` at `freq_hz` (z = e^(j w dt) if discrete).

    Parameters
    ----------
    sys : control.TransferFunction
        SISO, continuous or discrete.
    freq_hz : array
        Frequencies, Hz.

    Returns
    -------
    ndarray of complex
        Output units per input unit.
    """
    w = 2 * np.pi * np.asarray(freq_hz, dtype=float)
    if sys.isdtime(strict=True):
        x = np.exp(1j * w * sys.dt)
    else:
        x = 1j * w
    return np.asarray(sys(x)).reshape(-1)


def compare_frequency_response(sysd: ct.TransferFunction, sysc: ct.TransferFunction, *,
                               band_hz: tuple[float, float] = (0.01, 2.0), n: int = 400,
                               gain_limit_db: float = 1.0,
                               phase_limit_deg: float = 5.0) -> FrequencyCheck:
    """Largest gain (dB) and phase (deg) difference between `sysc` and `sysd` on a band.

    The band must lie below the discrete model's Nyquist frequency.

    Parameters
    ----------
    sysd : control.TransferFunction
        Discrete model (with its sample time, s).
    sysc : control.TransferFunction
        Continuous model.
    band_hz : (float, float)
        The band, Hz (0 < low < high < Nyquist).
    n : int
        Log-spaced frequencies on the band.
    gain_limit_db, phase_limit_deg : float
        Largest differences that pass, dB and deg.
    """
    lo, hi = band_hz
    nyq = 0.5 / sysd.dt
    if not 0 < lo < hi < nyq:
        raise HesspipeError(f"frequency check band {lo:g}-{hi:g} Hz must satisfy 0 < low < high < "
                            f"Nyquist ({nyq:g} Hz)")
    f = np.logspace(np.log10(lo), np.log10(hi), n)
    hd = frequency_response(sysd, f)
    hc = frequency_response(sysc, f)
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = hc / hd
        gain = np.abs(20 * np.log10(np.abs(ratio)))
    phase = np.abs(np.degrees(np.angle(ratio)))
    return FrequencyCheck(freq_hz=f, discrete=hd, continuous=hc,
                          max_gain_error_db=float(np.nanmax(gain)) if np.all(np.isfinite(gain)) else float("inf"),
                          max_phase_error_deg=float(np.nanmax(phase)) if np.all(np.isfinite(phase)) else float("inf"),
                          gain_limit_db=gain_limit_db, phase_limit_deg=phase_limit_deg,
                          band_hz=(float(lo), float(hi)))
