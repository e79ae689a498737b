"""Control-signal spectra and the fitness of the paper (Eqs. 5-10).

The paper's estimate (:class:`PaperWelch`): the record is padded with its
trim value to a whole number of segments (Eq. 9), cut into segments of 1024
samples overlapping by 32, each weighted by a Hamming window; the segment
periodograms ``|FFT|^2 / (N fs)`` (Eqs. 5-7: the correlation-sequence
spectrum divided by the sample rate) are averaged and divided by the
window's energy-loss factor U = 0.612 (Eq. 8). No mean is removed and the
spectrum is not folded (values at f >= 0 of the two-sided density), as in
the paper's equations. ``method="scipy"`` gives :func:`scipy.signal.welch`'s
one-sided density with the same window and segmentation instead.

Fitness (Eq. 10): the root mean square, over the bins of a band, of the
difference between measured and simulated PSDs. Lower is better.
"""

from __future__ import annotations

import dataclasses
import functools
from dataclasses import dataclass

import numpy as np
import scipy.fft
import scipy.signal

from ..core._time import decimate_signal
from ..core.errors import HesspipeError
from ..core.paper import FITNESS_BAND_HZ, WELCH_CORRECTION, WELCH_OVERLAP, WELCH_SEGMENT


@functools.lru_cache(maxsize=8)
def _hamming(n: int) -> np.ndarray:
    w = scipy.signal.get_window("hamming", n)
    w.flags.writeable = False
    return w


@functools.lru_cache(maxsize=8)
def _rfftfreq(n: int, fs: float) -> np.ndarray:
    return np.fft.rfftfreq(n, 1.0 / fs)


