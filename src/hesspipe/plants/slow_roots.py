"""Right-half-plane roots slower than a record can place (plants stage, step 7).

A record of duration T cannot tell a root at ``s = +a`` from one at ``-a``
when ``|a| < ln 2 / T`` (:func:`hesspipe.pilot.simulation.growth_limit`): the time constant
outlasts the record. :func:`reflect_slow_roots` reflects such roots into the
left half plane (gain response unchanged) so that the plants stage can report
the validation fit of both choices (:class:`SlowRoots`) and apply one.
"""

from __future__ import annotations

from dataclasses import dataclass

import control as ct
import numpy as np

from ..core.formats import siso_coefficients


@dataclass(frozen=True)
class SlowRoots:
    """Right-half-plane roots of one continuous plant that its record cannot place (step 7).

    Attributes
    ----------
    limit : float
        Record resolution, 1/s: ``ln 2 / duration`` (:func:`hesspipe.pilot.simulation.growth_limit`).
    roots : tuple of dict
        ``{"kind": "zero" | "pole", "before": {"re", "im"}, "after": {"re", "im"}}``
        per root slower than `limit` (a complex pair once) and its reflection.
    applied : {"keep", "reflect"}
        Which of the two went into plants.json.
    fit_validation_before, fit_validation_after : float
        Fit percent of the continuous model's simulated output on the
        validation tail as fitted and with the roots reflected.
    max_phase_change_deg : float
        Largest phase change the reflection makes on the check band.
    """

    limit: float
    roots: tuple[dict, ...]
    applied: str
    fit_validation_before: float
    fit_validation_after: float
    max_phase_change_deg: float

    def to_dict(self) -> dict:
        """The reflection as JSON-ready values (rule, limit in 1/s, roots, fits, phase change)."""
        return {"rule": "right-half-plane poles and zeros with |s| below the record's resolution "
                        "ln 2 / duration cannot be placed by the record; listed with the continuous "
                        "validation fit as fitted and reflected into the left half plane "
                        "(gain response unchanged)",
                "limit_1_per_s": self.limit, "roots": list(self.roots), "applied": self.applied,
                "fit_validation_continuous_as_fitted": self.fit_validation_before,
                "fit_validation_continuous_reflected": self.fit_validation_after,
                "max_phase_change_deg": self.max_phase_change_deg}


def _reflect(poly: np.ndarray, limit: float, kind: str) -> tuple[np.ndarray, list[dict]]:
    """Reflect the roots of `poly` with real part > 0 and modulus < `limit` by deflation."""
    poly = np.trim_zeros(np.atleast_1d(np.asarray(poly, dtype=float)), "f")
    done: list[dict] = []
    if poly.size < 2:
        return poly, done
    for r in np.roots(poly):
        if not (r.real > 0.0 and abs(r) < limit) or r.imag < 0:
            continue
        if abs(r.imag) > 1e-9 * max(1.0, abs(r)):
            old = np.array([1.0, -2.0 * r.real, abs(r) ** 2])
            new = np.array([1.0, 2.0 * r.real, abs(r) ** 2])
        else:
            old, new = np.array([1.0, -r.real]), np.array([1.0, r.real])
        q, _ = np.polydiv(poly, old)
        poly = np.polymul(q, new)
        done.append({"kind": kind, "before": {"re": float(r.real), "im": float(r.imag)},
                     "after": {"re": float(-r.real), "im": float(r.imag)}})
    return poly, done


def reflect_slow_roots(sys: ct.TransferFunction, limit: float) -> tuple[ct.TransferFunction, list[dict]]:
    """Reflect right-half-plane poles and zeros of modulus below `limit` (1/s).

    Each such root ``r`` becomes ``-conj(r)``: ``|j w - r| = |j w + conj(r)|``,
    so the gain response is unchanged and only the phase moves, by
    ``2 atan(Re r / w)`` per real root. Returns the new continuous transfer
    function and one entry per reflected root (see :class:`SlowRoots`).

    Parameters
    ----------
    sys : control.TransferFunction
        SISO, continuous.
    limit : float
        Record resolution, 1/s (> 0).
    """
    num, den = siso_coefficients(sys)
    num, zeros = _reflect(num, limit, "zero")
    den, poles = _reflect(den, limit, "pole")
    if not zeros and not poles:
        return sys, []
    return ct.tf(num, den), zeros + poles


def phase_change(before, after, band_hz) -> float:
    """Largest phase difference (deg) between two continuous models on a band (Hz).

    Parameters
    ----------
    before, after : control.TransferFunction
        Continuous SISO models.
    band_hz : (float, float)
        The band, Hz (> 0).
    """
    w = 2 * np.pi * np.logspace(np.log10(band_hz[0]), np.log10(band_hz[1]), 400)
    ratio = np.asarray(after(1j * w)).reshape(-1) / np.asarray(before(1j * w)).reshape(-1)
    return float(np.max(np.abs(np.degrees(np.angle(ratio)))))
