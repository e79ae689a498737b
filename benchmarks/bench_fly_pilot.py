"""Benchmark: the Hess pilot model flying the JSBSim 737 in closed loop (SYNTHETIC DATA).

Prints

1. speed: time of one 70 s closed-loop flight (load, trim, 8400 steps of JSBSim + pilot;
   median of several) against JSBSim alone in the same process (stage one's open-loop
   record, the same load/trim/steps without a pilot), as a ratio;
2. envelope: over N cohort pilots (drawn exactly as the pipeline's cohort,
   hesspipe.pilots.cohort.synth_pilot) the airspeed range, the least height AGL, the largest
   |bank| and the failures (a limit left);
3. identification: the same pilots' JSBSim-flown runs (40 Hz) identified with the
   *fitted* plants (hesspipe.identification.fit, expanded model) — relative errors of Ke, Km and the
   crossover; beside them the same pilots simulated by the linear frequency-domain model
   around the same plants with the same disturbance and remnant ("fft"), which separates
   what JSBSim adds (plant error, nonlinearity) from what the identification itself
   cannot resolve. Criterion `df` (the pipeline's; --criterion); errors of Ke, Km, the
   tracking crossover and the loop gain (|L| of the identified pilot at the true crossover).
   Free sets: the criterion's default, Ke and Km alone (the rest at the truth), and Ke, Km,
   tau0, wn, zn (K1, K2, 1/T1 at the truth);
4. diagnose (hesspipe.diagnose.workflow, baseline "original") on JSBSim-flown runs of pilots
   with a hidden motion feedback, a hidden extra delay, and none (baseline flights):
   how often the hidden effect is named, and what is named on baseline flights.

The plants are fitted by stages one and two (hesspipe.flight.approach / hesspipe.plants.fit) in a
temporary folder first. Everything is seeded; the numbers are reproducible.

Usage::

    nice python benchmarks/bench_fly_pilot.py [--pilots 20] [--diag-seeds 4] [--skip speed,envelope,ident,diagnose]
                                              [--cohort crossover_model|table1] [--diag-cohorts table1,crossover_model]
                                              [--diag-seed-start 0]
                                              [--forcing paper|two-input] [--diag-cases baseline,extra_delay] [--paired]
"""

from __future__ import annotations

import argparse
import math
import statistics
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from hesspipe.core.errors import HesspipeError
from hesspipe.core.formats import Run, read_plants
from hesspipe.core.seeds import derive_seed
from hesspipe.flight.approach import FlightConfig, fly, fly_records
from hesspipe.flight.closed_loop import fly_pilot_record, pilot_loop
from hesspipe.identification.fit import identify
from hesspipe.pilot.blocks import from_tf
from hesspipe.pilot.crossover import crossover, gain_scale
from hesspipe.pilot.hess import model_from_name
from hesspipe.pilot.simulation import Simulator
from hesspipe.pilots.cohort import cohort_spec, synth_pilot
from hesspipe.plants.fit import fit_plants
from hesspipe.plants.settings import PlantsConfig

EVERY = 3  # 120 Hz -> 40 Hz records, as the pipeline's JSBSim cohort
CASES = None  # the diagnose section's cases (--diag-cases)
PAIRED = False  # --paired: a baseline flight of each pilot for diagnose
RESTARTS, PASSES = 2, 10  # the pipeline's APID budget (--restarts/--passes change it)
CRITERION = "df"  # the pipeline's identification criterion (--criterion changes it)
DRAW = "crossover_model"  # the pipeline's cohort draw (--cohort changes it)
FORCING = "paper"  # --forcing: the paper's side wind + gusts, or the two-input multisines
TARGET_RMS = None  # --target-rms: the two-input target's RMS (rad/s; None: TWO_INPUT's)


def forcing_kwargs() -> dict:
    """fly_pilot_record's forcing arguments for --forcing (two-input: an 85 s flight whose last
    70 s, one whole period of the wind and target lines, are recorded)."""
    if FORCING == "paper":
        return {}
    from dataclasses import replace

    from hesspipe.flight.target import TWO_INPUT
    tg = TWO_INPUT if TARGET_RMS is None else replace(TWO_INPUT, target_rms=TARGET_RMS)
    return {"target": tg, "config": FlightConfig(duration_s=70.0 + tg.run_in_s)}


