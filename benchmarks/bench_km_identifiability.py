"""Benchmark: can Km be identified from JSBSim-flown runs of the disturbance task? (SYNTHETIC DATA)

Pilots of the pipeline's crossover-model cohort (expanded + remnant, cohort draws of seed 1)
fly the JSBSim 737 (hesspipe.flight.closed_loop, 120 Hz, recorded at 40 Hz) and are
identified with the fitted plants (expanded model, `df` criterion) with different sets of
parameters held at their true values (or, for 1/T1, at Hess's rule), to find what Km trades
with. Then the same pilots fly the two-input task (hesspipe.flight.target: wind and roll-rate
target multisines on interleaved lines), without a run-in, with TWO_INPUT's run-in, and with
the run-in and the remnant, identified by df at both line sets. Last, a structural check on
identification's own FFT generator.

Prints, per pilot and set, the relative errors of Ke, Km and K1 K2, then the medians.

With ``--runs N`` the two-input study's remnant case flies each pilot N times (each run its own
remnant and forcing phases, as a human repeats a condition) and identifies the pilot from the
runs' averaged describing function (:func:`hesspipe.identification.frf_average.average_frf`).

With ``--levers`` (issue 14's Km item): the same pilots, expanded + the cohort's remnant, flown
with TWO_INPUT and with three design changes (an output-equivalent wind, a flat target, a 140 s
record whose lines reach 0.01 Hz), each identified by df, by the motion test's equation-error
fit (Km free, with its vestibular delay tau_m free and held at 0; the flown pilot has none), by
df with the lines' errors from the smoothed remnant (motion_test.line_variances), and (default
design only) by the ``output`` criterion.

Usage::

    nice python benchmarks/bench_km_identifiability.py [--pilots 10] [--target-pilots 10] [--fft-pilots 4]
    nice python benchmarks/bench_km_identifiability.py --pilots 0 --target-pilots 0 --fft-pilots 0 --levers 10 [--pilot-start 10]
    nice python benchmarks/bench_km_identifiability.py --pilots 0 --target-pilots 10 --fft-pilots 0 --runs 8
"""

from __future__ import annotations

