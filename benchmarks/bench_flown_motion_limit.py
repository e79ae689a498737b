"""How far can the describing-function motion test see on JSBSim-flown runs? (SYNTHETIC DATA)

The pilots and hidden vestibular paths are those of ``benchmarks/bench_fly_pilot.py``'s
diagnose section (case ``motion_feedback``, Km 2-8 x gain scale, two-input forcing, the
crossover-model draw unless ``--cohort``), flown by JSBSim's 737 around plants fitted by
stages one and two. For each pilot:

* **measured**: :func:`hesspipe.identification.motion_test.motion_test` on the run as
  logged, started where diagnose starts it (the original model's defaults): its p-value
  (Bonferroni over its two alternatives; named when p < 0.01, diagnose's ``motion_alpha``).
* **oracle**: the same pilot re-flown with the remnant off (same seed: same wind and target
  lines, same JSBSim), so that its lines hold the pilot's exact describing function. The
  original model and the expanded model (Km alone, the alternative that matches a flown
  pilot: its vestibular path has no delay) are fitted to those noise-free lines, weighted by
  the logged run's true remnant level at each line (the true pilot's equation error at the
  logged run's unforced neighbours). ``nc`` = (RSS_original - RSS_expanded) of the noise-free
  lines in units of the remnant's variance per real value: the non-centrality of the test's
  F(1, dof). ``power`` = P(non-central F > the critical value) at the level the test's Km
  alternative is named at (p < 0.01 after Bonferroni x 2, halved for Km >= 0 on its bound).
  ``nc_w`` is the same with the weights the test itself measures (``line_variances``), the
  remnant's variance taken as the one those weights leave on average: what the test's weights
  cost against the ideal ones.

A high power where the test misses is a method loss; a low one says the record cannot
show the vestibular path to this model pair, whatever the estimator. The noise-free misfit
of the true pilot (remnant units; the remnant alone gives about 2 x lines) says whether the
record is the model's: where it exceeds the remnant, model error fills the test's
denominator and its F falls below what the oracle's nc promises.

Usage::

    python benchmarks/bench_flown_motion_limit.py [--seeds 16] [--seed-start 0]
                                                  [--cohort crossover_model|table1] [--case motion_feedback]
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from scipy import stats

sys.path.insert(0, str(Path(__file__).resolve().parent))
import bench_fly_pilot as bfp  # noqa: E402  (the same pilots, plants and forcing)
from hesspipe.core.errors import HesspipeError  # noqa: E402
from hesspipe.core.seeds import derive_seed  # noqa: E402
from hesspipe.flight.closed_loop import fly_pilot_record  # noqa: E402
from hesspipe.identification._line_fit import _fit, _predict, pilot_start  # noqa: E402
from hesspipe.identification.criteria import choose_k  # noqa: E402
from hesspipe.identification.frf import NEIGHBOURS  # noqa: E402
from hesspipe.identification.motion_test import (  # noqa: E402
    TAU_M_MAX,
    _line_sets,
    line_data,
    motion_test,
    windowed,
)
from hesspipe.pilot.crossover import gain_scale  # noqa: E402
from hesspipe.pilot.hess import PilotModel  # noqa: E402
from hesspipe.pilot.motion import motion_block  # noqa: E402

ALPHA = 0.01      # diagnose's motion_alpha
N_ALT = 2         # the test's Bonferroni factor with both line sets


def spectra(run):
    """(U, E, Y, s) of the run's analysis window (all bins)."""
    w = windowed(run)
    U = np.fft.rfft(np.asarray(w.control, float))
    Y = np.fft.rfft(np.asarray(w.output, float))
    E = np.fft.rfft(np.asarray(w.reference, float) - np.asarray(w.output, float))
    s = 1j * 2 * np.pi * np.fft.rfftfreq(len(w.control), w.dt)
    return U, E, Y, s, w


def true_remnant(U, E, Y, s, lines, forced, truth, model, cab):
    """Variance of the true pilot's equation error at each line: its mean |residual|^2 at the
    unforced bins within NEIGHBOURS of the line (the remnant alone drives the loop there)."""
    near = np.unique(np.concatenate([lines + j for j in range(-NEIGHBOURS, NEIGHBOURS + 1) if j]))
    near = near[(near > 0) & (near < U.size)]
    near = near[~forced[near]]
    res = U[near] - _predict(truth, model, cab, s[near], E[near], Y[near])
    return np.array([np.mean(np.abs(res[np.abs(near - b) <= NEIGHBOURS]) ** 2) for b in lines])


