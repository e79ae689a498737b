"""How far can the describing-function motion test see on angle tasks? (SYNTHETIC DATA)

Every run is drawn by the independent generator :mod:`hesspipe.humanlike` with a hidden
vestibular path (``motion_feedback``), target and disturbance on interleaved lines, 70 s
at 50 Hz, the case and seed as ``benchmarks/bench_diagnose.py`` draws them. For each run:

* **measured**: :func:`hesspipe.identification.motion_test.motion_test` on the run as
  logged (the test diagnose and compare-pilots use): its F and p-value.
* **oracle**: the same trial simulated again without remnant (the generator's own
  remnant gain set to 0: the pilot's exact describing function at every line), the
  original and the expanded model fitted to those noise-free lines with the weights the
  logged run gives (its remnant level at each line). ``nc`` = (RSS_original -
  RSS_expanded) of the noise-free lines over the logged run's residual variance per real
  value: the non-centrality of the test's F(1, dof). It is what the data could give any
  equation-error test of this model pair at best; ``power`` = P(F > the p < 0.01 critical
  value, halved for Km >= 0) for a non-central F with that nc.

The equation error U (1 + NM PF) = NM (vis E - ves cab Y) already uses both line sets:
at target lines E and Y differ (Y = Yc U there), at disturbance lines E = -Y; a small nc
says the original model with its free lag, delay and neuromuscular mode absorbs the
vestibular path at both sets at once, whatever the estimator.

Usage::

    python benchmarks/bench_motion_limit.py [--seeds 10] [--seed-start 0]
                                            [--cases roll:angle,paper:angle,K/s2:angle,roll:rate]
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
import tempfile
from pathlib import Path

import numpy as np
from scipy import stats

from hesspipe.core.errors import HesspipeError
from hesspipe.core.formats import read_plants, read_run
from hesspipe.core.seeds import derive_seed
from hesspipe.humanlike import draw_trial, simulate_trial, write_trial
from hesspipe.identification._line_fit import _fit, _predict
from hesspipe.identification.criteria import choose_k
from hesspipe.identification.frf import NEIGHBOURS
from hesspipe.identification.motion_test import (
    ALPHA,  # diagnose's motion_alpha
    analysis_window,
    forcing_lines,
    line_variances,
    motion_test,
)
from hesspipe.pilot.hess import PilotModel
from hesspipe.pilot.motion import motion_block


def _lines_spectra(run, start, length):
    cut = slice(start, start + length)
    u, y = np.asarray(run.control[cut], float), np.asarray(run.output[cut], float)
    e = np.asarray(run.reference[cut], float) - y
    return np.fft.rfft(u), np.fft.rfft(e), np.fft.rfft(y)


def oracle(run, clean, plants, k):
    """(nc, dof, measured F, measured p, F with the true weights, noise-free misfit of the
    expanded model) of one run and its noise-free twin."""
    t = motion_test(run, plants, PilotModel().complete({}, k), k=k)
    if not t.get("available"):
        return None
    start, length = analysis_window(run)
    window = dataclasses.replace(run, time=run.time[start:start + length],
                                 disturbance=run.disturbance[start:start + length],
                                 output=run.output[start:start + length],
                                 control=run.control[start:start + length],
                                 reference=run.reference[start:start + length])
    lines = forcing_lines(window)
    omega = 2 * np.pi * np.fft.rfftfreq(length, run.dt)
    s = 1j * omega
    U, E, Y = _lines_spectra(run, start, length)
    U0, E0, Y0 = _lines_spectra(clean, start, length)
    cab = motion_block(plants)
    original, expanded = PilotModel(), PilotModel(("motion_feedback",))
    p_o, p_e = t["parameters_original"], t["parameters_expanded"]
    free = ["Ke", "K1", "1/T1", "tau0", "wn", "zn"] + (["1/T2"] if k == 2 else [])
    big = 1e3 * max(abs(p_o["Ke"]), 1.0)
    sign = 1.0 if p_o["Ke"] >= 0 else -1.0
    lo = np.array([0.0 if sign > 0 else -big, 1e-3, 1e-4, 0.0, 1.0, 0.02] + ([1e-3] if k == 2 else []))
    hi = np.array([big if sign > 0 else 0.0, 100.0, 10.0, 0.6, 60.0, 2.0] + ([20.0] if k == 2 else []))
    lo_e, hi_e = np.append(lo, 0.0), np.append(hi, big)
    km = [p_e["Km"], 0.5 * abs(p_o["Ke"]), 0.1 * abs(p_o["Ke"]), 1e-6]

    def fits(UU, EE, YY, w, seeds_o, seeds_e):
        args = (cab, s[lines], EE[lines], YY[lines], UU[lines], None, None, w)   # one run: no groups, no feedforward
        starts = [[q[n] for n in free] for q in seeds_o]
        starts += [[*x[:3], tau, *x[4:]] for x in starts[:1] for tau in (0.15, 0.25, 0.35)]
        rss_o, q_o, _ = _fit(original, p_o, free, lo, hi, starts, *args)
        starts_e = [[q[n] for n in free] + [x] for q in (*seeds_e, q_o) for x in km]
        starts_e += [[q[n] for n in free] + [q["Km"]] for q in seeds_e]
        rss_e, q_e, _ = _fit(expanded, {**p_o, "Km": 0.0}, free + ["Km"], lo_e, hi_e, starts_e, *args)
        # Exchange of optima, as motion_test does: the original from the expanded's core.
        rss_o = min(rss_o, _fit(original, p_o, free, lo, hi, [[q_e[n] for n in free]], *args)[0])
        return rss_o, min(rss_e, rss_o), q_e

    # The pilot's exact describing function: the expanded model fits the noise-free lines
    # to rounding (the generator's pilot is in its class), which gives the true pilot.
    _, rss_true, q_true = fits(U0, E0, Y0, np.ones(lines.size), (p_o, p_e), (p_e,))
    # The true remnant level at each line: the true pilot's equation error at the logged
    # run's unforced neighbours (motion_test measures it model-free, with the describing
    # function at the nearest disturbance line; the ratio of the two is printed).
    forced = np.zeros(omega.size, bool)
    forced[lines] = True
    forced[0] = True
    near = np.unique(np.concatenate([lines + j for j in range(-NEIGHBOURS, NEIGHBOURS + 1) if j]))
    near = near[(near > 0) & (near < omega.size)]
    near = near[~forced[near]]
    res = U[near] - _predict(q_true, expanded, cab, s[near], E[near], Y[near])
    var = np.array([np.mean(np.abs(res[np.abs(near - b) <= NEIGHBOURS]) ** 2) for b in lines])
    w = 1.0 / np.sqrt(var)
    # The test's own (measured) remnant level over the true one, at the three lowest lines.
    ratio = line_variances(window, lines)[:3] / var[:3]
    rss_o0, rss_e0, _ = fits(U0, E0, Y0, w, (p_o, p_e), (q_true, p_e))
    # Weighted complex residuals of unit variance: 1/2 per real value.
    nc = (rss_o0 - rss_e0) / 0.5
    rss_o1, rss_e1, _ = fits(U, E, Y, w, (p_o, p_e), (q_true, p_e))
    dof = t["degrees_of_freedom"]
    f_true_w = (rss_o1 - rss_e1) / (rss_e1 / dof) if rss_e1 > 0 else 0.0
    return nc, dof, t["lr"], t["p_value"], f_true_w, rss_true, ratio


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=10)
    ap.add_argument("--seed-start", type=int, default=0)
    ap.add_argument("--cases", default="roll:angle,paper:angle,K/s2:angle,roll:rate")
    ap.add_argument("--task", default="both", choices=("both", "disturbance"),
                    help="forcing of bench_diagnose's case (disturbance: one describing function)")
    ap.add_argument("--repeats", type=int, default=1,
                    help="also print the ideal test's expectation on N runs pooled (nc x N)")
    args = ap.parse_args(argv)
    print("SYNTHETIC DATA: every run below is drawn by the independent generator hesspipe.humanlike.")
    with tempfile.TemporaryDirectory() as tmp:
        for case in args.cases.split(","):
            plant, output = case.split(":")
            rows = []
            for seed in range(args.seed_start, args.seed_start + args.seeds):
                sd = derive_seed(seed, "bench-diagnose", plant, output, args.task, "motion_feedback")
                kw = dict(disturbance="wind") if plant == "paper" else {}
                try:
                    spec = draw_trial(plant, sd, task=args.task, pilot="hess", effects=("motion_feedback",),
                                      fs=50.0, T_m=70.0, output=output, **kw)
                except HesspipeError:
                    continue   # no pilot in the generator's ranges
                twin = dataclasses.replace(spec, remnant={**spec.remnant, "share": 0.0})
                name = f"{plant}-{output}-{seed}".replace("/", "_")
                path = write_trial(Path(tmp) / name, simulate_trial(spec))
                path0 = write_trial(Path(tmp) / (name + "-clean"), simulate_trial(twin))
                plants = read_plants(path.parent / "plants.json")
                r = oracle(read_run(path), read_run(path0), plants, choose_k(plants)[0])
                if r is None:
                    continue
                nc, dof, f, p, f2, rss_true, ratio = r
                crit = stats.f.isf(2 * ALPHA, 1, dof)
                power = float(stats.ncf.sf(crit, 1, dof, max(nc, 1e-9)))
                # N runs pooled at best: N times the non-centrality on about N times the
                # residuals (each run as informative as this one; the retests' scatter ignored).
                n = args.repeats
                crit_n = stats.f.isf(2 * ALPHA, 1, n * dof)
                power_n = float(stats.ncf.sf(crit_n, 1, n * dof, max(n * nc, 1e-9)))
                rows.append((nc, power, p < ALPHA, power_n))
                print(f"  {plant}/{output} seed {seed}: oracle nc {nc:7.1f} (power {power:4.2f}); "
                      f"measured F {f:6.1f}, p {p:.2g} (with the true remnant weights: F {f2:.1f}; noise-free "
                      f"expanded misfit {rss_true:.1g}); test/true remnant variance at the 3 lowest lines "
                      f"{', '.join(f'{x:.2f}' for x in ratio)}", flush=True)
            if rows:
                nc, power, named, power_n = map(np.array, zip(*rows))
                pooled = (f"; {args.repeats} runs pooled: expected named {power_n.sum():.1f} at best"
                          if args.repeats > 1 else "")
                print(f"{plant}/{output}/{args.task} motion_feedback: {len(rows)} runs; oracle nc median "
                      f"{np.median(nc):.1f} (range {nc.min():.1f}-{nc.max():.1f}); expected named "
                      f"{power.sum():.1f} of {len(rows)} at best; measured named {int(named.sum())} of {len(rows)}{pooled}",
                      flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