import argparse
import statistics
import sys
import tempfile
from dataclasses import replace
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
import bench_fly_pilot as B  # noqa: E402  (the same plants, draws and helpers)
from hesspipe.core.seeds import derive_seed  # noqa: E402
from hesspipe.flight.approach import FlightConfig  # noqa: E402
from hesspipe.flight.closed_loop import fly_pilot_record  # noqa: E402
from hesspipe.flight.target import TWO_INPUT, TargetForcing  # noqa: E402
from hesspipe.identification.fit import identify  # noqa: E402
from hesspipe.identification.frf import estimate_frf  # noqa: E402
from hesspipe.pilot.crossover import crossover  # noqa: E402
from hesspipe.pilot.hess import table1  # noqa: E402
from hesspipe.pilots.cohort import hess_corner  # noqa: E402


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--pilots", type=int, default=10)
    ap.add_argument("--target-pilots", type=int, default=10)
    ap.add_argument("--target-rms", type=float, default=0.02, help="roll-rate target RMS, rad/s")
    ap.add_argument("--remnant-scale", type=float, default=1.0,
                    help="two-input study: fly only the run-in design with the cohort's remnant share x this")
    ap.add_argument("--fft-pilots", type=int, default=4,
                    help="pilots of the noise-free structural check (FFT generator)")
    ap.add_argument("--levers", type=int, default=0,
                    help="pilots of the Km levers study (identification and design levers, cohort remnant)")
    ap.add_argument("--bound", type=int, default=0,
                    help="pilots of the information bound (Cramer-Rao, FFT generator) per design")
    ap.add_argument("--levers-designs", default="",
                    help="levers study: only these designs (comma-separated names; default all)")
    ap.add_argument("--pilot-start", type=int, default=0,
                    help="levers study: first pilot index (0: pilot01; 10: pilots 11-20)")
    ap.add_argument("--runs", type=int, default=1,
                    help="two-input study: runs flown per pilot with the cohort's remnant (each its own "
                         "remnant and forcing phases), identified through their averaged describing "
                         "function (hesspipe.identification.frf_average)")
    args = ap.parse_args(argv)
    print("SYNTHETIC DATA: Hess pilot models flying the JSBSim 737; identified with the fitted plants")
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        plants = B.fitted_plants(root)
        corner = hess_corner(plants)
        sets = {  # name: (free, fixed from the truth, fixed values)
            "1/T1 by Hess's rule, K1 free": (("Ke", "K1", "Km", "tau0", "wn", "zn"), ("K2",), {"1/T1": corner}),
            "K1, K2, 1/T1 true": (("Ke", "Km", "tau0", "wn", "zn"), ("K1", "K2", "1/T1"), {}),
            "K1 at Table 1, 1/T1 by rule": (("Ke", "Km", "tau0", "wn", "zn"), ("K2",),
                                            {"1/T1": corner, "K1": table1(1)["K1"]}),
        }
        errs = {name: {"Ke": [], "Km": [], "K1K2": []} for name in sets}
        for i in range(args.pilots):
            pid = f"pilot{i + 1:02d}"
            pseed, truth, params = B.draw(plants, pid, 1, ("motion_feedback",))
            f = fly_pilot_record("737", plants, truth["model"], params, seed=pseed, workdir=root / "w",
                                 record_every=B.EVERY, remnant_share=truth["remnant_share"], run_id=pid)
            tp = f.truth["parameters"]
            row = [pid]
            for name, (free, from_truth, values) in sets.items():
                fixed = {**{k: tp[k] for k in from_truth}, **values}
                p = identify(f.run, plants, "expanded", free=free, fixed=fixed, seed=pseed, criterion="df",
                             with_benchmark=False, with_identifiability=False).parameters
                e = errs[name]
                e["Ke"].append(B.rel(p["Ke"], tp["Ke"]))
                e["Km"].append(B.rel(p["Km"], tp["Km"]))
                e["K1K2"].append(B.rel(p["K1"] * p["K2"], tp["K1"] * tp["K2"]))
                row.append(f"{name}: Ke {100 * e['Ke'][-1]:.0f}% Km {100 * e['Km'][-1]:.0f}% "
                           f"K1K2 {100 * e['K1K2'][-1]:.0f}%")
            print(" | ".join(row), flush=True)
        print(f"median |relative error| over {args.pilots} pilots (df criterion, disturbance only):")
        for name, e in errs.items() if args.pilots else ():
            print(f"  {name}: " + ", ".join(f"{k} {100 * statistics.median(v):.0f} %" for k, v in e.items()))

        if args.target_pilots:
            target_study(plants, corner, args, root)
        if args.fft_pilots:
            structure_check(plants, args)
        if args.levers or args.bound:
            import bench_km_levers
        if args.levers:
            bench_km_levers.levers_study(plants, args, root)
        if args.bound:
            bench_km_levers.information_bound(plants, args)
    return 0