def loop_gain(model, params, plants, w: float) -> float:
    """|L(j w)| of `model` with `params` around `plants` (1 at the truth's crossover w)."""
    m = model_from_name(model)
    loop = pilot_loop(m, m.complete({k: v for k, v in params.items() if k not in ("Kn", "Tn")}), plants)
    s = np.array([1j * w])
    return float(abs(loop.pilot_open_loop(s, from_tf(plants.control_to_output).response(s))[0]))


def fitted_plants(root: Path):
    fly("737", FlightConfig(), root / "flight", seed=1)
    fit_plants(root / "flight", root / "plants", PlantsConfig())
    return read_plants(root / "plants" / "plants.json")


def linear_run(plants, model, params, flown: Run, noise_seed: int) -> Run:
    """The linear loop around the plants with the flight's disturbance and remnant sequence.

    The remnant's white sequence is the flight's (same seed, same 120 Hz draw); the
    result is sampled like the flown run. Slowly growing loops (the fitted plants'
    right-half-plane zero near 0.006 rad/s) are simulated as they are: over 70 s such a
    mode grows by < 5 %.
    """
    dt = flown.dt / EVERY
    n = len(flown) * EVERY
    t = np.arange(n) * dt
    wind = np.interp(t, flown.time, flown.disturbance)
    m = model_from_name(model)
    sim = Simulator(plants, wind, dt, noise_seed=noise_seed, pad_factor=8)
    c, y = sim.spectra(pilot_loop(m, params, plants))
    u = sim.waveform(c)[::EVERY]   # spectra are on the shifted contour: un-weight them
    yy = sim.waveform(y)[::EVERY]
    return Run(time=flown.time, disturbance=flown.disturbance, output=yy, control=u,
               reference=np.zeros(len(u)), id=flown.id, synthetic=True)


def linear_td_run(plants, model, params, flown: Run, noise_seed: int) -> Run:
    """The flight's loop with JSBSim replaced by the fitted plants, stepped in the time domain.

    Same discrete pilot, same sampling convention (the pilot at step k sees the output of
    row k - 1), same wind and remnant sequence; the plants are Tustin sections at 120 Hz.
    It checks the closed-loop machinery: identification on it should match the
    frequency-domain reproduction ("fft"), leaving JSBSim vs plants as the only difference.
    """
    from hesspipe.flight.closed_loop import SAMPLE_LAG
    from hesspipe.pilot.discrete import DiscretePilot, _run_sections, tustin_sections

    dt = flown.dt / EVERY
    n = len(flown) * EVERY
    wind = np.interp(np.arange(n) * dt, flown.time, flown.disturbance)
    m = model_from_name(model)
    pilot = DiscretePilot(pilot_loop(m, params, plants), dt, sample_lag=SAMPLE_LAG)
    yc = tustin_sections(np.squeeze(plants.Yc.num[0][0]), np.squeeze(plants.Yc.den[0][0]), dt)
    yd = tustin_sections(np.squeeze(plants.Yd.num[0][0]), np.squeeze(plants.Yd.den[0][0]), dt)
    white = np.random.default_rng(noise_seed).standard_normal(n) if "remnant" in m.effects else np.zeros(n)
    u, y = np.empty(n), np.empty(n)
    prev = 0.0
    for k in range(n):
        u[k] = pilot.step(-prev, prev, float(white[k]))
        prev = y[k] = _run_sections(yc, u[k]) + _run_sections(yd, float(wind[k]))
    return Run(time=flown.time, disturbance=flown.disturbance, output=y[::EVERY], control=u[::EVERY],
               reference=np.zeros(len(flown)), id=flown.id, synthetic=True)


def rel(a, b):
    return abs(a / b - 1.0) if (b and math.isfinite(a) and math.isfinite(b)) else float("inf")


def median(xs):
    return statistics.median(xs) if xs else float("nan")