@dataclass(frozen=True)
class PaperWelch:
    """Welch estimate of the paper.

    Attributes
    ----------
    nperseg : int
        Segment length, samples (1024).
    noverlap : int
        Overlap between segments, samples (32).
    correction : float
        Energy-loss factor U of Eq. 8 (0.612).
    """

    nperseg: int = WELCH_SEGMENT
    noverlap: int = WELCH_OVERLAP
    correction: float = WELCH_CORRECTION

    def __post_init__(self):
        if not (1 <= self.nperseg and 0 <= self.noverlap < self.nperseg):
            raise HesspipeError(f"spectra: expected 0 <= noverlap < nperseg, got nperseg="
                                f"{self.nperseg}, noverlap={self.noverlap}")

    def segments(self, n: int) -> int:
        """Number of segments covering `n` samples after padding (Eq. 9).

        Parameters
        ----------
        n : int
            Samples of the record.
        """
        if n < self.nperseg:
            raise HesspipeError(f"record of {n} samples is shorter than one spectral segment "
                                f"({self.nperseg} samples); expected at least {self.nperseg}")
        step = self.nperseg - self.noverlap
        return 1 + -(-(n - self.nperseg) // step)

    def frequencies(self, fs: float) -> np.ndarray:
        """Frequencies of the estimate's bins, Hz (0 to fs/2, ``nperseg // 2 + 1`` of them).

        Parameters
        ----------
        fs : float
            Sample rate, Hz.
        """
        return _rfftfreq(self.nperseg, float(fs)).copy()

    @property
    def window(self) -> np.ndarray:
        """The Hamming window of one segment (read-only)."""
        return _hamming(self.nperseg)

    def __call__(self, x, fs: float, trim: float | None = None) -> tuple[np.ndarray, np.ndarray]:
        """``(freq_hz, psd)`` of `x` sampled at `fs` Hz; `trim` pads (default: x[0])."""
        x = np.asarray(x, dtype=float)
        nseg = self.segments(x.size)
        step = self.nperseg - self.noverlap
        total = self.nperseg + (nseg - 1) * step
        pad = x[0] if trim is None else float(trim)
        if total > x.size:
            x = np.concatenate([x, np.full(total - x.size, pad)])
        frames = np.lib.stride_tricks.as_strided(x, (nseg, self.nperseg),
                                                 (step * x.strides[0], x.strides[0]))
        spec = scipy.fft.rfft(frames * self.window, axis=-1)
        power = (spec.real ** 2 + spec.imag ** 2).mean(axis=0) / (self.nperseg * fs)
        return self.frequencies(fs), power / self.correction


def psd(x, fs: float, *, method: str = "paper", trim: float | None = None,
        nperseg: int = WELCH_SEGMENT, noverlap: int = WELCH_OVERLAP) -> tuple[np.ndarray, np.ndarray]:
    """Power spectral density of a control signal.

    Parameters
    ----------
    x : array
        Signal.
    fs : float
        Sample rate, Hz.
    method : {"paper", "scipy"}
        The paper's estimate (:class:`PaperWelch`) or scipy's one-sided
        Welch density (Hamming, same segments, no detrending).
    trim : float, optional
        Padding value of the paper's method (default: the first sample).

    Returns
    -------
    freq_hz, psd : ndarray
    """
    if method == "paper":
        return PaperWelch(nperseg, noverlap)(x, fs, trim)
    if method == "scipy":
        x = np.asarray(x, dtype=float)
        if x.size < nperseg:
            PaperWelch(nperseg, noverlap).segments(x.size)  # raises the same message
        return scipy.signal.welch(x, fs, window="hamming", nperseg=nperseg, noverlap=noverlap,
                                  detrend=False, scaling="density")
    raise HesspipeError(f"spectra: unknown method {method!r}; expected 'paper' or 'scipy'")


def band_mask(freq_hz, band=FITNESS_BAND_HZ) -> np.ndarray:
    """Boolean mask of the bins with ``band[0] <= f <= band[1]``.

    Parameters
    ----------
    freq_hz : array
        Bin frequencies, Hz, ascending up to the Nyquist frequency.
    band : (float, float)
        Lowest and highest frequency, Hz (0 <= low < high <= Nyquist).
    """
    lo, hi = float(band[0]), float(band[1])
    if not (np.isfinite(lo) and np.isfinite(hi) and 0 <= lo < hi):
        raise HesspipeError(f"band: expected 0 <= low < high in Hz, got {band!r}")
    freq_hz = np.asarray(freq_hz)
    nyquist = float(freq_hz[-1])
    if hi > nyquist * (1 + 1e-9):
        # Bins stop at the Nyquist frequency: a wider band would be clipped silently.
        raise HesspipeError(f"band: high edge {hi:g} Hz is above the data's Nyquist frequency "
                            f"{nyquist:g} Hz (sample interval {0.5 / nyquist:g} s); expected a band "
                            f"within 0-{nyquist:g} Hz (an implausibly low Nyquist frequency means the "
                            "time column is not in seconds)")
    mask = (freq_hz >= lo) & (freq_hz <= hi + 1e-9)
    if not mask.any():
        raise HesspipeError(f"band: {lo:g}-{hi:g} Hz holds no frequency bin (bins every "
                            f"{freq_hz[1] - freq_hz[0]:g} Hz up to {freq_hz[-1]:g} Hz)")
    return mask


def fitness(measured_psd, simulated_psd, freq_hz, band=FITNESS_BAND_HZ) -> float:
    """RMS difference of two PSDs over the bins of `band` (paper Eq. 10); lower is better.

    Parameters
    ----------
    measured_psd, simulated_psd : array
        Control PSDs on the bins `freq_hz`, control units^2/Hz (e.g. rad^2/Hz
        for a control in rad), from :func:`psd` with the same method.
    freq_hz : array
        Frequency of each bin, Hz (ascending, from 0).
    band : (float, float)
        Lowest and highest frequency of the bins that count, Hz.

    Returns
    -------
    float
        ``sqrt(mean((measured - simulated)^2))`` over the band's bins, in the
        PSDs' units, control^2/Hz; >= 0, 0 for identical spectra.
    """
    mask = band_mask(freq_hz, band)
    return rms_difference(np.asarray(measured_psd)[mask], np.asarray(simulated_psd)[mask])


def rms_difference(measured_psd, simulated_psd) -> float:
    """Eq. 10 on bins already chosen: the RMS difference of two PSDs, control^2/Hz.

    The one implementation of the paper's fitness; :func:`fitness` selects a
    band's bins first.

    Parameters
    ----------
    measured_psd, simulated_psd : array
        PSD values on the same bins, control units^2/Hz (order does not matter:
        the difference is squared).

    Returns
    -------
    float
        ``sqrt(mean((measured - simulated)^2))``, control^2/Hz (NaN/inf if an
        input is not finite).
    """
    d = np.asarray(measured_psd) - np.asarray(simulated_psd)
    return float(np.sqrt(np.mean(d * d)))


SPECTRAL_RATE = 128.0
"""Highest sample rate, Hz, at which the control-spectrum criteria see a record
(:func:`spectral_view`). The paper's 1024-sample segments are a time span only at a given
rate: at 1000 Hz they left 5 bins in 0-5 Hz, where 100 Hz gives 51, and diagnose on one run
logged at 100, 500 and 1000 Hz read four bands, four and none as disagreeing, with Ke 2.73,
3.50 and 31.4 (a reviewer's SYNTHETIC yaw run)."""


def spectral_view(run):
    """`run` as the control-spectrum criteria see it: a record logged faster than
    :data:`SPECTRAL_RATE` is decimated by the smallest integer that brings it to that rate
    or below (a zero-phase FIR anti-alias filter, :func:`hesspipe.core._time.decimate_signal`), so that the
    paper's segments span the same 8-20 s at every logging rate. Slower records are returned
    as they are.

    Parameters
    ----------
    run : hesspipe.core.formats.Run
        The measured run.

    Returns
    -------
    hesspipe.core.formats.Run
        The run, or the decimated run with a note saying so (its ``time`` every q-th sample).
    """
    q = int(np.ceil(run.fs / SPECTRAL_RATE - 1e-9))
    if q <= 1:
        return run
    cut = {name: decimate_signal(getattr(run, name), q) for name in ("disturbance", "output", "control", "reference")}
    n = min(v.size for v in cut.values())
    return dataclasses.replace(
        run, time=np.asarray(run.time, dtype=float)[::q][:n], interval=run.dt * q,
        notes=run.notes + (f"control spectrum estimated at {run.fs / q:.4g} Hz (the {run.fs:.4g} Hz record "
                           f"decimated by {q}): the paper's {WELCH_SEGMENT}-sample segments then span "
                           f"{WELCH_SEGMENT * q / run.fs:.3g} s",),
        **{k: v[:n] for k, v in cut.items()})
