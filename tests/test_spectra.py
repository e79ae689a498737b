"""Spectra of the paper (Eqs. 5-10) and the fitness."""

import numpy as np
import pytest
import scipy.signal

from hesspipe.core.errors import HesspipeError
from hesspipe.identification.spectra import PaperWelch, band_mask, fitness, psd

FS = 50.0


def test_segments_follow_eq9():
    w = PaperWelch()
    assert w.segments(1024) == 1
    assert w.segments(1025) == 2          # padded to 1024 + 992
    assert w.segments(3500) == 4          # 70 s at 50 Hz: 1024 + 3 * 992 = 4000 >= 3500
    assert w.segments(4000) == 4 and w.segments(4001) == 5
    with pytest.raises(HesspipeError, match="shorter than one spectral segment"):
        w.segments(1023)
    with pytest.raises(HesspipeError, match="shorter than one spectral segment"):
        psd(np.zeros(500), FS)
    with pytest.raises(HesspipeError, match="shorter than one spectral segment"):
        psd(np.zeros(500), FS, method="scipy")


def test_white_noise_level_matches_window_energy_and_U():
    rng = np.random.default_rng(0)
    x = rng.standard_normal(200 * 1024)
    f, p = psd(x, FS)
    assert f[1] == pytest.approx(FS / 1024) and f[-1] == pytest.approx(FS / 2)
    # E[|FFT(w x)|^2] = sum(w^2) sigma^2, divided by N fs and by U.
    expected = np.mean(np.hamming(1024) ** 2) / FS / 0.612
    assert np.mean(p[1:-1]) == pytest.approx(expected, rel=0.02)


def test_sinusoid_peak_at_its_bin_and_padding_uses_trim():
    t = np.arange(3500) / FS
    f0 = 20 * FS / 1024
    f, p = psd(np.sin(2 * np.pi * f0 * t), FS)
    assert f[np.argmax(p)] == pytest.approx(f0)
    # A constant record padded with its own (trim) value is a constant: power at DC only.
    _, pc = psd(np.full(3500, 2.0), FS)
    _, pc_zero_pad = psd(np.full(3500, 2.0), FS, trim=0.0)
    assert pc[5:].max() < 1e-12 * pc[0]
    assert pc_zero_pad[5:].max() > 1e-6 * pc_zero_pad[0]


def test_scipy_method_is_scipy_welch():
    x = np.random.default_rng(1).standard_normal(3500)
    f, p = psd(x, FS, method="scipy")
    f2, p2 = scipy.signal.welch(x, FS, window="hamming", nperseg=1024, noverlap=32, detrend=False)
    assert np.array_equal(f, f2) and np.allclose(p, p2)
    with pytest.raises(HesspipeError, match="unknown method"):
        psd(x, FS, method="burg")


def test_fitness_is_rms_difference_over_band():
    f = np.linspace(0, 25, 513)
    a = np.sin(f) ** 2
    assert fitness(a, a, f) == 0.0
    b = a + 0.5
    assert fitness(a, b, f) == pytest.approx(0.5)
    mask = band_mask(f, (1.0, 2.0))
    c = a.copy()
    c[mask] += 2.0
    assert fitness(a, c, f, band=(1.0, 2.0)) == pytest.approx(2.0)
    d = a.copy()
    d[~band_mask(f)] += 10.0  # outside 0-5 Hz: no effect
    assert fitness(a, d, f) == 0.0
    with pytest.raises(HesspipeError, match="band"):
        fitness(a, b, f, band=(5.0, 1.0))
    with pytest.raises(HesspipeError, match="no frequency bin"):
        fitness(a, b, f, band=(1.001, 1.02))
    # Bins stop at the Nyquist frequency: a band reaching above it is refused, not clipped.
    with pytest.raises(HesspipeError, match="band: high edge 40 Hz is above the data's Nyquist frequency 25 Hz"):
        fitness(a, b, f, band=(30.0, 40.0))
    assert fitness(a, b, f, band=(0.0, 25.0)) == pytest.approx(0.5)