def section_speed(plants, work: Path, repeats: int) -> None:
    print("== 1. speed (one 70 s record at 120 Hz, median of %d)" % repeats)
    closed, alone = [], []
    for i in range(repeats):
        t0 = time.perf_counter()
        fly_pilot_record("737", plants, "expanded+remnant", {}, seed=i, workdir=work / f"s{i}")
        closed.append(time.perf_counter() - t0)
        t0 = time.perf_counter()
        fly_records("737", FlightConfig(), i, work / f"s{i}")
        alone.append((time.perf_counter() - t0) / 2)  # two records per call
    c, a = statistics.median(closed), statistics.median(alone)
    print(f"closed-loop flight with the pilot: {c:.3f} s; JSBSim alone (open-loop record, same load/trim/"
          f"steps): {a:.3f} s; ratio {c / a:.2f}")


def draw(plants, pid: str, base_seed: int, effects, how: str | None = None):
    pseed = derive_seed(base_seed, pid)
    _, truth = synth_pilot(plants, pid, pseed, effects, cohort_spec(how or DRAW))
    params = {k: v for k, v in truth["parameters"].items() if k != "Kn"}
    return pseed, truth, params


def section_envelope_and_identification(plants, work: Path, n: int, ident: bool = True) -> None:
    print(f"\n== 2. envelope over {n} cohort pilots (expanded + remnant, cohort draws of seed 1)")
    flights, failures = [], []
    for i in range(n):
        pid = f"pilot{i + 1:02d}"
        pseed, truth, params = draw(plants, pid, 1, ("motion_feedback",))
        try:
            f = fly_pilot_record("737", plants, truth["model"], params, seed=pseed, workdir=work / "env",
                                 record_every=EVERY, remnant_share=truth["remnant_share"], run_id=pid)
            flights.append((pid, pseed, f))
        except HesspipeError as exc:
            failures.append(f"{pid}: {exc}")
    env = [f.truth["envelope"] for _, _, f in flights]
    if env:
        print(f"flown {len(flights)}/{n}: airspeed {min(e['speed_kts'][0] for e in env):.1f}-"
              f"{max(e['speed_kts'][1] for e in env):.1f} kt (trim {env[0]['trim_speed_kts']:.1f}, "
              f"limit +-10), min height {min(e['min_agl_ft'] for e in env):.0f} ft AGL (limit 50), "
              f"max |bank| {max(e['max_abs_bank_deg'] for e in env):.2f} deg (limit 15)")
    print(f"failures: {len(failures)}" + "".join(f"\n  {x}" for x in failures))
    if not ident:
        return

    print(f"\n== 3. identification with the fitted plants (expanded model, APID {PASSES} passes x "
          f"{RESTARTS} restarts)")
    print("control differences (rms, relative to the control's): td-fft = discretisation and sampling "
          "of the time-domain loop; jsb-td = JSBSim vs the fitted plants (plant error, nonlinearity)")
    print(f"criterion {CRITERION}; cohort draw {DRAW}; loop gain error = | |L_identified(j wc_true)| - 1 |")
    print("pilot   Ke_true Km_true wc_true | control diffs | jsbsim: dKe  dKm  dwc dLG | fft: dKe  dKm  dwc dLG | "
          "td: dKe dKm dwc dLG | Ke,Km free (the rest at the truth) jsbsim: dKe dKm | fft: dKe dKm | td: dKe dKm")
    errs = {f"{t}_{k}": [] for t in ("j", "f", "t") for k in ("ke", "km", "wc", "lg")}
    errs.update({f"{t}2_{k}": [] for t in ("j", "f", "t") for k in ("ke", "km")})
    for pid, pseed, f in flights:
        tp = f.truth["parameters"]
        core = {k: v for k, v in tp.items() if k not in ("Kn", "Tn")}
        wc_true = crossover("expanded", core, plants, duration_s=70.0).frequency_rad_s
        lin = linear_run(plants, f.truth["model"], tp, f.run, f.truth["seeds"]["remnant"])
        td = linear_td_run(plants, f.truth["model"], tp, f.run, f.truth["seeds"]["remnant"])
        row = [pid, f"{tp['Ke']:7.2f}", f"{tp['Km']:7.2f}", f"{wc_true:6.2f}", "|"]
        skip = slice(int(5.0 / f.run.dt), None)   # past the start transient
        scale = float(np.std(lin.control[skip]))
        d_td = float(np.std((td.control - lin.control)[skip])) / scale
        d_js = float(np.std((f.run.control - td.control)[skip])) / scale
        errs.setdefault("d_td", []).append(d_td)
        errs.setdefault("d_js", []).append(d_js)
        row += [f"u: td-fft {100 * d_td:4.1f}%, jsb-td {100 * d_js:4.1f}% |"]
        for tag, run in (("j", f.run), ("f", lin), ("t", td)):
            idf = identify(run, plants, "expanded", seed=pseed, with_benchmark=False,
                           with_identifiability=False, restarts=RESTARTS, passes=PASSES, criterion=CRITERION)
            at_truth = identify(run, plants, "expanded", free=(), fixed=core, with_benchmark=False,
                                with_identifiability=False, criterion=CRITERION).fitness
            # found < truth: the data's optimum is elsewhere (model/data mismatch);
            # found > truth: the search missed a better point (optimiser)
            errs.setdefault(f"{tag}_mismatch", []).append(idf.fitness < at_truth)
            wc_id = (idf.primary_crossover or idf.crossover).frequency_rad_s
            # loop gain: |L(j wc_true)| of the identified pilot (the truth's is 1)
            e = (rel(idf.parameters["Ke"], tp["Ke"]), rel(idf.parameters["Km"], tp["Km"]),
                 rel(wc_id, wc_true), abs(loop_gain("expanded", idf.parameters, plants, wc_true) - 1.0))
            for key, v in zip(("ke", "km", "wc", "lg"), e):
                errs[f"{tag}_{key}"].append(v)
            row += [f"{100 * x:5.0f}%" for x in e] + ["|"]
        for tag, run in (("j2", f.run), ("f2", lin), ("t2", td)):
            idf = identify(run, plants, "expanded", free=("Ke", "Km"),
                           fixed={k: v for k, v in core.items() if k not in ("Ke", "Km")}, seed=pseed,
                           with_benchmark=False, with_identifiability=False, restarts=RESTARTS,
                           passes=PASSES, criterion=CRITERION)
            e = (rel(idf.parameters["Ke"], tp["Ke"]), rel(idf.parameters["Km"], tp["Km"]))
            errs[f"{tag}_ke"].append(e[0])
            errs[f"{tag}_km"].append(e[1])
            row += [f"{100 * x:5.0f}%" for x in e] + ["|"]
        # Proprioception known (K1, K2, 1/T1 at the truth), the rest of the df criterion's set
        # free: does Km trade with the proprioceptive gain K1 K2 (both inner feedbacks)?
        idf = identify(f.run, plants, "expanded", free=("Ke", "Km", "tau0", "wn", "zn"),
                       fixed={k: core[k] for k in ("K1", "K2", "1/T1")}, seed=pseed, with_benchmark=False,
                       with_identifiability=False, restarts=RESTARTS, passes=PASSES, criterion=CRITERION)
        e = (rel(idf.parameters["Ke"], tp["Ke"]), rel(idf.parameters["Km"], tp["Km"]))
        errs.setdefault("j3_ke", []).append(e[0])
        errs.setdefault("j3_km", []).append(e[1])
        row += ["K1,K2,1/T1 true: jsbsim " + " ".join(f"{100 * x:5.0f}%" for x in e)]
        print(" ".join(row), flush=True)
    m = {k: 100 * median(v) for k, v in errs.items()}
    for tag, name in (("j", "jsbsim"), ("f", "fft"), ("t", "td")):
        mis = errs[f"{tag}_mismatch"]
        print(f"{name}: identified fitness below the truth's (optimum away from the truth: data vs "
              f"model) in {sum(mis)}/{len(mis)}; above it (the search missed) in {len(mis) - sum(mis)}/{len(mis)}")
    print(f"median control difference: td-fft {100 * median(errs['d_td']):.2f} %, jsb-td "
          f"{100 * median(errs['d_js']):.2f} %")
    print(f"median |relative error| over {len(flights)} pilots (<= 20 % wanted):")
    for t, name in (("j", "jsbsim"), ("f", "fft (same plants, no JSBSim)"), ("t", "td (plants stepped like JSBSim)")):
        print(f"  default free set, {name}: Ke {m[t + '_ke']:.0f} %, Km {m[t + '_km']:.0f} %, crossover "
              f"{m[t + '_wc']:.0f} %, loop gain {m[t + '_lg']:.0f} %")
    print(f"  free Ke,Km        jsbsim: Ke {m['j2_ke']:.0f} %, Km {m['j2_km']:.0f} %"
          f"   | fft: Ke {m['f2_ke']:.0f} %, Km {m['f2_km']:.0f} %   | td: Ke {m['t2_ke']:.0f} %, Km {m['t2_km']:.0f} %")
    print(f"  free Ke,Km,tau0,wn,zn (K1, K2, 1/T1 at the truth)  jsbsim: Ke {m['j3_ke']:.0f} %, Km {m['j3_km']:.0f} %")


