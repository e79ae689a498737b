"""The describing-function fits' loop at the lines (`identification._loop_at_lines`) and their
row-wise prediction (`_line_fit._predict_rows`): the direct evaluation, row by row, and the
Jacobian's columns evaluated at once must give the numbers of the blocks' path, one point at a
time, bit for bit (a search then takes the same steps to the same optimum)."""

from __future__ import annotations

import numpy as np
import pytest

from hesspipe.identification import _loop_at_lines as la
from hesspipe.identification._line_fit import MULTIMODAL, _predict, _predict_rows
from hesspipe.identification._lsq import _ForwardDifference
from hesspipe.pilot.blocks import tf
from hesspipe.pilot.hess import PilotModel

S = 1j * np.linspace(0.3, 12.0, 9)
E, Y = np.exp(1j * np.arange(9.0)), 0.3 * np.exp(-2j * np.arange(9.0))
CABS = {"paper": None, "angle": tf([1.0, 0.0], [0.01, 1.0]),
        "washed": tf([0.6, 0.0, 0.0, 0.0], [0.05, 1.1, 1.2, 0.25], delay=0.03)}


def _points(model, k, rng, n=12):
    base = model.defaults(k=k)
    for i in range(n):
        p = {**base, "Ke": float(rng.uniform(-3.0, 3.0)), "K1": float(rng.uniform(0.0, 5.0)),
             "1/T1": 0.0 if i == 3 else float(rng.uniform(0.1, 10.0)), "1/T2": float(rng.uniform(1.0, 20.0)),
             "tau0": float(rng.uniform(0.1, 0.4)), "wn": 1.0 if i == 5 else float(rng.uniform(5.0, 20.0)),
             "zn": float(rng.uniform(0.02, 1.0))}
        if "Km" in base:
            p["Km"] = 0.0 if i == 4 else float(rng.uniform(0.0, 4.0))
        yield p


@pytest.mark.parametrize("cab", sorted(CABS))
@pytest.mark.parametrize("k", [1, 2])
@pytest.mark.parametrize("effects", [(), ("motion_feedback",)])
def test_the_direct_loop_is_the_blocks_loop_bit_for_bit(cab, k, effects):
    # Km = 0 (the paper's path kept, times zero), 1/T1 = 0 (the lead a constant), wn = 1 and
    # Ke = 1 (a unit gain left out) and tau0 = 0 (no delay) included, one point at a time and
    # all as rows, with a fit's cache shared across the calls.
    model, rng, cache = PilotModel(effects), np.random.default_rng(k + len(effects)), {}
    points = list(_points(model, k, rng))
    points[6]["Ke"], points[7]["tau0"] = 1.0, 0.0
    rows = la.loop_rows(points, model, CABS[cab], S, cache)
    for i, p in enumerate(points):
        want = la.block_responses(p, model, CABS[cab], S)
        got = la.loop_rows([p], model, CABS[cab], S, cache)
        for a, b, c, name in zip(got, want, rows, ("nm", "vestibular", "visual", "1 + NM PF")):
            assert np.array_equal(a[0], b) and np.array_equal(c[i], b), (i, name)


def test_other_models_go_the_blocks_way():
    model = PilotModel(("motion_feedback", "extra_delay"))
    p = {**model.defaults(k=1), "Km": 0.8, "tau_x": 0.07}
    q = {**p, "tau_x": 0.02}
    rows = la.loop_rows([p, q], model, CABS["angle"], S, {})
    for i, point in enumerate((p, q)):
        want = la.block_responses(point, model, CABS["angle"], S)
        assert all(np.array_equal(a[i], b) for a, b in zip(rows, want))


def test_rows_are_the_points_one_at_a_time():
    # Each row with its own vestibular delay, equaliser, feedforward and vestibular form (some
    # zero, where a factor of exactly 1 is left out): row by row the one-point numbers.
    model, rng = PilotModel(("motion_feedback",)), np.random.default_rng(7)
    rows = []
    for i, p in enumerate(_points(model, 2, rng, n=8)):
        p.update({"tau_m": 0.0 if i % 3 == 0 else 0.12, "TL_v": 0.0 if i % 2 else 0.8,
                  "TI_v": 0.0 if i % 4 else 0.1, MULTIMODAL: float(i % 2), "Kff": 1.5, "T_ff": 0.2,
                  "ff_share": 0.6})
        rows.append(p)
    yc_inv = S ** 2 / 4.0
    for cache in (None, {}):
        u, g = _predict_rows(rows, model, CABS["washed"], S, E, Y, yc_inv, cache, response=True)
        for i, p in enumerate(rows):
            u1, g1 = _predict(p, model, CABS["washed"], S, E, Y, yc_inv, response=True)
            assert np.array_equal(u[i], u1) and np.array_equal(g[i], g1), i


