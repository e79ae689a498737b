"""Loop gains follow the plants (gain scale), remnant is a share of control power.

Two plant sets: SPEC.md's analytic roll plants and the JSBSim 737's ARX plants (coefficients
copied from ``hesspipe run`` with the default configuration: normalised aileron command ->
roll rate, |Yc| 0.31 at 1 rad/s, 0.12 at 3 rad/s).
"""

from __future__ import annotations

import math

import control as ct
import numpy as np
import pytest

from hesspipe.core.errors import HesspipeError
from hesspipe.core.formats import Plants
from hesspipe.core.paper import EQ14, EQ16
from hesspipe.identification.apid import Field
from hesspipe.identification.fit import identify
from hesspipe.identification.problem import default_fields
from hesspipe.pilot.crossover import crossover, gain_scale, reference_crossover
from hesspipe.pilot.hess import LOOP_GAINS, PilotModel, table1
from hesspipe.pilot.simulation import simulate
from hesspipe.pilots.cohort import SHARE_RANGE, CohortSpec, draw_parameters, synth_pilot
from hesspipe.pilots.compare import CompareSettings, compare_run

SHORT = CohortSpec(duration_s=24.0)  # 1200 samples: one spectral segment and a bit


def paper_plants() -> Plants:
    return Plants(ct.tf(*EQ14), ct.tf(*EQ16))


def jsbsim_plants() -> Plants:
    yc = ct.tf([-0.03001172341, 0.1537485569, 26.04518069, 623.0511997, 380.5606093, 608.3597978,
                -3.872701461],
               [1.0, 81.5503984, 1725.770434, 2620.984121, 2882.719558, 2025.26932, 129.2816927])
    yd = ct.tf([-0.0005812965402, 0.001519854882, 0.555086615, 12.50425046, 2.541826978, -0.07996726476],
               [1.0, 81.38979239, 1712.759841, 2350.793537, 2603.100254, 1615.633744])
    return Plants(yc, yd)


PLANTS = {"paper": paper_plants, "jsbsim": jsbsim_plants}


def test_gain_scale_is_one_for_the_plant_table1_is_calibrated_for():
    assert reference_crossover(1) == pytest.approx(2.886, abs=0.005)  # SPEC.md: ~2.9 rad/s
    assert gain_scale(ct.tf([1.0], [1.0, 0.0])) == pytest.approx(1.0, rel=1e-9)
    assert gain_scale(ct.tf([4.0], [1.0, 0.0])) == pytest.approx(0.25, rel=1e-9)
    assert gain_scale(ct.tf([1.0], [1.0, 0.0, 0.0]), k=2) == pytest.approx(1.0, rel=1e-9)
    with pytest.raises(HesspipeError, match="control_to_output has gain 0"):
        gain_scale(ct.tf([0.0], [1.0, 1.0]))


@pytest.mark.parametrize("name, expected", [("paper", 0.437), ("jsbsim", 2.71)])
def test_scaled_table1_crosses_over_where_table1_does_on_1_over_s(name, expected):
    plants = PLANTS[name]()
    g = gain_scale(plants)
    assert g == pytest.approx(expected, rel=0.01)
    model = PilotModel()
    unscaled = crossover(model, table1(1), plants).frequency_rad_s
    # Table 1 as is: far too fast on the paper's plant (7.4 rad/s), no crossover at all on the 737.
    assert (unscaled > 7.0) if name == "paper" else math.isnan(unscaled)
    scaled = crossover(model, model.defaults(1, g), plants)
    assert scaled.frequency_rad_s == pytest.approx(reference_crossover(1), rel=1e-6)


def test_only_the_loop_gains_scale_boxes_fields_and_defaults():
    model = PilotModel(("motion_feedback", "remnant"))
    g = 2.5
    f1, fg, b1, bg = model.fields(), model.fields(g), model.bounds(), model.bounds(g)
    d1, dg = model.defaults(1), model.defaults(1, g)
    for n in model.parameter_names():
        if n in LOOP_GAINS:
            assert fg[n][0] == f1[n][0] and 10 <= fg[n][0] <= 11  # same bits
            field1, fieldg = Field(n, *f1[n]), Field(n, *fg[n])
            assert (fieldg.lo, fieldg.hi) == pytest.approx((g * field1.lo, g * field1.hi))
            assert bg[n] == pytest.approx((g * b1[n][0], g * b1[n][1]))
            assert dg[n] == pytest.approx(g * d1[n])
            fieldg.check_within(*bg[n])
        else:
            assert (fg[n], bg[n], dg[n]) == (f1[n], b1[n], d1[n]), n
    # Ke's box leaves room above Table 1 (the paper's 0..20.47 put Ke = 20 at its edge).
    assert b1["Ke"][1] >= 2 * table1(1)["Ke"]
    plants = jsbsim_plants()
    assert default_fields(model, plants) == model.fields(gain_scale(plants))
    assert model.complete({}, gain=g)["Ke"] == pytest.approx(20 * g)
    with pytest.raises(HesspipeError, match="gain scale"):
        model.fields(0.0)


