"""Reliability of the main job (issue 10, item 1): stability relative to the record.

The 737 seeds that failed ``hesspipe run`` (0, 3, 4, 5, 6, 7: "no stable closed loop in
200 draws") are covered on the plants those seeds' flights produce (coefficients below,
fitted by ``hesspipe plants`` from the JSBSim 737 records of ``hesspipe flight --seed S``;
SYNTHETIC data). The simulation of a loop with a slow right-half-plane mode is checked
against an independent fine-step time-domain reference (python-control, Padé delay).
"""

from __future__ import annotations

import math

import control as ct
import numpy as np
import pytest
from scipy import signal

from hesspipe.core.formats import Plants
from hesspipe.core.seeds import derive_seed
from hesspipe.pilot.hess import PilotModel, table1
from hesspipe.pilot.simulation import Simulator, growth_limit, simulate
from hesspipe.pilots.cohort import CohortSpec, pilot_ids, synth_pilot
from hesspipe.plants import order, validation
from hesspipe.plants.slow_roots import reflect_slow_roots
from pilot_data import DT, YD, N, multisine, reference_control

#: Yc (aileron -> roll rate) and Yd (lateral wind -> roll rate) fitted for seed S (num, den).
FITTED_737 = {
    0: (((-0.03001983413, 0.1527896761, 26.08602966, 623.397944, 383.3707789, 612.1118206, -4.340240514),
          (1, 81.55618312, 1726.241113, 2630.881224, 2896.111639, 2040.201188, 128.4408235)),
        ((-0.000580226587, 0.001462765862, 0.5563504469, 12.47998274, 2.404899871, -0.07507439868),
          (1, 81.36621906, 1710.865275, 2312.347511, 2586.558703, 1563.157711))),
    3: (((-0.0301866129, 0.1592766458, 26.08729579, 623.7042921, 380.7102369, 618.8616485, -4.844092812),
          (1, 81.55345477, 1726.026646, 2626.832206, 2903.179427, 2059.961983, 128.3232448)),
        ((-0.002859871164, -0.1155110103, 4.531126503, 184.816785, 71.46780289, 1.330504862, -0.04618817772),
          (1, 701.0334706, 24776.97053, 38793.33497, 42972.11255, 30959.26766, 2817.134067))),
    4: (((-0.03012819588, 0.156714146, 26.10398688, 623.4211336, 380.0018933, 610.1192096, -5.0184328),
          (1, 81.55100038, 1725.818316, 2621.928711, 2882.557493, 2030.752323, 126.0560931)),
        ((-0.005070739527, -0.2042050895, 8.058214057, 326.7301876, 87.95063361, -3.271045097, 0.1028733119),
          (1, 1224.085629, 43643.43659, 62925.29848, 69421.6527, 46135.44754, 940.9255304))),
    5: (((-0.03027134819, 0.1610461217, 26.15512824, 623.5947578, 380.3727537, 613.3756725, -4.911154865),
          (1, 81.55060491, 1725.78976, 2621.547021, 2887.847158, 2037.928156, 126.7286182)),
        ((-0.001158257095, -0.0002367123543, 1.851477798, 0.3783959267, 2.773697848, 0.5501443208, -0.01659861552),
          (1, 242.2526595, 335.5459759, 745.266909, 739.1729016, 571.7698233, 356.6487509))),
    6: (((-0.03018788361, 0.1591142482, 26.08687636, 623.9765435, 384.1804941, 617.1516419, -4.91542239),
          (1, 81.55798175, 1726.390747, 2634.227731, 2906.042681, 2055.027523, 127.4075743)),
        ((-0.001236618152, -0.0002512119799, 1.977593041, 0.4017223196, 1.593609474, 0.3469572048, -0.01076138254),
          (1, 260.3851994, 354.7958081, 617.2029206, 544.3398112, 330.5262599, 210.502655))),
    7: (((-0.03012377394, 0.154793776, 26.17758075, 623.2467463, 380.7539038, 612.3787168, -4.517658158),
          (1, 81.5510334, 1725.82499, 2622.309264, 2889.421345, 2039.081844, 128.3862094)),
        ((-0.0006018124947, 0.002450100697, 0.5490638759, 12.56901964, 2.572629849, -0.08300442378),
          (1, 81.38888118, 1712.684881, 2349.160432, 2598.985987, 1599.339889))),
}


FAILED_SEEDS = sorted(FITTED_737)


def _plants(seed: int) -> Plants:
    (cn, cd), (dn, dd) = FITTED_737[seed]
    return Plants(ct.tf(list(cn), list(cd)), ct.tf(list(dn), list(dd)))