def test_a_jacobian_from_rows_is_the_one_column_by_column():
    def resid(x):
        return np.array([np.sin(3 * x[0]) * x[2], np.exp(-x[1]) + x[0] * x[2], x[1] ** 3 - x[2]])

    def rows(X):
        return np.array([resid(x) for x in X])

    lo, hi = np.array([-1.0, -2.0, 0.0]), np.array([1.0, 2.0, 3.0])
    for x in ([0.0, 0.0, 1.0], [1.0 - 1e-9, -2.0 + 1e-12, 3.0], [0.3, 1.7, 1e-300]):
        x = np.array(x)
        one, many = _ForwardDifference(resid, lo, hi), _ForwardDifference(resid, lo, hi, rows)
        assert np.array_equal(one.jac(x), many.jac(x))
        assert one.jac(x).flags.f_contiguous == many.jac(x).flags.f_contiguous


@pytest.mark.parametrize("weights", ["fixed", "errors-in-variables"])
def test_a_pooled_fit_by_rows_is_the_fit_column_by_column(monkeypatch, weights):
    # Three runs pooled line by line, the later two each with its own gain solved at every
    # step, a target's feedforward and a tie: the whole search with its Jacobians by rows
    # ends where the column-by-column search does, bit for bit.
    import hesspipe.identification._line_fit as lf

    model = PilotModel(("motion_feedback",))
    truth = {**model.defaults(k=1), "Km": 0.6, "tau_m": 0.1, "Kff": 0.8, "T_ff": 0.2, "ff_share": 0.7}
    s, cab = np.tile(S, 3), CABS["angle"]
    groups = np.repeat([0, 1, 2], S.size)
    rng = np.random.default_rng(3)
    e = np.exp(1j * rng.uniform(0, 2 * np.pi, s.size))
    y = 0.4 * np.exp(1j * rng.uniform(0, 2 * np.pi, s.size))
    yc_inv = s / 1.5
    u = _predict(truth, model, cab, s, e, y, yc_inv) * np.repeat([1.0, 1.1, 0.9], S.size)
    u = u + 0.05 * (rng.standard_normal(s.size) + 1j * rng.standard_normal(s.size))
    w = np.full(s.size, 2.0) if weights == "fixed" else (lambda g: 2.0 / np.sqrt(1.0 + np.abs(g) ** 2))
    free = ["Ke", "tau0", "wn", "Km", "tau_m", "Kff"]
    lo, hi = np.array([0.1, 0.1, 2.0, 0.0, 0.0, 0.0]), np.array([50.0, 0.5, 40.0, 10.0, 0.25, 20.0])
    starts = [[truth[n] * 1.3 + 0.01 for n in free], [truth[n] * 0.8 + 0.01 for n in free]]

    def tie(p):
        p["T_ff"] = 0.2 + 0.01 * p["Kff"]

    fit = lf._fit(model, truth, free, lo, hi, starts, cab, s, e, y, u, groups, yc_inv, w, tie=tie, keep=1)
    real = lf.best_least_squares
    monkeypatch.setattr(lf, "best_least_squares", lambda *a, resid_rows=None, **k: real(*a, **k))
    by_columns = lf._fit(model, truth, free, lo, hi, starts, cab, s, e, y, u, groups, yc_inv, w, tie=tie, keep=1)
    assert fit[0] == by_columns[0] and fit[1] == by_columns[1]
    assert np.array_equal(fit[2].jac, by_columns[2].jac) and fit[2].nfev == by_columns[2].nfev


def test_the_paired_delay_fit_by_rows_is_the_fit_column_by_column(monkeypatch):
    # The joint fit of a run and its baseline (two runs' lines, shared and own parameters):
    # its Jacobians by rows give the result of the column-by-column search, bit for bit.
    import hesspipe.identification.paired_delay as pd

    lines = np.array([5, 11, 23, 37, 53, 71, 97, 127, 163, 211])
    s = 1j * 2.0 * np.pi * lines / 81.92
    rng = np.random.default_rng(5)

    def record(tau):
        p = {**PilotModel().defaults(k=1), "tau0": tau}
        e = np.exp(1j * rng.uniform(0, 2 * np.pi, s.size))
        y = 0.5 * np.exp(1j * rng.uniform(0, 2 * np.pi, s.size))
        u = _predict(p, PilotModel(), None, s, e, y) + 0.03 * (rng.standard_normal(s.size) + 1j * rng.standard_normal(s.size))
        return s, e, y, u, np.full(s.size, 3.0)

    runs = {"run": record(0.3), "base": record(0.22)}
    monkeypatch.setattr(pd, "_lines", lambda r, band: runs[r])
    monkeypatch.setattr(pd, "as_runs", lambda r: [r])
    monkeypatch.setattr(pd, "motion_block", lambda plants: None)
    start = PilotModel().defaults(k=1)
    by_rows = pd.paired_delay("run", "base", None, (start, start), k=1)
    real = pd.best_least_squares
    monkeypatch.setattr(pd, "best_least_squares", lambda *a, resid_rows=None, **kw: real(*a, **kw))
    assert by_rows["difference_s"] == pytest.approx(0.08, abs=0.01)
    assert pd.paired_delay("run", "base", None, (start, start), k=1) == by_rows
