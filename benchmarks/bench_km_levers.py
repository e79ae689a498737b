"""Km levers on JSBSim-flown two-input runs with the cohort's remnant (SYNTHETIC DATA).

Called by ``bench_km_identifiability.py --levers N [--pilot-start S]``. Cohort pilots
(expanded + remnant, cohort draws of seed 1) fly JSBSim's 737 with a two-input design and are
identified with the fitted plants by

* ``df``: the pipeline's criterion (``identify(..., criterion="df")``);
* ``motion test``: :func:`hesspipe.identification.motion_test.motion_test` started at the df
  optimum — an equation-error fit at both line sets, each line weighted by the remnant
  measured between the lines (``line_variances``), Km and a vestibular delay tau_m free;
* ``motion test estimate``: that test's reported estimate (``parameters_estimate``: the visual
  equaliser free, errors-in-variables weights; :mod:`hesspipe.identification._km_estimate`);
* ``motion test, tau_m = 0``: the same with tau_m held at 0 (the flown pilot has no
  vestibular delay; for this measurement only, by narrowing the module's bound);
* ``df, smoothed line errors``: df with each line's error from ``line_variances`` (the
  remnant's level smoothed across the lines) instead of the line's own neighbours;
* ``output``: the output-error criterion (default design only; slower).

Designs: TWO_INPUT; an output-equivalent wind (``wind_equivalent=1``: every wind line moves
the roll rate as much as the target line beside it) with a flat target; a flat target alone;
a 140 s analysed record (one period) whose lines reach 0.01 Hz (the 155 s descent needs the record
terrain at -4000 ft). Prints per pilot and the medians of |relative error| (LG: | |L_id(j
wc_true)| - 1 |).

With ``--bound N`` (:func:`information_bound`): what the lines can tell at all, per design, on
identification's linear FFT generator: the Cramer-Rao bound with the lines' true errors.
"""

from __future__ import annotations

import contextlib
import statistics
import time
from dataclasses import replace

import numpy as np

import bench_fly_pilot as B
from hesspipe.flight.approach import FlightConfig
from hesspipe.flight.closed_loop import fly_pilot_record
from hesspipe.flight.target import TWO_INPUT
from hesspipe.identification import _motion_fits as MF
from hesspipe.identification import criteria as C
from hesspipe.identification import motion_test as MT
from hesspipe.identification.fit import identify
from hesspipe.identification.frf_average import with_remnant_levels
from hesspipe.pilot.crossover import crossover

DESIGNS = {  # name: (forcing, analysed record s, record terrain ft or None)
    "TWO_INPUT": (TWO_INPUT, 70.0, None),
    "output-equivalent wind, flat target": (replace(TWO_INPUT, wind_equivalent=1.0, corner_hz=0.0), 70.0, None),
    "flat target": (replace(TWO_INPUT, corner_hz=0.0), 70.0, None),
    "140 s record, lines from 0.01 Hz": (replace(TWO_INPUT, f_min_hz=0.01), 140.0, -4000.0),
}
KEYS = ("Ke", "Km", "Km/Ke", "K1K2", "LG")


class SmoothedDF(C.DFObjective):
    """df with each line's error from the smoothed remnant level (lever 2; benchmark only)."""

    def __init__(self, run, plants, model, base, frf, sim=None):
        super().__init__(run, plants, model, base, with_remnant_levels(run, frf), sim)


@contextlib.contextmanager
def _objective(cls):
    old = C.OBJECTIVES["df"]
    C.OBJECTIVES["df"] = cls
    try:
        yield
    finally:
        C.OBJECTIVES["df"] = old


@contextlib.contextmanager
def _tau_m_max(value):
    # Patched where the fits read it: motion_test only re-exports it.
    old = MF.TAU_M_MAX
    MF.TAU_M_MAX = value
    try:
        yield
    finally:
        MF.TAU_M_MAX = old