def test_growth_limit_is_a_doubling_over_the_record():
    assert growth_limit(70.0) == pytest.approx(math.log(2) / 70.0)
    assert growth_limit(70.0) == pytest.approx(0.0099, abs=1e-4)


@pytest.mark.parametrize("seed", FAILED_SEEDS)
def test_failed_seeds_draw_their_cohort_on_their_own_plants(seed):
    plants = _plants(seed)
    zeros = np.roots(np.squeeze(plants.control_to_output.num[0][0]))
    # These plants hold the slow right-half-plane zero that made every high-gain loop "unstable".
    assert np.any((zeros.real > 0) & (np.abs(zeros) < growth_limit(70.0)))
    spec = CohortSpec()
    model = PilotModel(("motion_feedback", "remnant"))
    rates = []
    for pid in pilot_ids(6):
        run, truth = synth_pilot(plants, pid, derive_seed(seed, pid), ("motion_feedback",), spec)
        assert np.all(np.isfinite(run.control)) and np.all(np.isfinite(run.output))
        assert np.std(run.control) > 0
        sim = Simulator(plants, run.disturbance, spec.dt_s)
        rates.append(sim.growth_rate(model.loop(model.complete(truth["parameters"]))))
        assert rates[-1] < sim.growth_limit
    # At least one drawn pilot grows (slower than the record can see): the case that failed.
    assert max(rates) > 0.0, rates


def test_slow_growing_loop_simulation_is_the_causal_time_domain_response():
    # A plant with a slow right-half-plane zero: Table 1's pilot pulls a closed-loop mode
    # next to it, growing at a few 1e-3 1/s (stable on a 70 s record, not asymptotically).
    yc = ct.tf([2.436, -2.436 * 0.004], [1.0, 1.0496 + 0.02, 1.0496 * 0.02])
    p = PilotModel().complete(table1(1))
    sim0 = Simulator(Plants(yc, YD), np.ones(N), DT)
    rate = sim0.growth_rate(PilotModel().loop(p))
    assert 0.0 < rate < sim0.growth_limit
    fine = 10
    t_fine = np.arange(N * fine) * DT / fine
    w_fine = multisine(t_fine, offset=2.0)   # a mean wind excites the slow mode
    ref = reference_control(p, t_fine, w_fine, yc=yc)[::fine]
    sim = simulate("original", p, Plants(yc, YD), w_fine[::fine], DT)
    assert sim.stable
    err = np.sqrt(np.mean((sim.control - ref) ** 2)) / np.sqrt(np.mean(ref ** 2))
    assert err < 0.01, err


def _growing_pair_data(n=1400, dt=0.05, seed=4):
    # A lightly damped pair growing at 0.003 1/s (an MD11-like Dutch roll) plus a roll mode.
    r = math.exp(0.003 * dt)
    w = 0.39 * dt
    a = np.convolve([1.0, -2 * r * math.cos(w), r * r], [1.0, -math.exp(-1.0 * dt)])
    b = np.array([0.0, 0.02, 0.01])
    t = dt * np.arange(n)
    rng = np.random.default_rng(seed)
    freqs = np.arange(1, 41) * 0.05
    u = sum(np.cos(2 * np.pi * f * t + rng.uniform(0, 2 * np.pi)) for f in freqs) / 5.0
    return u, signal.lfilter(b, a, u), dt


def test_order_selection_accepts_poles_growing_slower_than_the_record_resolves():
    u, y, dt = _growing_pair_data()
    n = int(0.7 * len(u))
    strict = order.select_order(u[:n], y[:n], dt=dt, focus="simulation")
    relaxed = order.select_order(u[:n], y[:n], dt=dt, focus="simulation",
                               max_growth=growth_limit(dt * len(u)))
    assert not relaxed.model.is_stable() and relaxed.model.is_stable(growth_limit(dt * len(u)))
    fit_relaxed = validation.fit_percent(y[n:], relaxed.model.simulate(u)[n:])
    fit_strict = validation.fit_percent(y[n:], strict.model.simulate(u)[n:])
    assert fit_relaxed > 99.0 and fit_strict < fit_relaxed - 5.0, (fit_strict, fit_relaxed)