def target_study(plants, corner, args, root):
    """Two-input flights (hesspipe.flight.target) identified by df at both line sets.

    Three designs of the same pilots: the forcing started with the record (no run-in: the
    loop's start-up transient lies in the analysed period), TWO_INPUT (a 15 s run-in flown
    and not recorded, no paper's side wind) without remnant, and TWO_INPUT with the cohort's
    remnant.
    """
    sets = {  # name: (free or None for the default set, fixed from the truth, fixed values)
        "default free set": (None, (), {}),
        "K1, K2, 1/T1 true": (("Ke", "Km", "tau0", "wn", "zn"), ("K1", "K2", "1/T1"), {}),
        "K1 at Table 1, 1/T1 by rule": (("Ke", "Km", "tau0", "wn", "zn"), ("K2",),
                                        {"1/T1": corner, "K1": table1(1)["K1"]}),
    }
    design = replace(TWO_INPUT, target_rms=args.target_rms)
    cases = {  # name: (forcing, flight duration s, with the remnant)
        "no run-in, no remnant": (replace(design, run_in_s=0.0), 70.0, False),
        "run-in 15 s, no remnant": (design, 70.0 + design.run_in_s, False),
        "run-in 15 s, cohort remnant": (design, 70.0 + design.run_in_s, True),
    }
    if args.remnant_scale != 1.0:
        cases = {f"run-in 15 s, remnant x {args.remnant_scale:g}": (design, 70.0 + design.run_in_s, True)}
    keys = ("Ke", "Km", "Km/Ke", "K1K2", "LG")
    errs = {(c, n): {k: [] for k in keys} for c in cases for n in sets}
    if args.runs > 1:
        print(f"\nwith the cohort's remnant: {args.runs} runs per pilot, averaged describing function")
    print(f"\ntwo-input task ({design.n_lines} wind lines, {design.wind_rms:g} ft/s, and {design.n_lines} "
          f"roll-rate target lines, {design.target_rms:g} rad/s, {design.f_min_hz:g}-{design.f_max_hz:g} Hz, "
          "no paper's side wind); df criterion at both line sets")
    for i in range(args.pilot_start, args.pilot_start + args.target_pilots):
        pid = f"pilot{i + 1:02d}"
        pseed, truth, params = B.draw(plants, pid, 1, ("motion_feedback",))
        for case, (tg, duration, remnant) in cases.items():
            model = truth["model"] if remnant else truth["model"].replace("+remnant", "")
            try:
                f = fly_pilot_record("737", plants, model, params, seed=pseed, workdir=root / "w",
                                     record_every=B.EVERY, run_id=pid, target=tg,
                                     remnant_share=truth["remnant_share"] * args.remnant_scale,
                                     config=FlightConfig(duration_s=duration))
            except Exception as exc:  # a limit left: reported, not counted
                print(f"{pid} {case}: {exc}")
                continue
            tp = f.truth["parameters"]
            core = {k: v for k, v in tp.items() if k not in ("Kn", "Tn")}
            wc = crossover("expanded", core, plants, duration_s=70.0).frequency_rad_s
            frf = estimate_frf(f.run, plants, seed=pseed)
            nref = 0 if frf.reference is None else frf.reference.H.size
            runs = [f.run]
            for j in range(1, args.runs if remnant else 1):
                runs.append(fly_pilot_record(
                    "737", plants, model, params, seed=derive_seed(pseed, "repeat", str(j)),
                    workdir=root / "w", record_every=B.EVERY, run_id=f"{pid}-{j + 1}", target=tg,
                    remnant_share=truth["remnant_share"] * args.remnant_scale,
                    config=FlightConfig(duration_s=duration)).run)
            row = [f"{pid} {case} (lines {frf.feedback.H.size}+{nref}, bank {f.truth['envelope']['max_abs_bank_deg']:.1f} deg)"]
            for name, (free, from_truth, values) in sets.items():
                fixed = {**{k: tp[k] for k in from_truth}, **values} or None
                p = identify(runs if len(runs) > 1 else f.run, plants, "expanded", free=free, fixed=fixed,
                             seed=pseed, criterion="df", with_benchmark=False,
                             with_identifiability=False).parameters
                e = errs[(case, name)]
                e["Ke"].append(B.rel(p["Ke"], tp["Ke"]))
                e["Km"].append(B.rel(p["Km"], tp["Km"]))
                e["Km/Ke"].append(B.rel(p["Km"] / p["Ke"], tp["Km"] / tp["Ke"]))
                e["K1K2"].append(B.rel(p["K1"] * p["K2"], tp["K1"] * tp["K2"]))
                e["LG"].append(abs(B.loop_gain("expanded", p, plants, wc) - 1.0))
                if i == 0 and remnant and free is None:
                    valley(plants, p, core, frf)
                row.append(f"{name}: " + " ".join(f"{k} {100 * e[k][-1]:.0f}%" for k in keys))
            print(" | ".join(row), flush=True)
    print("median |relative error| (two-input study; LG = | |L_id(j wc_true)| - 1 |):")
    for (case, name), e in errs.items():
        if e["Ke"]:
            print(f"  {case}, {name} ({len(e['Ke'])} pilots): "
                  + ", ".join(f"{k} {100 * statistics.median(v):.0f} %" for k, v in e.items()))