def _errors(p, tp, plants, wc):
    # The loop gain of the Hess model's own parameters: the motion test's vestibular delay and
    # visual equaliser (nuisances of its fits, not of the model) are left out.
    q = {k: v for k, v in p.items() if k not in ("tau_m", "TI_v", "TL_v", "Kff", "T_ff")}
    return {"Ke": B.rel(p["Ke"], tp["Ke"]), "Km": B.rel(p["Km"], tp["Km"]),
            "Km/Ke": B.rel(p["Km"] / p["Ke"], tp["Km"] / tp["Ke"]),
            "K1K2": B.rel(p["K1"] * p["K2"], tp["K1"] * tp["K2"]),
            "LG": abs(B.loop_gain("expanded", q, plants, wc) - 1.0)}


def levers_study(plants, args, root):
    """Fly and identify ``args.levers`` pilots from ``args.pilot_start`` per design; print medians."""
    first, n = args.pilot_start, args.levers
    print(f"\nKm levers (SYNTHETIC: cohort pilots {first + 1}-{first + n}, expanded + cohort remnant, "
          "JSBSim 737, fitted plants); median |relative error|")
    wanted = args.levers_designs.split(",") if getattr(args, "levers_designs", "") else list(DESIGNS)
    for dname, (tg, record, terrain) in DESIGNS.items():
        if dname not in wanted:
            continue
        methods = ["df", "motion test", "motion test estimate", "motion test, tau_m = 0", "df, smoothed line errors"]
        if dname == "TWO_INPUT":
            methods.append("output")
        errs = {m: {k: [] for k in KEYS} for m in methods}
        failed, t0 = [], time.perf_counter()
        for i in range(first, first + n):
            pid = f"pilot{i + 1:02d}"
            pseed, truth, params = B.draw(plants, pid, 1, ("motion_feedback",))
            try:
                f = fly_pilot_record("737", plants, truth["model"], params, seed=pseed, workdir=root / "w",
                                     record_every=B.EVERY, run_id=pid, target=tg,
                                     remnant_share=truth["remnant_share"],
                                     config=FlightConfig(duration_s=record + tg.run_in_s,
                                                         record_terrain_ft=terrain))
            except Exception as exc:  # a limit left: reported, not counted
                failed.append(f"{pid}: {str(exc).split('): ', 1)[-1][:80]}")
                continue
            tp = f.truth["parameters"]
            core = {k: v for k, v in tp.items() if k not in ("Kn", "Tn")}
            wc = crossover("expanded", core, plants, duration_s=record).frequency_rad_s
            kw = dict(seed=pseed, with_benchmark=False, with_identifiability=False)
            p_df = identify(f.run, plants, "expanded", criterion="df", **kw).parameters
            row = [pid]
            mt = MT.motion_test(f.run, plants, p_df, k=1)
            for m in methods:
                if m == "df":
                    p = p_df
                elif m == "motion test":
                    p = mt["parameters_expanded"]
                elif m == "motion test estimate":   # the same test's result, its estimate
                    p = mt["parameters_estimate"]
                elif m.startswith("motion test"):
                    with _tau_m_max(1e-9):
                        p = MT.motion_test(f.run, plants, p_df, k=1)["parameters_expanded"]
                elif m == "df, smoothed line errors":
                    with _objective(SmoothedDF):
                        p = identify(f.run, plants, "expanded", criterion="df", **kw).parameters
                else:
                    p = identify(f.run, plants, "expanded", criterion="output", **kw).parameters
                e = _errors(p, tp, plants, wc)
                for k in KEYS:
                    errs[m][k].append(e[k])
                row.append(f"{m}: Km {100 * e['Km']:.0f}%")
            print("  " + " | ".join(row), flush=True)
        print(f" {dname} ({record:g} s analysed; {time.perf_counter() - t0:.0f} s wall):")
        for line in failed:
            print(f"   not flown, {line}")
        for m, e in errs.items():
            if e["Ke"]:
                print(f"   {m} ({len(e['Ke'])} pilots): "
                      + ", ".join(f"{k} {100 * statistics.median(v):.0f} %" for k, v in e.items()), flush=True)