def test_identification_defaults_follow_the_plants():
    plants = jsbsim_plants()
    g = gain_scale(plants)
    run, truth = synth_pilot(plants, "p1", 3, ["motion_feedback"], SHORT)
    fixed_point = identify(run, plants, "expanded", free=(), with_benchmark=False,
                           with_identifiability=False)
    assert fixed_point.parameters["Ke"] == pytest.approx(20 * g)
    assert fixed_point.parameters["Km"] == pytest.approx(0.1 * g)
    assert fixed_point.to_dict(spectra=False)["gain_scale"] == pytest.approx(g)
    assert fixed_point.crossover.frequency_rad_s == pytest.approx(reference_crossover(1), rel=0.05)
    res = identify(run, plants, "expanded", free=["Ke"], fixed={"K1": truth["parameters"]["K1"],
                                                                 "K2": truth["parameters"]["K2"],
                                                                 "Km": truth["parameters"]["Km"]},
                   optimizer="scipy", with_benchmark=False, with_identifiability=False)
    ke_field = Field("Ke", *res.fields["Ke"])
    assert ke_field.hi == pytest.approx(40.94 * g) and ke_field.bits == 11
    # The truth (beyond the paper's unscaled 0..20.47) is inside the box and recovered.
    assert truth["parameters"]["Ke"] > 20.47
    assert res.parameters["Ke"] == pytest.approx(truth["parameters"]["Ke"], rel=0.15)


def test_draws_centre_on_table1_times_the_gain_scale():
    model = PilotModel(("motion_feedback", "remnant"))
    spec = CohortSpec()
    for g in (0.44, 2.7):
        rng = np.random.default_rng(0)
        draws = [draw_parameters(model, rng, spec, g) for _ in range(300)]
        ke = np.array([d["Ke"] for d in draws])
        km = np.array([d["Km"] for d in draws])
        assert np.median(ke) == pytest.approx(20 * g, rel=0.08)
        assert ke.max() <= model.bounds(g)["Ke"][1]
        assert np.all((km >= g * spec.km_range[0]) & (km <= g * spec.km_range[1]))
        assert np.median([d["K1"] for d in draws]) == pytest.approx(3.0, rel=0.1)  # not scaled


@pytest.mark.parametrize("name", ["paper", "jsbsim"])
def test_remnant_is_the_drawn_share_of_control_variance(name):
    plants = PLANTS[name]()
    run, truth = synth_pilot(plants, "p1", 11, ["motion_feedback"], SHORT)
    share = truth["remnant_share"]
    assert SHARE_RANGE[0] <= share <= SHARE_RANGE[1]
    assert truth["gain_scale"] == pytest.approx(gain_scale(plants))
    model = PilotModel(tuple(truth["effects"]))
    # The noise-free control of the same (causal) simulation synthetic runs are made by.
    u0 = simulate(model, {**truth["parameters"], "Kn": 0.0}, plants, run.disturbance, run.dt,
                  seed=truth["seeds"]["remnant"]).control
    remnant = run.control - u0
    assert np.var(remnant) / (np.var(u0) + np.var(remnant)) == pytest.approx(share, rel=1e-6)


def test_motion_feedback_shows_on_the_737_plants_and_only_when_present(tmp_path):
    plants = jsbsim_plants()
    settings = CompareSettings(restarts=1, passes=6)
    improvements = {}
    for effects in (("motion_feedback",), ()):
        runs = [synth_pilot(plants, f"p{i}", 20 + i, effects, SHORT)[0] for i in range(2)]
        results = [compare_run(run, plants, settings) for run in runs]
        for r in results:
            assert r.expanded_fixed["fitness"] == pytest.approx(r.original["fitness"], rel=0.1)
            assert r.expanded_fixed["parameters"]["Km"] == pytest.approx(0.1 * gain_scale(plants))
        improvements[effects] = [r.improvement for r in results]
    assert min(improvements[("motion_feedback",)]) > 0.1, improvements
    # 0.06, was 0.05: since stability is judged relative to the record (simulate.growth_limit)
    # these seeds' pilots are their first draws, no longer redrawn until the loop decays on
    # the slow plant zero (which biased Ke low); the high-gain pilot p1 leaves Km a Ke-Km
    # trade-off worth 5.4 % on this 24 s record (0.30 and 0.31 with motion feedback).
    assert max(improvements[()]) < 0.06, improvements
