"""A record too long to analyse at its logged rate is decimated, not refused (SYNTHETIC).

A laboratory logging at 1 kHz writes 300,000 samples in five minutes, more than
:data:`hesspipe.core.formats.MAX_SAMPLES`; such files were refused ("split the record").
The reader now decimates them through a zero-phase filter. The tests lower the limit on a
short run of the independent generator (:mod:`hesspipe.humanlike`) so that they stay fast;
the full-size case (a 300 s run at 1 kHz, decimated by 2) named the same effects with the
same F as the run kept at every tenth sample (development check, not timed here).
"""

from __future__ import annotations

import numpy as np
import pytest

import hesspipe.core.formats as formats
from hesspipe.core._time import MIN_DECIMATED_HZ, decimated
from hesspipe.core.errors import HesspipeError
from hesspipe.humanlike import draw_trial, simulate_trial, write_trial
from hesspipe.identification.frf import estimate_frf


@pytest.fixture(scope="module")
def logged(tmp_path_factory):
    """A two-input trial with a vestibular path, logged at 200 Hz as the generator writes it."""
    spec = draw_trial("1/s", 3, task="both", pilot="precision", output="angle", tau_m=0.15,
                      effects=("motion_feedback",), fs=200.0, T_m=40.96, name="fast")
    return write_trial(tmp_path_factory.mktemp("long") / "trial", simulate_trial(spec, fine_ratio=2))


def test_a_decimated_signal_keeps_its_timing():
    fs, q = 1000.0, 4
    t = np.arange(20000) / fs
    data = {"time": t, "control": np.sin(2 * np.pi * 2.0 * t + 0.3)}
    out, dt, notes = decimated("x.csv", data, 1.0 / fs, 5000)
    assert dt == pytest.approx(q / fs) and out["time"].size == 5000
    np.testing.assert_array_equal(out["time"], t[::q])          # each kept sample at its own time
    inner = slice(50, -50)   # the filter's ends aside
    # No phase lag: a lagging filter would read as the pilot's delay.
    assert np.max(np.abs(out["control"][inner] - np.sin(2 * np.pi * 2.0 * out["time"][inner] + 0.3))) < 1e-3
    assert "decimated by 4 to 250 Hz" in notes[0]
    same, dt2, none = decimated("x.csv", data, 1.0 / fs, 20000)
    assert same is data and dt2 == 1.0 / fs and none == ()


def test_a_run_over_the_limit_is_read_decimated_with_its_describing_function(logged, monkeypatch):
    full = formats.read_run(logged)
    assert full.time.size == 8192 and full.dt == pytest.approx(0.005)
    monkeypatch.setattr(formats, "MAX_SAMPLES", 5000)
    short = formats.read_run(logged)
    assert short.dt == pytest.approx(0.01) and short.time.size == 4096
    assert any("8192 samples at 200 Hz decimated by 2 to 100 Hz" in n for n in short.notes)
    a, b = estimate_frf(full), estimate_frf(short)
    for ra, rb in ((a.feedback, b.feedback), (a.reference, b.reference)):
        np.testing.assert_allclose(rb.freq_rad_s, ra.freq_rad_s)
        # Each line moves by far less than its own error (the filter's ends spread a
        # little broadband power; a remnant-dominated line at 20 rad/s moved 1.3 deg, 1 % of
        # its standard error), and a line known better than its size by < 1 % and 0.5 deg.
        assert np.all(np.abs(rb.H - ra.H) < 0.05 * ra.sigma)
        sure = ra.sigma < np.abs(ra.H)
        ratio = rb.H[sure] / ra.H[sure]
        assert sure.sum() >= 5
        assert np.max(np.abs(np.abs(ratio) - 1.0)) < 0.01
        assert np.max(np.abs(np.degrees(np.angle(ratio)))) < 0.5


def test_a_run_that_would_fall_below_the_lowest_rate_is_refused_in_one_line(logged, monkeypatch):
    monkeypatch.setattr(formats, "MAX_SAMPLES", 2000)   # 8192 at 200 Hz: by 5, 40 Hz < 50 Hz
    with pytest.raises(HesspipeError) as err:
        formats.read_run(logged)
    msg = str(err.value)
    assert "\n" not in msg and str(logged) in msg and "8192 samples at 200 Hz" in msg
    assert "(40.96 s); expected at most 40 s at this rate" in msg   # by 4 at most: 50 Hz
    assert f"no less than {MIN_DECIMATED_HZ:g} Hz" in msg and "split the record" in msg