def pair_rss(data, w, k, starts_o, starts_e, tau=False):
    """(RSS_original, RSS_expanded) of the weighted fits to `data` = (cab, s, E, Y, U) at the
    lines (the test's free set and bounds; best of the starts, exchange of optima)."""
    original, expanded = PilotModel(), PilotModel(("motion_feedback",))
    free = ["Ke", "K1", "1/T1", "tau0", "wn", "zn"] + (["1/T2"] if k == 2 else [])
    base = starts_o[0]
    big = 1e3 * max(abs(base["Ke"]), 1.0)
    lo = np.array([0.0, 1e-3, 1e-4, 0.0, 1.0, 0.02] + ([1e-3] if k == 2 else []))
    hi = np.array([big, 100.0, 10.0, 0.6, 60.0, 2.0] + ([20.0] if k == 2 else []))
    if base["Ke"] < 0:
        lo[0], hi[0] = -big, 0.0
    xs = [[q[n] for n in free] for q in starts_o]
    xs += [[*xs[0][:3], t, *xs[0][4:]] for t in (0.15, 0.25, 0.35)]
    rss_o, _, _ = _fit(original, base, free, lo, hi, xs, *data, None, None, w)
    extra = ["Km", "tau_m"] if tau else ["Km"]
    lo_e = np.append(lo, [0.0] * len(extra))
    hi_e = np.append(hi, [big, TAU_M_MAX][:len(extra)])
    xe = [[q[n] for n in free] + [q.get("Km", 0.0) * f] + ([q.get("tau_m", 0.0)] if tau else [])
          for q in starts_e for f in (1.0, 0.3, 3.0)]
    rss_e, q_e, _ = _fit(expanded, {**base, "Km": 0.0, "tau_m": 0.0}, free + extra, lo_e, hi_e, xe, *data, None, None, w)
    rss_o = min(rss_o, _fit(original, base, free, lo, hi, [[q_e[n] for n in free]], *data, None, None, w)[0])
    return rss_o, min(rss_e, rss_o)


