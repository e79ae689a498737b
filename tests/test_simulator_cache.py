"""The Simulator's block-shape cache is an optimisation only: cached answers equal fresh ones."""

from __future__ import annotations

import numpy as np

from hesspipe.pilot.hess import model_from_name
from hesspipe.pilot.simulation import Simulator
from pilot_data import DT, N, broadband, plants


def _loops(rng, n):
    models = [model_from_name(m) for m in ("original", "expanded", "expanded+remnant",
                                            "original+extra_delay")]
    for _ in range(n):
        model = models[rng.integers(len(models))]
        p = model.complete({}, 1)
        for name in ("Ke", "K1", "Km", "Kn"):
            if name in p:
                p[name] *= float(rng.uniform(0.3, 2.0))
        # Shapes change too: time constants and delays, not only gains.
        for name in ("tau0", "wn", "1/T1"):
            p[name] *= float(rng.choice([1.0, 1.0, rng.uniform(0.7, 1.4)]))
        yield model.loop(p)


def test_cached_spectra_equal_fresh_ones_over_random_loops():
    rng = np.random.default_rng(11)
    pl, w = plants(), broadband(seed=3)[:N]
    loops = list(_loops(rng, 40))
    warm = Simulator(pl, w, DT, noise_seed=5)
    for _ in range(3):  # a shape is cached once asked for twice; the third pass reads the cache
        cached = [warm.spectra(loop) for loop in loops]
    for loop, (c, y) in zip(loops, cached):
        fresh = Simulator(pl, w, DT, noise_seed=5)
        c0, y0 = fresh.spectra(loop)
        assert np.allclose(c, c0, rtol=1e-12, atol=0.0) and np.allclose(y, y0, rtol=1e-12, atol=0.0)
    assert warm._cache, "the test must exercise the cache"
