"""Hess structural model: parameters, effects, closed-loop simulation against an independent reference."""

import control as ct
import numpy as np
import pytest

from hesspipe.core.errors import HesspipeError
from hesspipe.core.formats import Plants
from hesspipe.identification.spectra import psd
from hesspipe.pilot.blocks import ZERO, from_tf, gain
from hesspipe.pilot.crossover import crossover, gain_scale
from hesspipe.pilot.effects import CANALS, EFFECTS, PLATFORM, WASHOUT, get_effect
from hesspipe.pilot.hess import PARAMETERS, PilotModel, model_from_name, table1
from hesspipe.pilot.simulation import Simulator, simulate, synthetic_run
from pilot_data import DT, YC, N, broadband, multisine, plants, reference_control


def test_table1_defaults_for_both_plant_types():
    for k in (1, 2):
        t = table1(k)
        assert t == {"Ke": 20.0, "K1": 3.0, "K2": 2.0, "1/T1": 0.01, "1/T2": 0.1, "k": float(k),
                     "tau0": 0.1, "zn": 0.707, "wn": 10.0, "Km": 0.1}
    with pytest.raises(HesspipeError, match="k"):
        table1(3)


def test_models_names_and_parameters():
    orig = model_from_name("original")
    exp = model_from_name("expanded")
    assert orig.name == "original" and exp.name == "expanded"
    assert orig.parameter_names() == PARAMETERS
    assert exp.parameter_names() == PARAMETERS + ("Km",)
    assert exp.defaults()["Km"] == 0.1
    assert orig.with_effect("remnant").name == "original+remnant"
    assert model_from_name("expanded+extra_delay").effects == ("motion_feedback", "extra_delay")
    assert set(exp.bounds()) == set(exp.parameter_names())
    with pytest.raises(HesspipeError, match="unknown model"):
        model_from_name("hess")
    with pytest.raises(HesspipeError, match="known effects"):
        get_effect("vertigo")
    with pytest.raises(HesspipeError, match="unknown parameter 'Kx'"):
        orig.complete({"Kx": 1.0})
    # Km of table1() is dropped for the original model, but strict mode refuses it.
    assert "Km" not in orig.complete(table1())
    with pytest.raises(HesspipeError, match="Km"):
        orig.complete({"Km": 1.0}, strict=True)


def test_effect_registry_is_complete_and_described():
    for eid in ("motion_feedback", "extra_delay", "remnant", "dutch_roll", "otoliths"):
        e = EFFECTS[eid]
        assert e.where in ("pilot", "aircraft", "simulator") and len(e.description) > 30
        for name, (default, lo, hi) in e.parameters.items():
            assert lo <= default <= hi and name not in PARAMETERS
            bits, scale, offset = e.fields[name]
            assert offset >= lo - 1e-12 and offset + (2 ** bits - 1) / scale <= hi + 1e-9


def _psd_error(d, dref):
    f, p1 = psd(d, 1 / DT)
    _, p2 = psd(dref, 1 / DT)
    band = f <= 5.0
    rel = np.abs(p1 - p2)[band] / p2[band]
    significant = p2[band] > 1e-2 * p2[band].max()
    return rel[significant].max(), np.abs(p1 - p2)[band].max() / p2[band].max()


@pytest.mark.parametrize("model,extra", [("original", {}), ("expanded", {"Km": 5.0})])
@pytest.mark.parametrize("offset", [0.0, 1.0])
def test_simulation_matches_fine_step_pade_reference(model, extra, offset):
    # Reference: python-control, 10x finer step, 10th-order Padé; the same
    # smooth multisine (optionally on a mean wind, which excites slow modes).
    fine = 10
    t_fine = np.arange(N * fine) * DT / fine
    w_fine = multisine(t_fine, offset=offset)
    m = model_from_name(model)
    p = m.complete(dict(table1(1), **extra))
    motion = None
    if extra:
        term = (CANALS * PLATFORM * WASHOUT).terms[0]
        motion = p["Km"] * ct.tf(list(term.num), list(term.den))
    dref = reference_control(p, t_fine, w_fine, motion=motion)[::fine]
    sim = simulate(m, p, plants(), w_fine[::fine], DT)
    assert sim.stable
    rel, peak = _psd_error(sim.control, dref)
    assert rel < 0.01, f"max relative PSD error {rel:.4f} over 0-5 Hz"
    assert peak < 0.01
    # Output consistent with the plants: y = Yc delta + Yd w, e = -y.
    assert np.allclose(sim.error, -sim.output)


def test_acceleration_plant_k2_matches_reference():
    # k = 2 (Y_PF with the extra lag) around Yc = 1/s^2 (SPEC.md's check plant) and a
    # roll-angle disturbance path Yd/s: integrators in both plants.
    yc, yd = ct.tf([1], [1, 0, 0]), plants().Yd * ct.tf([1], [1, 0])
    fine = 10
    t_fine = np.arange(N * fine) * DT / fine
    w_fine = multisine(t_fine)
    p = PilotModel().complete(table1(2))
    dref = reference_control(p, t_fine, w_fine, yc=yc, yd=yd)[::fine]
    sim = simulate("original", p, Plants(yc, yd), w_fine[::fine], DT)
    assert sim.stable
    rel, peak = _psd_error(sim.control, dref)
    assert rel < 0.01 and peak < 0.01


