"""The control-spectrum criteria see a record the same way at every logging rate (SYNTHETIC).

One run of the independent generator (:mod:`hesspipe.humanlike`) logged at 500 Hz, and the
same run kept at every fifth sample (100 Hz). The paper's 1024-sample segments left 10 bins
in 0-5 Hz at 500 Hz (51 at 100 Hz), and diagnose's band verdicts and spectral fits moved
with the rate; the record is now decimated to at most 128 Hz for them.
"""

from __future__ import annotations

import control as ct
import numpy as np
import pytest

from hesspipe.core.formats import Plants, Run
from hesspipe.humanlike import draw_trial, plants_dict, simulate_trial
from hesspipe.identification.problem import SpectralObjective
from hesspipe.identification.spectra import SPECTRAL_RATE, spectral_view
from hesspipe.pilot.hess import PilotModel


@pytest.fixture(scope="module")
def logged():
    spec = draw_trial("1/s", 2, task="disturbance", pilot="hess", fs=500.0, T_m=40.96, name="fast")
    tr = simulate_trial(spec, fine_ratio=2)
    pd = plants_dict(spec)
    plants = Plants(*(ct.tf(pd[k]["num"], pd[k]["den"]) for k in ("control_to_output", "disturbance_to_output")))
    fast = Run(time=tr.time, disturbance=tr.disturbance, output=tr.output, control=tr.control,
               reference=tr.reference, id="fast", synthetic=True)
    slow = Run(time=tr.time[::5], disturbance=tr.disturbance[::5], output=tr.output[::5],
               control=tr.control[::5], reference=tr.reference[::5], id="slow", synthetic=True)
    return fast, slow, plants


def test_a_fast_record_is_decimated_for_the_spectrum(logged):
    fast, slow, _ = logged
    view = spectral_view(fast)
    assert view.fs == pytest.approx(125.0) and view.fs <= SPECTRAL_RATE
    assert len(view.time) == len(fast.time) // 4 and "decimated by 4" in view.notes[-1]
    assert spectral_view(slow) is slow                      # 100 Hz: as logged
    # The anti-alias filter keeps the band: the decimated control is the record's own there.
    keep = np.interp(view.time, fast.time, fast.control)
    assert np.std(view.control - keep) < 0.05 * np.std(keep)


def test_the_spectral_bins_in_the_band_do_not_depend_on_the_rate(logged):
    fast, slow, plants = logged
    model = PilotModel()
    bins = {}
    for run in (fast, slow):
        obj = SpectralObjective(run, plants, model, model.complete())
        bins[run.id] = obj.freq_hz[obj.mask & (obj.freq_hz > 0)]
        assert obj.run.fs <= SPECTRAL_RATE
    assert bins["fast"].size >= 40 and bins["slow"].size >= 40    # 10 and 51 before