BOUND_DESIGNS = {  # name: (forcing without run-in, analysed record s)
    "TWO_INPUT lines": (replace(TWO_INPUT, run_in_s=0.0), 70.0),
    "output-equivalent wind, flat target": (replace(TWO_INPUT, run_in_s=0.0, wind_equivalent=1.0, corner_hz=0.0), 70.0),
    "flat target, lines from 0.005 Hz, 140 s": (replace(TWO_INPUT, run_in_s=0.0, corner_hz=0.0, f_min_hz=0.005), 140.0),
    "flat target, lines from 0.005 Hz, 280 s": (replace(TWO_INPUT, run_in_s=0.0, corner_hz=0.0, f_min_hz=0.005), 280.0),
    "flat target, lines from 0.005 Hz, 560 s": (replace(TWO_INPUT, run_in_s=0.0, corner_hz=0.0, f_min_hz=0.005), 560.0),
    "output-equivalent, flat, from 0.005 Hz, 140 s": (replace(TWO_INPUT, run_in_s=0.0, wind_equivalent=1.0, corner_hz=0.0,
                                                           f_min_hz=0.005), 140.0),
    "output-equivalent, flat, from 0.005 Hz, 280 s": (replace(TWO_INPUT, run_in_s=0.0, wind_equivalent=1.0, corner_hz=0.0,
                                                           f_min_hz=0.005), 280.0),
    "output-equivalent, flat, from 0.005 Hz, 560 s": (replace(TWO_INPUT, run_in_s=0.0, wind_equivalent=1.0, corner_hz=0.0,
                                                           f_min_hz=0.005), 560.0),
}
FREE = ("Ke", "K1", "1/T1", "tau0", "wn", "zn", "Km")
LOG_FREE = ("Ke", "K1", "1/T1", "wn", "zn", "Km")


