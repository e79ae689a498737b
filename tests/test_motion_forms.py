"""The motion test's vestibular forms (identification.motion_test.VESTIBULAR_FORMS): Hess's,
inside the proprioceptive loop; the multimodal pilot models', at the neuromuscular system (order
2); Hess's without the visual lag (order 1, UNEQUALISED).

The lines are built in the frequency domain from a multimodal person on a double integrator
(Zaal et al. 2009's structure: U = Hnm (Kv (1 + TL s) e^(-tau_v s) E - Km Hscc s e^(-tau_m s) Y)
+ N) or on a single integrator (Kv e^(-tau_v s) / (1 + TI s), gain only without a lag), so the
test meets a structure it does not share, and SYNTHETIC."""

from __future__ import annotations

import json

import numpy as np
import pytest

from hesspipe.core.formats import read_plants
from hesspipe.identification._line_fit import MULTIMODAL, _predict
from hesspipe.identification.lines import LineData
from hesspipe.identification.motion_test import (
    ALPHA,
    FORM_SHARES,
    FORMS_BY_ORDER,
    PRECISION,
    VESTIBULAR_FORMS,
    _either_order,
)
from hesspipe.pilot.hess import PilotModel
from hesspipe.pilot.motion import motion_block

KC = 4.0                      # the double integrator's gain, rad/s^2 per unit
T = 81.92                     # the forcing's period, s
D_BINS = np.array([5, 11, 23, 37, 53, 71, 97, 127, 163, 211])   # disturbance lines
R_BINS = D_BINS + 2                                              # target lines, interleaved


KC1 = 1.5                     # the single integrator's gain, rad/s per unit


def _plants(tmp_path, order: int = 2):
    path = tmp_path / "plants.json"
    el = {"num": [KC if order == 2 else KC1], "den": [1, 0, 0] if order == 2 else [1, 0]}
    path.write_text(json.dumps({"control_to_output": el, "disturbance_to_output": el,
                                "motion_path": {"num": [1, 0], "den": [0.01, 1]}}))
    return read_plants(path)


def _lines(km: float, seed: int, remnant: float = 0.03, order: int = 2, lag: float = 0.0) -> LineData:
    # A multimodal person closed around Yc = KC/s^2 (order 2) or KC1/s (order 1, with a visual
    # `lag`, s), disturbance at the plant input, the target's lines and the disturbance's
    # apart; remnant added to U at every line.
    lines = np.sort(np.concatenate([D_BINS, R_BINS]))
    s = 1j * 2.0 * np.pi * lines / T
    hnm = 10.0 ** 2 / (s ** 2 + 2 * 0.35 * 10.0 * s + 10.0 ** 2)
    hscc = 5.9 * s * (0.11 * s + 1) / ((5.9 * s + 1) * (0.005 * s + 1))
    if order == 2:
        tl = 1.2 * (1 - 0.3 * (km > 0))          # the visual lead, shortened where motion helps
        hpe, yc, d = hnm * 0.35 * (1 + tl * s) * np.exp(-0.22 * s), KC / s ** 2, 0.1
    else:
        hpe, yc, d = hnm * 2.0 * np.exp(-0.24 * s) / (1 + lag * s), KC1 / s, 0.3
    hpy = hnm * km * hscc * s * np.exp(-0.12 * s)
    rng = np.random.default_rng(seed)
    R = np.where(np.isin(lines, R_BINS), 1.0, 0.0) * np.exp(2j * np.pi * rng.random(lines.size))
    D = np.where(np.isin(lines, D_BINS), d, 0.0) * np.exp(2j * np.pi * rng.random(lines.size))
    sd = remnant * np.abs(hpe)
    N = sd * (rng.standard_normal(lines.size) + 1j * rng.standard_normal(lines.size)) / np.sqrt(2)
    Y = yc * (hpe * R + D + N) / (1 + yc * (hpe + hpy))
    E = R - Y
    U = hpe * E - hpy * Y + N
    # The remnant's own U/E at unforced bins is -1/Yc (e = -y = -Yc u there), all of U explained.
    return LineData(lines=lines, s=s, E=E, Y=Y, U=U, w=1.0 / sd, both=True, window_samples=8192,
                    h_level=hpe + hpy, g_remnant=-1.0 / yc, c_remnant=np.full(lines.size, 1e-9))


def _weighted_bonferroni(alts: dict) -> float:
    # Each form's share of the level split between its two alternatives; an alternative's
    # name is its form's (Hess's: none) before the parameters it adds.
    form = {a: a.split(" ")[0] if " " in a else "hess" for a in alts}
    return min(1.0, min(p / (FORM_SHARES[form[a]] / 2) for a, p in alts.items()))


