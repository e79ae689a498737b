"""Spectra for the diagnosis: the paper's Welch estimate, its chance scatter, the window's
kernel for expected PSDs, band-wise disagreement."""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import Sequence

import numpy as np
import scipy.optimize
import scipy.signal
import scipy.special
import scipy.stats

from ..identification.spectra import PaperWelch, fitness, psd

_DB = 10.0 / math.log(10.0)




# -- spectra, bins and bands ----------------------------------------------------------------

def _psd(x: np.ndarray, fs: float) -> tuple[np.ndarray, np.ndarray]:

    f, p = psd(np.asarray(x, dtype=float), fs)
    return np.asarray(f, dtype=float), np.asarray(p, dtype=float)


def _eq10(measured: np.ndarray, model: np.ndarray, freq: np.ndarray, band) -> float:

    return float(fitness(measured, model, freq, band=tuple(band)))


def welch_statistics(n_samples: int) -> tuple[float, float, float]:
    """Chance properties of the paper's Welch estimate of an `n_samples` record.

    Parameters
    ----------
    n_samples : int
        Samples in the record.

    Returns
    -------
    nu : float
        Equivalent chi-square degrees of freedom of one bin (2 per segment's worth of
        data; padding adds no information).
    var_floor : float
        ``psi'(nu/2)``: variance of the natural log of such an estimate.
    enbw_bins : float
        Equivalent noise bandwidth of the Hamming window in bins (bins per
        independent observation).
    """

    est = PaperWelch()
    nu = 2.0 * max(n_samples / est.nperseg, 1.0)
    w = np.asarray(est.window)
    enbw = est.nperseg * float(np.sum(w ** 2)) / float(np.sum(w)) ** 2
    return nu, float(scipy.special.polygamma(1, nu / 2.0)), enbw


@dataclass(frozen=True)
class Band:
    """Model-versus-measurement disagreement of the control PSD in one band.

    ``level_db`` > 0: the model has too much power (mean of 10 log10(model/measured));
    ``rms_db``: RMS of the same ratio; ``share``: fraction of the total squared log
    residual of the band set found in this band (which bands matter most);
    ``eq10_share``: the same for the squared linear PSD difference of Eq. 10;
    ``p_value``: chance of a mismatch this large if the band's log residuals scattered
    like the reference variance (chi-square over the band's independent bins);
    ``disagrees``: ``p_value < alpha``.

    Attributes
    ----------
    lo_hz, hi_hz : float
        Band edges, Hz.
    n_bins : int
        PSD bins in the band (DC left out).
    level_db : float
        Mean of 10 log10(model/measured), dB; > 0 when the model has too much power.
    rms_db : float
        RMS of the same ratio, dB.
    share : float
        Fraction of the band set's squared log residual found in this band.
    eq10_share : float
        The same for the squared linear PSD difference of Eq. 10.
    p_value : float
        Chance of a mismatch this large (chi-square over the independent bins).
    disagrees : bool
        ``p_value < alpha``.
    """

    lo_hz: float
    hi_hz: float
    n_bins: int
    level_db: float
    rms_db: float
    share: float
    eq10_share: float
    p_value: float
    disagrees: bool

    @property
    def direction(self) -> str:
        """"wrong shape" when ``|level_db| < rms_db / 2``, else "too much power" or "too
        little power" by the sign of ``level_db``."""
        if abs(self.level_db) < 0.5 * self.rms_db:
            return "wrong shape"
        return "too much power" if self.level_db > 0 else "too little power"

    def to_dict(self) -> dict:
        """The band as a JSON-ready dict, ``direction`` included."""
        return {**asdict(self), "direction": self.direction}


def band_disagreement(freq_hz: np.ndarray, measured_psd: np.ndarray, model_psd: np.ndarray,
                      edges_hz: Sequence[float], *, var_floor: float, enbw_bins: float,
                      alpha: float = 0.01, floor: float | None = None) -> tuple[Band, ...]:
    """Where, by how much and how significantly a model's control PSD misses the data.

    Parameters
    ----------
    freq_hz, measured_psd, model_psd : ndarray
        Common frequency grid (Hz) and the two PSDs (control units^2 / Hz).
    edges_hz : sequence of float
        Band edges, Hz; a bin belongs to [lo, hi) (the last band includes hi). DC is
        left out (its log is meaningless for a zero-mean control).
    var_floor : float
        Reference variance of one log-PSD bin: ``diagnose`` passes the residual
        variance of the final model (at least the resolution), so a band disagrees when
        its mismatch stands out from the rest of the record; the Welch scatter of
        :func:`welch_statistics` is the stricter "a repeat run would not erase it".
    enbw_bins : float
        Bins per independent observation (:func:`welch_statistics`).
    floor : float, optional
        PSD level added to both spectra before the logs (the estimator's dynamic range).
    """
    f = np.asarray(freq_hz, dtype=float)
    pm = np.asarray(measured_psd, dtype=float)
    ps = np.asarray(model_psd, dtype=float)
    r = _log_residual(pm, ps, floor)
    lin = (ps - pm) ** 2
    rows = []
    edges = list(edges_hz)
    for i, (lo, hi) in enumerate(zip(edges, edges[1:])):
        m = (f > 0) & (f >= lo) & ((f <= hi) if i == len(edges) - 2 else (f < hi))
        n = int(m.sum())
        if n == 0:
            continue
        rb = r[m]
        n_eff = max(n / enbw_bins, 1.0)
        chi = n_eff * float(np.mean(rb ** 2)) / var_floor
        rows.append(dict(lo_hz=float(lo), hi_hz=float(hi), n_bins=n, level_db=_DB * float(rb.mean()),
                         rms_db=_DB * math.sqrt(float(np.mean(rb ** 2))), ss=float(np.sum(rb ** 2)),
                         lin=float(np.sum(lin[m])), p_value=float(scipy.stats.chi2.sf(chi, n_eff))))
    total = sum(row["ss"] for row in rows) or 1.0
    total_lin = sum(row["lin"] for row in rows) or 1.0
    return tuple(Band(lo_hz=row["lo_hz"], hi_hz=row["hi_hz"], n_bins=row["n_bins"],
                      level_db=row["level_db"], rms_db=row["rms_db"], share=row["ss"] / total,
                      eq10_share=row["lin"] / total_lin, p_value=row["p_value"],
                      disagrees=row["p_value"] < alpha) for row in rows)