def information_bound(plants, args):
    """Cramer-Rao bound of df's parameters with the lines' TRUE errors, and df's own errors.

    Identification's FFT generator (linear, no plant error; two periods, the second analysed),
    the cohort's pilots and remnant share. The true error of the describing function at a line
    is n_k / E_k: n (the remnant as it appears in u: U - H E) from a noise-only twin run,
    smoothed over 9 bins, E_k from the noise-free twin. The Fisher information of the df
    parameters (FREE; gains and corners in ln units) at both line sets gives the smallest
    standard deviation any unbiased estimator can reach; beside it, df's median |error| on the
    noisy run itself. The plants' slow right-half-plane zeros (0.006 and 0.028 rad/s) are
    reflected (gain unchanged) so that the loop stays bounded over the long records.
    """
    import dataclasses as dc

    from hesspipe.core.formats import Run
    from hesspipe.flight.closed_loop import pilot_loop
    from hesspipe.flight.target import interleaved_lines
    from hesspipe.identification.criteria import model_df, model_df_reference
    from hesspipe.pilot.blocks import from_tf
    from hesspipe.pilot.hess import PilotModel, model_from_name
    from hesspipe.pilot.remnant import remnant_gain
    from hesspipe.pilot.simulation import Simulator, synthetic_run
    from hesspipe.plants.slow_roots import reflect_slow_roots

    pl = dc.replace(plants, control_to_output=reflect_slow_roots(plants.control_to_output, 0.05)[0],
                    disturbance_to_output=reflect_slow_roots(plants.disturbance_to_output, 0.05)[0])
    yd, yc = from_tf(pl.disturbance_to_output).response, from_tf(pl.control_to_output)
    m, mr = model_from_name("expanded"), PilotModel(("motion_feedback", "remnant"))
    dt = 0.025
    print(f"\ninformation bound (SYNTHETIC: identification's FFT generator, cohort pilots {args.pilot_start + 1}-"
          f"{args.pilot_start + args.bound}, cohort remnant, fitted plants with slow RHP zeros reflected): "
          "median Cramer-Rao std of ln Ke, ln Km, ln Km/Ke with the lines' true errors; df's median |error|")
    for name, (tg, record) in BOUND_DESIGNS.items():
        n = int(round(record / dt))
        bound, found, wind_rms = {"Ke": [], "Km": [], "Km/Ke": []}, {"Ke": [], "Km": [], "Km/Ke": []}, []
        t0 = time.perf_counter()
        for i in range(args.pilot_start, args.pilot_start + args.bound):
            pid = f"pilot{i + 1:02d}"
            pseed, truth, params = B.draw(pl, pid, 1, ("motion_feedback",))
            p = {k: v for k, v in params.items() if k not in ("Kn", "Tn")}
            wind, ref = tg.signals(np.arange(n) * dt, pseed, yd)
            W, R = np.tile(wind, 2), np.tile(ref, 2)
            pr = dict(p, Kn=remnant_gain(mr, mr.complete(p, 1), Simulator(pl, W, dt, reference=R, noise_seed=pseed),
                                         truth["remnant_share"]))
            clean = synthetic_run(m, p, pl, W, dt, seed=pseed, reference=R)
            quiet = synthetic_run(mr, pr, pl, 0 * W, dt, seed=pseed, reference=0 * R)
            noisy = synthetic_run(mr, pr, pl, W, dt, seed=pseed, reference=R)
            F = lambda x: np.fft.rfft(np.asarray(x, dtype=float)[n:])  # noqa: E731  (second period)
            om = 2 * np.pi * np.fft.rfftfreq(n, dt)
            kd, kt = interleaved_lines(n * dt, tg.n_lines, tg.f_min_hz, tg.f_max_hz)
            loop = pilot_loop(m, m.complete(p), pl)
            res = F(quiet.control)[1:] - model_df(loop, 1j * om[1:]) * F(-quiet.output)[1:]
            level = np.convolve(np.concatenate(([0.0], np.abs(res) ** 2)), np.ones(9) / 9, mode="same")
            E0 = F(R - clean.output)
            sd, sr = 1j * om[kd], 1j * om[kt]
            sig = np.sqrt(np.concatenate((level[kd], level[kt]))) / np.abs(np.concatenate((E0[kd], E0[kt])))
            ycr = yc.response(sr)

            def h(q):
                lp = pilot_loop(m, m.complete(q), pl)
                return np.concatenate((model_df(lp, sd), model_df_reference(lp, sr, ycr)))

            h0, J = h(p), []
            for name_ in FREE:
                q = dict(p)
                q[name_] = p[name_] * np.exp(1e-4) if name_ in LOG_FREE else p[name_] + 1e-4
                J.append((h(q) - h0) / 1e-4 / sig)
            J = np.array(J).T
            cov = np.linalg.inv(2 * (J.conj().T @ J).real)
            g = np.zeros(len(FREE))
            g[FREE.index("Km")], g[FREE.index("Ke")] = 1.0, -1.0
            for k, v in (("Ke", cov[0, 0]), ("Km", cov[-1, -1]), ("Km/Ke", g @ cov @ g)):
                bound[k].append(float(np.sqrt(v)))
            run = Run(time=noisy.time[:n], disturbance=wind, output=noisy.output[n:], control=noisy.control[n:],
                      reference=ref, id=pid, synthetic=True)
            q = identify(run, pl, "expanded", seed=pseed, criterion="df", with_benchmark=False,
                         with_identifiability=False).parameters
            found["Ke"].append(B.rel(q["Ke"], p["Ke"]))
            found["Km"].append(B.rel(q["Km"], p["Km"]))
            found["Km/Ke"].append(B.rel(q["Km"] / q["Ke"], p["Km"] / p["Ke"]))
            wind_rms.append(float(np.std(wind)))
        print(f"  {name} (wind {statistics.median(wind_rms):.0f} ft/s RMS; {time.perf_counter() - t0:.0f} s): "
              "bound " + ", ".join(f"ln {k} {statistics.median(v):.2f}" for k, v in bound.items())
              + "; df |error| " + ", ".join(f"{k} {100 * statistics.median(v):.0f} %" for k, v in found.items()),
              flush=True)