def valley(plants, found, truth, frf):
    """How far the identified describing function is from the truth's at the lines."""
    from hesspipe.flight.closed_loop import pilot_loop
    from hesspipe.identification.criteria import model_df, model_df_reference
    from hesspipe.pilot.blocks import from_tf
    from hesspipe.pilot.hess import model_from_name

    m = model_from_name("expanded")
    for name, resp, fn in (("wind", frf.feedback, model_df), ("target", frf.reference, model_df_reference)):
        s = 1j * resp.freq_rad_s
        args = () if fn is model_df else (from_tf(plants.control_to_output).response(s),)
        h = [fn(pilot_loop(m, m.complete(p), plants), s, *args) for p in (found, truth)]
        ratio = h[0] / h[1]
        print(f"    identified / true describing function at the {name} lines "
              f"({', '.join(f'{w:.2f}' for w in resp.freq_rad_s)} rad/s): |ratio| "
              f"{', '.join(f'{abs(r):.2f}' for r in ratio)}; phase difference deg "
              f"{', '.join(f'{np.degrees(np.angle(r)):.0f}' for r in ratio)}; line relative error "
              f"{', '.join(f'{x:.2f}' for x in resp.sigma / np.abs(resp.H))}")


def structure_check(plants, args):
    """Noise-free two-input runs of identification's own FFT generator: what the line sets pin.

    No plant error, steady state (the second of two periods analysed); without remnant what is
    left is the structure, with the cohort's remnant share what noise does to it. Signed errors, so a common scale of Ke and Km shows.
    """
    from hesspipe.core.formats import Run
    from hesspipe.pilot.hess import PilotModel
    from hesspipe.pilot.remnant import remnant_gain
    from hesspipe.pilot.simulation import Simulator, synthetic_run

    dt, n = 0.025, 2800
    print("\nstructural check (SYNTHETIC, identification's own FFT generator, with and without the cohort's remnant, "
          "fitted plants; signed errors, default free set, df criterion):")
    for i in range(args.fft_pilots):
        pid = f"pilot{i + 1:02d}"
        pseed, truth, params = B.draw(plants, pid, 1, ("motion_feedback",))
        p = {k: v for k, v in params.items() if k not in ("Kn", "Tn")}
        for rms, remnant in ((0.0, False), (args.target_rms, False), (0.0, True), (args.target_rms, True)):
            wind, ref = TargetForcing(target_rms=rms).signals(np.arange(n) * dt, pseed)
            model, pr = "expanded", dict(p)
            if remnant:  # the cohort's remnant share of the control variance
                model = PilotModel(("motion_feedback", "remnant"))
                sim = Simulator(plants, np.tile(wind, 2), dt, reference=np.tile(ref, 2), noise_seed=pseed)
                pr["Kn"] = remnant_gain(model, model.complete(pr, 1), sim, truth["remnant_share"])
            full = synthetic_run(model, pr, plants, np.tile(wind, 2), dt, seed=pseed,
                                 reference=np.tile(ref, 2))
            run = Run(time=full.time[:n], disturbance=wind, output=full.output[n:],
                      control=full.control[n:], reference=ref, id=pid, synthetic=True)
            q = identify(run, plants, "expanded", seed=pseed, criterion="df", with_benchmark=False,
                         with_identifiability=False).parameters
            sgn = {"Ke": q["Ke"] / p["Ke"] - 1, "Km": q["Km"] / p["Km"] - 1,
                   "Km/Ke": q["Km"] / q["Ke"] / (p["Km"] / p["Ke"]) - 1,
                   "K1K2/Ke": q["K1"] * q["K2"] / q["Ke"] / (p["K1"] * p["K2"] / p["Ke"]) - 1}
            print(f"  {pid} target {rms:g} rad/s, {'remnant' if remnant else 'no remnant'}: " + ", ".join(f"{k} {100 * v:+.0f} %" for k, v in sgn.items()),
                  flush=True)


if __name__ == "__main__":
    raise SystemExit(main())
