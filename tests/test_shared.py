"""Ideas written once (issue 11) agree with what they replaced and with each other.

The loop's denominator ``1 + NM PF + NM (visual + vestibular) Yc plant`` (frequency
response, products for the Simulator's cache, characteristic polynomial), Eq. 10 (the
paper's fitness), SISO coefficient extraction, and the paper's printed constants.
"""

from __future__ import annotations

import control as ct
import numpy as np
import pytest

from hesspipe.core.formats import siso_coefficients, tf_coefficients
from hesspipe.core.paper import EQ14, EQ16, WELCH_OVERLAP, WELCH_SEGMENT
from hesspipe.identification.problem import SpectralObjective
from hesspipe.identification.spectra import PaperWelch, fitness, psd, rms_difference
from hesspipe.pilot.blocks import ONE, from_tf
from hesspipe.pilot.hess import model_from_name
from hesspipe.pilot.simulation import Simulator, synthetic_run
from pilot_data import DT, N, broadband, plants

S = 1j * np.logspace(-1, 1.5, 60)


def _loops():
    for name in ("original", "expanded", "expanded+dutch_roll", "original+remnant"):
        model = model_from_name(name)
        yield model.loop(model.complete({}, 1))


@pytest.mark.parametrize("loop", list(_loops()), ids=["original", "expanded", "dutch_roll", "remnant"])
def test_return_difference_forms_agree(loop):
    yc_block = from_tf(plants().Yc)
    yc = yc_block.response(S)
    full = loop.return_difference(S, yc)
    inner = loop.return_difference(S, yc, visual=False)
    # Closing the visual loop around the open loop L gives the full denominator.
    assert np.allclose((1.0 + loop.pilot_open_loop(S, yc)) * inner, full, rtol=1e-12)
    # Opened at the plant: the pilot's own 1 + NM PF.
    nm, pf = loop.neuromuscular.response(S), loop.proprioceptive.response(S)
    assert np.allclose(loop.return_difference(S, None), 1.0 + nm * pf, rtol=1e-12)
    assert not np.allclose(loop.return_difference(S, None), full, rtol=1e-3)
    # The Simulator's products sum to the same denominator.
    ycp = yc_block if loop.plant.terms == ONE.terms else yc_block * loop.plant
    total = 1.0 + sum(np.prod([b.response(S) for b in prod], axis=0)
                      for prod in loop.return_difference_products(ycp))
    assert np.allclose(total, full, rtol=1e-12)
    # The characteristic polynomial's slowest-decaying root is a zero of the exact
    # (delays not approximated) denominator.
    roots = np.roots(loop.characteristic(yc_block, pade_order=12))
    r = roots[np.argmax(roots.real)]
    d = loop.return_difference(np.array([r]), yc_block.response(np.array([r])))[0]
    assert abs(d) < 1e-6, (r, d)


def test_eq10_one_implementation():
    run = synthetic_run("original", None, plants(), broadband(seed=2), DT, seed=1)
    f, measured = psd(run.control, run.fs)
    sim = measured * np.linspace(0.5, 1.5, measured.size)
    mask = (f >= 0.0) & (f <= 5.0 + 1e-9)
    expected = float(np.sqrt(np.mean((measured[mask] - sim[mask]) ** 2)))
    assert fitness(measured, sim, f) == pytest.approx(expected, rel=1e-12)
    assert rms_difference(measured[mask], sim[mask]) == pytest.approx(expected, rel=1e-12)
    model = model_from_name("original")
    obj = SpectralObjective(run, plants(), model, model.complete())
    assert obj.psd_fitness(sim) == pytest.approx(fitness(obj.measured, sim, obj.freq_hz), rel=1e-12)
    assert fitness(measured, measured, f) == 0.0


def test_siso_coefficients():
    sys = ct.tf(*EQ16)
    num, den = siso_coefficients(sys)
    assert num.tolist() == list(EQ16[0]) and den.tolist() == list(EQ16[1])
    assert tf_coefficients(ct.tf([3.0], [1.0])) == {"num": [3.0], "den": [1.0]}
    assert siso_coefficients(ct.tf([2.0], [1.0, 0.5], 0.1))[1].tolist() == [1.0, 0.5]


def test_paper_constants():
    # SPEC.md: Eq. 14 is 2.436 / (s + 1.0496); Eq. 16 has 4 poles and 3 zeros;
    # Welch segments of 1024 overlapping by 32.
    assert float(ct.dcgain(ct.tf(*EQ14))) == pytest.approx(2.436 / 1.0496)
    assert len(EQ16[0]) == 4 and len(EQ16[1]) == 5
    assert (PaperWelch().nperseg, PaperWelch().noverlap) == (WELCH_SEGMENT, WELCH_OVERLAP) == (1024, 32)
    assert Simulator(plants(), broadband(seed=1)[:N], DT).n == N