def _log_residual(measured: np.ndarray, model: np.ndarray, floor: float | None = None) -> np.ndarray:
    """``ln(model + floor) - ln(measured + floor)``; `floor` defaults to 1e-12 of the
    measured peak."""
    eps = 1e-12 * max(float(np.max(measured)), 1e-300) if floor is None else floor
    return np.log(np.maximum(model, 0.0) + eps) - np.log(np.maximum(measured, 0.0) + eps)



def _window_gain(n_samples: int) -> float:
    """Expected paper-Welch PSD of unit two-sided density (white noise of variance fs).

    ``mean(window^2) / U`` per full segment; the padding of the last segment (Eq. 9)
    carries no noise, so each segment counts by the window energy on its data samples.
    """

    est = PaperWelch()
    w2 = np.asarray(est.window) ** 2
    k = est.segments(n_samples)
    step = est.nperseg - est.noverlap
    energy = sum(float(np.sum(w2[:max(0, min(est.nperseg, n_samples - i * step))])) for i in range(k))
    return energy / (k * est.nperseg) / est.correction


def welch_kernel(n_samples: int, fs: float, freq_hz: np.ndarray, grid_hz: np.ndarray,
                 *, lattice: int = 1 << 16) -> np.ndarray:
    """Matrix turning a two-sided PSD on `grid_hz` into the paper-Welch estimate's expectation.

    ``E[P_welch(f_k)] = sum_j G[k, j] S(nu_j)`` for a stationary signal of two-sided
    density ``S`` (units^2/Hz, even in frequency) sampled on the increasing grid
    ``grid_hz`` (starting at 0, spacing free to vary): the Riemann sum (each point
    weighted by half the distance between its neighbours; the point at 0 by its whole
    cell, which spans both signs) of
    ``∫ S(nu) K(f_k - nu) dnu / (N fs U)`` over both signs of ``nu``, with ``K`` the
    squared magnitude of the window's transform averaged over the segments (the last
    segment's window counts only on its data samples, as in :func:`_window_gain`).

    Why not ``S(f_k)`` times the window gain: a Welch bin averages the density over the
    window's main lobe (4 bins wide for Hamming), and a closed-loop remnant can have
    features much narrower than that — e.g. a spike at DC where the plant's static gain
    is near zero, so the loop does not oppose slow noise. A point value there is what
    the estimator never sees, and it wrecked the Eq. 10 gap (which includes DC) of every
    model with a remnant.

    Parameters
    ----------
    n_samples : int
        Samples in the record.
    fs : float
        Sample rate, Hz.
    freq_hz : ndarray
        Frequencies of the Welch bins, Hz.
    grid_hz : ndarray
        Increasing grid (starting at 0) the density ``S`` is sampled on, Hz.
    lattice : int
        FFT length on which the window's squared transform is tabulated.

    Returns
    -------
    ndarray
        ``G``, shape ``(len(freq_hz), len(grid_hz))``; ``G @ S`` is in the units of
        ``S`` (control units^2/Hz for a control spectrum).
    """

    est = PaperWelch()
    n = est.nperseg
    k_seg = est.segments(n_samples)
    step = n - est.noverlap
    w = np.asarray(est.window)
    kern = np.zeros(lattice // 2 + 1)
    for i in range(k_seg):
        m = max(0, min(n, n_samples - i * step))
        kern += np.abs(np.fft.rfft(w[:m], lattice)) ** 2
    kern /= k_seg
    lat_f = np.fft.rfftfreq(lattice, 1.0 / fs)
    f = np.asarray(freq_hz, dtype=float)[:, None]
    nu = np.asarray(grid_hz, dtype=float)[None, :]
    edges = np.asarray(grid_hz, dtype=float)
    d = np.empty_like(edges)
    d[1:-1] = 0.5 * (edges[2:] - edges[:-2])
    d[0] = edges[1] - edges[0]
    d[-1] = edges[-1] - edges[-2]

    def k_at(phi):
        return np.interp(np.abs(phi), lat_f, kern)

    g = k_at(f - nu) + np.where(nu > 0, k_at(f + nu), 0.0)
    return g * d / (n * fs * est.correction)
