"""How far a wandering pilot gain spreads the forcing's lines (SYNTHETIC DATA).

A human's visual gain wanders within a run. The generator (:mod:`hesspipe.humanlike`,
``gain_drift``) multiplies the delayed error by ``1 + delta(t)``; over the analysis window
the Fourier coefficients of ``delta(t) e(t)`` are exactly the circular convolution of
``delta``'s coefficients Delta_k with E's. This script draws one trial per seed as
``bench_diagnose.py`` does (70 s at 50 Hz, no remnant to speak of), takes the logged error
and the generator's own gain factor at the logged samples (``Trial.gain_factor``), and prints:

* ``|Delta_k| / N`` for k = 1..6 (how fast the wander's coefficients fall off), and
* the share of ``DFT(delta e)`` at the forcing lines that offsets ``|k| <= K`` explain, for
  K = 1, 2, 4, 8, 20.

A nuisance model of the wander at the lines (two real unknowns per offset) can only afford a
few offsets on 20 lines; where the share at K = 2 is low, no such model removes the error
(README, Known limits, the real-trials row).

Usage::

    python benchmarks/bench_drift_sidebands.py [--cases paper:angle:both:5,roll:angle:both:108]
                                               [--gain-drift 0.15]
"""

from __future__ import annotations

import argparse
import sys

import numpy as np

from hesspipe.core.seeds import derive_seed
from hesspipe.humanlike import draw_trial, simulate_trial

OFFSETS = (1, 2, 4, 8, 20)


def spread(plant: str, output: str, task: str, seed: int, cv: float) -> tuple[np.ndarray, dict]:
    """(|Delta_k|/N for k = 1..6, {K: share of DFT(delta e) at the lines within |k| <= K})."""
    s = derive_seed(seed, "bench-diagnose", plant, output, task, "none")
    kw = dict(disturbance="wind") if plant == "paper" else {}
    spec = draw_trial(plant, s, task=task, pilot="hess", fs=50.0, T_m=70.0, output=output,
                      gain_drift=cv, remnant_share=0.001, **kw)
    tr = simulate_trial(spec)
    n_log = tr.time.size
    e = tr.reference - tr.output
    delta = tr.gain_factor - tr.gain_factor.mean()
    lines = np.concatenate([m.k for m in (spec.disturbance, spec.target) if m is not None])
    D, Ef = np.fft.fft(delta), np.fft.fft(e)
    exact = np.fft.fft(delta * e)[lines]
    share = {}
    for K in OFFSETS:
        approx = sum(D[k % n_log] * Ef[(lines - k) % n_log] for k in range(-K, K + 1) if k) / n_log
        share[K] = 1.0 - float(np.sum(np.abs(exact - approx) ** 2) / np.sum(np.abs(exact) ** 2))
    return np.abs(D[1:7]) / n_log, share


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cases", default="paper:angle:both:5,paper:angle:both:9,roll:angle:both:108",
                    help="plant:output:task:seed, comma-separated")
    ap.add_argument("--gain-drift", type=float, default=0.15)
    args = ap.parse_args(argv)
    print("SYNTHETIC DATA: trials of the independent generator hesspipe.humanlike (Hess pilots, "
          f"gain drift CV {args.gain_drift:g}, correlation time 10 s, 70 s at 50 Hz).")
    for case in args.cases.split(","):
        plant, output, task, seed = case.split(":")
        d, share = spread(plant, output, task, int(seed), args.gain_drift)
        print(f"  {case:<24} |Delta_k|/N k=1-6: {' '.join(f'{x:.4f}' for x in d)}; share within "
              + ", ".join(f"+-{K}: {100 * v:.0f} %" for K, v in share.items()))
    return 0


if __name__ == "__main__":
    sys.exit(main())