def test_reflecting_slow_roots_keeps_the_gain_and_moves_only_them():
    sys = ct.tf(np.polymul([1.0, -0.005], [1.0, 3.0]), np.polymul([1.0, 0.5], [1.0, 0.2, 4.0]))
    out, roots = reflect_slow_roots(sys, 0.0099)
    assert [r["kind"] for r in roots] == ["zero"]
    assert roots[0]["before"]["re"] == pytest.approx(0.005) and roots[0]["after"]["re"] == pytest.approx(-0.005)
    np.testing.assert_allclose(np.sort(np.roots(np.squeeze(out.num[0][0])).real), [-3.0, -0.005], rtol=1e-9)
    w = np.logspace(-3, 2, 200)
    np.testing.assert_allclose(np.abs(out(1j * w)), np.abs(sys(1j * w)), rtol=1e-9)
    # A resolved right-half-plane zero (faster than the record's resolution) stays.
    same, none = reflect_slow_roots(ct.tf([1.0, -0.5], [1.0, 1.0]), 0.0099)
    assert none == [] and same is not None


def test_plant_check_response_of_a_near_integrating_plant_matches_time_domain():
    # B747 seed 4's fitted Yc holds a pole at -1.3e-5 1/s: on s = j w with 4 records of
    # padding its tail wrapped around and diagnose's plant check read -465 %.
    from hesspipe.diagnose.checks import forced_response

    sys = ct.tf([2.0, 1.0], np.polymul([1.0, 1.3e-5], [1.0, 0.85, 1.0]))
    t = DT * np.arange(N)
    u = multisine(t, offset=0.5)
    fine = 10
    t_fine = np.arange(N * fine) * DT / fine
    ref = np.asarray(ct.forced_response(sys, T=t_fine, U=multisine(t_fine, offset=0.5)).outputs)[::fine]
    y = forced_response(sys, u, DT)
    err = np.sqrt(np.mean((y - ref) ** 2)) / np.sqrt(np.mean(ref ** 2))
    assert err < 0.01, err


def test_slow_roots_setting_is_checked():
    from hesspipe.core.errors import HesspipeError
    from hesspipe.plants.settings import PlantsConfig

    assert PlantsConfig().slow_roots == "keep"
    assert PlantsConfig.from_table({"slow_roots": "reflect"}).slow_roots == "reflect"
    with pytest.raises(HesspipeError, match="slow_roots"):
        PlantsConfig.from_table({"slow_roots": "maybe"})


def test_df_search_leaves_a_flown_pilot_that_is_stable_on_the_record_near_its_truth(tmp_path):
    """JSBSim-flown two-input runs (SYNTHETIC, cohort pilots with motion feedback and the cohort's
    remnant) on the 737 plants fitted for seed 0, whose slow right-half-plane zero keeps every
    such loop growing at +0.002..0.004 1/s: stable on the 70 s record. The df search started at
    the truth must not be pushed off it by its stability residual (it was, when the residual
    started 0.01 1/s left of the axis: K1 fell 94-99 % and Ke 74-83 % on all four pilots)."""
    from hesspipe.flight.approach import FlightConfig
    from hesspipe.flight.closed_loop import fly_pilot_record
    from hesspipe.flight.target import TWO_INPUT
    from hesspipe.identification.fit import identify
    from hesspipe.pilot.hess import model_from_name
    from hesspipe.pilots.cohort import cohort_spec

    plants, m = _plants(0), model_from_name("expanded")
    for pid in ("pilot01", "pilot02", "pilot03", "pilot04"):
        seed = derive_seed(1, pid)
        _, truth = synth_pilot(plants, pid, seed, ("motion_feedback",), cohort_spec("crossover_model"))
        params = {k: v for k, v in truth["parameters"].items() if k != "Kn"}
        f = fly_pilot_record("737", plants, "expanded+remnant", params, seed=seed, workdir=tmp_path,
                             record_every=3, run_id=pid, target=TWO_INPUT, remnant_share=truth["remnant_share"],
                             config=FlightConfig(duration_s=70.0 + TWO_INPUT.run_in_s))
        tp = f.truth["parameters"]
        sim = Simulator(plants, f.run.disturbance, f.run.dt)
        rate = sim.growth_rate(sim.prepare(m.loop(m.complete({k: tp[k] for k in m.parameter_names()}))))
        assert 0.0 < rate < sim.growth_limit  # the case: growing, but stable on the record
        start = {k: tp[k] for k in ("Ke", "K1", "1/T1", "tau0", "wn", "zn", "Km")}
        q = identify(f.run, plants, "expanded", seed=seed, criterion="df", with_benchmark=False,
                     with_identifiability=False, initial=start, restarts=1).parameters
        for k in ("Ke", "K1"):
            assert abs(math.log(q[k] / tp[k])) < math.log(2.0), (pid, k, q[k] / tp[k])
