"""Fitness-evaluation speed and one APID identification's wall time (issue 4 performance).

Compares, in the same run, hesspipe's fitness evaluation (FFT-grid closed loop,
exact delay, paper Welch) with a straightforward implementation: python-control
``forced_response`` of the closed loop with a Padé delay, then
``scipy.signal.welch``. Record: 70 s at 50 Hz, plants of SPEC.md (Eq. 14, Eq. 16),
synthetic (model-generated) control data.

Run: ``python benchmarks/bench_fitness.py``
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import control as ct
import numpy as np
import scipy.signal

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from hesspipe.identification.apid import Field, bit_climb  # noqa: E402
from hesspipe.identification.fit import identify  # noqa: E402
from hesspipe.identification.problem import SpectralObjective  # noqa: E402
from hesspipe.pilot.hess import PilotModel, table1
from hesspipe.pilot.simulation import synthetic_run  # noqa: E402
from pilot_data import DT, YC, YD, N, broadband, plants  # noqa: E402


def straightforward(values, base, t, w, measured, pade_order=5):
    """The obvious implementation: build the closed loop, forced_response, scipy Welch."""
    p = dict(base, **values)
    wn, zn = p["wn"], p["zn"]
    nm = ct.tf([wn * wn], [1, 2 * zn * wn, wn * wn])
    pf = ct.tf([p["K1"] * p["K2"], 0], [1, p["1/T1"]])
    delay = ct.tf(*ct.pade(p["tau0"], pade_order))
    pilot = ct.feedback(nm, pf) * p["Ke"] * delay
    t_dw = -ct.feedback(pilot, YC) * YD
    delta = ct.forced_response(t_dw, t, w).outputs
    f, psd = scipy.signal.welch(delta, 1 / DT, window="hamming", nperseg=1024, noverlap=32)
    band = f <= 5.0
    return float(np.sqrt(np.mean((psd[band] - measured[band]) ** 2)))


def rate(fn, seconds):
    """Calls per second of CPU time of this process (robust to other processes' load)."""
    fn()
    n, t0 = 0, time.process_time()
    while time.process_time() - t0 < seconds:
        fn()
        n += 1
    return n / (time.process_time() - t0)


def interleaved(fast_fn, slow_fn, rounds=5):
    """Rates measured in alternating short rounds, so load changes hit both alike."""
    fast, slow = [], []
    for _ in range(rounds):
        fast.append(rate(fast_fn, 0.5))
        slow.append(rate(slow_fn, 1.0))
    return float(np.median(fast)), float(np.median(slow)), float(np.median(np.divide(fast, slow)))


def _pilot_batch_item(i):
    """Three configurations of one synthetic pilot (as a compare run does)."""
    c0 = time.process_time()
    pl = plants()
    true = dict(table1(1), Ke=9.0 + i % 4, K1=3.0 + 0.25 * (i % 3), K2=1.5, Km=1.0 + 0.1 * (i % 8),
                Kn=0.1, Tn=0.3)
    run = synthetic_run("expanded+remnant", true, pl, broadband(seed=200 + i), DT, seed=300 + i,
                        run_id=f"syn{i:02d}")
    orig = identify(run, pl, "original", seed=i)
    gains = {n: orig.parameters[n] for n in ("Ke", "K1", "K2")}
    identify(run, pl, "expanded", fixed=dict(gains, Km=0.1))  # the paper's "Exp." row, timed too
    star = identify(run, pl, "expanded", seed=i)
    return time.process_time() - c0, (orig.evaluations, star.evaluations)


def batch(n_pilots=16, workers=2):
    from concurrent.futures import ProcessPoolExecutor

    t0 = time.perf_counter()
    with ProcessPoolExecutor(workers) as pool:
        out = list(pool.map(_pilot_batch_item, range(n_pilots)))
    return time.perf_counter() - t0, out


def main():
    pl, w = plants(), broadband(seed=2)
    t = np.arange(N) * DT
    true = dict(table1(1), Ke=12.0, K1=3.0, K2=1.5)
    run = synthetic_run("original", true, pl, w, DT, seed=0, run_id="bench")
    model = PilotModel()
    base = model.complete(table1(1))
    obj = SpectralObjective(run, pl, model, base)
    rng = np.random.default_rng(0)
    samples = [{"Ke": rng.uniform(5, 20), "K1": rng.uniform(1, 8), "K2": rng.uniform(0.5, 3)}
               for _ in range(64)]
    it = iter(range(10 ** 9))
    _, measured_scipy = scipy.signal.welch(run.control, 1 / DT, window="hamming", nperseg=1024,
                                           noverlap=32)
    fast, slow, ratio = interleaved(lambda: obj(samples[next(it) % 64]),
                                    lambda: straightforward(samples[next(it) % 64], base, t, w,
                                                            measured_scipy))
    print("SYNTHETIC DATA (model-generated record, 70 s at 50 Hz)")
    print(f"fitness evaluations per CPU-second (median of 5 interleaved rounds)  hesspipe: {fast:8.1f}"
          f"   straightforward (control.forced_response + Pade(5) + scipy welch): {slow:6.2f}"
          f"   speed-up: {ratio:6.0f}x")

    fields = [Field("Ke", 10, 50.0), Field("K1", 10), Field("K2", 10)]  # 3 params x 10 bits
    for coding in ("binary", "gray"):
        times, evals = [], []
        for seed in range(5):
            obj2 = SpectralObjective(run, pl, model, base)
            t0 = time.perf_counter()
            r = bit_climb(obj2, fields, passes=10, seed=seed, coding=coding)
            times.append(time.perf_counter() - t0)
            evals.append(r.evaluations)
        print(f"one APID climb (original, 3 params x 10 bits, 10 passes, {coding}): wall "
              f"median {np.median(times):.3f} s, max {max(times):.3f} s, evaluations "
              f"{min(evals)}-{max(evals)}")
    t0 = time.perf_counter()
    res = identify(run, pl, "original", seed=0, with_benchmark=False, with_identifiability=False)
    t1 = time.perf_counter()
    print(f"identify() default (APID gray, 4 restarts, 10 passes): {t1 - t0:.3f} s, "
          f"{res.evaluations} evaluations, fitness {res.fitness:.3g}")
    t0 = time.perf_counter()
    res = identify(run, pl, "original", seed=0)
    print(f"identify() with McRuer benchmark + identifiability: {time.perf_counter() - t0:.3f} s")
    wall, out = batch()
    cpu = sum(o[0] for o in out)
    print(f"batch: 16 synthetic pilots x 3 configurations (original, expanded Km fixed, expanded "
          f"Km identified; APID defaults, benchmark + identifiability) on 2 processes: {wall:.1f} s wall, "
          f"{cpu:.1f} s CPU in the workers (wall >= CPU/2 when other processes share the cores)")
    import os
    print(f"load average during the run: {os.getloadavg()}")


if __name__ == "__main__":
    main()