def one_pilot(plants, work: Path, seed: int, how: str, case: str):
    pid = f"diag-{case}-{seed}"
    effects, ranges = bfp.DIAG_CASES[case]
    pseed, truth, params = bfp.draw(plants, pid, 7, (), how)
    rng = np.random.default_rng(derive_seed(pseed, "hidden"))
    g = gain_scale(plants)
    hidden = {k: float(rng.uniform(lo, hi)) * (g if k == "Km" else 1.0) for k, (lo, hi) in ranges.items()}
    model = "expanded" if "motion_feedback" in effects else "original"
    kw = bfp.forcing_kwargs()
    f = fly_pilot_record("737", plants, model + "+remnant", {**params, **hidden}, seed=pseed,
                         workdir=work / "diag", record_every=bfp.EVERY, remnant_share=truth["remnant_share"],
                         run_id=pid, **kw)
    f0 = fly_pilot_record("737", plants, model, {**params, **hidden}, seed=pseed, workdir=work / "diag",
                          record_every=bfp.EVERY, run_id=pid + "-clean", **kw)
    k = choose_k(plants)[0]
    t = motion_test(f.run, plants, PilotModel().defaults(k=k), k=k)
    if not t.get("available"):
        return None
    cab = motion_block(plants)
    expanded = PilotModel(("motion_feedback",))
    ld = line_data(f.run)
    lines = ld.lines
    U, E, Y, s, w_run = spectra(f.run)
    U0, E0, Y0, _, _ = spectra(f0.run)
    d_l, r_l = _line_sets(w_run)
    forced = np.zeros(U.size, bool)
    forced[np.union1d(d_l, r_l).astype(int)] = True
    forced[0] = True
    tp = {n: v for n, v in f.truth["parameters"].items() if n not in ("Kn", "Tn")}
    true = pilot_start(expanded, tp, k)     # K1 carries K1 K2 as the test's fits do
    true["Km"] = tp.get("Km", 0.0)
    true["tau_m"] = 0.0
    var = true_remnant(U, E, Y, s, lines, forced, true, expanded, cab)
    w_true = 1 / np.sqrt(var)
    clean = (cab, s[lines], E0[lines], Y0[lines], U0[lines])
    # The noise-free lines against the true pilot: the discrete pilot at 120 Hz, logged at
    # 40 Hz, is not exactly the continuous model; this is that misfit in remnant units.
    r0 = (U0[lines] - _predict(true, expanded, cab, s[lines], E0[lines], Y0[lines])) * w_true
    misfit_true = float(np.sum(np.abs(r0) ** 2) / 0.5)
    po, pe = t["parameters_original"], t["parameters_expanded"]
    starts_o = [{**po}, {**true}]
    starts_e = [true, {**pe}]
    rss_o0, rss_e0 = pair_rss(clean, w_true, k, starts_o, starts_e)
    nc = (rss_o0 - rss_e0) / 0.5
    # The test's own weights: their noise level per real value, on average over the lines.
    sig2 = float(np.mean(var * ld.w ** 2) / 2)
    rss_o1, rss_e1 = pair_rss(clean, ld.w, k, starts_o, starts_e)
    nc_w = (rss_o1 - rss_e1) / sig2
    # The measured record with the ideal weights: the F the test would have seen.
    logged = (cab, ld.s, ld.E, ld.Y, ld.U)
    rss_o2, rss_e2 = pair_rss(logged, w_true, k, starts_o, starts_e)
    dof_km = 2 * lines.size - (7 if k == 2 else 6) - 1
    f_true_w = (rss_o2 - rss_e2) / (rss_e2 / dof_km)
    crit = stats.f.isf(2 * ALPHA / N_ALT, 1, dof_km)     # Km alone, halved on its bound, x N_ALT
    power = float(stats.ncf.sf(crit, 1, dof_km, max(nc, 1e-9)))
    power_w = float(stats.ncf.sf(crit, 1, dof_km, max(nc_w, 1e-9)))
    return dict(rss_e0=rss_e0 / 0.5, n_real=2 * lines.size, pid=pid, km=tp.get("Km", 0.0), km_g=tp.get("Km", 0.0) / g, p=t["p_value"],
                alts=t["alternatives"], km_fit=t["Km"], nc=nc, power=power, nc_w=nc_w, power_w=power_w,
                f_true_w=f_true_w, f=t["lr"], misfit_true=misfit_true, dof=dof_km,
                wratio=float(np.median(var * ld.w ** 2) / np.mean(var * ld.w ** 2)),
                wspread=float(np.std(np.log(var * ld.w ** 2))))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=16)
    ap.add_argument("--seed-start", type=int, default=0)
    ap.add_argument("--cohort", default="crossover_model", choices=("crossover_model", "table1"))
    ap.add_argument("--case", default="motion_feedback", choices=("motion_feedback", "baseline"))
    args = ap.parse_args(argv)
    bfp.FORCING = "two-input"
    print("SYNTHETIC DATA: Hess pilot models flying the JSBSim 737 (hesspipe.flight.closed_loop), "
          "two-input forcing; oracle = the same flight with the remnant off")
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        plants = bfp.fitted_plants(root)
        g = gain_scale(plants)
        print(f"gain scale {g:.3f}; cohort {args.cohort}; case {args.case}; seeds "
              f"{args.seed_start}-{args.seed_start + args.seeds - 1}")
        for seed in range(args.seed_start, args.seed_start + args.seeds):
            t0 = time.perf_counter()
            try:
                r = one_pilot(plants, root, seed, args.cohort, args.case)
            except HesspipeError as exc:
                print(f"  seed {seed}: skipped ({exc})", flush=True)
                continue
            if r is None:
                print(f"  seed {seed}: no describing function", flush=True)
                continue
            rows.append(r)
            alts = ", ".join(f"{a} {v:.2g}" for a, v in r["alts"].items())
            print(f"  {r['pid']}: Km {r['km']:.3f} ({r['km_g']:.2f} x gain scale); measured p {r['p']:.2g} "
                  f"({'named' if r['p'] < ALPHA else 'missed'}; alternatives {alts}; F {r['f']:.1f}, Km fit "
                  f"{r['km_fit']:.3g}) | oracle nc {r['nc']:.1f}, power {r['power']:.2f} | test's weights: nc "
                  f"{r['nc_w']:.1f}, power {r['power_w']:.2f} (log spread of true/weight {r['wspread']:.2f}) | "
                  f"logged lines, ideal weights: F {r['f_true_w']:.1f} | noise-free misfit (remnant units; the remnant "
                  f"itself gives {r['n_real']}): true pilot {r['misfit_true']:.0f}, expanded fit {r['rss_e0']:.0f} "
                  f"(dof {r['dof']}) [{time.perf_counter() - t0:.0f} s]", flush=True)
    if rows:
        named = sum(r["p"] < ALPHA for r in rows)
        print(f"SUMMARY ({len(rows)} pilots, SYNTHETIC): measured named {named} of {len(rows)}; oracle expected "
              f"{sum(r['power'] for r in rows):.1f} (median nc {np.median([r['nc'] for r in rows]):.1f}); with the "
              f"test's weights expected {sum(r['power_w'] for r in rows):.1f} (median nc "
              f"{np.median([r['nc_w'] for r in rows]):.1f})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