def test_unstable_parameters_flagged_not_raised_and_boundary_matches_phase_margin():
    pl = plants()
    w = broadband()
    m = PilotModel()
    # Find the gain where the phase margin crosses zero (Nyquist boundary for
    # this open-loop-stable L) and check the simulator's stability test on both sides.
    base = table1()

    def pm(ke):
        return crossover(m, dict(base, Ke=ke), pl).phase_margin_deg

    lo = 20.0
    assert pm(lo) > 0
    while pm(lo * 1.1) > 0:  # march until the margin first changes sign
        lo *= 1.1
    hi = lo * 1.1
    for _ in range(30):
        mid = np.sqrt(lo * hi)
        lo, hi = (mid, hi) if pm(mid) > 0 else (lo, mid)
    sim = Simulator(pl, w, DT)
    assert sim.stable(m.loop(m.complete(dict(base, Ke=lo * 0.98))))
    assert not sim.stable(m.loop(m.complete(dict(base, Ke=hi * 1.02))))
    bad = simulate(m, dict(base, Ke=hi * 1.5), pl, w, DT)
    assert bad.stable is False and np.all(np.isnan(bad.control))


def test_remnant_is_seeded_and_shaped():
    pl = plants()
    w = np.zeros(N)
    m = model_from_name("original+remnant")
    a = simulate(m, {"Kn": 0.05, "Tn": 0.5}, pl, w, DT, seed=7)
    b = simulate(m, {"Kn": 0.05, "Tn": 0.5}, pl, w, DT, seed=7)
    c = simulate(m, {"Kn": 0.05, "Tn": 0.5}, pl, w, DT, seed=8)
    assert np.array_equal(a.control, b.control) and not np.allclose(a.control, c.control)
    assert np.std(a.control) > 0
    zero = simulate(m, {"Kn": 0.0}, pl, broadband(), DT, seed=7)
    orig = simulate("original", {}, pl, broadband(), DT)
    assert np.allclose(zero.control, orig.control)
    # Remnant PSD follows the analytic closed-loop noise transfer (unit white, 0.5-3 Hz).
    f, p_sim = psd(a.control, 1 / DT)
    # simulate's defaults: Table 1 with the loop gains scaled to the plants
    loop = m.loop(m.complete({"Kn": 0.05, "Tn": 0.5}, gain=gain_scale(pl, 1)))
    s = 2j * np.pi * f
    nm, pf = loop.neuromuscular.response(s), loop.proprioceptive.response(s)
    yc = from_tf(YC).response(s)
    tn = loop.noise.response(s) / (1 + nm * pf + nm * loop.visual.response(s) * yc)
    hw = np.hamming(1024)
    expected = np.abs(tn) ** 2 * DT * np.mean(hw ** 2) / 0.612
    band = (f > 0.5) & (f < 3.0)
    ratio = np.mean(p_sim[band]) / np.mean(expected[band])
    assert 0.8 < ratio < 1.2


def test_effects_change_the_loop_and_reduce_to_original_at_neutral_values():
    pl, w = plants(), broadband()
    orig = simulate("original", {}, pl, w, DT).control
    for name, neutral, active in [("original+extra_delay", {"tau_x": 0.0}, {"tau_x": 0.1}),
                                  ("expanded", {"Km": 0.0}, {"Km": 5.0}),
                                  ("original+otoliths", {"Ko": 0.0}, {"Ko": 5.0}),
                                  ("original+dutch_roll", {"r_dr": 1.0}, {"z_dr": 0.05})]:
        same = simulate(name, neutral, pl, w, DT).control
        other = simulate(name, active, pl, w, DT).control
        assert np.allclose(same, orig, atol=1e-9 * np.abs(orig).max()), name
        assert np.max(np.abs(other - orig)) > 1e-3 * np.abs(orig).max(), name


def test_synthetic_run_is_labelled_and_consistent():
    pl, w = plants(), broadband()
    run = synthetic_run("expanded", {"Km": 2.0}, pl, w, DT, seed=3, run_id="p01")
    assert run.synthetic and run.id == "p01"
    assert any("synthetic" in c for c in run.comments) and any("Km=2" in c for c in run.comments)
    assert any("seed: 3" in c for c in run.comments)
    assert np.allclose(run.error, -run.output)
    with pytest.raises(HesspipeError, match="unstable"):
        synthetic_run("original", {"Ke": 20.0, "tau0": 0.9}, pl, w, DT, seed=0)


def test_reference_input_and_bad_plants():
    pl = plants()
    r = 0.01 * np.sin(2 * np.pi * 0.3 * np.arange(N) * DT)
    sim = simulate("original", {}, pl, np.zeros(N), DT, reference=r)
    assert np.std(sim.control) > 0 and np.allclose(sim.error, r - sim.output)
    bad = Plants(YC, ct.tf([1.0], [1.0, -0.5]))
    with pytest.raises(HesspipeError, match="unstable"):
        simulate("original", {}, bad, np.zeros(N), DT)
    # An integrating control plant (K/s) is fine.
    assert simulate("original", {}, Plants(ct.tf([1], [1, 0]), pl.Yd), broadband(), DT).stable


def test_a_loops_blocks_are_replaced_by_name_and_nothing_else_changes():
    loop = PilotModel().loop(PilotModel().complete({}, 1))
    new = loop.replace(noise=gain(2.0))
    assert new.noise == gain(2.0) and loop.noise == ZERO            # a new loop; the old one kept
    assert all(getattr(new, f) is getattr(loop, f) for f in ("visual", "vestibular", "neuromuscular",
                                                             "proprioceptive", "plant", "sensation"))
    with pytest.raises(TypeError, match="no block nois"):
        loop.replace(nois=ZERO)