DIAG_CASES = {
    "baseline": ((), {}),
    "motion_feedback": (("motion_feedback",), {"Km": (2.0, 8.0)}),   # x gain scale
    "extra_delay": (("extra_delay",), {"tau_x": (0.05, 0.2)}),
}
# --diag-cases adds this one: a simulator delay that takes the total beyond a human's 0.40 s
# (diagnose's max_pilot_delay), the only extra delay a record can attribute to the simulator.
EXTRA_CASES = {"extra_delay_long": (("extra_delay",), {"tau_x": (0.25, 0.4)})}


def section_diagnose(plants, work: Path, seeds: int, how: str, seed_start: int = 0) -> None:
    from hesspipe.diagnose.workflow import diagnose

    print(f"\n== 4. diagnose (baseline 'original') on JSBSim-flown runs ({FORCING} forcing), {seeds} seeds per case (from {seed_start}), "
          f"pilots of the '{how}' draw" + (" (tau0 = 0.1 s and 1/T1 = 0.01 as diagnose's baseline holds them: "
                                          "the hidden effect is the only pilot-side difference)" if how == "table1" else
                                          " (the pipeline's cohort: tau0 ~0.2 s, 1/T1 by Hess's rule, which "
                                          "diagnose's baseline holds at Table 1's 0.1 s and 0.01)"))
    g = gain_scale(plants)
    for case, (effects, ranges) in CASES.items():
        named, named_lin, rows = [], [], []
        for s in range(seed_start, seed_start + seeds):
            pid = f"diag-{case}-{s}"
            try:
                pseed, truth, params = draw(plants, pid, 7, (), how)   # a baseline pilot (original + remnant)
            except HesspipeError as exc:
                rows.append(f"  {pid}: no pilot drawn ({exc})")
                continue
            rng = np.random.default_rng(derive_seed(pseed, "hidden"))
            hidden = {k: float(rng.uniform(lo, hi)) * (g if k == "Km" else 1.0) for k, (lo, hi) in ranges.items()}
            model = "+".join(["expanded" if "motion_feedback" in effects else "original"]
                             + [e for e in effects if e != "motion_feedback"] + ["remnant"])
            try:
                f = fly_pilot_record("737", plants, model, {**params, **hidden}, seed=pseed,
                                     workdir=work / "diag", record_every=EVERY,
                                     remnant_share=truth["remnant_share"], run_id=pid, **forcing_kwargs())
            except HesspipeError as exc:
                rows.append(f"  {pid}: flight failed ({exc})")
                continue
            lin = (linear_run(plants, f.truth["model"], f.truth["parameters"], f.run, f.truth["seeds"]["remnant"])
                   if FORCING == "paper" else None)  # (the linear twin has no reference)
            base = None
            if PAIRED:
                # The same pilot's baseline flight: no hidden effect, its own remnant and
                # forcing phases (a model pilot: no run-to-run scatter of its parameters).
                try:
                    base = fly_pilot_record("737", plants, "original+remnant", params,
                                            seed=derive_seed(pseed, "baseline-run"), workdir=work / "diag",
                                            record_every=EVERY, remnant_share=truth["remnant_share"],
                                            run_id=pid + "-baseline", **forcing_kwargs()).run
                except HesspipeError as exc:
                    rows.append(f"  {pid}: baseline flight failed ({exc})")
                    continue
                lin = None
            try:
                d = diagnose(f.run, plants, model="original", seed=pseed, baseline_run=base)
                d_lin = diagnose(lin, plants, model="original", seed=pseed) if lin is not None else None
            except HesspipeError as exc:
                rows.append(f"  {pid}: diagnose refused ({exc})")
                continue
            named.append(tuple(d.named_effects))
            if d_lin is not None:
                named_lin.append(tuple(d_lin.named_effects))
            rows.append(f"  {pid}: hidden {hidden or '-'} -> jsbsim run: named {list(d.named_effects) or 'nothing'} "
                        f"(plant check fit {d.plant_check.fit_percent:.0f} %)"
                        + (f"; same pilot, linear fft run: named {list(d_lin.named_effects) or 'nothing'}"
                           if d_lin is not None else ""))
        print(f"{case}:")
        print("\n".join(rows))
        for label, got in (("jsbsim", named), ("fft", named_lin)) if named_lin else (("jsbsim", named),):
            if case == "baseline":
                side = sum(any(e in ("motion_feedback", "extra_delay", "otoliths") for e in n) for n in got)
                print(f"  -> {label}: baseline runs naming a pilot-side effect other than the remnant they "
                      f"carry: {side}/{len(got)}")
            else:
                hit = sum(effects[0] in n for n in got)
                print(f"  -> {label}: {effects[0]} named in {hit}/{len(got)} ({100 * hit / max(len(got), 1):.0f} %)")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--pilots", type=int, default=20)
    ap.add_argument("--diag-seeds", type=int, default=4)
    ap.add_argument("--diag-seed-start", type=int, default=0,
                    help="first seed of the diagnose section (reported figures: 0; develop on others)")
    ap.add_argument("--repeats", type=int, default=7)
    ap.add_argument("--skip", default="", help="comma list of sections to skip: speed,envelope,ident,diagnose "
                    "(skipping envelope skips ident too)")
    ap.add_argument("--restarts", type=int, default=2)
    ap.add_argument("--passes", type=int, default=10)
    ap.add_argument("--criterion", default="df", choices=("df", "paper", "output"))
    ap.add_argument("--cohort", default="crossover_model", choices=("crossover_model", "table1"))
    ap.add_argument("--forcing", default="paper", choices=("paper", "two-input"),
                    help="the paper's side wind and gusts, or hesspipe.flight.target.TWO_INPUT (wind and "
                         "roll-rate target multisines, 15 s run-in not recorded) for the diagnose section")
    ap.add_argument("--target-rms", type=float, default=None, help="two-input target RMS, rad/s")
    ap.add_argument("--diag-cases", default=",".join(DIAG_CASES),
                    help=f"comma list of {', '.join([*DIAG_CASES, *EXTRA_CASES])}")
    ap.add_argument("--diag-cohorts", default="table1,crossover_model",
                    help="cohort draws of the diagnose section's pilots (comma list)")
    ap.add_argument("--paired", action="store_true",
                    help="diagnose section: each pilot also flies a baseline flight, given to diagnose "
                         "as baseline_run (the within-subject extra-delay test; needs --forcing two-input)")
    args = ap.parse_args(argv)
    globals().update(RESTARTS=args.restarts, PASSES=args.passes, CRITERION=args.criterion, DRAW=args.cohort,
                     FORCING=args.forcing, TARGET_RMS=args.target_rms, PAIRED=args.paired,
                     CASES={c: {**DIAG_CASES, **EXTRA_CASES}[c] for c in args.diag_cases.split(",")})
    skip = set(args.skip.split(","))
    print("SYNTHETIC DATA: Hess pilot models flying the JSBSim 737 (hesspipe.flight.closed_loop)")
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        t0 = time.perf_counter()
        plants = fitted_plants(root)
        print(f"plants fitted by stages one and two (flight seed 1) in {time.perf_counter() - t0:.1f} s; "
              f"gain scale {gain_scale(plants):.3f}")
        if "speed" not in skip:
            section_speed(plants, root, args.repeats)
        if "envelope" not in skip:
            section_envelope_and_identification(plants, root, args.pilots, ident="ident" not in skip)
        if "diagnose" not in skip:
            for how in args.diag_cohorts.split(","):
                section_diagnose(plants, root, args.diag_seeds, how, args.diag_seed_start)
    return 0


if __name__ == "__main__":
    sys.exit(main())