def test_the_multimodal_form_keeps_the_vestibular_path_outside_the_proprioceptive_loop(tmp_path):
    plants = _plants(tmp_path)
    model = PilotModel(("motion_feedback",))
    p = {**model.defaults(k=2), "Km": 0.7, "tau_m": 0.1, "K1": 4.0}
    s = 1j * np.linspace(0.3, 12.0, 7)
    E, Y = np.exp(1j * np.arange(7.0)), 0.3 * np.exp(-2j * np.arange(7.0))
    cab = motion_block(plants)
    loop = model.loop(p)
    nm = loop.neuromuscular.response(s)
    rd = loop.return_difference(s, None)
    vis = loop.visual.response(s)
    ves = p["Km"] * cab.response(s) * (80 * 5.73 * s ** 2 / ((1 + 80 * s) * (1 + 5.73 * s))) \
        * np.exp(-s * p["tau_m"])
    hess = _predict(p, model, cab, s, E, Y)
    multimodal = _predict({**p, MULTIMODAL: 1.0}, model, cab, s, E, Y)
    np.testing.assert_allclose(hess, nm * (vis * E - ves * Y) / rd, rtol=1e-9)
    np.testing.assert_allclose(multimodal, nm * (vis * E / rd - ves * Y), rtol=1e-9)
    # Without the vestibular path the two forms are one model (the test's null is shared).
    np.testing.assert_allclose(_predict({**p, "Km": 0.0, MULTIMODAL: 1.0}, model, cab, s, E, Y),
                               _predict({**p, "Km": 0.0}, model, cab, s, E, Y), rtol=1e-12)


@pytest.mark.parametrize("seed", [1, 2])
def test_a_multimodal_persons_motion_is_found_in_the_precision_structure(tmp_path, seed):
    # Order 2 fits McRuer's precision structure too (PRECISION: no proprioceptive loop, the lead
    # a core parameter), the person's own, and keeps it: its expanded model scores better.
    plants = _plants(tmp_path)
    start = PilotModel().defaults(k=2, gain=1.0 / KC)
    r, _ = _either_order(_lines(0.35, seed), plants, start, k=2, max_delay=None, display="compensatory")
    assert r["structure"] == PRECISION and r["k"] == 2
    assert r["parameters_original"]["K1"] == 0.0 and r["parameters_original"]["TL_v"] > 0.5
    assert set(r["alternatives"]) == {"Km", "Km+tau_m"}           # one form: nothing else shapes the lead
    assert r["p_value"] == pytest.approx(min(1.0, 2 * min(r["alternatives"].values())))
    hess = r["hess"]                                               # Hess's result rides along
    assert hess["structure"] == "hess" and "hess" not in hess
    # Without it Hess's multimodal form names the person, whose own structure is surer still.
    alts = hess["alternatives"]
    assert set(alts) == {"Km", "Km+tau_m", "multimodal Km", "multimodal Km+tau_m"}
    assert hess["p_value"] == pytest.approx(_weighted_bonferroni(alts))
    assert hess["p_value"] < ALPHA and hess["vestibular_form"] == "multimodal"
    # Hess's form, the path led by the loop's lead, fits it far worse (p 100 times larger or more).
    assert min(alts["multimodal Km"], alts["multimodal Km+tau_m"]) < 1e-2 * min(alts["Km"], alts["Km+tau_m"])
    assert r["p_value"] < 1e-3 * hess["p_value"]


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_without_motion_neither_form_names_it(tmp_path, seed):
    plants = _plants(tmp_path)
    start = PilotModel().defaults(k=2, gain=1.0 / KC)
    r, _ = _either_order(_lines(0.0, seed), plants, start, k=2, max_delay=None, display="compensatory")
    assert r["p_value"] >= ALPHA


def test_the_forms_are_hess_first_and_share_the_level():
    # Hess's form is the paper's model, where the Km estimate is read, and the primary alternative.
    assert VESTIBULAR_FORMS[0] == "hess"
    assert set(FORM_SHARES) == set(VESTIBULAR_FORMS)
    for k, forms in FORMS_BY_ORDER.items():
        assert forms[0] == "hess" and len(forms) == 2 and set(forms) <= set(VESTIBULAR_FORMS)
        assert sum(FORM_SHARES[f] for f in forms) == pytest.approx(1.0)
        assert FORM_SHARES["hess"] > FORM_SHARES[forms[1]]


def test_a_single_integrator_persons_motion_is_tested_in_both_order_1_forms(tmp_path):
    r, _ = _either_order(_lines(0.3, 1, remnant=0.1, order=1), _plants(tmp_path, 1),
                         PilotModel().defaults(k=1, gain=1.0 / KC1), k=1, max_delay=None,
                         display="compensatory")
    alts = r["alternatives"]
    assert r["k"] == 1
    assert set(alts) == {"Km", "Km+tau_m", "unequalised Km", "unequalised Km+tau_m"}
    assert r["p_value"] == pytest.approx(_weighted_bonferroni(alts))
    assert r["p_value"] < ALPHA
    assert alts["unequalised Km"] < ALPHA


@pytest.mark.parametrize("seed", [2, 3])
def test_the_unequalised_form_is_not_admitted_where_the_lag_fits_better(tmp_path, seed):
    # A static person with a 0.6 s visual lag: without the lag the original misfits, and Km
    # takes up some of it (p 0.8-0.92 for Km with its delay), but that fit stays worse than the
    # original with the lag, so the form's alternatives are not admitted (p exactly 1).
    r, _ = _either_order(_lines(0.0, seed, remnant=0.1, order=1, lag=0.6), _plants(tmp_path, 1),
                         PilotModel().defaults(k=1, gain=1.0 / KC1), k=1, max_delay=None,
                         display="compensatory")
    assert r["k"] == 1 and r["p_value"] >= ALPHA
    assert r["alternatives"]["unequalised Km+tau_m"] == 1.0
